#include "sim/cosim/cosim.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <systemc>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

#include "hls/interp_core.hpp"
#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/motion/interp_plan.hpp"
#include "sim/cosim/core_model.hpp"
#include "sim/cosim/rtl_core.hpp"
#include "sim/plant/dc_motor.hpp"
#include "sim/plant/host_loop.hpp"

namespace mc::sim {

using mc::host::InputError;

const char* engine_name(Engine e) {
  return e == Engine::Rtl ? "rtl" : "twin";
}
const char* policy_name(GainPolicy p) {
  return p == GainPolicy::Same ? "same" : "tuned";
}

namespace {

constexpr int kLatency = mc::pid_latency(kCoreAxes);

// Clocks per plant step: the plant step must be a whole number of clocks,
// so that pins and drive change on clock edges.
uint32_t clocks_per_step(const MachineConfig& m) {
  const double k = m.clock_hz * m.plant_dt_s;
  if (!(k >= 1) || std::fabs(k - std::round(k)) > 1e-6)
    throw InputError("plant_dt_s * clock_hz (" + m.source + ")", std::to_string(k),
                     "a whole number of core clocks per plant step");
  return uint32_t(std::llround(k));
}

uint32_t ts_cycles(const MachineConfig& m, double ts) {
  const double c = std::round(ts * m.clock_hz);
  return uint32_t(std::max<double>(kLatency, c));
}

}  // namespace

double fpga_min_ts(const MachineConfig& m) {
  return kLatency / m.clock_hz;
}

std::vector<Platform> bench_platforms(const MachineConfig& m) {
  return {
      {"host-10ms", true, m.host_period_s}, {"fpga-10ms", false, 10e-3}, {"fpga-1ms", false, 1e-3},
      {"fpga-100us", false, 100e-6},        {"fpga-10us", false, 10e-6}, {"fpga-min", false, fpga_min_ts(m)}};
}

Platform find_platform(const MachineConfig& m, const std::string& name) {
  std::string names;
  for (const Platform& p : bench_platforms(m)) {
    if (p.name == name) return p;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  throw InputError("platform", "'" + name + "'", "one of " + names);
}

std::string Scenario::describe() const {
  std::ostringstream s;
  switch (kind) {
    case ScenarioKind::Step:
      s << "x position step of " << size_m * 1e3 << " mm";
      break;
    case ScenarioKind::Line:
      s << "XY line of " << size_m * 1e3 << " mm at " << angle_deg << " deg, " << feed_m_s * 1e3 << " mm/s";
      break;
    case ScenarioKind::Circle:
      s << "XY circle of radius " << size_m * 1e3 << " mm (stairs interpolator), " << feed_m_s * 1e3
        << " mm/s";
      break;
    case ScenarioKind::Job:
      s.precision(4);
      s << "G-code job " << job->file << ": " << job->summary.moves << " moves (" << job->summary.arcs
        << " arcs), " << job->summary.length_mm << " mm cutting, " << job->pieces.size()
        << " segments streamed by the queue's level, " << job->summary.time_s << " s planned, " << duration_s
        << " s simulated";
      return s.str();
  }
  s << ", " << duration_s << " s";
  return s.str();
}

std::vector<Scenario> bench_scenarios(bool quick) {
  const double settle = quick ? 0.05 : 0.2;
  const double feed = 0.025;  // 1500 mm/min: a small router's cutting feed
  const double line = quick ? 0.002 : 0.02, radius = quick ? 0.0005 : 0.005;
  return {{"step", ScenarioKind::Step, 0.001, 0, 0, quick ? 0.05 : 0.3, nullptr},
          {"line-45", ScenarioKind::Line, line, 45, feed, line / feed + settle, nullptr},
          {"line-30", ScenarioKind::Line, line, 30, feed, line / feed + settle, nullptr},
          {"circle", ScenarioKind::Circle, radius, 0, feed, 2 * M_PI * radius / feed + settle, nullptr}};
}

std::string_view quick_job_program() {
  // A line, a quarter circle and a line at a cutting feed: ramps, a corner
  // and an arc in a quarter of a second.
  return "G21 G90 G17 G94\nG1 X2 F1200\nG3 X3 Y1 I0 J1\nG1 Y2\nM2\n";
}

Scenario job_scenario(const MachineConfig& m, std::string_view program, const std::string& source,
                      double settle_s) {
  auto job = std::make_shared<mc::machine::Job>(mc::machine::plan_program(program, source, m, {0, 0, 0}));
  double lo[2] = {0, 0}, hi[2] = {0, 0};
  for (const mc::host::Move& mv : job->moves) {
    if (mv.kind == mc::host::Move::Kind::arc && mv.plane != mc::gcode::Plane::xy)
      throw InputError(source + ":" + std::to_string(mv.line) + ": arc", "outside the XY plane",
                       "arcs in the XY plane (G17)", "the co-simulation's table has X and Y only");
    if (!mv.is_motion()) continue;
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::min({lo[a], mv.start[size_t(a)], mv.end[size_t(a)]});
      hi[a] = std::max({hi[a], mv.start[size_t(a)], mv.end[size_t(a)]});
    }
  }
  Scenario s;
  s.name = "job";
  s.kind = ScenarioKind::Job;
  s.size_m = std::max(1e-3, std::hypot(hi[0] - lo[0], hi[1] - lo[1]) * 1e-3);
  s.duration_s = job->summary.time_s + settle_s;
  s.job = std::move(job);
  return s;
}

Scenario bench_job(const MachineConfig& m, const std::string& path, bool quick) {
  if (path.empty())
    return quick ? job_scenario(m, quick_job_program(), "quick job", 0.05)
                 : job_scenario(m, profile_program(), "examples/profile.nc");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("--job", "'" + path + "'", "a readable G-code file");
  std::ostringstream text;
  text << in.rdbuf();
  return job_scenario(m, text.str(), path, quick ? 0.05 : 0.1);
}

Scenario find_scenario(const std::string& name, bool quick) {
  std::string names;
  for (const Scenario& s : bench_scenarios(quick)) {
    if (s.name == name) return s;
    names += (names.empty() ? "" : ", ") + s.name;
  }
  throw InputError("scenario", "'" + name + "'", "one of " + names);
}

double loop_delay_s(const MachineConfig& m, const Platform& p, const JitterHistogram& jitter) {
  // The board: half a period of hold, and the sweep's latency plus the drive
  // register and the PWM: a bound, as each axis's drive takes its output
  // before the sweep ends (MotionCore::drv_clock), the last one
  // 5 clocks earlier (LATENCY - drv_clock(NAXES - 1) for every NAXES).
  if (!p.host) return 0.5 * ts_cycles(m, p.ts_s) / m.clock_hz + (kLatency + 2) / m.clock_hz;
  double mean = 0, n = 0;
  for (size_t i = 0; i < jitter.count.size(); ++i) {
    mean += 0.5 * (jitter.lo_s[i] + jitter.hi_s[i]) * double(jitter.count[i]);
    n += double(jitter.count[i]);
  }
  return 0.5 * p.ts_s + m.host_io_latency_s + (n > 0 ? mean / n : 0);
}

const char* feedforward_name(FeedForward f) {
  switch (f) {
    case FeedForward::None:
      return "none";
    case FeedForward::Velocity:
      return "vel";
    case FeedForward::Full:
      return "vel+acc";
    case FeedForward::Fitted:
      break;
  }
  return "fitted";
}

FeedForward parse_feedforward(const std::string& name) {
  for (FeedForward f : {FeedForward::None, FeedForward::Velocity, FeedForward::Full, FeedForward::Fitted})
    if (name == feedforward_name(f)) return f;
  throw InputError("--feedforward", "'" + name + "'", "none, vel, vel+acc or fitted");
}

void add_model_feedforward(mc::host::PidGains& g, const AxisConfig& a, FeedForward f) {
  if (f == FeedForward::None) return;
  const AxisModel model = axis_model(a);
  const double ff1 = 1 / model.kg, ff2 = model.tau / model.kg;
  const double full = a.pid.out_limit;
  if (f == FeedForward::Fitted) {
    // The core's terms act on the whole-count command: a step of one count
    // in a sample is FF1/Ts of drive for that sample, and its second
    // difference a doublet of FF2/Ts^2 each way. A term whose one-count
    // pulse saturates the output loses its mean (a doublet's useful part
    // is the small imbalance between its halves), so it is left out.
    g.ff1 = ff1 / g.ts <= full ? ff1 : 0;
    g.ff2 = ff2 / (g.ts * g.ts) <= full / 8 ? ff2 : 0;
    return;
  }
  g.ff1 = ff1;
  g.ff2 = f == FeedForward::Full ? ff2 : 0;
}

mc::host::PidGains gains_for(const MachineConfig& m, const AxisConfig& a, const Platform& p,
                             GainPolicy policy, const JitterHistogram& jitter, FeedForward feedforward) {
  const double ts = p.host ? p.ts_s : ts_cycles(m, p.ts_s) / m.clock_hz;
  if (policy == GainPolicy::Tuned) {
    mc::host::PidGains g = tuned_gains(a, ts, loop_delay_s(m, p, jitter));
    add_model_feedforward(g, a, feedforward);
    return g;
  }
  mc::host::PidGains g{};
  g.kp = a.pid.kp;
  g.ki = a.pid.ki;
  g.kd = a.pid.kd;
  g.tf = a.pid.tf_s;
  g.ts = ts;
  g.ff1 = a.pid.ff1;
  g.ff2 = a.pid.ff2;
  add_model_feedforward(g, a, feedforward);
  return g;
}

namespace {

// ---------------------------------------------------------------------------
// The command: what the interpolator is asked to do, and the ideal path.
struct Command {
  bool set = false;  // a step: load the position at the start
  int32_t set_pos[3] = {};
  std::vector<uint32_t> words;   // segments to stream from the start
  std::vector<PathPiece> ideal;  // metres, for the contour error
  // Job: the moves with Z dropped (the table is XY; Z's moves keep their
  // time in the words), for host/machine/job's contour error.
  std::vector<mc::host::Move> xy_moves;
};

Command make_command(const MachineConfig& m, const Scenario& s) {
  const AxisConfig &x = m.axes.at(0), &y = m.axes.at(1);
  const double cpm = counts_per_m(x);
  if (std::fabs(counts_per_m(y) - cpm) > 1e-9 * cpm)
    throw InputError("counts per metre of axis y (" + m.source + ")", std::to_string(counts_per_m(y)),
                     "the same as axis x's, " + std::to_string(cpm), "the XY scenarios need one scale");
  Command c;
  const mc::host::Vec3 origin{0, 0, 0};
  const double feed = s.feed_m_s * cpm;
  if (s.kind == ScenarioKind::Job) {
    for (const mc::host::Piece& p : s.job->pieces)
      if (!p.action)  // a stop: the planner already brought the machine to rest
        for (uint32_t w : seg::pack(p.seg.seg)) c.words.push_back(w);
    c.xy_moves = s.job->moves;
    for (mc::host::Move& mv : c.xy_moves) mv.start[2] = mv.end[2] = mv.centre[2] = 0;
    return c;
  }
  if (s.kind == ScenarioKind::Step) {
    c.set = true;
    c.set_pos[0] = int32_t(std::llround(s.size_m * cpm));
    return c;
  }
  mc::host::PlannedSegment p;
  if (s.kind == ScenarioKind::Line) {
    const double a = s.angle_deg * M_PI / 180;
    const mc::host::Vec3 to{std::llround(s.size_m * std::cos(a) * cpm),
                            std::llround(s.size_m * std::sin(a) * cpm), 0};
    p = mc::host::plan_line(origin, to, feed, m.clock_hz);
    c.ideal.push_back(Segment{{0, 0}, {double(to[0]) / cpm, double(to[1]) / cpm}});
  } else {
    const int64_t r = std::llround(s.size_m * cpm);
    p = mc::host::plan_arc(origin, origin, {-r, 0}, true, feed, seg::PLANE_XY, m.clock_hz);
    c.ideal.push_back(Arc{{-double(r) / cpm, 0}, double(r) / cpm, 0, 2 * M_PI});
  }
  for (uint32_t w : seg::pack(p.seg)) c.words.push_back(w);
  return c;
}

// The host's side of the core's segment queue, as over the link: whole
// segments, a word a clock, whenever the queue has room for one by the
// level the core showed, and never more than `window` words queued. The
// level a clock shows is the one before its edge (the word written in that
// clock is not in it yet, a word loaded at that edge still is), so the
// room is never overestimated and no segment is ever dropped. Every engine
// sees the same levels clock by clock (a skipped stretch changes no level),
// hence writes at the same clocks.
class SegmentFeed {
 public:
  SegmentFeed(const std::vector<uint32_t>& words, int window) : words_(words), window_(window) {
    if (window_ < seg::SEG_WORDS || words_.size() % seg::SEG_WORDS != 0)
      throw std::logic_error("segment feed: a window of at least one segment, whole segments");
  }
  // A word goes in this clock: the rest of a segment, or a new one with room.
  bool due() const {
    return at_ < words_.size() &&
           (at_ % seg::SEG_WORDS != 0 || level_ + int(wrote_) + seg::SEG_WORDS <= window_);
  }
  uint32_t word() const { return words_[at_]; }
  // After a clock (or a skipped stretch): the level it showed, and whether
  // a word went in.
  void clocked(int level, bool wrote) {
    level_ = level;
    wrote_ = wrote;
    at_ += wrote ? 1 : 0;
  }

 private:
  const std::vector<uint32_t>& words_;
  int window_;
  size_t at_ = 0;
  int level_ = 0;
  bool wrote_ = false;
};

// The drive is the PWM pin itself rather than its average.
bool switching(const DriveConfig& d) {
  return d.kind == DriveConfig::Kind::Pwm && d.pwm_switching;
}

// ---------------------------------------------------------------------------
// The machine: plants, the controller, the recorder. Advances in plant steps;
// the SystemC processes decide when to stop and let the others in.
class Machine {
 public:
  explicit Machine(const RunSpec& spec)
      : s_(spec),
        k_(clocks_per_step(spec.machine)),
        cmd_(make_command(spec.machine, spec.scenario)),
        // Whole segments: a window of the FIFO's depth holds 51 of 10 words.
        feed_(cmd_.words, spec.queue_words > 0 ? spec.queue_words
                                               : mc::InterpCore<>::DEPTH / seg::SEG_WORDS * seg::SEG_WORDS) {
    const MachineConfig& m = s_.machine;
    if (m.axes.size() < 2)
      throw InputError("axes (" + m.source + ")", std::to_string(m.axes.size()), "at least x and y");
    for (int a = 0; a < kCoreAxes; ++a) {
      plant_.emplace_back(m.axes[size_t(a)], m.plant_dt_s);
      ahead_.push_back(plant_.back());
      gains_[a] = gains_for(m, m.axes[size_t(a)], s_.platform, s_.policy, s_.jitter, s_.feedforward);
    }
    start_step_ = uint64_t(std::llround(1e-3 / m.plant_dt_s));  // the command starts at 1 ms
    end_step_ = start_step_ + uint64_t(std::llround(s_.scenario.duration_s / m.plant_dt_s));
    record_every_ = std::max<uint64_t>(1, uint64_t(std::llround(s_.record_dt_s / m.plant_dt_s)));
    // The trace's length is known: the records are written in place
    // (record_values, and jump()'s holds the positions). Their times are
    // the record's index scaled, which nothing in the run reads: finish()
    // writes them with the metrics. The command is kept as the core's
    // counts, half the pages of metres, and scaled there too.
    records_ = size_t((end_step_ - start_step_) / record_every_);
    for (int a = 0; a < kCoreAxes; ++a) {
      cmd_counts_[size_t(a)].resize(records_);
      res_.pos_m[size_t(a)].resize(records_);
      if (job_) enc_[size_t(a)].resize(records_);
    }
    // One controller output a period, a few more for a PC's late wakes:
    // the outputs are not copied as they come.
    if (s_.platform.ts_s > 0) {
      const double period_s = std::max(s_.platform.ts_s, dt_);
      const size_t outputs = size_t(double(end_step_ - start_step_) * dt_ / period_s * 1.05) + 16;
      res_.sample_clock.reserve(outputs);
      for (auto& u : res_.sample_u) u.reserve(outputs);
    }
    if (s_.platform.host) {
      for (int a = 0; a < kCoreAxes; ++a) {
        HostLoopConfig hc;
        hc.gains = gains_[a];
        hc.period_s = s_.platform.ts_s;
        hc.io_latency_s = m.host_io_latency_s;
        // One program serves both axes: both see the same wake-ups.
        host_.emplace_back(hc, JitterSampler(s_.jitter, s_.seed));
        DriveConfig d = m.axes[size_t(a)].drive;
        d.kind = DriveConfig::Kind::Dac;
        d.dac_bits = m.host_dac_bits;
        d.dac_range_v = m.host_dac_range_v;
        dac_[a] = d;
      }
    } else {
      // The averaged drive is integrated over skips that go through the
      // sweep's updates (add_skip_volts); switching pins are not.
      bool averaged = true;
      for (int a = 0; a < kCoreAxes; ++a) averaged = averaged && !switching(m.axes[size_t(a)].drive);
      core_ = s_.engine == Engine::Rtl ? make_rtl_core(s_.fst_path) : std::make_unique<TwinCore>(averaged);
      configure_core();
    }
    res_.platform = s_.platform.name;
    res_.scenario = s_.scenario.name;
    res_.policy = policy_name(s_.policy);
    res_.feedforward = feedforward_name(s_.feedforward);
    res_.engine = s_.platform.host ? "host" : engine_name(s_.engine);
    res_.gains = gains_[0];
  }

  uint64_t step_index() const { return step_; }
  uint64_t end_step() const { return end_step_; }
  double dt() const { return dt_; }
  bool host() const { return s_.platform.host; }
  // The plant step at or after which the PC next wakes.
  uint64_t next_wake_step() const { return uint64_t(std::ceil(host_[0].next_wake_s() / dt() - 1e-9)); }
  // The PC wakes: it reads the command and the encoders as they are now.
  void host_wake() {
    generator_to(step_ * k_);
    for (int a = 0; a < kCoreAxes; ++a) {
      host_[size_t(a)].wake(double(cmd_now_[a]), double(plant_[size_t(a)].encoder_count()));
      if (step_ >= start_step_) {
        res_.sample_u[size_t(a)].push_back(int32_t(std::lround(host_[size_t(a)].last_output())));
        if (a == 0) res_.sample_clock.push_back(step_ * k_);
      }
    }
  }

  // To step `target` at least; a jump under way may go on to its own end
  // (where the drive next changes), up to `limit`.
  void advance_to(uint64_t target, uint64_t limit) {
    while (step_ < target) {
      if (host())
        host_step();
      else if (!jump(limit))
        fpga_step();
    }
  }

  RunResult finish(double wall_s) {
    check_records(end_step_, 0);
    res_.t.resize(records_);
    for (size_t i = 0; i < records_; ++i) res_.t[i] = double(uint64_t(i + 1) * record_every_) * dt_;
    for (int a = 0; a < kCoreAxes; ++a) {
      res_.cmd_m[size_t(a)].resize(records_);
      for (size_t i = 0; i < records_; ++i)
        res_.cmd_m[size_t(a)][i] = double(cmd_counts_[size_t(a)][i]) / cpm_;
    }
    res_.sim_s = double(end_step_ - start_step_) * dt();
    res_.wall_s = wall_s;
    for (int a = 0; a < kCoreAxes; ++a)
      res_.follow[size_t(a)] = following_error(res_.t, res_.cmd_m[size_t(a)], res_.pos_m[size_t(a)]);
    const Scenario& sc = s_.scenario;
    if (sc.kind == ScenarioKind::Step) {
      res_.step = mc::host::step_metrics(res_.t, res_.pos_m[0], 0, sc.size_m, res_.t.front());
    } else if (sc.kind == ScenarioKind::Job) {
      job_contour();
    } else {
      std::vector<Point2> pts(res_.t.size());
      for (size_t i = 0; i < pts.size(); ++i) pts[i] = {res_.pos_m[0][i], res_.pos_m[1][i]};
      res_.contour = contour_error(pts, cmd_.ideal);
    }
    // Still far off the command at the end: oscillating, diverged, or slow.
    const size_t n = res_.t.size(), from = n - std::max<size_t>(1, n / 10);
    double worst = 0;
    for (size_t i = from; i < n; ++i)
      for (int a = 0; a < kCoreAxes; ++a)
        worst = std::max(worst, std::fabs(res_.cmd_m[size_t(a)][i] - res_.pos_m[size_t(a)][i]));
    res_.tracking = worst < 0.25 * sc.size_m;
    if (host()) res_.underrun = gen_.underrun();
    return std::move(res_);
  }

 private:
  // The job's contour error by host/machine/job's measure, in metres: of the
  // true table position, and of the encoder counts the board would report.
  void job_contour() {
    const mc::machine::Job& j = *s_.scenario.job;
    const size_t n = res_.t.size();
    std::vector<std::array<int32_t, 3>> cmd(n);
    std::vector<mc::host::Vec3d> pos(n), enc(n);
    for (size_t i = 0; i < n; ++i) {
      for (size_t a = 0; a < size_t(kCoreAxes); ++a) {
        cmd[i][a] = cmd_counts_[a][i];
        pos[i][a] = res_.pos_m[a][i] * 1e3;
        enc[i][a] = double(enc_[a][i]) / cpm_ * 1e3;
      }
      cmd[i][2] = 0;
      pos[i][2] = enc[i][2] = 0;
    }
    const auto metres = [](ErrorStats e) {
      e.rms *= 1e-3;
      e.max *= 1e-3;
      return e;
    };
    res_.contour = metres(mc::machine::contour_error(cmd, pos, cmd_.xy_moves, j.cfg, &res_.contour_each));
    for (double& d : res_.contour_each) d *= 1e-3;
    res_.measured_contour = metres(mc::machine::contour_error(cmd, enc, cmd_.xy_moves, j.cfg));
  }

  // Reset, gains, Ts, enables: through the core's own ports, clock by clock.
  void configure_core() {
    CoreIn in;
    in.rst = true;
    for (int i = 0; i < 4; ++i) core_->cycle(in);
    in.rst = false;
    std::vector<std::pair<uint8_t, uint32_t>> w;
    for (int a = 0; a < kCoreAxes; ++a) {
      const mc::host::PidDesign d = mc::host::design(gains_[a]);
      mc::host::CoreLimits lim;
      lim.out_limit = uint32_t(std::lround(s_.machine.axes[size_t(a)].pid.out_limit));
      const mc::PidParams p = mc::host::core_params(d, lim);
      for (int r = 0; r < mc::pid_reg::NREGS_RAM; ++r) w.push_back({uint8_t(a << 4 | r), p.word[r]});
      w.push_back({uint8_t(a << 4 | mc::pid_reg::CTRL), 1});
    }
    w.push_back({uint8_t(mc::pid_reg::GLOBAL_AXIS << 4 | mc::pid_reg::G_TS),
                 ts_cycles(s_.machine, s_.platform.ts_s)});
    for (const auto& [addr, data] : w) {
      in.pid_we = true;
      in.pid_waddr = addr;
      in.pid_wdata = data;
      // Taken in the clock whose outputs say the port is ready.
      while (!core_->cycle(in).pid_wready) {
      }
    }
    in.pid_we = false;
    for (int a = 0; a < kCoreAxes; ++a) {
      in.drv_allow[a] = true;
      in.enc_filt[a] = 1;
    }
    in_ = in;
  }

  // The twin engine's event loop: from a step boundary, the whole plant
  // steps in which the core changes nothing the plant sees (no PID tick,
  // drive update or done, no segment loaded or ended; a running segment's
  // position may move) go by at once: the core skipped over them, each
  // plant held on its drive's volts (AxisPlant::hold). The plants take the
  // steps the clock path takes, with the same volts, so positions and
  // samples are the clock path's (Cosim.TwinAndRtlGiveIdenticalOutputs).
  // A step that starts with one new count an axis shows it as fpga_step
  // does, an edge at its clock 0, and the jump goes on: the plants are held
  // through the window first (their drive is known over it), each count
  // they reach noted with its step, and the core is shown each as an edge
  // at that step's clock 0, inside a skip where the decoder takes it
  // cleanly (advance_core). The records inside take the plants'
  // positions sampled along the holds and the command as the core's moves
  // left it at each. A jump ends after a step that brings more than one
  // new count (fpga_step shows those), inside a step where the core stops
  // before an event, or at a segment's end.
  bool jump(uint64_t limit) {
    if (s_.engine != Engine::Twin || step_ == start_step_ || pending_ || feeding()) return false;
    bool edge = false;
    for (int a = 0; a < kCoreAxes; ++a) {
      const int64_t d = plant_[size_t(a)].encoder_count() - shown_[a];
      if (switching(s_.machine.axes[size_t(a)].drive) || d < -1 || d > 1) return false;
      edge = edge || d != 0;
    }
    if (edge) {
      emit_plan();
      set_encoder_pins(0);
    }
    uint64_t steps = limit - step_;
    if (step_ < start_step_) steps = std::min(steps, start_step_ - step_);
    // Whole steps, up to where the next sample's sweep changes the drive.
    uint64_t most = std::min<uint64_t>(steps * k_, core_->known_drive_clocks()) / k_;
    if (most == 0) return false;
    Skipped sk;
    for (int a = 0; a < kCoreAxes; ++a) sk.drive[a] = core_->drive_steps(in_, a);
    const int level = core_->seg_count();
    // The first record in the stretch, counted in steps from here (none
    // before the command starts).
    const uint64_t first =
        step_ < start_step_ ? most + 1 : record_every_ - (step_ - start_step_) % record_every_;
    // The plants through the window, sampled at the records, their counts
    // noted.
    int64_t count0[kCoreAxes];
    for (int a = 0; a < kCoreAxes; ++a) {
      count0[a] = plant_[size_t(a)].encoder_count();
      ahead_[size_t(a)].take_motion(plant_[size_t(a)]);
      AxisPlant::Samples at{first, record_every_, res_.pos_m[size_t(a)].data() + rec_, records_ - rec_};
      ahead_steps_[a] = hold_counting(ahead_[size_t(a)], a, sk, most, at, counts_[a]);
      most = std::min(most, ahead_steps_[a]);
    }
    // The edges: a count reached at the end of step s shows from clock
    // s k_ on.
    edges_.clear();
    for (int a = 0; a < kCoreAxes; ++a)
      for (const StepCount& c : counts_[a])
        if (c.step < most) edges_.push_back(Edge{c.step * k_, a, c.count});
    std::sort(edges_.begin(), edges_.end(), [](const Edge& x, const Edge& y) { return x.clock < y.clock; });
    int32_t cmd[kCoreAxes];
    for (int a = 0; a < kCoreAxes; ++a) cmd[a] = core_->cmd(a);
    const uint64_t m = advance_core(most * k_);
    if (m == 0) return false;
    const uint64_t whole = m / k_;
    for (int a = 0; a < kCoreAxes && whole > 0; ++a) {
      if (ahead_steps_[a] == whole)
        plant_[size_t(a)].take_motion(ahead_[size_t(a)]);
      else if (AxisPlant::Samples none;
               hold_counting(plant_[size_t(a)], a, sk, whole, none, recount_) != whole)
        throw std::logic_error("co-simulation: a plant held again took other steps");
    }
    // The records (their positions the holds wrote): a step's command is
    // the one its last clock showed, after all its edges but the last; its
    // count, the last the axis reached.
    size_t mv = 0, cn[kCoreAxes] = {};
    const CmdChange* const moves = moves_.data();
    const size_t n_moves = moves_.size();
    for (uint64_t j = first, last = j * k_ - 1; j <= whole; j += record_every_, last += record_every_ * k_) {
      for (; mv < n_moves && moves[mv].clock <= last; ++mv)
        for (int a = 0; a < kCoreAxes; ++a) cmd[a] = moves[mv].cmd[a];
      int64_t count[kCoreAxes] = {};
      if (job_)
        for (int a = 0; a < kCoreAxes; ++a) {
          const std::vector<StepCount>& c = counts_[size_t(a)];
          while (cn[a] < c.size() && c[cn[a]].step <= j) ++cn[a];
          count[a] = cn[a] == 0 ? count0[a] : c[cn[a] - 1].count;
        }
      record_command(cmd, count);
    }
    check_records(step_ + whole, 0);
    step_ += whole;
    for (int a = 0; a < kCoreAxes; ++a) cmd_now_[a] = core_->cmd(a);
    if (step_ >= start_step_) feed_.clocked(level, false);
    if (const uint32_t rem = uint32_t(m % k_); rem > 0) {
      StepVolts before[kCoreAxes];
      for (int a = 0; a < kCoreAxes; ++a) add_skip_volts(before[a], a, sk, whole * k_, rem);
      fpga_step(rem, before);
    }
    return true;
  }

  // Up to n clocks of the core from the start of this step, the pins held
  // but at edges_ (each shown at its clock, as emit_plan() shows it): the
  // quiet stretches skipped, taking the edges inside them that the
  // decoders settle cleanly (CoreModel::foldable), the clocks of a PID
  // sample cycled (the sample's output recorded at done, as fpga_step does
  // a clock later). Ends early before anything else (a segment's end).
  // moves_ gets the command's changes, counted in clocks from here.
  // Returns the clocks done.
  uint64_t advance_core(uint64_t n) {
    moves_.clear();
    const uint64_t at = step_ * k_;
    uint64_t done = 0;
    size_t e = 0;
    bool again = false;  // the pins as the last look saw them, or moved by edges it allowed
    while (done < n) {
      if (e < edges_.size() && edges_[e].clock == done) {
        again = false;
        show_edges(e);
      }
      bool sample = false;
      const uint32_t q =
          core_->quiet_clocks(in_, uint32_t(std::min<uint64_t>(n - done, 1u << 30)), sample, again);
      again = true;
      if (q > 0) {
        // The edges inside the stretch, each one count on (show() would
        // spread more): the stretch ends at the first the core cannot take.
        pins_.clear();
        int64_t last[kCoreAxes];
        for (int a = 0; a < kCoreAxes; ++a) last[a] = shown_[a];
        for (size_t i = e; i < edges_.size() && edges_[i].clock < done + q; ++i) {
          const Edge& g = edges_[i];
          const int64_t d = g.count - last[g.axis];
          if (d != 1 && d != -1) break;
          last[g.axis] = g.count;
          const QuadPins p = quadrature_pins(g.count, s_.machine.axes[size_t(g.axis)].encoder_cpr);
          pins_.push_back(PinChange{uint32_t(g.clock - done), g.axis, p.a, p.b, p.z});
        }
        const size_t fold = pins_.empty() ? 0 : core_->foldable(in_, pins_.data(), pins_.size());
        uint32_t len = q;
        if (e + fold < edges_.size() && edges_[e + fold].clock < done + q)
          len = uint32_t(edges_[e + fold].clock - done);
        const size_t from = moves_.size();
        const uint32_t to_done = core_->done_in();
        const uint32_t m = core_->skip_edges(in_, len, moves_, pins_.data(), fold);
        for (size_t i = from; i < moves_.size(); ++i) moves_[i].clock += uint32_t(done);
        // A sample's done inside the stretch: recorded as after a cycled one
        // (the drive commands hold to the next sweep).
        if (to_done < m && (at + done + to_done + 1) / k_ >= start_step_) record_sample(at + done + to_done);
        done += m;
        res_.clocks_skipped += m;
        // The pins as the skip left them.
        while (e < edges_.size() && edges_[e].clock < done) show_edges(e);
        if (m > 0) continue;
      }
      // A quiet clock the skip stopped before moves the command last, or
      // ends the segment: the first is cycled here, the second not; so is a
      // sample's clock. (What is not quiet for q clocks is not for one:
      // quiet_clocks bounds q to what the timers allow.)
      if (core_->segment_ends() || (q == 0 && !sample)) break;
      const CoreOut o = core_->cycle(in_);
      ++res_.clocks_cycled;
      ++done;
      res_.underrun = res_.underrun || o.ip_underrun;
      bool moved = false;
      CmdChange c;
      c.clock = uint32_t(done);
      for (int a = 0; a < kCoreAxes; ++a) {
        c.cmd[a] = core_->cmd(a);
        moved = moved || c.cmd[a] != o.cmd[a];
      }
      if (moved) moves_.push_back(c);
      if (o.done && (at + done) / k_ >= start_step_) record_sample(at + done - 1);
    }
    return done;
  }

  // Shows the core the counts of edges_[e] and of the others at its clock,
  // as emit_plan() shows a step's; e moves past them.
  void show_edges(size_t& e) {
    int64_t to[kCoreAxes];
    for (int a = 0; a < kCoreAxes; ++a) to[a] = shown_[a];
    const uint64_t clock = edges_[e].clock;
    for (; e < edges_.size() && edges_[e].clock == clock; ++e) to[edges_[e].axis] = edges_[e].count;
    show(to);
    set_encoder_pins(0);
  }

  // A count an axis reached at the end of a step of a jump (from 1).
  using StepCount = AxisPlant::CountChange;
  // Up to n steps of a skip that sk.drive describes, as the clock path
  // takes them (each step on the mean of its clocks' volts, StepVolts),
  // through the count changes: each count reached goes in counts with its
  // step. Ends at n or after a step that brings more than one new count.
  // Positions sampled along the way are written through out
  // (AxisPlant::Samples). Returns the last step taken.
  uint64_t hold_counting(AxisPlant& p, int a, const Skipped& sk, uint64_t n, AxisPlant::Samples out,
                         std::vector<StepCount>& counts) {
    counts.clear();
    const DriveSteps& ds = sk.drive[a];
    uint64_t s = 0;
    while (s < n) {
      const uint64_t c0 = s * k_;
      // The next clock with another drive value.
      uint64_t next = ds.next_change(c0);
      while (next != DriveSteps::kNever && ds.at(next) == ds.at(c0)) next = ds.next_change(next);
      uint64_t len;
      double v;
      if (next < c0 + k_) {
        // A change inside this step: the mean of its pieces.
        StepVolts sv;
        add_skip_volts(sv, a, sk, c0, k_);
        v = sv.mean(k_);
        len = 1;
      } else {
        v = averaged_volts(a, ds.at(c0));
        len = std::min(n, next / k_) - s;
      }
      const AxisPlant::Held h = p.hold_counting(v, len, out, counts, s);
      s += h.steps;
      if (h.big) break;
    }
    return s;
  }

  // Encoder pins: the counts the plant reached at the start of the step are
  // shown one edge every other clock (the decoder's limit is about one per
  // clock), more than half a step's worth carried to the next step.
  void emit_plan() {
    int64_t to[kCoreAxes];
    for (int a = 0; a < kCoreAxes; ++a) to[a] = plant_[size_t(a)].encoder_count();
    show(to);
  }
  void show(const int64_t* target) {
    for (int a = 0; a < kCoreAxes; ++a) {
      const int64_t d = std::clamp<int64_t>(target[a] - shown_[a], -int64_t(k_ / 2), int64_t(k_ / 2));
      emit_from_[a] = shown_[a];
      emit_n_[a] = d;
      shown_[a] += d;
    }
  }
  int64_t emitted(int a, uint32_t c) const {
    const int64_t n = std::min<int64_t>(std::llabs(emit_n_[a]), int64_t(c / 2 + 1));
    return emit_from_[a] + (emit_n_[a] < 0 ? -n : (emit_n_[a] > 0 ? n : 0));
  }
  // The clock of the step's last pin change (edges at clocks 0, 2, ...):
  // from it on the pins hold.
  uint32_t emit_settled_at() const {
    uint32_t c = 0;
    for (int a = 0; a < kCoreAxes; ++a)
      if (emit_n_[a] != 0) c = std::max<uint32_t>(c, uint32_t(2 * (std::llabs(emit_n_[a]) - 1)));
    return c;
  }

  // A controller sample: the clock of its done, and the output the drive
  // commands hold from the clock after (o: that clock's outputs).
  void record_sample(uint64_t done_clock, const CoreOut& o) {
    res_.sample_clock.push_back(done_clock);
    for (int a = 0; a < kCoreAxes; ++a) res_.sample_u[size_t(a)].push_back(o.drv_cmd[a]);
  }
  // The same from the core as it stands (after a skip through done).
  void record_sample(uint64_t done_clock) {
    res_.sample_clock.push_back(done_clock);
    for (int a = 0; a < kCoreAxes; ++a) res_.sample_u[size_t(a)].push_back(core_->drv_cmd(a));
  }

  // The pins of clock c of this step (emit_plan).
  void set_encoder_pins(uint32_t c) {
    for (int a = 0; a < kCoreAxes; ++a) {
      const QuadPins p = quadrature_pins(emitted(a, c), s_.machine.axes[size_t(a)].encoder_cpr);
      in_.enc_a[a] = p.a;
      in_.enc_b[a] = p.b;
      in_.enc_z[a] = p.z;
    }
  }

  void host_step() {
    const double t = double(step_) * dt();
    for (int a = 0; a < kCoreAxes; ++a)
      plant_[size_t(a)].step(drive_volts(dac_[a], int32_t(std::lround(host_[size_t(a)].output_at(t)))));
    stepped();
  }
  // After a plant step: the trace.
  void stepped() {
    ++step_;
    if (step_ > start_step_ && (step_ - start_step_) % record_every_ == 0) record();
  }

  // A word is due for the core's queue in this clock (from the start on).
  bool feeding() const { return step_ >= start_step_ && feed_.due(); }
  // The command's inputs for clock c of this step: a step's position at the
  // start, then the segment words as the queue takes them.
  void command_inputs(CoreIn& in, uint32_t c) const {
    in.ip_set = step_ == start_step_ && cmd_.set && c == 0 ? 7 : 0;
    for (int a = 0; a < 3; ++a) in.ip_set_pos[a] = cmd_.set_pos[a];
    in.seg_wr = feeding();
    in.seg_wdata = in.seg_wr ? feed_.word() : 0;
  }

  // The volts of one axis over the clocks of a plant step, as runs of
  // equal values: a drive that held the whole step gives exactly its value
  // (so that the plant's run goes on, sim/plant/dc_motor.hpp), and the
  // engines, which see the same values in different stretches, the same
  // sum.
  class StepVolts {
   public:
    void add(double v, uint32_t clocks) {
      if (clocks == 0) return;
      if (runs_ > 0 && v == v_) {
        n_ += clocks;
        return;
      }
      sum_ += v_ * double(n_);
      v_ = v;
      n_ = clocks;
      ++runs_;
    }
    double mean(uint32_t k) const { return runs_ == 1 ? v_ : (sum_ + v_ * double(n_)) / k; }

   private:
    double sum_ = 0, v_ = 0;
    uint64_t n_ = 0;
    int runs_ = 0;
  };

  // One plant step of the FPGA platform clock by clock, from clock c0 (a
  // jump that ended inside the step gives the volts of the clocks before),
  // skipping the quiet stretches of the twin.
  void fpga_step(uint32_t c0 = 0, const StepVolts* before = nullptr) {
    StepVolts volts[kCoreAxes];
    if (before)
      for (int a = 0; a < kCoreAxes; ++a) volts[a] = before[a];
    // A jump ends inside a step only where no count changed: no edges.
    if (c0 == 0) emit_plan();
    const uint32_t settle = c0 == 0 ? emit_settled_at() : 0;
    uint32_t c = c0;
    while (c < k_) {
      // The pins change only while edges are due (up to clock settle).
      if (c <= settle) set_encoder_pins(c);
      command_inputs(in_, c);
      // The step's position goes in clock 0 of the start; its first clock is
      // never skipped (the existing runs' schedule).
      const bool commanding = in_.ip_set != 0 || in_.seg_wr || (step_ == start_step_ && c == 0);
      if (c >= settle && !pending_ && !commanding) {
        if (const uint32_t n = core_->quiet_clocks(in_, k_ - c); n > 0) {
          Skipped sk;
          // The command at the step's end is what the skip's last clock
          // showed: its changes before do not matter here.
          moves_.clear();
          if (const uint32_t m = core_->skip(in_, n, &sk, moves_); m > 0) {
            for (int a = 0; a < kCoreAxes; ++a) {
              add_skip_volts(volts[a], a, sk, 0, m);
              cmd_now_[a] = core_->cmd(a);
            }
            res_.clocks_skipped += m;
            if (step_ >= start_step_) feed_.clocked(sk.first.seg_count, false);
            c += m;
            continue;
          }
        }
      }
      const CoreOut o = core_->cycle(in_);
      ++res_.clocks_cycled;
      if (step_ >= start_step_) feed_.clocked(o.seg_count, in_.seg_wr);
      res_.underrun = res_.underrun || o.ip_underrun;
      for (int a = 0; a < kCoreAxes; ++a) {
        volts[a].add(clock_volts(a, o), 1);
        cmd_now_[a] = o.cmd[a];
      }
      if (pending_) {
        pending_ = false;
        if (step_ >= start_step_) record_sample(done_clock_, o);
      }
      if (o.done) {
        pending_ = true;
        done_clock_ = step_ * k_ + c;
      }
      ++c;
    }
    in_.ip_set = 0;
    in_.seg_wr = false;
    for (int a = 0; a < kCoreAxes; ++a) plant_[size_t(a)].step(volts[a].mean(k_));
    stepped();
  }

  double clock_volts(int a, const CoreOut& o) {
    const DriveConfig& d = s_.machine.axes[size_t(a)].drive;
    if (!switching(d)) return averaged_volts(a, o.drv_u[a]);
    if (!o.drv_en[a] || !o.pwm[a]) return 0;
    return o.dir[a] ? -d.supply_v : d.supply_v;
  }
  // The averaged drive's volts for a drive value.
  double averaged_volts(int a, int16_t u) {
    // The drive value changes once a sample: convert it then.
    if (u != volts_u_[a] || !volts_set_[a]) {
      volts_u_[a] = u;
      volts_v_[a] = drive_volts(s_.machine.axes[size_t(a)].drive, u);
      volts_set_[a] = true;
    }
    return volts_v_[a];
  }
  // Clocks from .. from + n - 1 of a skip: the drive value as it steps
  // (DriveSteps), or the PWM pin following the counter.
  void add_skip_volts(StepVolts& volts, int a, const Skipped& sk, uint64_t from, uint64_t n) {
    const DriveConfig& d = s_.machine.axes[size_t(a)].drive;
    if (!switching(d)) {
      const DriveSteps& ds = sk.drive[a];
      for (uint64_t c = from, end = from + n; c < end;) {
        const uint64_t to = std::min(ds.next_change(c), end);
        volts.add(averaged_volts(a, ds.at(c)), uint32_t(to - c));
        c = to;
      }
      return;
    }
    add_skipped(volts, a, sk.first, sk.pwm0, uint32_t(n));
  }
  // n quiet clocks of a switching drive: the drive value holds (skips end
  // before the sweep's updates); the PWM pin follows the counter.
  void add_skipped(StepVolts& volts, int a, const CoreOut& o, uint32_t p0, uint32_t n) {
    const DriveConfig& d = s_.machine.axes[size_t(a)].drive;
    const double v = o.dir[a] ? -d.supply_v : d.supply_v;
    const uint32_t duty = CoreTwin::duty(o.drv_u[a]), mask = (1u << CoreTwin::pwm_bits) - 1;
    for (uint32_t k = 0; k < n; ++k) {
      const bool on = o.drv_en[a] && (k == 0 ? o.pwm[a] : duty > ((p0 + k - 1) & mask));
      volts.add(on ? v : 0.0, 1);
    }
  }

  // The PC's command: the same interpolator, run on its own, so both
  // platforms follow the very same position command, its segments streamed
  // into its queue as into the core's. It runs open loop, so it is brought
  // up to a clock only when the command is read (a wake, a record): the
  // stretches between its iterations then go by at once (run_quiet).
  void generator_to(uint64_t clock) {
    const uint64_t start = start_step_ * k_;
    while (gen_clock_ < clock) {
      const bool started = gen_clock_ >= start;
      mc::InterpIn in;
      in.set = gen_clock_ == start && cmd_.set ? 7 : 0;
      for (int a = 0; a < 3; ++a) in.set_pos[a] = cmd_.set_pos[a];
      in.wr = started && feed_.due();
      in.wdata = in.wr ? feed_.word() : 0;
      // Up to the start, the start, and then any clock count at once.
      const uint64_t until = gen_clock_ < start ? start : clock;
      if (gen_.quiet(in) && until > gen_clock_) {
        gen_.skip(uint32_t(std::min<uint64_t>(until - gen_clock_, 2)));
        gen_clock_ = until;
        if (started) feed_.clocked(gen_.count(), false);
        continue;
      }
      if (const uint64_t q = std::min<uint64_t>(gen_.run_quiet(in), until - gen_clock_); q > 0) {
        gen_.skip_run(uint32_t(q));
        gen_clock_ += q;
        if (started) feed_.clocked(gen_.count(), false);
        continue;
      }
      const int level = gen_.count();
      gen_.clock(in);
      ++gen_clock_;
      if (started) feed_.clocked(level, in.wr);
    }
    for (int a = 0; a < kCoreAxes; ++a) cmd_now_[a] = gen_.pos(a);
  }

  void record() {
    if (host()) generator_to(step_ * k_);
    double pos[kCoreAxes];
    int64_t count[kCoreAxes];
    for (int a = 0; a < kCoreAxes; ++a) {
      pos[a] = plant_[size_t(a)].position_m();
      count[a] = plant_[size_t(a)].encoder_count();
    }
    record_values(step_, cmd_now_, pos, count);
  }
  // The trace's sample at the end of plant step `step`.
  void record_values(uint64_t step, const int32_t* cmd, const double* pos_m, const int64_t* count) {
    check_records(step, 1);
    for (int a = 0; a < kCoreAxes; ++a) res_.pos_m[size_t(a)][rec_] = pos_m[a];
    record_command(cmd, count);
  }
  // The rest of the next record, its positions in place (a jump's holds
  // wrote them): the command, a job's counts.
  void record_command(const int32_t* cmd, const int64_t* count) {
    for (int a = 0; a < kCoreAxes; ++a) {
      cmd_counts_[size_t(a)][rec_] = cmd[a];
      if (job_) enc_[size_t(a)][rec_] = count[a];
    }
    ++rec_;
  }
  // By the end of plant step `step`, the records due are those written and
  // `coming` more, and the trace has room for them.
  void check_records(uint64_t step, size_t coming) const {
    const uint64_t due = step > start_step_ ? (step - start_step_) / record_every_ : 0;
    if (rec_ + coming != due || due > records_)
      throw std::logic_error("co-simulation: " + std::to_string(rec_ + coming) + " records by step " +
                             std::to_string(step) + ", " + std::to_string(due) + " due");
  }

  const RunSpec& s_;
  const uint32_t k_;
  const bool job_ = s_.scenario.kind == ScenarioKind::Job;  // the trace keeps the encoder counts
  const double cpm_ = counts_per_m(s_.machine.axes[0]);     // the command's counts per metre
  const double dt_ = s_.machine.plant_dt_s;
  Command cmd_;
  SegmentFeed feed_;
  std::array<TraceVector<int32_t>, kCoreAxes>
      cmd_counts_;                                   // the command per record, counts (finish(): metres)
  std::array<TraceVector<int64_t>, kCoreAxes> enc_;  // job: encoder counts per record
  std::vector<AxisPlant> plant_;
  std::vector<AxisPlant> ahead_;  // jump(): the plants held ahead
  uint64_t ahead_steps_[kCoreAxes] = {};
  std::vector<StepCount> counts_[kCoreAxes], recount_;  // jump(): the counts they reached
  // jump(): the edges to show the core, in clocks from the jump's start.
  struct Edge {
    uint64_t clock;
    int axis;
    int64_t count;
  };
  std::vector<Edge> edges_;
  std::vector<PinChange> pins_;   // advance_core(): the edges inside a stretch, as pins
  std::vector<CmdChange> moves_;  // jump(): the command's changes in the skip
  mc::host::PidGains gains_[kCoreAxes];
  std::vector<HostLoop> host_;
  DriveConfig dac_[kCoreAxes]{};
  std::unique_ptr<CoreModel> core_;
  mc::InterpCore<9> gen_;
  uint64_t gen_clock_ = 0;  // clocks gen_ has run
  CoreIn in_;
  uint64_t step_ = 0, start_step_ = 0, end_step_ = 0, record_every_ = 1;
  size_t records_ = 0, rec_ = 0;  // the trace's records, and the next to write
  int64_t shown_[kCoreAxes] = {}, emit_from_[kCoreAxes] = {}, emit_n_[kCoreAxes] = {};
  uint64_t done_clock_ = 0;
  double volts_v_[kCoreAxes] = {};  // averaged_volts(): the volts of volts_u_
  int32_t cmd_now_[kCoreAxes] = {};
  int16_t volts_u_[kCoreAxes] = {};  // averaged_volts(): the last drive value converted
  bool volts_set_[kCoreAxes] = {};
  bool pending_ = false;
  RunResult res_;
};

// ---------------------------------------------------------------------------
// The SystemC system model. The machine process owns the plant and the core
// and runs ahead of the kernel by at most a quantum (temporal decoupling),
// stopping exactly where another process needs the state: the PC's wake-ups.
// The PC process runs the host loop at its own jittered times; the monitor
// reports progress at its own rate.
SC_MODULE(SystemModel) {
  Machine& m;
  const RunSpec& spec;
  uint64_t quantum;
  sc_core::sc_event wake_ev, woke_ev;

  SC_HAS_PROCESS(SystemModel);
  // SystemC's module naming takes the name by value.
  SystemModel(sc_core::sc_module_name nm,  // NOLINT(performance-unnecessary-value-param)
              Machine & machine, const RunSpec& s)
      : sc_core::sc_module(nm), m(machine), spec(s) {
    // Without the PC loop only the monitor looks at the kernel's time: a
    // longer quantum, which the machine may overrun to the end of a jump
    // (a jump cut there would cost a second one: a tenth more jumps at
    // 100 us, the same figures).
    quantum = std::max<uint64_t>(1, uint64_t(std::llround((m.host() ? 100e-6 : 1e-3) / m.dt())));
    SC_THREAD(machine_proc);
    if (m.host()) SC_THREAD(host_proc);
    if (spec.progress) SC_THREAD(monitor_proc);
  }

  sc_core::sc_time at_step(uint64_t s) const {
    return sc_core::sc_time(double(s) * m.dt(), sc_core::SC_SEC);
  }

  void machine_proc() {
    while (m.step_index() < m.end_step()) {
      uint64_t target = std::min(m.step_index() + quantum, m.end_step());
      const bool wake = m.host() && m.next_wake_step() <= target;
      if (wake) target = m.next_wake_step();
      m.advance_to(target, m.host() ? target : m.end_step());
      wait(at_step(m.step_index()) - sc_core::sc_time_stamp());
      if (wake) {
        wake_ev.notify(sc_core::SC_ZERO_TIME);
        wait(woke_ev);
      }
    }
    sc_core::sc_stop();
  }

  void host_proc() {
    for (;;) {
      wait(wake_ev);
      m.host_wake();
      woke_ev.notify(sc_core::SC_ZERO_TIME);
    }
  }

  void monitor_proc() {
    const double total = double(m.end_step()) * m.dt();
    for (;;) {
      wait(sc_core::sc_time(total / 100, sc_core::SC_SEC));
      spec.progress(std::min(1.0, sc_core::sc_time_stamp().to_seconds() / total));
    }
  }
};

// --- Serialization: a flat little-endian record, same machine both ends. ---
struct Writer {
  std::string b;
  template <typename T>
  void pod(const T& v) {
    b.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    b += s;
  }
  template <typename T, typename A>
  void vec(const std::vector<T, A>& v) {
    pod(uint64_t(v.size()));
    if (!v.empty()) b.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
};
struct Reader {
  const std::string& b;
  size_t at = 0;
  void need(size_t n) {
    if (b.size() - at < n) throw std::runtime_error("co-simulation result truncated");
  }
  template <typename T>
  void pod(T& v) {
    need(sizeof v);
    std::memcpy(&v, b.data() + at, sizeof v);
    at += sizeof v;
  }
  void str(std::string& s) {
    uint64_t n = 0;
    pod(n);
    need(n);
    s.assign(b, at, n);
    at += n;
  }
  template <typename T, typename A>
  void vec(std::vector<T, A>& v) {
    uint64_t n = 0;
    pod(n);
    need(n * sizeof(T));
    v.resize(n);
    if (n == 0) return;  // an empty vector's data() may be null, which memcpy may not take
    std::memcpy(v.data(), b.data() + at, n * sizeof(T));
    at += n * sizeof(T);
  }
};

template <typename IO, typename R>
void fields(IO& io, R& r) {
  io.str(r.platform);
  io.str(r.scenario);
  io.str(r.policy);
  io.str(r.engine);
  io.str(r.feedforward);
  io.pod(r.gains);
  io.vec(r.t);
  for (int a = 0; a < 2; ++a) {
    io.vec(r.cmd_m[size_t(a)]);
    io.vec(r.pos_m[size_t(a)]);
    io.vec(r.sample_u[size_t(a)]);
    io.pod(r.follow[size_t(a)]);
  }
  io.vec(r.sample_clock);
  io.pod(r.contour);
  io.pod(r.measured_contour);
  io.vec(r.contour_each);
  io.pod(r.underrun);
  io.pod(r.step);
  io.pod(r.tracking);
  io.pod(r.sim_s);
  io.pod(r.wall_s);
  io.pod(r.setup_s);
  io.pod(r.cpu_s);
  io.pod(r.clocks_cycled);
  io.pod(r.clocks_skipped);
}

void write_all(int fd, const std::string& s) {
  size_t at = 0;
  while (at < s.size()) {
    const ssize_t n = ::write(fd, s.data() + at, s.size() - at);
    if (n <= 0) _exit(3);
    at += size_t(n);
  }
}

}  // namespace

std::string serialize(const RunResult& r) {
  Writer w;
  fields(w, r);
  return std::move(w.b);
}

RunResult deserialize(const std::string& bytes) {
  Reader rd{bytes};
  RunResult r;
  fields(rd, r);
  return r;
}

double process_cpu_s() {
  timespec ts{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

RunResult run(const RunSpec& spec) {
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = process_cpu_s();
  Machine machine(spec);
  SystemModel model("system", machine, spec);
  sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
  const auto t1 = std::chrono::steady_clock::now();
  sc_core::sc_start();
  // Both clocks stop here, before finish() computes the result's metrics.
  const auto t2 = std::chrono::steady_clock::now();
  const double cpu = process_cpu_s() - cpu0;
  RunResult r = machine.finish(std::chrono::duration<double>(t2 - t0).count());
  r.setup_s = std::chrono::duration<double>(t1 - t0).count();
  r.cpu_s = cpu;
  return r;
}

// The child writes 'P' + double for progress, then 'R' + size + result, or
// 'E' + size + message; the parent reads until the pipe closes.
Child::Child(const RunSpec& spec) : name_(spec.platform.name + "/" + spec.scenario.name) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed: " + std::string(std::strerror(errno)));
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error("fork failed: " + std::string(std::strerror(errno)));
  if (pid_ == 0) {
    ::close(fds[0]);
    RunSpec s = spec;
    s.progress = [fd = fds[1]](double f) {
      std::string m(1, 'P');
      m.append(reinterpret_cast<const char*>(&f), sizeof f);
      write_all(fd, m);
    };
    const auto message = [](char kind, const std::string& body) {
      std::string m(1, kind);
      const uint64_t n = body.size();
      m.append(reinterpret_cast<const char*>(&n), sizeof n);
      return m + body;
    };
    std::string out;
    try {
      out = message('R', serialize(run(s)));
    } catch (const std::exception& e) {
      out = message('E', e.what());
    }
    write_all(fds[1], out);
    ::close(fds[1]);
    _exit(0);
  }
  ::close(fds[1]);
  fd_ = fds[0];
}

Child::~Child() {
  if (fd_ >= 0) ::close(fd_);
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
}

bool Child::pump() {
  char chunk[65536];
  const ssize_t n = ::read(fd_, chunk, sizeof chunk);
  if (n < 0 && errno == EINTR) return true;
  if (n <= 0) return false;
  buf_.append(chunk, size_t(n));
  while (!buf_.empty() && buf_[0] == 'P' && buf_.size() >= 1 + sizeof(double)) {
    std::memcpy(&progress_, buf_.data() + 1, sizeof progress_);
    buf_.erase(0, 1 + sizeof progress_);
  }
  return true;
}

RunResult Child::result() {
  ::close(fd_);
  fd_ = -1;
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
  if (buf_.size() >= 1 + sizeof(uint64_t) && (buf_[0] == 'R' || buf_[0] == 'E')) {
    uint64_t n;
    std::memcpy(&n, buf_.data() + 1, sizeof n);
    const std::string body = buf_.substr(1 + sizeof n);
    if (body.size() == n) {
      if (buf_[0] == 'R') return deserialize(body);
      throw std::runtime_error(name_ + ": " + body);
    }
  }
  throw std::runtime_error("co-simulation of " + name_ + " ended without a result (status " +
                           std::to_string(status) + ")");
}

RunResult run_isolated(const RunSpec& spec) {
  Child c(spec);
  while (c.pump())
    if (spec.progress) spec.progress(c.progress());
  return c.result();
}

}  // namespace mc::sim
