// System tests of the co-simulation (sim/cosim.hpp): the Verilated core and
// the twin give identical controller outputs on the same scenario; the
// closed loop tracks; runs are deterministic for a seed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hls/interp_seg.hpp"
#include "host/base/errors.hpp"
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

// The twin's run of s (an RTL spec), checked against the RTL's: the same
// controller outputs, sample for sample, hence the same plant motion and
// trace.
RunResult twin_like(const RunResult& rtl, RunSpec s) {
  s.engine = Engine::Twin;
  RunResult twin = run_isolated(s);
  print(rtl);
  print(twin);
  EXPECT_EQ(rtl.sample_clock, twin.sample_clock);
  for (size_t a = 0; a < 2; ++a) {
    EXPECT_EQ(rtl.sample_u[a], twin.sample_u[a]) << "axis " << a;
    EXPECT_EQ(rtl.pos_m[a], twin.pos_m[a]) << "axis " << a;
    EXPECT_EQ(rtl.cmd_m[a], twin.cmd_m[a]) << "axis " << a;
  }
  EXPECT_GT(twin.clocks_skipped, 0u);
  // The set-up is timed, and is part of the run's wall time.
  EXPECT_GT(twin.setup_s, 0);
  EXPECT_LT(twin.setup_s, twin.wall_s);
  return twin;
}

// The twin-only path and the RTL path: the same controller outputs, sample
// for sample, hence the same plant motion.
TEST(Cosim, TwinAndRtlGiveIdenticalOutputs) {
  // 1207 clocks a sample: the tick, hence each drive update the twin's
  // jumps go through, falls at every clock of a plant step in turn (at
  // 100 us, always at the same one).
  const MachineConfig m = machine::default_machine();
  const Platform odd{"fpga-1207", false, 1207 / m.clock_hz};
  for (const Platform& p : {find_platform(m, "fpga-100us"), odd})
    for (const char* sc : {"step", "circle"}) {
      // Records every 10 us, as `motionctl cosim` takes them: most fall inside
      // the twin's jumps, some after a move of the command there.
      RunSpec s = spec_for("fpga-100us", sc, Engine::Rtl);
      s.platform = p;
      s.record_dt_s = 1e-5;
      const RunResult rtl = run_isolated(s);
      const RunResult twin = twin_like(rtl, s);
      ASSERT_GT(rtl.sample_u[0].size(), 100u);
    }
}

// A G-code job, streamed: the encoder counts the board would report at each
// record (the twin's jumps take them from the counts the plants reach
// inside) give the same measured contour as the RTL path's, to the bit.
TEST(Cosim, TwinAndRtlGiveTheSameJobCounts) {
  RunSpec s = spec_for("fpga-100us", "step", Engine::Rtl);
  s.scenario = bench_job(s.machine, "", true);
  s.record_dt_s = 1e-4;  // as `motionctl cosim --scenario job` records
  const RunResult rtl = run_isolated(s);
  const RunResult twin = twin_like(rtl, s);
  ASSERT_GT(rtl.sample_u[0].size(), 1000u);
  EXPECT_GT(rtl.measured_contour.max, 0);
  EXPECT_EQ(rtl.measured_contour.rms, twin.measured_contour.rms);
  EXPECT_EQ(rtl.measured_contour.max, twin.measured_contour.max);
  EXPECT_GT(twin.clocks_skipped, 0u);
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

// The job scenario's contour error (host/machine/job's measure on the
// streamed, planned program) against an independent computation: the
// metrics library's distance to the analytic lines and arc, on the same
// recorded positions.
TEST(Cosim, JobContourMatchesTheAnalyticPath) {
  RunSpec s = spec_for("fpga-1ms", "step", Engine::Twin);
  s.policy = GainPolicy::Tuned;
  s.scenario = job_scenario(s.machine, "G21 G90 G17 G94\nG1 X4 F900\nG3 X4 Y4 I0 J2\nG1 X0\nM2\n", "t.nc");
  s.record_dt_s = 1e-4;
  const RunResult r = run_isolated(s);
  print(r);
  // Metres: the line (0,0)-(4,0) mm, the half circle about (4,2) mm from
  // -90 to +90 degrees (G3: counter-clockwise), the line (4,4)-(0,4) mm.
  const std::vector<PathPiece> path{Segment{{0, 0}, {4e-3, 0}}, Arc{{4e-3, 2e-3}, 2e-3, -M_PI / 2, M_PI},
                                    Segment{{4e-3, 4e-3}, {0, 4e-3}}};
  std::vector<Point2> pts;
  for (size_t i = 0; i < r.t.size(); ++i) pts.push_back({r.pos_m[0][i], r.pos_m[1][i]});
  const ErrorStats want = contour_error(pts, path);
  EXPECT_EQ(r.contour.n, want.n);
  EXPECT_NEAR(r.contour.rms, want.rms, 1e-12);
  EXPECT_NEAR(r.contour.max, want.max, 1e-12);
  ASSERT_EQ(r.contour_each.size(), pts.size());
  for (size_t i = 0; i < pts.size(); i += 97) EXPECT_NEAR(r.contour_each[i], distance(path, pts[i]), 1e-12);
  // A loop at 1 ms follows a 15 mm/s path to a few counts, ends on it, and
  // the streamed queue never ran dry.
  EXPECT_GT(r.contour.rms, 0);
  EXPECT_LT(r.contour.max, 25e-6);
  EXPECT_FALSE(r.underrun);
  EXPECT_TRUE(r.tracking);
  EXPECT_NEAR(r.pos_m[0].back(), 0, 2.0 / counts_per_m(s.machine.axes[0]));
  EXPECT_NEAR(r.pos_m[1].back(), 4e-3, 2.0 / counts_per_m(s.machine.axes[0]));
}

// Streaming by the queue's level: a job that fits the FIFO (all its words
// written at the start, as the scenarios were before streaming) and the same
// job fed two segments at a time give the same run, bit for bit; and the
// Verilated core, fed by the levels it shows, writes at the same clocks.
TEST(Cosim, StreamedQueueGivesTheAllAtOnceRun) {
  RunSpec s = spec_for("fpga-100us", "step", Engine::Twin);
  s.policy = GainPolicy::Tuned;
  s.feedforward = FeedForward::Fitted;
  s.scenario = job_scenario(s.machine, "G21 G90 G17 G94\nG1 X1 F600\nG1 Y1\nG3 X0 Y2 I-1 J0\nG1 X-0.5\nM2\n",
                            "t.nc", 0.02);
  const size_t segs = s.scenario.job->pieces.size();
  ASSERT_GE(segs, 10u);                          // enough to stream
  ASSERT_LE(segs * seg::SEG_WORDS, 512u - 10u);  // and all fit at once
  const RunResult all = run_isolated(s);
  s.queue_words = 2 * seg::SEG_WORDS;
  const RunResult fed = run_isolated(s);
  s.engine = Engine::Rtl;
  const RunResult rtl = run_isolated(s);
  print(all);
  print(fed);
  print(rtl);
  ASSERT_GT(all.sample_u[0].size(), 1000u);
  for (const RunResult* r : {&fed, &rtl}) {
    EXPECT_EQ(r->sample_clock, all.sample_clock);
    EXPECT_EQ(r->sample_u[0], all.sample_u[0]);
    EXPECT_EQ(r->sample_u[1], all.sample_u[1]);
    EXPECT_EQ(r->pos_m[0], all.pos_m[0]);
    EXPECT_EQ(r->cmd_m[1], all.cmd_m[1]);
    EXPECT_EQ(r->contour.rms, all.contour.rms);
    EXPECT_FALSE(r->underrun);
  }
  EXPECT_GT(fed.clocks_skipped, 0u);
  // A window below one segment is a bug in the caller.
  s.engine = Engine::Twin;
  s.queue_words = 5;
  EXPECT_THROW(run_isolated(s), std::runtime_error);
}

// The fitted feed-forward keeps what the core can apply at its Ts: both
// terms at 1 ms, the velocity term alone at 100 us on the default machine.
TEST(Cosim, FittedFeedForward) {
  const MachineConfig m = machine::default_machine();
  const JitterHistogram j = default_jitter();
  const AxisModel g = axis_model(m.axes[0]);
  const auto ff = [&](const char* p, FeedForward f) {
    return gains_for(m, m.axes[0], find_platform(m, p), GainPolicy::Tuned, j, f);
  };
  EXPECT_DOUBLE_EQ(ff("fpga-1ms", FeedForward::Fitted).ff1, 1 / g.kg);
  EXPECT_DOUBLE_EQ(ff("fpga-1ms", FeedForward::Fitted).ff2, g.tau / g.kg);
  EXPECT_DOUBLE_EQ(ff("fpga-100us", FeedForward::Fitted).ff1, 1 / g.kg);
  EXPECT_EQ(ff("fpga-100us", FeedForward::Fitted).ff2, 0);
  EXPECT_DOUBLE_EQ(ff("fpga-100us", FeedForward::Full).ff2, g.tau / g.kg);
  EXPECT_EQ(ff("fpga-min", FeedForward::Velocity).ff2, 0);
  EXPECT_EQ(ff("fpga-min", FeedForward::None).ff1, 0);
  EXPECT_EQ(parse_feedforward("vel+acc"), FeedForward::Full);
  EXPECT_THROW(parse_feedforward("lots"), mc::host::InputError);
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
