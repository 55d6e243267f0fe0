// The motion_core twin's fast-forward (quiet/skip), which the long
// co-simulations rely on: a twin that skips every quiet stretch must stay
// identical to one that runs every clock. The clock-by-clock twin is itself
// held to the RTL by test_motion_core_rtl.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "hls/motion_core.hpp"
#include "sim/plant/dc_motor.hpp"

namespace mc::test {
namespace {

using Twin = MotionCore<2>;

void expect_same(const Twin::Out& a, const Twin::Out& b, uint64_t clock) {
  ASSERT_EQ(a.tick, b.tick) << clock;
  ASSERT_EQ(a.done, b.done) << clock;
  ASSERT_EQ(a.pid_wready, b.pid_wready) << clock;
  ASSERT_EQ(a.seg_count, b.seg_count) << clock;
  ASSERT_EQ(a.ip_busy, b.ip_busy) << clock;
  ASSERT_EQ(a.smp_rdata, b.smp_rdata) << clock;
  for (int x = 0; x < 2; ++x) {
    ASSERT_EQ(a.enc[x], b.enc[x]) << "axis " << x << " clock " << clock;
    ASSERT_EQ(a.pwm[x], b.pwm[x]) << "axis " << x << " clock " << clock;
    ASSERT_EQ(a.dir[x], b.dir[x]) << clock;
    ASSERT_EQ(a.drv_en[x], b.drv_en[x]) << clock;
    ASSERT_EQ(a.drv_u[x], b.drv_u[x]) << clock;
    ASSERT_EQ(a.drv_cmd[x], b.drv_cmd[x]) << clock;
    ASSERT_EQ(a.pos[x], b.pos[x]) << clock;
    ASSERT_EQ(a.cmd[x], b.cmd[x]) << clock;
  }
}

// Encoder counts change only at the start of a 12-clock step, as the plant
// makes them; the PID runs a P+I+D loop on them with a random Ts.
TEST(MotionCoreTwin, SkipEqualsClocks) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    std::mt19937_64 rng(seed);
    Twin ref, fast;
    Twin::In in;
    in.rst = true;
    for (int i = 0; i < 3; ++i) {
      ref.clock(in);
      fast.clock(in);
    }
    in.rst = false;
    const uint32_t ts = 52 + uint32_t(rng() % 3000);
    const std::pair<uint8_t, uint32_t> cfg[] = {{0x00, (1u << 20) | (16u << 24)},
                                                {0x01, (1u << 20) | (30u << 24)},
                                                {0x10, (3u << 20) | (16u << 24)},
                                                {0x0F, 1},
                                                {0x1F, 1},
                                                {0xF0, ts}};
    int64_t count[2] = {0, 0};
    uint64_t skipped = 0, clocks = 0;
    size_t next_cfg = 0;
    for (int step = 0; step < 40000; ++step) {
      const int k = 12;
      if (step % 50 == 0)
        for (int x = 0; x < 2; ++x) count[x] += int64_t(rng() % 5) - 2;
      if (rng() % 3000 == 0) in.drv_allow[rng() % 2] ^= true;
      if (step == 100) in.drv_allow[0] = in.drv_allow[1] = true;
      if (rng() % 5000 == 0) in.drv_ovr[rng() % 2] ^= true;
      in.drv_ovr_we[0] = rng() % 300 == 0;
      in.drv_ovr_val = int16_t(rng() % 2000);
      if (rng() % 50 == 0) in.smp_raddr = uint8_t(rng() % 32);
      in.ip_set = step == 2000 || step == 20000 ? 7 : 0;
      in.ip_set_pos[0] = int32_t(step) / 10;
      in.ip_set_pos[1] = -int32_t(step) / 10;
      for (int x = 0; x < 2; ++x) {
        const sim::QuadPins p = sim::quadrature_pins(count[x], 2000);
        in.enc_a[x] = p.a;
        in.enc_b[x] = p.b;
        in.enc_filt[x] = uint32_t(seed % 4);
      }
      int c = 0;
      while (c < k) {
        const auto o = ref.outputs(in.pid_we);
        if (next_cfg < std::size(cfg)) {
          in.pid_we = true;
          in.pid_waddr = cfg[next_cfg].first;
          in.pid_wdata = cfg[next_cfg].second;
          if (o.pid_wready) ++next_cfg;
        } else {
          in.pid_we = false;
        }
        const uint32_t rest = uint32_t(k - c);
        if (!in.ip_set && fast.quiet(in, rest)) {
          ASSERT_TRUE(!in.pid_we);
          for (uint32_t i = 0; i < rest; ++i) ref.clock(in);
          fast.skip(rest);
          skipped += rest;
          clocks += rest;
          expect_same(ref.outputs(), fast.outputs(), clocks);
          break;
        }
        expect_same(o, fast.outputs(in.pid_we), clocks);
        ref.clock(in);
        fast.clock(in);
        in.ip_set = 0;
        ++c;
        ++clocks;
      }
    }
    // Most steps are quiet: the fast-forward is worth having, and this test
    // exercised it.
    EXPECT_GT(skipped, clocks / 2) << "seed " << seed;
    EXPECT_NE(ref.outputs().drv_cmd[0], 0) << "the loop never acted, seed " << seed;
  }
}

}  // namespace
}  // namespace mc::test
