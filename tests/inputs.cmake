# Bad input refused before anything is written or run (issue 18): the option
# checks as functions (unit), and as a user meets them through motionctl on
# the virtual board, with the board unchanged after each refusal (system).

mc_gtest(test_input_checks unit test_input_checks.cpp)
target_link_libraries(test_input_checks PRIVATE mc_machine)

mc_gtest(test_cli_refusals system test_cli_refusals.cpp)
target_link_libraries(test_cli_refusals PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_refusals PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>"
                                                     MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
add_dependencies(test_cli_refusals motionctl)
