// motionctl step, tune and hostloop against the virtual board, each test
// with its own `sim serve --fast` process: the step capture agrees with the
// hls twin co-simulation of the same scenario, `tune --method model --apply`
// beats the default gains, a tune without --apply leaves the gains as they
// were, hostloop runs and reports, and bad arguments give one error line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "host/control/step_metrics.hpp"
#include "sim/cosim/cosim.hpp"
#include "vboard_server.hpp"

namespace mc::test {
namespace {

using nlohmann::json;

// motionctl --port PTY args... --json, parsed.
json board_json(const Server& sv, std::vector<std::string> args) {
  args.insert(args.begin(), {"--port", sv.pty()});
  args.push_back("--json");
  const Result r = run(args);
  std::string cmd;
  for (const auto& a : args) cmd += " " + a;
  // A failed command ends the test (gtest reports the exception): what
  // follows reads fields the output would have had.
  if (r.exit_code != 0)
    throw std::runtime_error("motionctl" + cmd + " exited " + std::to_string(r.exit_code) + ":\n" + r.err);
  return json::parse(r.out);
}

json step_json(const Server& sv) {
  return board_json(sv, {"step", "--axis", "x", "--size", "1", "--duration", "0.2s"});
}

TEST(CliStep, CaptureAgreesWithTheTwinCosimulation) {
  PrivateRuntimeDir rt;
  Server sv;
  board_json(sv, {"gains", "set", "--axis", "x", "--defaults"});
  const std::string dir = std::getenv("XDG_RUNTIME_DIR");
  const json b = board_json(sv, {"step", "--axis", "x", "--size", "1", "--duration", "0.2s", "--csv",
                                 dir + "/step.csv", "--plot", dir + "/step.png"});
  ASSERT_TRUE(b.contains("metrics"));
  // The CSV: the header with units, one row per sample, time increasing,
  // the command stepping by 400 counts at t = 0.
  std::ifstream csv(dir + "/step.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t_s,cmd_counts,pos_counts,err_counts,out_drive_units");
  size_t rows = 0;
  double t_prev = -1;
  for (; std::getline(csv, line); ++rows) {
    double t = 0;
    int cmd = 0, pos = 0, err = 0, out = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%d,%d,%d", &t, &cmd, &pos, &err, &out), 5) << line;
    EXPECT_GT(t, t_prev);
    t_prev = t;
    EXPECT_EQ(cmd, t < 0 ? 0 : 400) << line;
  }
  EXPECT_EQ(rows, size_t(b["samples"]));
  std::ifstream png(dir + "/step.png", std::ios::binary);
  char sig[4] = {};
  png.read(sig, 4);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG") << "gnuplot wrote the plot";
  EXPECT_EQ(b["step_counts"], 400);
  EXPECT_EQ(b["gaps"], 0) << "the decimation the step chose must carry every frame";
  EXPECT_EQ(b["faults"], "none");
  const json& m = b["metrics"];

  // The same scenario in the co-simulation: default machine and gains, Ts
  // 100 us, a 1 mm step by the interpolator's set, the core's hls twin.
  mc::sim::RunSpec spec;
  spec.machine = mc::machine::default_machine();
  spec.platform = mc::sim::find_platform(spec.machine, "fpga-100us");
  spec.scenario = mc::sim::find_scenario("step");
  spec.scenario.duration_s = 0.2;
  spec.engine = mc::sim::Engine::Twin;
  const mc::sim::RunResult tw = mc::sim::run_isolated(spec);
  const double cpm = mc::machine::counts_per_m(spec.machine.axes[0]);
  std::vector<double> y;
  for (double p : tw.pos_m[0]) y.push_back(p * cpm);
  const mc::host::StepMetrics t = mc::host::step_metrics(tw.t, y, 0, 400, 0);
  ASSERT_TRUE(m["settled"]) << b.dump();
  ASSERT_TRUE(t.settled);
  std::printf("board: overshoot %.2f %%, settling %.2f ms, rise %.2f ms, IAE %.4f count*s\n",
              double(m["overshoot_pct"]), double(m["settling_s"]) * 1e3, double(m["rise_s"]) * 1e3,
              double(m["iae_counts_s"]));
  std::printf("twin:  overshoot %.2f %%, settling %.2f ms, rise %.2f ms, IAE %.4f count*s\n", t.overshoot_pct,
              t.settling_s * 1e3, t.rise_s * 1e3, t.iae);
  // The board's capture samples every 5th PID sample (500 us): a peak or a
  // band crossing can fall between frames.
  EXPECT_NEAR(double(m["overshoot_pct"]), t.overshoot_pct, 2.0);
  EXPECT_NEAR(double(m["settling_s"]), t.settling_s, 0.10 * t.settling_s);
  EXPECT_NEAR(double(m["rise_s"]), t.rise_s, 0.10 * t.rise_s);
  EXPECT_NEAR(double(m["iae_counts_s"]), t.iae, 0.10 * t.iae);
  EXPECT_NEAR(double(m["ss_error_counts"]), 0, 1.0);
}

TEST(CliStep, TuneModelApplyBeatsTheDefaultGains) {
  PrivateRuntimeDir rt;
  Server sv;
  board_json(sv, {"gains", "set", "--axis", "x", "--defaults"});
  const json before = step_json(sv)["metrics"];

  // Relay without --apply: an experiment, then the gains exactly as before.
  const json words = board_json(sv, {"gains", "show", "--axis", "x"})["words"];
  const json relay = board_json(sv, {"tune", "--axis", "x", "--method", "relay"});
  EXPECT_FALSE(relay["applied"]);
  EXPECT_GT(double(relay["relay"]["ku"]), 0);
  EXPECT_EQ(board_json(sv, {"gains", "show", "--axis", "x"})["words"], words);

  const json tuned = board_json(sv, {"tune", "--axis", "x", "--method", "model", "--apply"});
  ASSERT_TRUE(tuned.contains("proposed"));
  EXPECT_TRUE(tuned["applied"]);
  const json now = board_json(sv, {"gains", "show", "--axis", "x"});
  EXPECT_NEAR(double(now["kp"]), double(tuned["proposed"]["kp"]), 1e-4 * double(tuned["proposed"]["kp"]));
  const json after = step_json(sv)["metrics"];
  ASSERT_TRUE(before["settled"]) << before.dump();
  ASSERT_TRUE(after["settled"]) << after.dump();
  ASSERT_TRUE(tuned["proposed"]["predicted"]["settled"]) << tuned.dump();
  std::printf(
      "default gains: overshoot %.2f %%, settling %.2f ms; tuned (Kp %.2f, Ki %.0f, Kd %.4f): "
      "overshoot %.2f %%, settling %.2f ms; predicted %.2f %%, %.2f ms\n",
      double(before["overshoot_pct"]), double(before["settling_s"]) * 1e3, double(now["kp"]),
      double(now["ki"]), double(now["kd"]), double(after["overshoot_pct"]), double(after["settling_s"]) * 1e3,
      double(tuned["proposed"]["predicted"]["overshoot_pct"]),
      double(tuned["proposed"]["predicted"]["settling_s"]) * 1e3);
  EXPECT_LE(double(after["overshoot_pct"]), 10.0);
  EXPECT_LT(double(after["settling_s"]), double(before["settling_s"]));
}

TEST(CliStep, InterruptedTuneRestoresTheGains) {
  PrivateRuntimeDir rt;
  Server sv;
  board_json(sv, {"gains", "set", "--axis", "x", "--defaults"});
  const json before = board_json(sv, {"gains", "show", "--axis", "x"});
  const int devnull = ::open("/dev/null", O_WRONLY);
  int err[2];
  ASSERT_EQ(::pipe(err), 0);
  const pid_t tune = spawn({"--port", sv.pty(), "tune", "--axis", "x"}, devnull, err[1]);
  ::close(devnull);
  ::close(err[1]);
  ASSERT_GT(tune, 0);
  // Interrupted once it says its handler is in place and the experiment
  // runs (1 s of board time): the next telemetry wait sees the flag.
  std::string said;
  const bool running = read_until(err[0], "Ctrl-C stops it", said);
  ::kill(tune, SIGINT);
  said += read_all(err[0]);
  ::close(err[0]);
  int st = 0;
  ::waitpid(tune, &st, 0);
  ASSERT_TRUE(running) << said;
  EXPECT_NE(said.find("interrupted"), std::string::npos) << said;
  ASSERT_TRUE(WIFEXITED(st)) << "SIGINT is caught, not fatal";
  EXPECT_NE(WEXITSTATUS(st), 0);
  const json after = board_json(sv, {"gains", "show", "--axis", "x"});
  EXPECT_EQ(after["words"], before["words"]);
  EXPECT_EQ(after["ts"], before["ts"]) << "the experiment's sample period is undone";
}

TEST(CliStep, HostloopRunsAndReports) {
  PrivateRuntimeDir rt;
  // Paced: the host's reaction to each telemetry sample is wall time, which
  // a free-running board would turn into tens of milliseconds of board time
  // on a loaded machine (each write landing that much later, the periods'
  // mean off by the spread over 40 samples).
  Server sv(false, true);
  board_json(sv, {"gains", "set", "--axis", "x", "--defaults"});
  const json h = board_json(sv, {"hostloop", "--axis", "x", "--ts", "10ms", "--duration", "0.4s"});
  ASSERT_TRUE(h.contains("period_board_s"));
  std::printf(
      "hostloop: %d samples, period mean %.3f ms p99 %.3f max %.3f; latency mean %.3f ms; "
      "following error host RMS %.1f um max %.1f, FPGA RMS %.1f um max %.1f\n",
      int(h["host_samples"]), double(h["period_board_s"]["mean"]) * 1e3,
      double(h["period_board_s"]["p99"]) * 1e3, double(h["period_board_s"]["max"]) * 1e3,
      double(h["latency_board_s"]["mean"]) * 1e3, double(h["host_following_error_um"]["rms"]),
      double(h["host_following_error_um"]["max"]), double(h["fpga_following_error_um"]["rms"]),
      double(h["fpga_following_error_um"]["max"]));
  // 0.4 s at 10 ms: 40 host samples, 10 ms of board time apart. A period is
  // measured between two writes landing, each its latency after its sample,
  // so the mean is 10 ms give or take the latency's spread over the samples
  // (at most its largest, the smallest being 0 or more), and a sample of Ts.
  const int n = int(h["host_samples"]);
  EXPECT_GE(n, 38);
  EXPECT_NEAR(double(h["period_board_s"]["mean"]), 0.01,
              1e-4 + double(h["latency_board_s"]["max"]) / std::max(1, n - 1));
  EXPECT_GE(double(h["period_board_s"]["max"]), 0.01);
  EXPECT_EQ(h["gaps"], 0);
  EXPECT_EQ(h["faults"], "none");
  // The 10 ms loop follows the jog, but far worse than the board's 100 us loop.
  EXPECT_GT(double(h["host_following_error_um"]["rms"]), 0);
  EXPECT_LT(double(h["host_following_error_um"]["max"]), 1000);
  EXPECT_GT(double(h["host_following_error_um"]["rms"]), 3 * double(h["fpga_following_error_um"]["rms"]));
}

TEST(CliStep, BadArgumentsAreOneLine) {
  PrivateRuntimeDir rt;
  expect_one_error_line({"--port", "/dev/null", "step"}, "--axis");
  expect_one_error_line({"--port", "/dev/null", "step", "--axis", "w"}, "--axis");
  expect_one_error_line({"--port", "/dev/null", "step", "--axis", "x", "--size", "0"}, "--size");
  expect_one_error_line({"--port", "/dev/null", "step", "--axis", "x", "--size", "1mm"}, "--size");
  expect_one_error_line({"--port", "/dev/null", "step", "--axis", "x", "--duration", "20s"}, "--duration");
  expect_one_error_line({"--port", "/dev/null", "tune", "--axis", "x", "--method", "magic"}, "--method");
  expect_one_error_line({"--port", "/dev/null", "tune", "--axis", "x", "--zeta", "-1"}, "--zeta");
  expect_one_error_line(
      {"--port", "/dev/null", "tune", "--axis", "x", "--method", "relay", "--bandwidth", "100"},
      "--bandwidth");
  expect_one_error_line({"--port", "/dev/null", "hostloop", "--axis", "x", "--feed", "0"}, "--feed");
  expect_one_error_line({"--port", "/dev/null", "hostloop", "--axis", "x", "--ts", "soon"}, "--ts");
}

}  // namespace
}  // namespace mc::test
