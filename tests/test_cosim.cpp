// System tests of the co-simulation (sim/cosim.hpp): the Verilated core and
// the twin give identical controller outputs on the same scenario; the
// closed loop tracks; runs are deterministic for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sim/cosim/cosim.hpp"

namespace mc::sim {
namespace {

RunSpec spec_for(const std::string& platform, const std::string& scenario, Engine e, bool quick = true) {
  RunSpec s;
  s.machine = machine::default_machine();
  s.platform = find_platform(s.machine, platform);
  s.scenario = find_scenario(scenario, quick);
  s.engine = e;
  s.jitter = default_jitter();
  return s;
}

void print(const RunResult& r) {
  std::printf(
      "%s %s %s %s: follow x rms %.3f um max %.3f um, contour rms %.3f um, %zu samples, %.3f s sim in %.3f s"
      " (%.2fx real time), cycled %llu skipped %llu, tracking %d\n",
      r.platform.c_str(), r.scenario.c_str(), r.policy.c_str(), r.engine.c_str(), r.follow[0].rms * 1e6,
      r.follow[0].max * 1e6, r.contour.rms * 1e6, r.sample_u[0].size(), r.sim_s, r.wall_s, r.sim_s / r.wall_s,
      (unsigned long long)r.clocks_cycled, (unsigned long long)r.clocks_skipped, r.tracking);
}

// The twin-only path and the RTL path: the same controller outputs, sample
// for sample, hence the same plant motion.
TEST(Cosim, TwinAndRtlGiveIdenticalOutputs) {
  for (const char* sc : {"step", "circle"}) {
    const RunResult rtl = run_isolated(spec_for("fpga-100us", sc, Engine::Rtl));
    const RunResult twin = run_isolated(spec_for("fpga-100us", sc, Engine::Twin));
    print(rtl);
    print(twin);
    ASSERT_GT(rtl.sample_u[0].size(), 100u);
    EXPECT_EQ(rtl.sample_clock, twin.sample_clock);
    EXPECT_EQ(rtl.sample_u[0], twin.sample_u[0]);
    EXPECT_EQ(rtl.sample_u[1], twin.sample_u[1]);
    EXPECT_EQ(rtl.pos_m[0], twin.pos_m[0]);
    EXPECT_EQ(rtl.pos_m[1], twin.pos_m[1]);
    EXPECT_GT(twin.clocks_skipped, 0u);
  }
}

// The PC platform: deterministic for a seed, and the seed matters (the
// wake-up times are drawn from the measured histogram).
TEST(Cosim, HostLoopDeterministicPerSeed) {
  RunSpec s = spec_for("host-10ms", "line-45", Engine::Twin);
  s.policy = GainPolicy::Tuned;
  const RunResult a = run_isolated(s), b = run_isolated(s);
  s.seed = 2;
  const RunResult c = run_isolated(s);
  print(a);
  EXPECT_EQ(a.pos_m[0], b.pos_m[0]);
  EXPECT_EQ(a.sample_u[0], b.sample_u[0]);
  EXPECT_NE(a.pos_m[0], c.pos_m[0]);
  // One wake per 10 ms, give or take the lateness at the ends.
  EXPECT_NEAR(double(a.sample_u[0].size()), s.scenario.duration_s / 0.01, 2);
}

// The FPGA loop at 100 us closes a stable, well-damped loop on the default
// machine: the step settles (2 %) with modest overshoot, exactly at the
// commanded count, and the tuned policy at 10 ms is slower than at 100 us.
TEST(Cosim, StepResponseOfTheFpgaLoop) {
  RunSpec s = spec_for("fpga-100us", "step", Engine::Twin, false);
  const RunResult r = run_isolated(s);
  print(r);
  EXPECT_TRUE(r.tracking);
  EXPECT_LT(r.step.overshoot_pct, 30);
  EXPECT_LT(r.step.settling_s, 0.1);
  EXPECT_NEAR(r.pos_m[0].back(), 1e-3, 2.0 / counts_per_m(s.machine.axes[0]));
  s.platform = find_platform(s.machine, "fpga-10ms");
  s.policy = GainPolicy::Tuned;
  const RunResult slow = run_isolated(s);
  print(slow);
  EXPECT_TRUE(slow.tracking);
  EXPECT_GT(slow.step.rise_s, 2 * r.step.rise_s);
}

// The tuned rule: the bandwidth falls with the loop delay, never rises above
// the machine's own design, and the gains place the poles it says.
TEST(Cosim, TunedRule) {
  const MachineConfig m = machine::default_machine();
  const AxisConfig& x = m.axes[0];
  const double w0 = 3 * x.pid.ki / x.pid.kp;
  const mc::host::PidGains fast = tuned_gains(x, 1e-5, 1e-6), slow = tuned_gains(x, 1e-2, 6e-3);
  EXPECT_NEAR(3 * fast.ki / fast.kp, w0, 1e-9 * w0);
  EXPECT_NEAR(3 * slow.ki / slow.kp, 1 / (4 * 6e-3), 1e-9);
  // tau s^3 + (1 + Kg Kd) s^2 + Kg Kp s + Kg Ki = tau (s + w)^3 when Kd > 0.
  const AxisModel g = axis_model(x);
  const double w = 3 * fast.ki / fast.kp;
  ASSERT_GT(fast.kd, 0);
  EXPECT_NEAR((1 + g.kg * fast.kd) / g.tau, 3 * w, 1e-9 * w);
  EXPECT_NEAR(g.kg * fast.kp / g.tau, 3 * w * w, 1e-9 * w * w);
  EXPECT_NEAR(g.kg * fast.ki / g.tau, w * w * w, 1e-9 * w * w * w);
}

}  // namespace
}  // namespace mc::sim
