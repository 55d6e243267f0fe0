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

# The virtual board on the twin against the same on the Verilated board.
mc_gtest(test_vboard system test_vboard.cpp)
target_link_libraries(test_vboard PRIVATE mc_motion mc_vboard)

# The same CLI tests with `sim serve --engine rtl` (tests/vboard_server.hpp
# reads MC_VBOARD_ENGINE): the commands behave the same on the Verilated
# board as on the twin.
foreach(t test_cli_board test_cli_step)
  gtest_discover_tests(${t} TEST_PREFIX "Rtl." PROPERTIES LABELS system ENVIRONMENT MC_VBOARD_ENGINE=rtl
    DISCOVERY_TIMEOUT 60)
endforeach()

# Segments counted where they land (the board's queue, tapped): no frame
# queued twice by late replies and a full queue, and issue 18's soak, short
# (30 s of board time; `make soak` runs the hour).
mc_gtest(test_link_soak system TIMEOUT 600 test_link_soak.cpp)
target_link_libraries(test_link_soak PRIVATE mc_motion mc_vboard)
target_compile_definitions(test_link_soak PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")

# Stepper axes on the virtual board: steps against the command, pull-out.
mc_gtest(test_vboard_stepper system test_vboard_stepper.cpp)
target_link_libraries(test_vboard_stepper PRIVATE mc_motion mc_vboard)
target_compile_definitions(test_vboard_stepper PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")

# The board's machine I/O on the virtual board: home switches and the probe
# (bounce, latches), the spindle and coolant recorded, twin against RTL.
mc_gtest(test_vboard_io system test_vboard_io.cpp)
target_link_libraries(test_vboard_io PRIVATE mc_motion mc_vboard)
target_compile_definitions(test_vboard_io PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")

# The handwheel jog on the virtual board: detents move the step, twin
# against RTL edge for edge, MPG off drops what is pending.
mc_gtest(test_vboard_mpg system test_vboard_mpg.cpp)
target_link_libraries(test_vboard_mpg PRIVATE mc_motion mc_vboard)
target_compile_definitions(test_vboard_mpg PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")

# motionctl mpg and sim wheel against a sim server.
mc_gtest(test_cli_mpg system test_cli_mpg.cpp)
target_link_libraries(test_cli_mpg PRIVATE nlohmann_json::nlohmann_json)
target_compile_definitions(test_cli_mpg PRIVATE MOTIONCTL_PATH="$<TARGET_FILE:motionctl>")
add_dependencies(test_cli_mpg motionctl)

# Machine cycles on the virtual board: homing repeatable against the plant,
# probing a known surface (issue 19).
mc_gtest(test_cycles system TIMEOUT 900 test_cycles.cpp)
target_link_libraries(test_cycles PRIVATE mc_motion mc_vboard)
target_compile_definitions(test_cycles PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
