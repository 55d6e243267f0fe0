// The step generator's twin (hls/step_gen.hpp) driving a model of an
// A4988/DRV8825 STEP/DIR input (tests/step_driver.hpp): the driver ends
// where the command ends, and every pulse keeps the timing the generator
// was configured with. The RTL is held to the twin clock by clock in
// test_step_gen_rtl.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>

#include "hls/step_gen.hpp"
#include "tests/step_driver.hpp"

namespace mc {
namespace {

using Gen = StepGen<8, 4>;

struct Rig {
  Gen g;
  StepGenIn in;
  int64_t cmd = 0;  // the whole command, counts
  bool err_seen = false;
  int max_backlog = 0;
  test::StepDriver drv;
  Rig(uint32_t pw, uint32_t setup) : drv(std::max(pw, 1u), std::max(pw, 1u) + 1, std::max(setup, 1u)) {
    in.pw = pw;
    in.setup = setup;
    in.en = true;
    in.rst = true;
    clock();
    in.rst = false;
  }
  void clock() {
    in.cmd = uint8_t(cmd & 3);
    g.clock(in);
    in.sync = false;
    drv.clock(g.step_o, g.dir_o);
    err_seen |= g.err_o;
    max_backlog = std::max(max_backlog, std::abs(g.backlog()));
  }
  void move(int d) {
    cmd += d;
    clock();
  }
  void idle(int n) {
    for (int i = 0; i < n; ++i) clock();
  }
};

// Interval between command iterations that the timing can always follow:
// a reversal's setup, a pulse and its low time.
int safe_interval(uint32_t pw, uint32_t setup) {
  return int(std::max(setup, 1u) + 2 * std::max(pw, 1u) + 3);
}

TEST(StepGen, ADriverFollowsARandomWalkWithTheConfiguredTiming) {
  std::mt19937 rng(7);
  for (uint32_t pw : {0u, 1u, 3u, 24u, 255u})
    for (uint32_t setup : {0u, 1u, 6u, 30u}) {
      SCOPED_TRACE("pw " + std::to_string(pw) + " setup " + std::to_string(setup));
      Rig r(pw, setup);
      int dir = 1;
      const int interval = safe_interval(pw, setup);
      int64_t moves = 0;
      for (int i = 0; i < 3000; ++i) {
        if (rng() % 10 == 0) dir = -dir;  // runs with reversals
        r.move(dir);
        ++moves;
        r.idle(interval - 1 + int(rng() % 3));
      }
      r.idle(4 * interval);
      EXPECT_EQ(r.drv.position(), r.cmd);
      EXPECT_EQ(r.g.backlog(), 0);
      EXPECT_FALSE(r.err_seen);
      EXPECT_LE(r.drv.pulses(), moves);
      EXPECT_EQ(r.drv.short_high(), 0);
      EXPECT_EQ(r.drv.short_low(), 0);
      EXPECT_EQ(r.drv.short_setup(), 0);
      EXPECT_EQ(r.drv.dir_in_pulse(), 0);
    }
}

TEST(StepGen, ABurstFasterThanThePulsesWaitsInTheBacklog) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const uint32_t pw = 1 + uint32_t(rng() % 40), setup = uint32_t(rng() % 40);
    Rig r(pw, setup);
    // Up to 6 counts one clock apart (the backlog holds 7), either way, then
    // room to step them out; sometimes the burst turns back on itself.
    for (int burst = 0; burst < 20; ++burst) {
      const int n = 1 + int(rng() % 6), dir = rng() % 2 ? 1 : -1;
      for (int i = 0; i < n; ++i) r.move(i == n - 1 && rng() % 4 == 0 ? -dir : dir);
      r.idle(int(n + 2) * safe_interval(pw, setup));
    }
    ASSERT_FALSE(r.err_seen) << "pw " << pw << " setup " << setup;
    ASSERT_EQ(r.drv.position(), r.cmd) << "pw " << pw << " setup " << setup;
    ASSERT_EQ(r.drv.short_high() + r.drv.short_low() + r.drv.short_setup() + r.drv.dir_in_pulse(), 0);
  }
}

TEST(StepGen, ACommandTooFastForThePulsesIsAnErrorNotLostSteps) {
  Rig r(24, 10);
  for (int i = 0; i < 100; ++i) {
    r.move(1);
    r.idle(1);  // a count every 2 clocks, a step every 49 at most
  }
  EXPECT_TRUE(r.err_seen);
  EXPECT_TRUE(r.g.err_o);  // sticky
  EXPECT_EQ(r.max_backlog, 7);
  // clr clears it once the cause is gone.
  r.idle(2000);
  r.in.clr = true;
  r.clock();
  r.in.clr = false;
  EXPECT_FALSE(r.g.err_o);
}

TEST(StepGen, ALoadedCommandIsNotAStepAndATwoCountJumpIsAnError) {
  Rig r(3, 3);
  r.cmd += 2;
  r.in.sync = true;  // loaded: taken without a step
  r.clock();
  r.idle(100);
  EXPECT_EQ(r.drv.pulses(), 0);
  EXPECT_FALSE(r.err_seen);
  r.cmd += 2;  // moved two counts at once: the generator cannot tell which way
  r.clock();
  EXPECT_TRUE(r.g.err_o);
}

TEST(StepGen, DisablingEndsThePulseAndDropsWhatIsOwed) {
  Rig r(50, 0);
  for (int i = 0; i < 5; ++i) r.move(1);
  r.idle(10);
  ASSERT_TRUE(r.g.step_o);
  ASSERT_EQ(r.g.backlog(), 4);
  r.in.en = false;
  r.clock();
  EXPECT_FALSE(r.g.step_o);
  EXPECT_EQ(r.g.backlog(), 0);
  r.move(1);  // moves while disabled are not steps either
  r.in.en = true;
  r.idle(500);
  EXPECT_EQ(r.drv.pulses(), 1);
}

}  // namespace
}  // namespace mc
