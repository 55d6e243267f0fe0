// Stepper axes on the virtual board (configs/stepper_router.toml): the
// board's step generators (STEP_CFG) drive a stepper plant behind a
// microstep driver on each axis's STEP/DIR pins. A sequence of moves like a
// G-code job's is followed with exactly as many steps as the command moved
// and none lost; a step train started far beyond the motor's torque loses
// whole electrical periods, and with the encoder closing the loop the
// board's following-error check trips.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "hls/board_regs.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/motion/board_run.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::test {
namespace {

namespace br = board::reg;
namespace bb = board::bits;

// 2 us pulses and 1 us of direction setup: what the A4988 and DRV8825
// datasheets ask (1 us high, 1 us low, 200-650 ns setup), with margin.
constexpr uint32_t kPulseClocks = 24, kSetupClocks = 12;

machine::MachineConfig stepper_router() {
  return machine::load_machine(std::string(MC_SOURCE_DIR) + "/configs/stepper_router.toml");
}

struct Rig {
  explicit Rig(const machine::MachineConfig& m) : cfg(m), board(m), stream(board), link(stream) {
    link.connect();
    link.write(br::WDOG, (1u << 24) - 1);
  }
  void steppers(uint32_t closed_mask) {
    link.write(br::STEP_CFG, 7u << bb::SC_STEPPER_LSB | closed_mask << bb::SC_CLOSED_LSB |
                                 kPulseClocks << bb::SC_PW_LSB | kSetupClocks << bb::SC_SETUP_LSB);
    link.write(br::CTRL, 1u << bb::C_ARM);
  }
  // A straight move at feed (m/s along the path), queued and run to the end.
  void move(const host::Vec3& to, double feed_m_s) {
    const double cpm = machine::counts_per_m(cfg.axes[0]);
    host::run_segments(link, host::plan_move(at, to, feed_m_s * cpm, cfg.clock_hz));
    at = to;
  }
  int32_t cmd(int a) { return int32_t(link.read(br::axis(a, br::AX_CMD))); }

  machine::MachineConfig cfg;
  sim::VirtualBoard board;
  sim::BoardStream stream;
  host::BoardLink link;
  host::Vec3 at{0, 0, 0};
};

TEST(VBoardStepper, FollowsAJobStepForStep) {
  Rig r(stepper_router());
  r.steppers(0);
  const double cpm = machine::counts_per_m(r.cfg.axes[0]);  // 400 000 counts/m: 400 steps per mm
  const auto c = [cpm](double mm) { return std::llround(mm * 1e-3 * cpm); };
  // Down to depth, a square pocket's outline, a diagonal, a step back up.
  const std::vector<std::pair<host::Vec3, double>> job = {
      {{0, 0, c(-0.5)}, 0.005},        {{c(3), 0, c(-0.5)}, 0.02},      {{c(3), c(2), c(-0.5)}, 0.02},
      {{0, c(2), c(-0.5)}, 0.02},      {{0, 0, c(-0.5)}, 0.02},         {{c(2), c(1.5), c(-0.5)}, 0.015},
      {{c(2), c(1.5), c(0.3)}, 0.005}, {{c(-1), c(-1.2), c(0.3)}, 0.03}};
  for (const auto& [to, feed] : job) {
    r.move(to, feed);
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(r.cmd(a), to[a]) << "axis " << a;
      EXPECT_EQ(r.board.driver_steps(a), to[a]) << "axis " << a << ": a step per count";
      EXPECT_EQ(r.board.lost_full_steps(a), 0) << "axis " << a;
    }
  }
  EXPECT_EQ(r.link.read(br::FAULT), 0u);
  // Open loop, POS counts the steps sent.
  r.link.poll(std::chrono::milliseconds(2));
  for (int a = 0; a < 3; ++a) EXPECT_EQ(int32_t(r.link.read(br::axis(a, br::AX_POS))), job.back().first[a]);
  std::printf("job: %.3f s of board time, X ends at %lld steps, none lost\n", r.board.board_seconds(),
              static_cast<long long>(r.board.driver_steps(0)));
}

// 0.25 m/s is 31 rev/s, started with no ramp: far past what 0.4 N m can
// accelerate the rotor and the screw to within the first steps.
constexpr double kTooFast = 0.25;

TEST(VBoardStepper, PastPullOutLosesStepsOpenLoop) {
  Rig r(stepper_router());
  r.steppers(0);
  const double cpm = machine::counts_per_m(r.cfg.axes[0]);
  const int64_t to = std::llround(0.02 * cpm);
  r.move({to, 0, 0}, kTooFast);
  EXPECT_EQ(r.board.driver_steps(0), to) << "the board sent every step";
  const int64_t lost = r.board.lost_full_steps(0);
  EXPECT_GE(lost, 4);
  EXPECT_EQ(lost % 4, 0) << "a rotor slips whole electrical periods";
  EXPECT_EQ(r.link.read(br::FAULT), 0u) << "open loop, nothing notices";
  std::printf("open loop at %.2f m/s: %lld full steps lost\n", kTooFast, static_cast<long long>(lost));
}

TEST(VBoardStepper, PastPullOutTripsTheFollowingErrorClosedLoop) {
  const machine::MachineConfig m = stepper_router();
  Rig r(m);
  r.steppers(1);  // X on its encoder
  const double cpm = machine::counts_per_m(m.axes[0]);
  const uint32_t ferr = uint32_t(m.axes[0].max_following_error_m * cpm);
  r.link.write(br::axis(0, br::AX_FERR), ferr);
  // Within its torque a closed-loop axis runs as an open-loop one.
  r.move({std::llround(0.002 * cpm), 0, 0}, 0.01);
  ASSERT_EQ(r.link.read(br::FAULT), 0u);
  EXPECT_EQ(r.board.lost_full_steps(0), 0);
  EXPECT_THROW(r.move({std::llround(0.03 * cpm), 0, 0}, kTooFast), host::BoardError);
  EXPECT_EQ(r.link.read(br::FAULT), 1u << bb::F_FERR_LSB) << "X's following error, nothing else";
  EXPECT_FALSE(r.board.drive_enabled(0)) << "the drivers are off";
  const int32_t follow = int32_t(r.link.read(br::axis(0, br::AX_CMD)) - r.link.read(br::axis(0, br::AX_POS)));
  std::printf(
      "closed loop at %.2f m/s: tripped with the rotor %d counts behind (FERR %u), %lld full steps lost\n",
      kTooFast, follow, ferr, static_cast<long long>(r.board.lost_full_steps(0)));
}

}  // namespace
}  // namespace mc::test
