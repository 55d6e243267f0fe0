# Host library and motionctl tests (label: unit).

mc_gtest(test_pid_design unit test_pid_design.cpp)
target_link_libraries(test_pid_design PRIVATE mc_control)

# Runs the built binary, as a user would: the error contract (one stderr line,
# exit code) is part of what is tested.
mc_gtest(test_cli_coeffs unit test_cli_coeffs.cpp)
target_link_libraries(test_cli_coeffs PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_coeffs PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_coeffs motionctl)

mc_gtest(test_cli_units unit test_cli_units.cpp)
target_link_libraries(test_cli_units PRIVATE mc_base)

mc_gtest(test_cli_interp unit test_cli_interp.cpp)
target_link_libraries(test_cli_interp PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_interp PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_interp motionctl)

mc_gtest(test_step_metrics unit test_step_metrics.cpp)
target_link_libraries(test_step_metrics PRIVATE mc_control)

mc_gtest(test_tuning unit test_tuning.cpp)
target_link_libraries(test_tuning PRIVATE mc_cosim)

mc_gtest(test_board_capture unit test_board_capture.cpp)
target_link_libraries(test_board_capture PRIVATE mc_link)

# The layer rule: includes go down only, by folder path (docs/architecture.md).
mc_gtest(test_layers unit test_layers.cpp)
target_compile_definitions(test_layers PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
