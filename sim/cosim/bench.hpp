// The sample-period benchmark (`motionctl bench`, `make bench`): every
// platform x scenario x gain policy co-simulated (sim/cosim.hpp), several
// at once in child processes, then results.csv, report.md and PNG plots.
#pragma once

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
  Engine engine = Engine::Rtl;
  int jobs = 2;
  uint64_t seed = 1;
  std::vector<std::string> platforms, scenarios;  // empty: all
  std::vector<GainPolicy> policies{GainPolicy::Same, GainPolicy::Tuned};
  bool plots = true;
  bool probe_kernel = true;  // also measure the SystemC clocked-module alternative
};

struct KernelProbe {
  double clocked_speed = 0;    // simulated s per wall s, core as an sc_clock-driven module
  double decoupled_speed = 0;  // the same core, stepped in a decoupled process
  double probe_sim_s = 0;
};

struct BenchResult {
  std::vector<RunResult> runs;
  KernelProbe probe;
  double wall_s = 0;
};

// status(done, total, what, fraction of the running ones) as runs progress.
using BenchStatus = std::function<void(int, int, const std::string&, double)>;
BenchResult run_bench(const BenchOptions& o, const BenchStatus& status);

// The files: results.csv, report.md, plots/*.png (needs gnuplot), data/*.dat.
// Returns the paths written.
std::vector<std::string> write_bench(const BenchOptions& o, const BenchResult& r);

// Sim speed of the core driven as a SystemC module by an sc_clock at the
// core clock (SC_METHOD on each rising edge), against the decoupled process;
// runs in a child process (SystemC elaborates once per process).
KernelProbe probe_kernel(const MachineConfig& m, double sim_s);

}  // namespace mc::sim
