// The closed-loop co-simulation: an XY table of two DC-motor axes
// (sim/dc_motor.hpp) under one of two controllers,
// - the FPGA: rtl/motion_core.v clock by clock at the core clock, Verilated
//   (Engine::Rtl) or its hls twin (Engine::Twin), with the encoder pins it
//   would see and the drive it puts out;
// - the PC: the same PID in double precision, woken every 10 ms with the
//   wake-up jitter of a real Linux machine (sim/jitter.hpp), its position
//   read and its output written through a DAQ with an I/O latency and a
//   12-bit DAC (sim/host_loop.hpp);
// tracking the same command: the interpolator's output for a step, a line,
// a circle or a planned G-code job, whose segments are streamed into the
// core's queue by its level as the host streams them over the link. A
// SystemC model runs the parts as processes at their own
// rates (docs/decisions.md says how and why); run() does one scenario.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "host/control/metrics.hpp"
#include "host/control/pid_design.hpp"
#include "host/control/step_metrics.hpp"
#include "host/machine/job.hpp"
#include "host/machine/machine_config.hpp"
#include "sim/cosim/zeroed.hpp"
#include "sim/plant/jitter.hpp"

namespace mc::sim {

// The tracking metrics are the host's (the board captures use them too).
using mc::host::Arc;
using mc::host::contour_error;
using mc::host::ErrorStats;
using mc::host::following_error;
using mc::host::PathPiece;
using mc::host::Point2;
using mc::host::Segment;
// The machine description every run is built from.
using mc::machine::axis_model;
using mc::machine::AxisConfig;
using mc::machine::AxisModel;
using mc::machine::MachineConfig;
using mc::machine::tuned_gains;

enum class Engine { Rtl, Twin };
const char* engine_name(Engine e);

struct Platform {
  std::string name;   // "host-10ms", "fpga-100us", ...
  bool host = false;  // the PC loop instead of the FPGA core
  double ts_s = 0;    // sample period (the FPGA's is a whole number of clocks)
};
// The benchmark's platforms: host-10ms, fpga-10ms, fpga-1ms, fpga-100us,
// fpga-10us and fpga-min (the shortest Ts the two-axis core runs).
std::vector<Platform> bench_platforms(const MachineConfig& m);
// The shortest sample period of the two-axis core, s.
double fpga_min_ts(const MachineConfig& m);

enum class ScenarioKind { Step, Line, Circle, Job };
struct Scenario {
  std::string name;
  ScenarioKind kind = ScenarioKind::Step;
  double size_m = 0;      // step size, line length, circle radius; a job's XY extent
  double angle_deg = 0;   // line direction from +x
  double feed_m_s = 0;    // path speed (lines, circle)
  double duration_s = 0;  // simulated time after the command starts
  // Job: the program as the planner of `motionctl run` planned it, from the
  // machine origin (shared: every run of a bench reads the same plan).
  std::shared_ptr<const mc::machine::Job> job;
  std::string describe() const;
};
// step (x, 1 mm), line-45 and line-30 (20 mm), circle (R 5 mm), feeds as
// stated by describe(); quick: shorter versions for a smoke run.
std::vector<Scenario> bench_scenarios(bool quick);
Scenario find_scenario(const std::string& name, bool quick = false);
// The G-code job scenario "job": `program` (named `source` in errors and
// reports) planned for machine m from its origin, run for its planned time
// plus settle_s. The co-simulation's table has X and Y only: the plan keeps
// Z's moves (their time), the contour error is that of the XY path, and an
// arc outside the XY plane is refused (InputError).
Scenario job_scenario(const MachineConfig& m, std::string_view program, const std::string& source,
                      double settle_s = 0.1);
// examples/profile.nc as compiled in (the bench's job), and a short job of
// a line and an arc for quick runs.
std::string_view profile_program();
std::string_view quick_job_program();
// The job scenario of `bench` and `cosim --scenario job`: the G-code file at
// `path` (InputError if unreadable), or with an empty path the built-in
// examples/profile.nc (quick: quick_job_program()).
Scenario bench_job(const MachineConfig& m, const std::string& path, bool quick);
Platform find_platform(const MachineConfig& m, const std::string& name);

// "same": the machine's continuous design at every Ts (the paper's method).
// "tuned": the rule of tuned_gains() for each platform's own delay.
enum class GainPolicy { Same, Tuned };
const char* policy_name(GainPolicy p);

// The delay a loop adds at its sample period: half a sample (hold) plus
// the computation or I/O latency; for the PC also the mean wake-up lateness.
double loop_delay_s(const MachineConfig& m, const Platform& p, const JitterHistogram& jitter);
// The core's velocity and acceleration feed-forward from the axis model
// G(s) = Kg / (s (tau s + 1)): FF1 = 1/Kg (the drive that holds the
// command's velocity), FF2 = tau/Kg (that accelerates the motor). The core
// derives velocity and acceleration from the command's first and second
// difference per sample, and the command moves in whole counts: Fitted
// keeps each term only where a one-count pulse of it fits the output
// (FF1/Ts <= out_limit, FF2/Ts^2 <= out_limit/8), which on the default
// machine drops FF2 at 100 us and below (docs/cosim.md has the measurement).
enum class FeedForward { None, Velocity, Full, Fitted };
const char* feedforward_name(FeedForward f);             // none, vel, vel+acc, fitted
FeedForward parse_feedforward(const std::string& name);  // InputError naming --feedforward
// Sets g's ff1 and ff2 (None: leaves them), for its Ts.
void add_model_feedforward(mc::host::PidGains& g, const AxisConfig& a, FeedForward f);
// feedforward other than None replaces the gains' own FF1 and FF2.
mc::host::PidGains gains_for(const MachineConfig& m, const AxisConfig& a, const Platform& p,
                             GainPolicy policy, const JitterHistogram& jitter,
                             FeedForward feedforward = FeedForward::None);
struct RunSpec {
  MachineConfig machine;
  Platform platform;
  Scenario scenario;
  GainPolicy policy = GainPolicy::Same;
  FeedForward feedforward = FeedForward::None;
  Engine engine = Engine::Rtl;
  // The most segment words kept in the core's queue (0: as many whole
  // segments as its FIFO holds). Segments are written as room frees, by the
  // level the core shows, as the host streams them over the link.
  int queue_words = 0;
  uint64_t seed = 1;
  std::string fst_path;                  // waveform of the core (RTL engine only)
  double record_dt_s = 1e-4;             // trace interval
  JitterHistogram jitter;                // the PC's wake-up lateness
  std::function<void(double)> progress;  // fraction done, now and then
};

struct RunResult {
  std::string platform, scenario, policy, engine;
  std::string feedforward = "none";  // feedforward_name(); gains.ff1, ff2 say what it applied
  mc::host::PidGains gains;          // axis x's
  TraceVector<double> t;             // s from the command start
  std::array<TraceVector<double>, 2> cmd_m, pos_m;
  // Every controller output: the FPGA's per PID sample (clock of its done),
  // the PC's per wake.
  std::vector<uint64_t> sample_clock;
  std::array<std::vector<int32_t>, 2> sample_u;
  std::array<ErrorStats, 2> follow;  // m
  ErrorStats contour;                // m, paths only: the table's true position
  // Job: the contour error of the encoder counts (what the board measures,
  // as `motionctl run` reports it), m; and each recorded sample's distance
  // of the true position (m, NaN while the command is on a rapid).
  ErrorStats measured_contour;
  std::vector<double> contour_each;
  bool underrun = false;         // the core's queue ran dry while moving (ip_underrun)
  mc::host::StepMetrics step{};  // step only, axis x
  bool tracking = true;          // within a quarter of the move of the command at the end
  double sim_s = 0, wall_s = 0;
  double setup_s = 0;  // of wall_s, building the machine, its trace and the model, before the kernel runs
  double cpu_s = 0;    // the process's CPU time for the run (the machine may be shared)
  uint64_t clocks_cycled = 0, clocks_skipped = 0;
};
// This process's CPU time, s.
double process_cpu_s();

// One scenario. SystemC elaborates a design once per process: call run() at
// most once in a process, or use run_isolated().
RunResult run(const RunSpec& spec);
// run() in a forked child process; progress is relayed; an error in the
// child comes back as std::runtime_error with its message.
RunResult run_isolated(const RunSpec& spec);

// One run in a forked child, for callers that run several at once: pump()
// reads what the child sent (blocking once; false at the end), fd() is for
// poll(), result() waits for the child and returns or throws.
class Child {
 public:
  explicit Child(const RunSpec& spec);
  ~Child();
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  int fd() const { return fd_; }
  bool pump();
  double progress() const { return progress_; }
  RunResult result();

 private:
  std::string name_;
  int pid_ = -1, fd_ = -1;
  std::string buf_;
  double progress_ = 0;
};

std::string serialize(const RunResult& r);
RunResult deserialize(const std::string& bytes);

}  // namespace mc::sim
