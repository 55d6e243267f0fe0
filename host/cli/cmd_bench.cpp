// motionctl bench: the sample-period benchmark (sim/bench.hpp). Every
// platform (the 10 ms PC loop, the FPGA loop at 10 ms down to its shortest
// Ts) on every scenario under both gain policies, and the G-code job with
// tuned gains without and with feed-forward, co-simulated; writes
// report.md, results.csv and plots, and prints the report.
#include <unistd.h>
#include <CLI/CLI.hpp>
#include <chrono>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/cli/commands.hpp"
#include "sim/cosim/bench.hpp"
#include "sim/vboard/board_stream.hpp"

namespace mc::host::cli {
namespace {

struct BenchCli {
  std::string out = "build/bench", config, jitter, engine = "twin", policy = "both", job;
  bool quick = false, json = false, no_plots = false, no_rtl_check = false, no_vboard_speed = false;
  int jobs = 0;
  uint64_t seed = 1;
  std::vector<std::string> platforms, scenarios, job_platforms;
};

// A progress bar on a terminal; otherwise one line per finished run.
class Progress {
 public:
  Progress() : tty_(::isatty(2)) {}
  void operator()(int done, int total, const std::string& last, double running) {
    if (!tty_) {
      if (done != shown_) std::fprintf(stderr, "bench: %d/%d done (%s)\n", done, total, last.c_str());
      shown_ = done;
      return;
    }
    const double f = total ? (done + running) / total : 1;
    const int width = 40, fill = int(std::lround(f * width));
    std::fprintf(stderr, "\r[%s%s] %3d%%  %d/%d runs  %-32s", std::string(size_t(fill), '#').c_str(),
                 std::string(size_t(width - fill), ' ').c_str(), int(f * 100), done, total, last.c_str());
    if (done == total) std::fprintf(stderr, "\n");
  }

 private:
  bool tty_;
  int shown_ = -1;
};

mc::sim::Engine parse_engine(const std::string& e) {
  if (e != "rtl" && e != "twin") throw InputError("--engine", "'" + e + "'", "rtl or twin");
  return e == "rtl" ? mc::sim::Engine::Rtl : mc::sim::Engine::Twin;
}

// "same" or "tuned"; `both` also allows "both" (nullopt).
std::optional<mc::sim::GainPolicy> parse_policy(const std::string& p, bool both) {
  if (p == "same") return mc::sim::GainPolicy::Same;
  if (p == "tuned") return mc::sim::GainPolicy::Tuned;
  if (both && p == "both") return std::nullopt;
  throw InputError("--policy", "'" + p + "'", both ? "same, tuned or both" : "same or tuned");
}

// The virtual board's speed on both engines (three axes holding, X and Y
// moving), for the report's speed table.
void add_vboard_speeds(const mc::sim::BenchOptions& o, mc::sim::BenchResult& r) {
  const auto t0 = std::chrono::steady_clock::now();
  // The board has three axes: a two-axis machine gets a third like its last.
  mc::machine::MachineConfig m = o.machine;
  while (m.axes.size() < 3) {
    m.axes.push_back(m.axes.back());
    m.axes.back().name = "xyz"[m.axes.size() - 1];
  }
  for (const mc::sim::BoardEngine e : {mc::sim::BoardEngine::Twin, mc::sim::BoardEngine::Rtl}) {
    // The RTL runs at a fraction of real time: a shorter stretch.
    const double board_s = (e == mc::sim::BoardEngine::Twin ? 1.0 : 0.05) * (o.quick ? 0.1 : 1.0);
    for (const char* w : {"hold", "move"}) {
      std::fprintf(stderr, "bench: virtual board, %s, %s engine\n", w, mc::sim::board_engine_name(e));
      const mc::sim::VBoardSpeed v = mc::sim::measure_vboard_speed(m, e, w, board_s);
      r.other_speeds.push_back({"virtual board, " + std::to_string(v.axes) + " axes, " +
                                    (v.workload == "hold" ? "holding" : "X and Y moving"),
                                mc::sim::board_engine_name(e), v.board_s, v.wall_s, v.cpu_s});
    }
  }
  r.wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// --jitter: the shipped histogram, or a file that must be text (a binary
// file is refused with the offset of its first non-text byte).
mc::sim::JitterHistogram jitter_or_default(const std::string& path) {
  if (path.empty()) return mc::sim::default_jitter();
  require_text_file(path, "--jitter");
  return mc::sim::load_jitter(path);
}

void bench_command(const BenchCli& c) {
  mc::sim::BenchOptions o;
  o.machine = mc::machine::machine_or_default(c.config);
  require_writable_dir(c.out, "--out");  // before the bench, not after it
  o.jitter = jitter_or_default(c.jitter);
  o.out_dir = c.out;
  o.quick = c.quick;
  o.engine = parse_engine(c.engine);
  if (const auto p = parse_policy(c.policy, true)) o.policies = {*p};
  if (c.jobs < 0) throw InputError("--jobs", std::to_string(c.jobs), "a positive number of processes");
  o.jobs = c.jobs ? c.jobs : int(std::max(1u, std::thread::hardware_concurrency()));
  o.seed = c.seed;
  o.platforms = c.platforms;
  o.scenarios = c.scenarios;
  o.job_file = c.job;
  if (!c.job_platforms.empty()) o.job_platforms = c.job_platforms;
  o.plots = !c.no_plots;
  o.rtl_check = !c.no_rtl_check;
  Progress progress;
  mc::sim::BenchResult r = mc::sim::run_bench(o, std::ref(progress));
  if (!c.no_vboard_speed) add_vboard_speeds(o, r);
  const std::vector<std::string> files = mc::sim::write_bench(o, r);
  if (c.json) {
    nlohmann::json j = nlohmann::json::array();
    for (const mc::sim::RunResult& x : r.runs)
      j.push_back({{"platform", x.platform},
                   {"scenario", x.scenario},
                   {"policy", x.policy},
                   {"engine", x.engine},
                   {"feedforward", x.feedforward},
                   {"ts_s", x.gains.ts},
                   {"follow_rms_x_um", x.follow[0].rms * 1e6},
                   {"follow_rms_y_um", x.follow[1].rms * 1e6},
                   {"contour_rms_um", x.contour.rms * 1e6},
                   {"contour_max_um", x.contour.max * 1e6},
                   {"tracking", x.tracking},
                   {"sim_speed", x.sim_s / x.wall_s}});
    std::cout << nlohmann::json{{"runs", j}, {"files", files}}.dump(2) << "\n";
    return;
  }
  std::ifstream md(c.out + "/report.md");
  std::cout << md.rdbuf();
  std::cout << "\nWrote:";
  for (const std::string& f : files) std::cout << "\n  " << f;
  std::cout << "\n";
}

struct CosimCli {
  std::string config, jitter, engine = "rtl", policy = "same", platform = "fpga-100us", scenario = "step",
                              trace, csv, job;
  std::string feedforward = "none";
  bool quick = false, json = false;
  int queue_words = 0;
  uint64_t seed = 1;
};

void cosim_command(const CosimCli& c) {
  mc::sim::RunSpec s;
  s.machine = mc::machine::machine_or_default(c.config);
  if (!c.csv.empty()) require_writable_file(c.csv, "--csv");
  if (!c.trace.empty()) require_writable_file(c.trace, "--trace");
  s.jitter = jitter_or_default(c.jitter);
  s.platform = mc::sim::find_platform(s.machine, c.platform);
  s.scenario = c.scenario == "job" ? mc::sim::bench_job(s.machine, c.job, c.quick)
                                   : mc::sim::find_scenario(c.scenario, c.quick);
  if (!c.job.empty() && c.scenario != "job")
    throw InputError("--job", "'" + c.job + "'", "--scenario job with it");
  s.feedforward = mc::sim::parse_feedforward(c.feedforward);
  s.queue_words = c.queue_words;
  s.engine = parse_engine(c.engine);
  s.policy = *parse_policy(c.policy, false);
  if (!c.trace.empty() && (s.platform.host || s.engine != mc::sim::Engine::Rtl))
    throw InputError("--trace", "'" + c.trace + "'",
                     "an FPGA platform with --engine rtl (the waveform is the RTL's)");
  s.fst_path = c.trace;
  s.seed = c.seed;
  // A job's seconds: every 100 us (2 um of travel at its 1200 mm/min).
  s.record_dt_s = c.scenario == "job" ? 1e-4 : 1e-5;
  const mc::sim::RunResult r = mc::sim::run_isolated(s);
  if (!c.csv.empty()) {
    std::ofstream f(c.csv);
    f << "t_s,cmd_x_m,cmd_y_m,pos_x_m,pos_y_m\n";
    for (size_t i = 0; i < r.t.size(); ++i)
      f << r.t[i] << ',' << r.cmd_m[0][i] << ',' << r.cmd_m[1][i] << ',' << r.pos_m[0][i] << ','
        << r.pos_m[1][i] << '\n';
    if (!f) throw InputError("--csv", "'" + c.csv + "'", "a writable file path");
  }
  const bool step = r.scenario == "step";
  if (c.json) {
    nlohmann::json j{{"platform", r.platform},
                     {"scenario", r.scenario},
                     {"policy", r.policy},
                     {"engine", r.engine},
                     {"feedforward", r.feedforward},
                     {"ts_s", r.gains.ts},
                     {"kp", r.gains.kp},
                     {"ki", r.gains.ki},
                     {"kd", r.gains.kd},
                     {"tf_s", r.gains.tf},
                     {"follow_rms_x_um", r.follow[0].rms * 1e6},
                     {"follow_max_x_um", r.follow[0].max * 1e6},
                     {"follow_rms_y_um", r.follow[1].rms * 1e6},
                     {"follow_max_y_um", r.follow[1].max * 1e6},
                     {"tracking", r.tracking},
                     {"samples", r.sample_u[0].size()},
                     {"sim_s", r.sim_s},
                     {"wall_s", r.wall_s},
                     {"setup_s", r.setup_s},
                     {"clocks_cycled", r.clocks_cycled},
                     {"clocks_skipped", r.clocks_skipped}};
    if (step) {
      j["settling_time_s"] = r.step.settling_s;
      j["overshoot_pct"] = r.step.overshoot_pct;
      j["rise_time_s"] = r.step.rise_s;
    } else {
      j["contour_rms_um"] = r.contour.rms * 1e6;
      j["contour_max_um"] = r.contour.max * 1e6;
    }
    if (r.scenario == "job") {
      j["measured_contour_rms_um"] = r.measured_contour.rms * 1e6;
      j["measured_contour_max_um"] = r.measured_contour.max * 1e6;
      j["underrun"] = r.underrun;
    }
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf(
      "%s on %s, %s gains%s, %s engine: Ts %.6g s, kp %.6g ki %.6g kd %.6g tf %.6g ff1 %.6g ff2 %.6g\n",
      r.scenario.c_str(), r.platform.c_str(), r.policy.c_str(),
      r.feedforward == "none" ? "" : (" + feed-forward " + r.feedforward).c_str(), r.engine.c_str(),
      r.gains.ts, r.gains.kp, r.gains.ki, r.gains.kd, r.gains.tf, r.gains.ff1, r.gains.ff2);
  std::printf("following error x: RMS %.3f um, max %.3f um; y: RMS %.3f um, max %.3f um\n",
              r.follow[0].rms * 1e6, r.follow[0].max * 1e6, r.follow[1].rms * 1e6, r.follow[1].max * 1e6);
  if (step)
    std::printf(
        "step: rise %.3f ms, overshoot %.2f %%, settling (2 %%) %.3f ms, steady-state error %.3f um\n",
        r.step.rise_s * 1e3, r.step.overshoot_pct, r.step.settling_s * 1e3, r.step.ss_error * 1e6);
  else
    std::printf("contour error: RMS %.3f um, max %.3f um\n", r.contour.rms * 1e6, r.contour.max * 1e6);
  if (r.scenario == "job")
    std::printf("contour error of the encoder counts: RMS %.3f um, max %.3f um; %s\n",
                r.measured_contour.rms * 1e6, r.measured_contour.max * 1e6,
                r.underrun ? "the queue RAN DRY" : "no underrun");
  std::printf("%s; %zu controller samples; %.3f s simulated in %.3f s (%.3gx real time)\n",
              r.tracking ? "tracking at the end" : "NOT TRACKING at the end", r.sample_u[0].size(), r.sim_s,
              r.wall_s, r.sim_s / r.wall_s);
  if (!c.trace.empty()) std::printf("waveform: %s\n", c.trace.c_str());
}

}  // namespace

void add_cosim_command(CLI::App& app) {
  auto c = std::make_shared<CosimCli>();
  CLI::App* cmd = app.add_subcommand("cosim", "One closed-loop co-simulation: a platform on a scenario");
  cmd->add_option("--platform", c->platform,
                  "host-10ms, fpga-10ms, fpga-1ms, fpga-100us, fpga-10us or fpga-min")
      ->capture_default_str();
  cmd->add_option("--scenario", c->scenario, "step, line-45, line-30, circle or job")->capture_default_str();
  cmd->add_option("--job", c->job,
                  "G-code file of --scenario job (default: the built-in examples/profile.nc)");
  cmd->add_option("--feedforward", c->feedforward,
                  "The core's feed-forward from the axis model: none, vel, vel+acc, or fitted (each term "
                  "where a one-count pulse of it fits the output)")
      ->capture_default_str();
  cmd->add_option("--queue-words", c->queue_words,
                  "Most segment words kept in the core's queue (default: its FIFO's whole segments)");
  cmd->add_option("--policy", c->policy, "Gain policy: same or tuned")->capture_default_str();
  cmd->add_option("--engine", c->engine, "FPGA model: rtl (Verilated) or twin (hls/ C++)")
      ->capture_default_str();
  cmd->add_flag("--quick", c->quick, "The shortened scenario of `bench --quick`");
  cmd->add_option("--seed", c->seed, "Seed of the host loop's jitter draws")->capture_default_str();
  cmd->add_option("--trace", c->trace, "Write the core's waveform (FST, for GTKWave); RTL engine only");
  cmd->add_option("--csv", c->csv, "Write the trace (t, command, position; metres) to this CSV file");
  cmd->add_option("--config", c->config, "Machine TOML (default: the built-in configs/default.toml)");
  cmd->add_option("--jitter", c->jitter,
                  "Wake-up histogram from `motionctl jitter` (default: the shipped one)");
  cmd->add_flag("--json", c->json, "Machine-readable output");
  cmd->callback([c] { cosim_command(*c); });
}

void add_bench_command(CLI::App& app) {
  auto c = std::make_shared<BenchCli>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Sample-period benchmark: the 10 ms PC loop against the FPGA loop at 10 ms .. its shortest Ts");
  cmd->add_option("--out", c->out, "Output directory (report.md, results.csv, plots/, data/)")
      ->capture_default_str();
  cmd->add_flag("--quick", c->quick, "Short scenarios: a smoke run, not for comparison");
  cmd->add_option("--engine", c->engine, "FPGA model: twin (hls/ C++) or rtl (Verilated)")
      ->capture_default_str();
  cmd->add_flag("--no-rtl-check", c->no_rtl_check,
                "With the twin engine, do not rerun a subset on the Verilated RTL to compare");
  cmd->add_flag("--no-vboard-speed", c->no_vboard_speed, "Do not measure the virtual board's speed");
  cmd->add_option("--policy", c->policy, "Gain policy: same, tuned or both")->capture_default_str();
  cmd->add_option("--platform", c->platforms,
                  "Only these platforms (host-10ms, fpga-10ms, fpga-1ms, fpga-100us, fpga-10us, fpga-min)");
  cmd->add_option("--scenario", c->scenarios, "Only these scenarios (step, line-45, line-30, circle, job)");
  cmd->add_option("--job", c->job,
                  "G-code file of the job scenario (default: the built-in examples/profile.nc)");
  cmd->add_option("--job-platform", c->job_platforms,
                  "Platforms of the job scenario unless --platform is given (default: host-10ms, fpga-10ms, "
                  "fpga-1ms, fpga-100us)");
  cmd->add_option("--jobs", c->jobs, "Runs at once (default: the number of CPUs)");
  cmd->add_option("--seed", c->seed, "Seed of the host loop's jitter draws")->capture_default_str();
  cmd->add_option("--config", c->config, "Machine TOML (default: the built-in configs/default.toml)");
  cmd->add_option("--jitter", c->jitter,
                  "Wake-up histogram from `motionctl jitter` (default: the shipped one)");
  cmd->add_flag("--no-plots", c->no_plots, "Skip the PNG plots (gnuplot)");
  cmd->add_flag("--json", c->json, "Print the results as JSON instead of the report");
  cmd->callback([c] { bench_command(*c); });
}

}  // namespace mc::host::cli
