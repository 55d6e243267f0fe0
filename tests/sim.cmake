# Plant models and machine config (sim/), and motionctl plant (label: unit).

mc_gtest(test_sim_plant unit test_sim_plant.cpp)
target_link_libraries(test_sim_plant PRIVATE mc_sim)

mc_gtest(test_sim_config unit test_sim_config.cpp)
target_link_libraries(test_sim_config PRIVATE mc_sim)
