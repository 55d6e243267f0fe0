# The virtual board and the host link (label: system): the link against the
# board over a pseudo-terminal, and motionctl's board commands as a user
# runs them.

mc_gtest(test_board_link system test_board_link.cpp)
target_link_libraries(test_board_link PRIVATE mc_motion mc_vboard)

mc_gtest(test_cli_board system test_cli_board.cpp)
target_link_libraries(test_cli_board PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_board PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_board motionctl)

mc_gtest(test_cli_step system test_cli_step.cpp)
target_link_libraries(test_cli_step PRIVATE mc_cosim nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_step PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_step motionctl)

# G-code jobs: motionctl gcode and run on the virtual board.
mc_gtest(test_cli_run system test_cli_run.cpp)
target_link_libraries(test_cli_run PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_run PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_run motionctl)
