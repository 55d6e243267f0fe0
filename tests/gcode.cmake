# G-code interpreter tests (host/gcode/), label unit.

mc_gtest(test_gcode_parse unit test_gcode_parse.cpp)
target_link_libraries(test_gcode_parse PRIVATE mc_gcode)

# Against LinuxCNC's rs274 (package linuxcnc-uspace) on tests/gcode/*.ngc.
mc_gtest(test_gcode_reference unit test_gcode_reference.cpp)
target_link_libraries(test_gcode_reference PRIVATE mc_gcode)
target_compile_definitions(test_gcode_reference PRIVATE MC_GCODE_CORPUS_DIR="${CMAKE_CURRENT_SOURCE_DIR}/gcode")

mc_gtest(test_gcode_interp unit test_gcode_interp.cpp)
target_link_libraries(test_gcode_interp PRIVATE mc_gcode)

mc_gtest(test_gcode_properties unit test_gcode_properties.cpp)
target_link_libraries(test_gcode_properties PRIVATE mc_gcode)

# The path planner (host/motion/planner) and the job (host/machine/job).
mc_gtest(test_planner unit test_planner.cpp)
target_link_libraries(test_planner PRIVATE mc_machine)

# Bed levelling: the height map file and programs deformed by it.
mc_gtest(test_height_map unit test_height_map.cpp)
target_link_libraries(test_height_map PRIVATE mc_machine mc_gcode)
mc_gtest(test_workpiece unit test_workpiece.cpp)
target_link_libraries(test_workpiece PRIVATE mc_machine mc_motion mc_gcode)
