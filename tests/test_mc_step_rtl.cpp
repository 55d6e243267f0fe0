// rtl/mc_step.v against its twin (hls/mc_step.hpp), clock by clock over
// random stimulus: STEP_CFG rewritten at random (axes switched between servo
// and stepper, open and closed loop, pulse width, setup, polarities), a
// command that walks, jumps and reverses, loads, the drives allowed and
// not, fault clears, resets, and the H-bridge and encoder pins moving.
// Every output is compared after each edge: the pins, what the decoders
// see, the generators' errors and the following-error strobes.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>

#include "Vmc_step.h"
#include "Vmc_step5.h"
#include "hls/board_regs.hpp"
#include "hls/mc_step.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc {
namespace {

namespace bb = board::bits;

// One run of random stimulus on a build with the generators in STEPPERS.
template <class Dut, int STEPPERS>
void random_run(uint32_t seed) {
  {
    auto ctx = test::random_context(seed);
    Dut dut(ctx.get());
    McStep<3, STEPPERS> twin;
    std::mt19937 rng(seed);
    auto pick = [&](uint32_t n) { return uint32_t(rng() % n); };
    McStepIn in;
    in.rst = true;
    int64_t cmd[3] = {};
    long steps = 0, ferrs = 0, loop_edges = 0;
    uint8_t last_a = 0;
    for (int t = 0; t < 1000000; ++t) {
      // STEP_CFG now and then: mostly steppers, short pulses.
      in.bus_we = pick(20000) == 0;
      in.bus_addr = uint8_t(pick(4) ? board::reg::STEP_CFG & 0x1F : pick(32));
      in.bus_wdata = uint32_t(rng());
      if (in.bus_we && pick(2))
        in.bus_wdata = (in.bus_wdata & ~(0x3Fu << bb::SC_PW_LSB | 0x3Fu << bb::SC_SETUP_LSB)) |
                       pick(8) << bb::SC_PW_LSB | pick(8) << bb::SC_SETUP_LSB | 7u << bb::SC_STEPPER_LSB;
      // Commands that move in runs, sometimes faster than the steps, or jump.
      const uint32_t rate = t / 50000 % 4;
      for (int64_t& c : cmd) {
        if (pick(rate == 3 ? 2 : 60 >> rate * 2) == 0) c += pick(6) == 0 ? -1 : 1;
        if (pick(20000) == 0) c += 2;
      }
      in.cmd = uint8_t((cmd[0] & 3) | (cmd[1] & 3) << 2 | (cmd[2] & 3) << 4);
      in.sync = uint8_t(pick(500) == 0 ? 1u << pick(3) : 0);
      if (pick(30000) == 0) in.allow = pick(4) != 0;
      in.clr = uint8_t(pick(3000) == 0 ? 7 : 0);
      in.pwm = uint8_t(rng() & 7);
      in.dir = uint8_t(rng() & 7);
      if (pick(10) == 0) in.enc_a = uint8_t(in.enc_a ^ 1u << pick(3));
      if (pick(10) == 0) in.enc_b = uint8_t(in.enc_b ^ 1u << pick(3));
      if (t > 0) in.rst = pick(300000) == 0;

      dut.clk = 0;
      dut.rst = in.rst;
      dut.bus_we_i = in.bus_we;
      dut.bus_addr_i = in.bus_addr;
      dut.bus_wdata_i = in.bus_wdata;
      dut.cmd_i = in.cmd;
      dut.sync_i = in.sync;
      dut.allow_i = in.allow;
      dut.clr_i = in.clr;
      dut.pwm_i = in.pwm;
      dut.dir_i = in.dir;
      dut.enc_a_i = in.enc_a;
      dut.enc_b_i = in.enc_b;
      dut.eval();
      dut.clk = 1;
      dut.eval();
      twin.clock(in);
      // The multiplexers are wires: after the edge, with the inputs held.
      const McStepOut o = twin.out(in);
      ASSERT_EQ(dut.pwm_o, o.pwm) << "clock " << t;
      ASSERT_EQ(dut.dir_o, o.dir) << "clock " << t;
      ASSERT_EQ(dut.enc_a_o, o.enc_a) << "clock " << t;
      ASSERT_EQ(dut.enc_b_o, o.enc_b) << "clock " << t;
      ASSERT_EQ(dut.stepper_o, twin.stepper_o()) << "clock " << t;
      ASSERT_EQ(dut.err_o, twin.err_o()) << "clock " << t;
      ASSERT_EQ(dut.ferr_o, twin.ferr_o()) << "clock " << t;
      for (int a = 0; a < 3; ++a) steps += twin.u_gen[a].step_o && (twin.stepper_o() >> a & 1);
      ferrs += twin.ferr_o() != 0;
      const uint8_t loop = uint8_t(twin.stepper & ~twin.closed & 7);
      loop_edges += ((o.enc_a ^ last_a) & loop) != 0;
      last_a = o.enc_a;
    }
    std::printf(
        "STEPPERS %d, seed %u: %ld step-high clocks, %ld following-error strobes, %ld loopback A edges\n",
        STEPPERS, seed, steps, ferrs, loop_edges);
    EXPECT_GT(steps, 10000);
    EXPECT_GT(ferrs, 10);
    EXPECT_GT(loop_edges, 1000);
    // An axis built without a generator never steps and keeps its pins.
    EXPECT_EQ(twin.stepper & ~STEPPERS, 0);
  }
}

TEST(McStepRtl, RandomStimulusIsBitExact) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    random_run<Vmc_step, 7>(seed);
  }
}

// The board builds generators only where asked (Y without one here): the
// unbuilt axis must behave as a servo axis whatever STEP_CFG says.
TEST(McStepRtl, AxesBuiltWithoutAGeneratorStayServo) {
  random_run<Vmc_step5, 5>(4);
}

}  // namespace
}  // namespace mc
