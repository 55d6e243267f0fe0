// rtl/step_gen.v against its twin (hls/step_gen.hpp), clock by clock, with
// every input random: command walks with bursts, reversals, loads and
// impossible jumps, the drive enabled and disabled, the timing changed
// mid-pulse, resets. Two builds: the board's widths and the small ones the
// formal proof uses (scripts/formal.sh step_gen).
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <string>

#include "Vstep_gen.h"
#include "Vstep_gen_small.h"
#include "hls/step_gen.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc {
namespace {

template <class Top, int PW_W, int BL_W>
void compare(uint32_t seed, int clocks) {
  auto ctx = test::random_context(seed);
  Top dut(ctx.get());
  StepGen<PW_W, BL_W> twin;
  std::mt19937 rng(seed);  // 32-bit draws
  StepGenIn in;
  int64_t cmd = 0;
  int pulses = 0, errors = 0;
  auto pick = [&](uint32_t n) { return uint32_t(rng() % n); };
  in.rst = true;
  for (int t = 0; t < clocks; ++t) {
    // A command that moves in runs, sometimes faster than the pulses.
    const uint32_t rate = t / 20000 % 4;  // 0: stepping slowly .. 3: every clock
    if (pick(rate == 3 ? 1 : 40 >> rate * 2) == 0) cmd += pick(8) == 0 ? -1 : 1;
    if (pick(5000) == 0) cmd += 2;  // a jump: loaded (sync) or an error
    in.cmd = uint8_t(cmd & 3);
    in.sync = pick(300) == 0;
    if (pick(4000) == 0) in.en = !in.en;
    if (pick(3000) == 0) in.pw = pick(8) == 0 ? 0 : pick(1u << PW_W) % 40;
    if (pick(3000) == 0) in.setup = pick(1u << PW_W) % 40;
    in.clr = pick(1000) == 0;
    if (t > 0) in.rst = pick(200000) == 0;

    dut.clk = 0;
    dut.rst = in.rst;
    dut.cmd_i = in.cmd;
    dut.sync_i = in.sync;
    dut.en_i = in.en;
    dut.pw_i = uint8_t(in.pw);
    dut.setup_i = uint8_t(in.setup);
    dut.clr_i = in.clr;
    dut.eval();
    dut.clk = 1;
    dut.eval();
    twin.clock(in);
    pulses += twin.step_o;
    errors += twin.err_o;
    ASSERT_EQ(bool(dut.step_o), twin.step_o) << "clock " << t;
    ASSERT_EQ(bool(dut.dir_o), twin.dir_o) << "clock " << t;
    ASSERT_EQ(bool(dut.err_o), twin.err_o) << "clock " << t;
    ASSERT_EQ(uint32_t(dut.backlog_o), twin.backlog_o) << "clock " << t;
  }
  dut.final();
  // The stimulus reached what it is for: pulses, and errors.
  EXPECT_GT(pulses, clocks / 100);
  EXPECT_GT(errors, 0);
}

TEST(StepGenRtl, MatchesTheTwinClockByClock) {
  compare<Vstep_gen, 8, 4>(1, 1'000'000);
}

TEST(StepGenRtl, MatchesTheTwinWithTheFormalProofsWidths) {
  compare<Vstep_gen_small, 4, 3>(2, 1'000'000);
}

}  // namespace
}  // namespace mc
