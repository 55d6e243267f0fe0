// rtl/mc_io.v against its twin (hls/mc_io.hpp), clock by clock over random
// stimulus, and the behaviours the machine cycles rely on, on both: a probe
// edge latches every armed axis in one clock and stops the interpolator in
// the same clock; 100 handwheel detents at x10 move the selected axis
// exactly 1000 counts; the spindle and coolant go low the clock after the
// drives are disarmed.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>

#include "Vmc_io.h"
#include "hls/board_regs.hpp"
#include "hls/mc_io.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc {
namespace {

namespace br = board::reg;
namespace bb = board::bits;

// The RTL and the twin side by side, every output compared after each edge.
class Pair {
 public:
  explicit Pair(uint32_t seed)
      : ctx_(test::random_context(seed)), dut_(std::make_unique<Vmc_io>(ctx_.get())) {}

  void clock(const McIoIn& in) {
    dut_->clk = 0;
    dut_->rst = in.rst;
    dut_->bus_we_i = in.bus_we;
    dut_->bus_addr_i = in.bus_addr;
    dut_->bus_wdata_i = in.bus_wdata;
    dut_->armed_i = in.armed;
    dut_->lim_inv_i = in.lim_inv;
    dut_->lim_i = in.lim;
    dut_->probe_i = in.probe;
    dut_->idx_armed_i = in.idx_armed;
    dut_->ip_idle_i = in.ip_idle;
    dut_->hw_pos_i = in.hw_pos;
    dut_->eval();
    dut_->clk = 1;
    dut_->eval();
    twin.clock(in);
    ++t_;
    const auto& r = twin.r;
    ASSERT_EQ(dut_->latch_o, r.latch_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->stop_o), r.stop_o) << "clock " << t_;
    ASSERT_EQ(dut_->jog_o, r.jog_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->jog_neg_o), r.jog_neg_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->sp_pwm_o), r.sp_pwm_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->sp_en_o), r.sp_en_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->sp_dir_o), r.sp_dir_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->flood_o), r.flood_o) << "clock " << t_;
    ASSERT_EQ(bool(dut_->mist_o), r.mist_o) << "clock " << t_;
    ASSERT_EQ(dut_->stat_o, twin.stat_o()) << "clock " << t_;
  }

  McIo<3> twin;

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmc_io> dut_;
  long t_ = 0;
};

McIoIn write(McIoIn in, uint16_t addr, uint32_t v) {
  in.bus_we = true;
  in.bus_addr = uint8_t(addr & 0x1F);
  in.bus_wdata = v;
  return in;
}

TEST(McIoRtl, RandomStimulusIsBitExact) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    Pair p(seed);
    std::mt19937 rng(seed);
    auto pick = [&](uint32_t n) { return uint32_t(rng() % n); };
    McIoIn in;
    in.rst = true;
    const uint16_t regs[] = {br::IO_CTRL, br::LATCH, br::MPG, br::MPG_INC, br::SAFETY, br::STEP_CFG};
    long latches = 0, jogs = 0, pwm = 0;
    for (int t = 0; t < 1000000; ++t) {
      in.bus_we = pick(300) == 0;
      in.bus_addr = uint8_t(regs[pick(6)] & 0x1F);
      in.bus_wdata = uint32_t(rng());
      // Mostly MPG on with small rates, so that jogs happen.
      if (in.bus_we && in.bus_addr == (br::MPG & 0x1F) && pick(3) != 0)
        in.bus_wdata = (in.bus_wdata & ~(0xFFu << bb::M_RATE_LSB) & ~0x1u) | 1u | pick(6) << bb::M_RATE_LSB;
      if (pick(50000) == 0) in.armed = pick(4) != 0;  // mostly armed
      if (pick(20000) == 0) in.lim_inv = uint8_t(pick(8));
      // Switches that bounce: runs of random length, sometimes a clock or two.
      if (pick(pick(2) ? 8 : 3000) == 0) in.lim = uint8_t(in.lim ^ (1u << pick(3)));
      if (pick(pick(2) ? 6 : 2000) == 0) in.probe = !in.probe;
      in.idx_armed = uint8_t(pick(8));
      if (pick(3000) == 0) in.ip_idle = pick(4) != 0;
      // The handwheel: walks, sometimes several counts in one clock.
      if (pick(60) == 0)
        in.hw_pos = uint8_t(in.hw_pos + (pick(2) ? 1 : -1) * int(1 + pick(pick(20) == 0 ? 9 : 1)));
      if (t > 0) in.rst = pick(150000) == 0;
      p.clock(in);
      if (HasFatalFailure()) return;
      latches += p.twin.r.latch_o != 0;
      jogs += p.twin.r.jog_o != 0;
      pwm += p.twin.r.sp_pwm_o;
    }
    std::printf("seed %u: %ld latch strobes, %ld jog strobes, %ld PWM-high clocks\n", seed, latches, jogs,
                pwm);
    // The stimulus reached what it is meant to test.
    EXPECT_GT(latches, 100);
    EXPECT_GT(jogs, 1000);
    EXPECT_GT(pwm, 1000);
  }
}

// One probe edge: the axes set to the probe latch in the same clock, the
// stop comes with them when one of them is armed, and a bounce shorter
// than the filter latches nothing.
TEST(McIoRtl, AProbeEdgeLatchesEveryAxisInOneClockAndStops) {
  Pair p(7);
  McIoIn in;
  in.rst = true;
  p.clock(in);
  in.rst = false;
  const uint32_t probe_all = (bb::L_SRC_PROBE << 0 | bb::L_SRC_PROBE << 2 | bb::L_SRC_PROBE << 4)
                             << bb::L_SRC_LSB;
  p.clock(write(in, br::LATCH, probe_all | 1u << bb::L_STOP));
  in.idx_armed = 0b010;  // one axis armed is enough to stop
  for (int i = 0; i < 10; ++i) p.clock(in);
  // A bounce of three clocks is filtered out.
  in.probe = true;
  for (int i = 0; i < 3; ++i) p.clock(in);
  in.probe = false;
  for (int i = 0; i < 10; ++i) {
    p.clock(in);
    ASSERT_EQ(p.twin.r.latch_o, 0) << "a 3-clock bounce latched";
  }
  in.probe = true;
  int latched_at = -1;
  for (int i = 0; i < 10; ++i) {
    p.clock(in);
    if (HasFatalFailure()) return;
    if (p.twin.r.latch_o != 0) {
      ASSERT_EQ(latched_at, -1) << "latched twice";
      latched_at = i;
      EXPECT_EQ(p.twin.r.latch_o, 0b111) << "every axis in the same clock";
      EXPECT_TRUE(p.twin.r.stop_o) << "the stop in the same clock";
    } else {
      EXPECT_FALSE(p.twin.r.stop_o);
    }
  }
  // The strobe leaves on the edge of the new level's fourth clock.
  EXPECT_EQ(latched_at, 3);
}

// Out of reset, the drives armed and the interpolator idle.
McIoIn armed_and_idle(Pair& p) {
  McIoIn in;
  in.rst = true;
  p.clock(in);
  in.rst = false;
  in.armed = true;
  in.ip_idle = true;
  return in;
}

// The figure: 100 detents at x10 move the selected axis 1000 counts
// (jog strobes for that axis only, in the detents' direction), then back.
TEST(McIoRtl, HundredDetentsAtTimesTenMoveExactlyAThousandCounts) {
  Pair p(9);
  McIoIn in = armed_and_idle(p);
  const uint32_t mpg = 1u << bb::M_ON | 1u << bb::M_AXIS_LSB | 1u << bb::M_STEP_LSB | 3u << bb::M_RATE_LSB;
  p.clock(write(in, br::MPG, mpg));
  for (int dir : {1, -1}) {
    long moved = 0, other = 0;
    // The handwheel turns faster than the axis moves: counts pile up.
    // One clock, counting the jog strobes: Y's signed, any other axis's.
    const auto clock = [&] {
      p.clock(in);
      const int sign = p.twin.r.jog_neg_o ? -1 : 1;
      moved += (p.twin.r.jog_o >> 1 & 1) * sign;
      other += (p.twin.r.jog_o & 0b101) != 0;
    };
    for (int d = 0; d < 100; ++d)
      for (int c = 0; c < 4; ++c) {
        in.hw_pos = uint8_t(in.hw_pos + dir);
        for (int k = 0; k < 5; ++k) {
          clock();
          if (HasFatalFailure()) return;
        }
      }
    for (int k = 0; k < 1000 * 48 + 100; ++k) {
      clock();
      if (HasFatalFailure()) return;
    }
    EXPECT_EQ(moved, 1000 * dir);
    EXPECT_EQ(other, 0);
    EXPECT_EQ(p.twin.stat_o() >> bb::IOS_MPG_PEND_LSB, 0u) << "nothing left pending";
  }
}

// Spindle, coolant and the jog stop the clock after the drives are disarmed.
TEST(McIoRtl, DisarmingStopsTheSpindleCoolantAndJog) {
  Pair p(11);
  McIoIn in = armed_and_idle(p);
  p.clock(write(in, br::IO_CTRL,
                1u << bb::IO_SPINDLE | 1u << bb::IO_FLOOD | 1u << bb::IO_MIST | 1023u << bb::IO_DUTY_LSB));
  p.clock(write(in, br::MPG, 1u << bb::M_ON | 2u << bb::M_STEP_LSB));
  in.hw_pos = 4;  // a detent at x100
  for (int i = 0; i < 100; ++i) p.clock(in);
  ASSERT_TRUE(p.twin.r.sp_pwm_o && p.twin.r.sp_en_o && p.twin.r.flood_o && p.twin.r.mist_o);
  ASSERT_NE(p.twin.stat_o() >> bb::IOS_MPG_PEND_LSB, 0u) << "counts still pending";
  in.armed = false;
  for (int i = 0; i < 2000; ++i) {
    p.clock(in);
    if (HasFatalFailure()) return;
    ASSERT_FALSE(p.twin.r.sp_pwm_o || p.twin.r.sp_en_o || p.twin.r.sp_dir_o || p.twin.r.flood_o ||
                 p.twin.r.mist_o || p.twin.r.jog_o != 0)
        << "clock " << i << " after disarming";
  }
}

}  // namespace
}  // namespace mc
