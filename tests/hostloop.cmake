# Host-loop platform: the double-precision PID, the jitter recorder and model,
# the host-loop event model and the benchmark metrics (label: unit).

mc_gtest(test_pid_double unit test_pid_double.cpp)
target_link_libraries(test_pid_double PRIVATE mc_control)

mc_gtest(test_jitter unit test_jitter.cpp)
target_link_libraries(test_jitter PRIVATE mc_plant)

mc_gtest(test_host_loop unit test_host_loop.cpp)
target_link_libraries(test_host_loop PRIVATE mc_plant)

mc_gtest(test_metrics unit test_metrics.cpp)
target_link_libraries(test_metrics PRIVATE mc_control)

# Runs the built binary; records for a fraction of a second per case.
mc_gtest(test_cli_jitter unit test_cli_jitter.cpp)
target_link_libraries(test_cli_jitter PRIVATE mc_plant nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_jitter PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_jitter motionctl)
