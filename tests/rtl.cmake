# Verilated RTL models (mc_verilate: cmake/verilate.cmake) and the C/RTL
# co-simulation tests.

mc_verilate(vpid_core TOP pid_core SOURCES ${MC_RTL_DIR}/pid_core.v ${MC_RTL_DIR}/mul_align.v)
mc_verilate(vpid_core_noloops TOP pid_core PREFIX Vpid_core_noloops PARAMS -GSERVO=0
            SOURCES ${MC_RTL_DIR}/pid_core.v ${MC_RTL_DIR}/mul_align.v)
mc_verilate(vpid_core1 TOP pid_core PREFIX Vpid_core1 PARAMS -GNAXES=1
  SOURCES ${MC_RTL_DIR}/pid_core.v ${MC_RTL_DIR}/mul_align.v)
mc_verilate(vmul_align TOP mul_align SOURCES ${MC_RTL_DIR}/mul_align.v)
mc_verilate(vinterp_core TOP interp_core SOURCES ${MC_INTERP_RTL})
# The motion datapath: decoders, interpolator, PID and drive together.
# (The two-axis build, vmotion_core2, is the co-simulation's: sim/CMakeLists.txt.)
mc_verilate(vmotion_core TOP motion_core SOURCES ${MC_MOTION_RTL})
mc_verilate(vquad_decoder TOP quad_decoder SOURCES ${MC_RTL_DIR}/quad_decoder.v)
# Small widths, so that every counter saturates in a short test: the same
# values as mc::test::QuadSmall (tests/quad_harness.hpp).
mc_verilate(vquad_decoder_small TOP quad_decoder PREFIX Vquad_decoder_small
  PARAMS -GFILT_W=5 -GERR_W=2 -GVEL_W=4 -GAGE_W=4
  SOURCES ${MC_RTL_DIR}/quad_decoder.v)
# The index latch in block RAM, as the board builds it: mc::test::QuadIdxRam.
mc_verilate(vquad_decoder_idxram TOP quad_decoder PREFIX Vquad_decoder_idxram
  PARAMS -GFILT_W=4 -GIDX_RAM=1
  SOURCES ${MC_RTL_DIR}/quad_decoder.v)

# Twin-only tests.
mc_gtest(test_pid_twin unit test_pid_twin.cpp)
target_link_libraries(test_pid_twin PRIVATE mc_hls)
mc_gtest(test_interp_twin unit test_interp_twin.cpp)
target_link_libraries(test_interp_twin PRIVATE mc_hls mc_motion)
mc_gtest(test_quad_decoder_twin unit test_quad_decoder_twin.cpp)
target_link_libraries(test_quad_decoder_twin PRIVATE mc_hls)

# C/RTL co-simulation: the twin is the scoreboard.
mc_gtest(test_pid_rtl rtl test_pid_rtl.cpp)
target_link_libraries(test_pid_rtl PRIVATE mc_hls vpid_core vpid_core1 vpid_core_noloops)
mc_gtest(test_interp_rtl rtl test_interp_rtl.cpp)
target_link_libraries(test_interp_rtl PRIVATE mc_hls mc_motion vinterp_core)
mc_gtest(test_mul_align_rtl rtl test_mul_align_rtl.cpp)
target_link_libraries(test_mul_align_rtl PRIVATE mc_hls vmul_align)
mc_gtest(test_quad_decoder_rtl rtl test_quad_decoder_rtl.cpp)
target_link_libraries(test_quad_decoder_rtl PRIVATE mc_hls vquad_decoder vquad_decoder_small vquad_decoder_idxram)
# The max-count-rate table of docs/encoder.md, and its assertions.
mc_gtest(test_quad_rate_rtl rtl test_quad_rate_rtl.cpp)
target_link_libraries(test_quad_rate_rtl PRIVATE mc_hls vquad_decoder)

# Widths and register addresses: the Verilog includes agree with the C++ headers.
mc_gtest(test_regs_agree unit test_regs_agree.cpp)
target_link_libraries(test_regs_agree PRIVATE mc_hls)
target_compile_definitions(test_regs_agree PRIVATE MC_RTL_DIR="${MC_RTL_DIR}")

# RTL lint and synthesizability (Yosys reads and maps every module).
add_test(NAME rtl_lint COMMAND ${CMAKE_SOURCE_DIR}/scripts/lint_rtl.sh)
set_tests_properties(rtl_lint PROPERTIES LABELS rtl TIMEOUT ${MC_TEST_TIMEOUT})
add_test(NAME synth_pid_core_ice40
  COMMAND ${CMAKE_SOURCE_DIR}/scripts/synth_check.sh pid_core ${CMAKE_BINARY_DIR}/synth_check)
set_tests_properties(synth_pid_core_ice40 PROPERTIES LABELS synth TIMEOUT 600)
add_test(NAME synth_interp_core_ice40
  COMMAND ${CMAKE_SOURCE_DIR}/scripts/synth_check.sh interp_core ${CMAKE_BINARY_DIR}/synth_check)
set_tests_properties(synth_interp_core_ice40 PROPERTIES LABELS synth TIMEOUT 600)
add_test(NAME synth_quad_decoder_ice40
  COMMAND ${CMAKE_SOURCE_DIR}/scripts/synth_check.sh quad_decoder ${CMAKE_BINARY_DIR}/synth_check)
set_tests_properties(synth_quad_decoder_ice40 PROPERTIES LABELS synth TIMEOUT 600)

# Fixed point against double precision (needs the host's coefficient design).
mc_gtest(test_pid_numerics unit test_pid_numerics.cpp)
target_link_libraries(test_pid_numerics PRIVATE mc_hls mc_control)
mc_gtest(test_motion_core_rtl rtl test_motion_core_rtl.cpp)
target_link_libraries(test_motion_core_rtl PRIVATE mc_hls mc_cosim vmotion_core vmotion_core2)
mc_gtest(test_motion_core_twin unit test_motion_core_twin.cpp)
target_link_libraries(test_motion_core_twin PRIVATE mc_hls mc_cosim)

# The iCEBreaker top with its link: a host speaks the protocol bit by bit on
# the UART pins (tests/board_harness.hpp, sim/uart_model.hpp).
# (The Verilated top, vboard, is the virtual board's too: sim/CMakeLists.txt.)
mc_gtest(test_board_rtl rtl test_board_rtl.cpp)
target_link_libraries(test_board_rtl PRIVATE mc_hls mc_motion vboard)
# The board's machine I/O through its pins: handwheel jog, probe latch and stop.
mc_gtest(test_board_io_rtl rtl test_board_io_rtl.cpp)
target_link_libraries(test_board_io_rtl PRIVATE mc_hls mc_motion vboard)
# Hostile bytes on the board's RX pin: no bad frame changes a register
# (fuzz/board_rx.hpp) and on the board twin (fuzz/board_rx_twin.hpp); the
# fuzz_board_rx* targets run the same checks under libFuzzer.
mc_gtest(test_board_rx rtl test_board_rx.cpp)
target_link_libraries(test_board_rx PRIVATE mc_link vboard)

# The generated register map is up to date; the protocol codec.
mc_gtest(test_board_regs unit test_board_regs.cpp)
target_link_libraries(test_board_regs PRIVATE mc_link)
target_compile_definitions(test_board_regs PRIVATE MC_SOURCE_DIR="${CMAKE_SOURCE_DIR}")
mc_gtest(test_protocol unit test_protocol.cpp)
target_link_libraries(test_protocol PRIVATE mc_link)

# The board flow as `make synth` runs it: three axes and the handwheel,
# bitstream, fit and timing at the real clock (docs/board.md). nextpnr's
# result depends on its seed, not on the load, so it runs beside the other
# tests: alone, it held one of CI's two cores idle for four minutes.
add_test(NAME synth_board_icebreaker
  COMMAND ${CMAKE_SOURCE_DIR}/scripts/synth.sh ${CMAKE_BINARY_DIR}/synth_test)
set_tests_properties(synth_board_icebreaker PROPERTIES LABELS synth TIMEOUT 1800 COST 1800)
# The stepper board as `make synth-stepper` builds it: a step generator on
# every axis, no PID loops.
add_test(NAME synth_board_icebreaker_stepper
  COMMAND ${CMAKE_COMMAND} -E env STEPPERS=7 SERVO=0
    ${CMAKE_SOURCE_DIR}/scripts/synth.sh ${CMAKE_BINARY_DIR}/synth_test_stepper)
set_tests_properties(synth_board_icebreaker_stepper PROPERTIES LABELS synth TIMEOUT 1800 COST 1800)

# The step/dir generator of stepper axes: its twin driving a model of a
# driver's STEP/DIR input, and the RTL against the twin at two widths.
mc_verilate(vstep_gen TOP step_gen SOURCES ${MC_RTL_DIR}/step_gen.v)
mc_verilate(vstep_gen_small TOP step_gen PREFIX Vstep_gen_small PARAMS -GPW_W=4 -GBL_W=3
  SOURCES ${MC_RTL_DIR}/step_gen.v)
mc_gtest(test_step_gen unit test_step_gen.cpp)
target_link_libraries(test_step_gen PRIVATE mc_hls)
mc_gtest(test_step_gen_rtl rtl test_step_gen_rtl.cpp)
target_link_libraries(test_step_gen_rtl PRIVATE mc_hls vstep_gen vstep_gen_small)
# The board's machine I/O (probe and home latches, spindle, handwheel jog).
mc_verilate(vmc_io TOP mc_io SOURCES ${MC_RTL_DIR}/mc_io.v)
mc_gtest(test_mc_io_rtl rtl test_mc_io_rtl.cpp)
target_link_libraries(test_mc_io_rtl PRIVATE mc_hls vmc_io)
# The board's stepper axes (step_gen per axis, the steps' quadrature copy).
mc_verilate(vmc_step TOP mc_step SOURCES ${MC_RTL_DIR}/mc_step.v ${MC_RTL_DIR}/step_gen.v)
mc_verilate(vmc_step5 TOP mc_step PREFIX Vmc_step5 PARAMS -GSTEPPERS=5
  SOURCES ${MC_RTL_DIR}/mc_step.v ${MC_RTL_DIR}/step_gen.v)
mc_gtest(test_mc_step_rtl rtl test_mc_step_rtl.cpp)
target_link_libraries(test_mc_step_rtl PRIVATE mc_hls vmc_step vmc_step5)
