# The twin of the whole board (hls/motioncore_icebreaker.hpp) against the
# Verilated board top, vboard (sim/CMakeLists.txt), pin for pin over random
# traffic; its fast-forward against clock-by-clock stepping; and the speed of
# both, printed.

mc_gtest(test_board_twin rtl test_board_twin.cpp)
target_link_libraries(test_board_twin PRIVATE mc_hls mc_motion vboard)

# The running interpolator's fast-forward against clocking every clock.
mc_gtest(test_board_twin_ff unit test_board_twin_ff.cpp)
target_link_libraries(test_board_twin_ff PRIVATE mc_hls mc_motion)

# The servo and stepper builds of the board twin: INFO and the loops.
mc_gtest(test_board_builds unit test_board_builds.cpp)
target_link_libraries(test_board_builds PRIVATE mc_hls mc_link)
