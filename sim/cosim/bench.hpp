// The sample-period benchmark (`motionctl bench`, `make bench`): every
// platform x scenario x gain policy co-simulated (sim/cosim.hpp), and the
// G-code job scenario (examples/profile.nc as `motionctl run` plans it) on
// the job platforms with tuned gains, without and with the core's
// feed-forward; several runs at once in child processes, then results.csv,
// report.md and PNG plots.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "sim/cosim/cosim.hpp"

namespace mc::sim {

struct BenchOptions {
  MachineConfig machine;
  JitterHistogram jitter;
  std::string out_dir = "build/bench";
  bool quick = false;
  Engine engine = Engine::Twin;
  // With the twin engine: rerun a subset on the RTL (rtl_check_runs()) and
  // compare the controller outputs sample for sample.
  bool rtl_check = true;
  int jobs = 2;
  uint64_t seed = 1;
  std::vector<std::string> platforms, scenarios;  // empty: all ("job" is the job scenario's name)
  // The job scenario: this G-code file (empty: the built-in
  // examples/profile.nc), on these platforms unless `platforms` names some.
  // The job runs for its planned time (11.7 s for the profile), so by
  // default it skips the two shortest Ts, which cost 3-5 times as much and
  // give what 100 us gives (docs/cosim.md).
  std::string job_file;
  std::vector<std::string> job_platforms{"host-10ms", "fpga-10ms", "fpga-1ms", "fpga-100us"};
  std::vector<FeedForward> job_feedforward{FeedForward::None, FeedForward::Fitted};
  std::vector<GainPolicy> policies{GainPolicy::Same, GainPolicy::Tuned};
  bool plots = true;
  bool probe_kernel = true;  // also measure the SystemC clocked-module alternative
};

struct KernelProbe {
  double bare_speed = 0;       // simulated s per wall s, the Verilated core alone in a C++ loop
  double clocked_speed = 0;    // simulated s per wall s, core as an sc_clock-driven module
  double decoupled_speed = 0;  // the same core, stepped in a decoupled process
  double probe_sim_s = 0;
};

// A run of the table repeated on the RTL engine.
struct RtlCheck {
  size_t run = 0;  // index into BenchResult::runs
  RunResult rtl;
  bool same_outputs = false;  // every controller output and sample clock equal
  // Simulated s per CPU s of the Verilated core alone in a bare loop: the
  // mean of its runs just before and just after this one.
  double bare_speed = 0;
};

// The runs the RTL check repeats: (platform, scenario, policy).
std::vector<std::array<std::string, 3>> rtl_check_runs();

// A speed measured outside the co-simulation (the virtual board), for the
// report's speed table.
struct SpeedRow {
  std::string what, engine;
  double sim_s = 0, wall_s = 0, cpu_s = 0;
};

struct BenchResult {
  std::vector<RunResult> runs;
  std::string job;  // the job scenario's description, empty without it
  std::vector<RtlCheck> rtl_checks;
  std::vector<SpeedRow> other_speeds;
  KernelProbe probe;
  // The goal's case (the circle at 100 us, same gains, on the twin) run
  // alone after the pool, kGoalAloneRuns times: in the pool it shares the
  // machine's cores with another run.
  static constexpr int kGoalAloneRuns = 5;
  double goal_alone_sim_s = 0;
  std::vector<double> goal_alone_wall_s;
  std::vector<double> goal_alone_setup_s;  // of each, the run's set-up (RunResult::setup_s)
  double wall_s = 0;
};

// status(done, total, what, fraction of the running ones) as runs progress.
using BenchStatus = std::function<void(int, int, const std::string&, double)>;
BenchResult run_bench(const BenchOptions& o, const BenchStatus& status);

// The files: results.csv, report.md, plots/*.png (needs gnuplot), data/*.dat.
// Returns the paths written.
std::vector<std::string> write_bench(const BenchOptions& o, const BenchResult& r);

// Sim speed of the Verilated core alone (a bare C++ loop, inputs held), of
// the core driven as a SystemC module by an sc_clock at the core clock
// (SC_METHOD on each rising edge), and of the decoupled process; each in a
// child process (SystemC elaborates once per process).
KernelProbe probe_kernel(const MachineConfig& m, double sim_s);

}  // namespace mc::sim
