// System tests of the co-simulation (sim/cosim.hpp): the Verilated core and
// the twin give identical controller outputs on the same scenario; the
// closed loop tracks; runs are deterministic for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "cosim.hpp"

namespace mc::sim {
namespace {

RunSpec spec_for(const std::string& platform, const std::string& scenario, Engine e, bool quick = true) {
  RunSpec s;
  s.machine = default_machine();
  s.platform = find_platform(s.machine, platform);
  s.scenario = find_scenario(scenario, quick);
  s.engine = e;
  s.jitter = default_jitter();
  return s;
}

void print(const RunResult& r) {
  std::printf("%s %s %s %s: follow x rms %.3f um max %.3f um, contour rms %.3f um, %zu samples, %.3f s sim in %.3f s"
              " (%.2fx real time), cycled %llu skipped %llu, stable %d\n",
              r.platform.c_str(), r.scenario.c_str(), r.policy.c_str(), r.engine.c_str(), r.follow[0].rms * 1e6,
              r.follow[0].max * 1e6, r.contour.rms * 1e6, r.sample_u[0].size(), r.sim_s, r.wall_s,
              r.sim_s / r.wall_s, (unsigned long long)r.clocks_cycled, (unsigned long long)r.clocks_skipped,
              r.stable);
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

}  // namespace
}  // namespace mc::sim
