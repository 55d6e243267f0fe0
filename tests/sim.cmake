# Plant models and machine config (sim/), and motionctl plant (label: unit).

mc_gtest(test_sim_plant unit test_sim_plant.cpp)
target_link_libraries(test_sim_plant PRIVATE mc_plant)

mc_gtest(test_sim_config unit test_sim_config.cpp)
target_link_libraries(test_sim_config PRIVATE mc_plant)
target_compile_definitions(test_sim_config PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")

mc_gtest(test_cli_plant unit test_cli_plant.cpp)
target_link_libraries(test_cli_plant PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_plant PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>"
  MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
add_dependencies(test_cli_plant motionctl)

# The stepper axis's plant: resonance, detents, followed and lost steps.
mc_gtest(test_stepper_motor unit test_stepper_motor.cpp)
target_link_libraries(test_stepper_motor PRIVATE mc_plant)
mc_gtest(test_board_setup unit test_board_setup.cpp)
target_link_libraries(test_board_setup PRIVATE mc_machine)
target_compile_definitions(test_board_setup PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
