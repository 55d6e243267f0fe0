#include "sim/cosim/bench.hpp"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <systemc>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <tuple>

#include "host/base/errors.hpp"
#include "sim/cosim/core_model.hpp"
#include "sim/cosim/rtl_core.hpp"

namespace mc::sim {

namespace fs = std::filesystem;

std::vector<std::array<std::string, 3>> rtl_check_runs() {
  // Short runs (the step) at two sample periods, and the circle at 1 ms:
  // about 15 s of RTL time on two cores.
  return {{"fpga-100us", "step", "same"}, {"fpga-min", "step", "tuned"}, {"fpga-1ms", "circle", "tuned"}};
}

namespace {

// Runs f in a child process and returns the double it computes.
template <typename F>
double in_child(F f) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    double v = f();
    if (::write(fds[1], &v, sizeof v) != sizeof v) _exit(1);
    _exit(0);
  }
  ::close(fds[1]);
  double v = 0;
  const bool ok = ::read(fds[0], &v, sizeof v) == sizeof v;
  ::close(fds[0]);
  ::waitpid(pid, nullptr, 0);
  if (!ok)
    throw std::runtime_error("a measurement in a child process failed (the bare loop or a kernel probe)");
  return v;
}

// The Verilated core alone in a bare C++ loop, its inputs held: simulated
// s per CPU s, in a child (a process runs one Verilated model of it).
double bare_speed(const MachineConfig& m, double sim_s) {
  return in_child(
      [&] { return bare_rtl_clocks_per_s(uint64_t(std::llround(sim_s * m.clock_hz))) / m.clock_hz; });
}

// Runs the specs in child processes, `jobs` at once, the costliest first.
std::vector<RunResult> run_pool(const std::vector<RunSpec>& specs, int jobs, const BenchStatus& status) {
  std::vector<size_t> order(specs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const auto cost = [](const RunSpec& s) {
      // The RTL runs about 200 times slower than the twin.
      return s.scenario.duration_s * (s.platform.host ? 0.1 : s.engine == Engine::Rtl ? 200.0 : 1.0);
    };
    return cost(specs[a]) > cost(specs[b]);
  });
  std::vector<RunResult> runs(specs.size());
  std::vector<std::pair<size_t, std::unique_ptr<Child>>> running;
  size_t next = 0;
  int done = 0;
  const int total = int(specs.size());
  std::string last;
  while (done < total) {
    while (next < order.size() && int(running.size()) < std::max(1, jobs)) {
      const size_t i = order[next++];
      running.emplace_back(i, std::make_unique<Child>(specs[i]));
    }
    std::vector<pollfd> fds;
    fds.reserve(running.size());
    for (auto& [i, c] : running) fds.push_back({c->fd(), POLLIN, 0});
    if (::poll(fds.data(), fds.size(), 500) < 0 && errno != EINTR)
      throw std::runtime_error(std::string("poll failed: ") + std::strerror(errno));
    for (size_t k = 0; k < running.size();) {
      auto& [i, c] = running[k];
      if (fds[k].revents && !c->pump()) {
        runs[i] = c->result();
        ++done;
        last = specs[i].platform.name + " " + specs[i].scenario.name + " " + policy_name(specs[i].policy) +
               " " + engine_name(specs[i].engine);
        running.erase(running.begin() + long(k));
        fds.erase(fds.begin() + long(k));
        continue;
      }
      ++k;
    }
    double frac = 0;
    for (auto& [i, c] : running) frac += c->progress();
    if (status) status(done, total, last, frac);
  }
  return runs;
}

// The speed goal's own case: the two-axis circle at 100 us on the twin.
bool is_goal_case(const RunSpec& s) {
  return s.engine == Engine::Twin && s.platform.name == "fpga-100us" && s.scenario.name == "circle" &&
         s.policy == GainPolicy::Same;
}

}  // namespace

BenchResult run_bench(const BenchOptions& o, const BenchStatus& status) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<RunSpec> specs;
  std::vector<Platform> platforms;
  for (const Platform& p : bench_platforms(o.machine))
    if (o.platforms.empty() || std::count(o.platforms.begin(), o.platforms.end(), p.name))
      platforms.push_back(p);
  for (const std::string& n : o.platforms) find_platform(o.machine, n);  // names checked
  std::vector<Scenario> scenarios;
  for (const Scenario& s : bench_scenarios(o.quick))
    if (o.scenarios.empty() || std::count(o.scenarios.begin(), o.scenarios.end(), s.name))
      scenarios.push_back(s);
  for (const std::string& n : o.scenarios)
    if (n != "job") find_scenario(n, o.quick);
  // One run of the bench: what every run shares, and what this one is.
  const auto spec = [&](const Platform& p, const Scenario& s, GainPolicy g, double record_dt_s) {
    RunSpec r;
    r.machine = o.machine;
    r.platform = p;
    r.scenario = s;
    r.policy = g;
    r.engine = o.engine;
    r.seed = o.seed;
    r.jitter = o.jitter;
    r.record_dt_s = record_dt_s;
    return r;
  };
  for (const Scenario& s : scenarios)
    for (GainPolicy g : o.policies)
      for (const Platform& p : platforms)
        // Every 10 us: fine enough for the contour error at the bench feeds
        // (0.25 um of travel), small enough files.
        specs.push_back(spec(p, s, g, 1e-5));
  // The job: tuned gains (each platform's own), without and with the
  // feed-forward, planned once.
  std::string job;
  if (o.scenarios.empty() || std::count(o.scenarios.begin(), o.scenarios.end(), "job")) {
    const Scenario js = bench_job(o.machine, o.job_file, o.quick);
    job = js.describe();
    const std::vector<std::string>& names = o.platforms.empty() ? o.job_platforms : o.platforms;
    for (const std::string& n : names) find_platform(o.machine, n);
    for (FeedForward f : o.job_feedforward)
      for (const Platform& p : bench_platforms(o.machine)) {
        if (!std::count(names.begin(), names.end(), p.name)) continue;
        // Every 100 us: 2 um of travel at the profile's 1200 mm/min.
        RunSpec r = spec(p, js, GainPolicy::Tuned, 1e-4);
        r.feedforward = f;
        specs.push_back(std::move(r));
      }
  }
  // The RTL check: the same specs on the Verilated core, one at a time
  // after the pool. Its speed is set against the bare Verilated loop, which
  // runs alone too: two runs at a time share the machine's two cores and
  // slow each other, by how much depending on the machine's load.
  std::vector<size_t> checked;
  if (o.rtl_check && o.engine == Engine::Twin)
    for (const auto& [p, sc, pol] : rtl_check_runs())
      for (size_t i = 0; i < specs.size(); ++i)
        if (specs[i].platform.name == p && specs[i].scenario.name == sc &&
            policy_name(specs[i].policy) == pol)
          checked.push_back(i);
  std::vector<RunSpec> rtl_specs;
  for (size_t i : checked) {
    rtl_specs.push_back(specs[i]);
    rtl_specs.back().engine = Engine::Rtl;
  }
  // One count of runs over both pools.
  const int n_all = int(specs.size() + rtl_specs.size());
  const auto counted = [&](int from) -> BenchStatus {
    if (!status) return {};
    return [&status, from, n_all](int done, int, const std::string& last, double frac) {
      status(from + done, n_all, last, frac);
    };
  };
  BenchResult res;
  res.job = job;
  res.runs = run_pool(specs, o.jobs, counted(0));
  // The bare loop's yardstick just before and after each RTL run: the
  // machine's speed drifts (a shared VM, by a factor of two within
  // minutes), so the two are measured together.
  const double bare_s = o.quick ? 2e-3 : 2e-2;
  double before = rtl_specs.empty() ? 0 : bare_speed(o.machine, bare_s);
  for (size_t k = 0; k < checked.size(); ++k) {
    RtlCheck c;
    c.run = checked[k];
    c.rtl = std::move(run_pool({rtl_specs[k]}, 1, counted(int(specs.size() + k))).front());
    const double after = bare_speed(o.machine, bare_s);
    c.bare_speed = (before + after) / 2;
    before = after;
    const RunResult& t = res.runs[c.run];
    c.same_outputs = t.sample_clock == c.rtl.sample_clock && t.sample_u == c.rtl.sample_u;
    res.rtl_checks.push_back(std::move(c));
  }
  if (o.probe_kernel && (o.engine == Engine::Rtl || !checked.empty()))
    res.probe = probe_kernel(o.machine, o.quick ? 2e-4 : 2e-3);
  for (size_t i = 0; i < specs.size(); ++i)
    if (is_goal_case(specs[i])) {
      for (int k = 0; k < BenchResult::kGoalAloneRuns; ++k) {
        const RunResult r = run_isolated(specs[i]);
        res.goal_alone_sim_s = r.sim_s;
        res.goal_alone_wall_s.push_back(r.wall_s);
        res.goal_alone_setup_s.push_back(r.setup_s);
      }
      break;
    }
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

// ---------------------------------------------------------------------------
// The kernel-choice probe.
namespace {

// The core as a clocked SystemC module: the Verilated model evaluated by an
// SC_METHOD on every rising edge of an sc_clock, as Verilator's --sc wrapper
// runs it.
SC_MODULE(ClockedCore) {
  sc_core::sc_in<bool> clk;
  std::unique_ptr<CoreModel> core = make_rtl_core();
  CoreIn in;
  uint64_t cycles = 0;
  SC_HAS_PROCESS(ClockedCore);
  // SystemC's module naming takes the name by value.
  explicit ClockedCore(sc_core::sc_module_name n)  // NOLINT(performance-unnecessary-value-param)
      : sc_core::sc_module(n) {
    SC_METHOD(edge);
    sensitive << clk.pos();
    dont_initialize();
  }
  void edge() {
    in.rst = cycles < 4;
    core->cycle(in);
    ++cycles;
  }
};

// The core stepped inside one process, synchronizing every 100 us.
SC_MODULE(DecoupledCore) {
  std::unique_ptr<CoreModel> core = make_rtl_core();
  CoreIn in;
  uint64_t cycles = 0, quantum = 1200;
  double clock_hz = 12e6;
  SC_HAS_PROCESS(DecoupledCore);
  // SystemC's module naming takes the name by value.
  explicit DecoupledCore(sc_core::sc_module_name n)  // NOLINT(performance-unnecessary-value-param)
      : sc_core::sc_module(n) {
    SC_THREAD(run);
  }
  void run() {
    const sc_core::sc_time q(double(quantum) / clock_hz, sc_core::SC_SEC);
    for (;;) {
      for (uint64_t i = 0; i < quantum; ++i) {
        in.rst = cycles < 4;
        core->cycle(in);
        ++cycles;
      }
      wait(q);
    }
  }
};

}  // namespace

KernelProbe probe_kernel(const MachineConfig& m, double sim_s) {
  KernelProbe p;
  p.probe_sim_s = sim_s;
  const double period = 1 / m.clock_hz;
  // The bare loop runs 10 times as long: it is the yardstick of the RTL
  // engine's speed.
  p.bare_speed = bare_speed(m, 10 * sim_s);
  p.clocked_speed = in_child([&] {
    sc_core::sc_clock clk("clk", sc_core::sc_time(period, sc_core::SC_SEC));
    ClockedCore c("core");
    c.clk(clk);
    const auto t0 = std::chrono::steady_clock::now();
    sc_core::sc_start(sc_core::sc_time(sim_s, sc_core::SC_SEC));
    return sim_s / std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  });
  p.decoupled_speed = in_child([&] {
    DecoupledCore c("core");
    c.quantum = uint64_t(std::llround(100e-6 * m.clock_hz));
    c.clock_hz = m.clock_hz;
    const auto t0 = std::chrono::steady_clock::now();
    sc_core::sc_start(sc_core::sc_time(sim_s, sc_core::SC_SEC));
    return sim_s / std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  });
  return p;
}

// ---------------------------------------------------------------------------
// Output files.
namespace {

std::string fmt(double v, int prec = 3) {
  if (std::isnan(v)) return "n/a";
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(prec);
  s << v;
  return s.str();
}
std::string um(double m) {
  return fmt(m * 1e6, m * 1e6 < 10 ? 3 : 1);
}
std::string ms(double s) {
  return std::isnan(s) ? "not settled" : fmt(s * 1e3, 2);
}
std::string tag(const RunResult& r) {
  return r.platform + "_" + r.scenario + "_" + r.policy + (r.scenario == "job" ? "_ff-" + r.feedforward : "");
}
// The feed-forward terms a run applied (the fitted policy drops those the
// core cannot apply at its Ts).
std::string ff_applied(const RunResult& r) {
  if (r.gains.ff1 != 0 && r.gains.ff2 != 0) return "vel+acc";
  if (r.gains.ff1 != 0) return "vel";
  return r.gains.ff2 != 0 ? "acc" : "none";
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream f(p);
  f << text;
  if (!f) throw mc::host::InputError("--out", "'" + p.string() + "'", "a writable directory");
}

void run_gnuplot(const fs::path& script) {
  const std::string cmd = "gnuplot '" + script.string() + "' 2>&1";
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) throw std::runtime_error("cannot run gnuplot");
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int rc = ::pclose(p);
  if (rc != 0) throw std::runtime_error("gnuplot failed on " + script.string() + ": " + out);
}

}  // namespace

std::vector<std::string> write_bench(const BenchOptions& o, const BenchResult& br) {
  const fs::path dir(o.out_dir);
  std::error_code ec;
  fs::create_directories(dir / "data", ec);
  fs::create_directories(dir / "plots", ec);
  if (ec) throw mc::host::InputError("--out", "'" + o.out_dir + "'", "a directory that can be created");
  std::vector<std::string> written;

  // results.csv
  std::ostringstream csv;
  csv << "platform,scenario,policy,engine,ts_s,kp_per_count,ki_per_count_s,kd_per_count_per_s,tf_s,"
         "follow_rms_x_um,follow_max_x_um,follow_rms_y_um,follow_max_y_um,contour_rms_um,contour_max_um,"
         "settling_time_s,overshoot_pct,rise_time_s,tracking,sim_s,wall_s,sim_speed_x_real_time,"
         "feedforward,ff1_per_count_per_s,ff2_per_count_per_s2,contour_rms_counts,contour_max_counts,"
         "encoder_contour_rms_counts,encoder_contour_max_counts,queue_ran_dry\n";
  const double cpm = counts_per_m(o.machine.axes[0]);
  for (const RunResult& r : br.runs) {
    const bool step = r.scenario == "step";
    csv << r.platform << ',' << r.scenario << ',' << r.policy << ',' << r.engine << ',' << r.gains.ts << ','
        << r.gains.kp << ',' << r.gains.ki << ',' << r.gains.kd << ',' << r.gains.tf << ','
        << r.follow[0].rms * 1e6 << ',' << r.follow[0].max * 1e6 << ',' << r.follow[1].rms * 1e6 << ','
        << r.follow[1].max * 1e6 << ',';
    if (step)
      csv << ",," << r.step.settling_s << ',' << r.step.overshoot_pct << ',' << r.step.rise_s;
    else
      csv << r.contour.rms * 1e6 << ',' << r.contour.max * 1e6 << ",,,";
    csv << ',' << (r.tracking ? 1 : 0) << ',' << r.sim_s << ',' << r.wall_s << ',' << r.sim_s / r.wall_s
        << ',' << r.feedforward << ',' << r.gains.ff1 << ',' << r.gains.ff2 << ',';
    if (!step)
      csv << r.contour.rms * cpm << ',' << r.contour.max * cpm;
    else
      csv << ',';
    csv << ',';
    if (r.scenario == "job")
      csv << r.measured_contour.rms * cpm << ',' << r.measured_contour.max * cpm;
    else
      csv << ',';
    csv << ',' << (r.underrun ? 1 : 0) << '\n';
  }
  write_file(dir / "results.csv", csv.str());
  written.push_back((dir / "results.csv").string());

  // Traces for the plots: t, command and position of both axes, errors.
  for (const RunResult& r : br.runs) {
    std::ostringstream d;
    d << "# t_s cmd_x_m cmd_y_m pos_x_m pos_y_m err_x_um err_y_um\n";
    const size_t stride = std::max<size_t>(1, r.t.size() / 20000);
    for (size_t i = 0; i < r.t.size(); i += stride)
      d << r.t[i] << ' ' << r.cmd_m[0][i] << ' ' << r.cmd_m[1][i] << ' ' << r.pos_m[0][i] << ' '
        << r.pos_m[1][i] << ' ' << (r.cmd_m[0][i] - r.pos_m[0][i]) * 1e6 << ' '
        << (r.cmd_m[1][i] - r.pos_m[1][i]) * 1e6 << '\n';
    write_file(dir / "data" / (tag(r) + ".dat"), d.str());
  }

  // Grouping for the tables and plots.
  std::vector<std::string> platform_order, scenario_order;
  for (const RunResult& r : br.runs) {
    if (!std::count(platform_order.begin(), platform_order.end(), r.platform))
      platform_order.push_back(r.platform);
    // The job has a section of its own.
    if (r.scenario != "job" && !std::count(scenario_order.begin(), scenario_order.end(), r.scenario))
      scenario_order.push_back(r.scenario);
  }
  std::vector<std::string> all_p;
  for (const Platform& p : bench_platforms(o.machine)) all_p.push_back(p.name);
  std::sort(platform_order.begin(), platform_order.end(), [&](const std::string& a, const std::string& b) {
    return std::find(all_p.begin(), all_p.end(), a) < std::find(all_p.begin(), all_p.end(), b);
  });
  const auto find = [&](const std::string& p, const std::string& s, const char* pol) -> const RunResult* {
    for (const RunResult& r : br.runs)
      if (r.platform == p && r.scenario == s && r.policy == pol) return &r;
    return nullptr;
  };
  std::vector<const char*> policies;
  for (GainPolicy g : o.policies) policies.push_back(policy_name(g));

  // report.md
  std::ostringstream md;
  md << "# MotionCore sample-period benchmark\n\n";
  md << "Machine: " << o.machine.source << " (XY table, " << o.machine.axes[0].name << "/"
     << o.machine.axes[1].name << "); core clock " << o.machine.clock_hz / 1e6 << " MHz; plant step "
     << o.machine.plant_dt_s * 1e6 << " us. FPGA engine: " << engine_name(o.engine)
     << ". Host loop: " << o.machine.host_period_s * 1e3 << " ms nominal, I/O latency "
     << o.machine.host_io_latency_s * 1e3 << " ms, " << o.machine.host_dac_bits
     << "-bit DAC, wake-up jitter from " << o.jitter.source << ". Seed " << o.seed << "."
     << (o.quick ? " **Quick run: shortened scenarios, not for comparison.**" : "") << "\n\n";
  md << "Scenarios:\n";
  for (const Scenario& s : bench_scenarios(o.quick))
    if (std::count(scenario_order.begin(), scenario_order.end(), s.name))
      md << "- `" << s.name << "`: " << s.describe() << "\n";
  md << "\nGain policies: `same` = the machine's one continuous PID design (configs: [axis.*.pid]) "
        "discretized at every Ts, the paper's method; `tuned` = per platform, closed-loop poles at a triple "
        "real pole -w with w = min(w0, 1/(4 x loop delay)), where the loop delay is half a sample plus the "
        "computation or I/O latency (and the mean wake-up lateness for the host). Following error = command "
        "- "
        "actual table position; contour error = distance of the actual point from the ideal line or circle. "
        "`tracking` = the run ends within a quarter of the move of its command (no: it oscillates, diverged "
        "or "
        "has not caught up yet; the plots tell which).\n\n";
  for (const std::string& s : scenario_order) {
    for (const char* pol : policies) {
      md << "## " << s << ", " << pol << " gains\n\n";
      if (s == "step")
        md << "| platform | Ts | RMS follow x (um) | max follow x (um) | settling 2% (ms) | overshoot (%) | "
              "tracking |\n|---|---|---|---|---|---|---|\n";
      else
        md << "| platform | Ts | RMS contour (um) | max contour (um) | RMS follow x (um) | RMS follow y (um) "
              "| "
              "max follow (um) | tracking |\n|---|---|---|---|---|---|---|---|\n";
      for (const std::string& p : platform_order) {
        const RunResult* r = find(p, s, pol);
        if (!r) continue;
        md << "| " << p << " | " << fmt(r->gains.ts * 1e6, 2) << " us | ";
        if (s == "step")
          md << um(r->follow[0].rms) << " | " << um(r->follow[0].max) << " | " << ms(r->step.settling_s)
             << " | " << fmt(r->step.overshoot_pct, 1) << " | ";
        else
          md << um(r->contour.rms) << " | " << um(r->contour.max) << " | " << um(r->follow[0].rms) << " | "
             << um(r->follow[1].rms) << " | " << um(std::max(r->follow[0].max, r->follow[1].max)) << " | ";
        md << (r->tracking ? "yes" : "**no**") << " |\n";
      }
      md << "\n";
    }
  }
  // A short reading: the headline ratios.
  md << "## Reading\n\n";
  for (const char* pol : policies) {
    for (const std::string& s : scenario_order) {
      const RunResult* host = find("host-10ms", s, pol);
      const RunResult* f10 = find("fpga-10ms", s, pol);
      const RunResult* fmin = find("fpga-min", s, pol);
      const RunResult* f100 = find("fpga-100us", s, pol);
      const auto err = [&](const RunResult* r) { return s == "step" ? r->follow[0].rms : r->contour.rms; };
      const char* what = s == "step" ? "RMS following error" : "RMS contour error";
      if (host && f10)
        md << "- " << s << ", " << pol << ": " << what << " " << um(err(host)) << " um on the 10 ms host loop"
           << (host->tracking ? "" : " (off the command at the end)") << " against " << um(err(f10))
           << " um on the FPGA at the same Ts" << (f10->tracking ? "" : " (off the command at the end)");
      else if (f10)
        md << "- " << s << ", " << pol << ": " << what << " " << um(err(f10)) << " um at fpga-10ms";
      else
        continue;
      if (f100) md << ", " << um(err(f100)) << " um at 100 us";
      if (fmin)
        md << " and " << um(err(fmin)) << " um at the shortest Ts (" << fmt(fmin->gains.ts * 1e6, 2)
           << " us)";
      md << ".\n";
    }
  }
  md << "\nWhat the numbers mean: at the same Ts the FPGA loop differs from the PC loop only by the PC's "
        "jitter, its I/O latency and its DAC; shortening Ts removes the sample-and-hold delay, which lets "
        "the "
        "tuned policy raise the loop bandwidth until the plant's own design bandwidth (w0) is reached, so "
        "the "
        "error stops falling below a few hundred microseconds. With the same gains at every Ts, a design "
        "made "
        "for a fast loop can be unstable at 10 ms.\n\n";

  // The job: its own table, every platform and feed-forward.
  std::vector<const RunResult*> jobs;
  for (const RunResult& r : br.runs)
    if (r.scenario == "job") jobs.push_back(&r);
  const auto job_find = [&](const std::string& p, const std::string& ff) -> const RunResult* {
    for (const RunResult* r : jobs)
      if (r->platform == p && r->feedforward == ff) return r;
    return nullptr;
  };
  std::vector<std::string> ff_order;
  for (const RunResult* r : jobs)
    if (!std::count(ff_order.begin(), ff_order.end(), r->feedforward)) ff_order.push_back(r->feedforward);
  // The floor a loop on an encoder cannot go below: a position known to a
  // count, uniformly within it, is 1/sqrt(12) count RMS off.
  const double floor_counts = 1 / std::sqrt(12.0);
  const auto counts = [&](double m) { return fmt(m * cpm, 3); };
  if (!jobs.empty()) {
    md << "## job, tuned gains, without and with feed-forward\n\n`job`: " << br.job
       << ".\n\nThe planner of `motionctl run` made the segments; the co-simulation streams them into the "
          "core's queue as room frees, by its level, as the host does over the link (the PC loop's "
          "command generator takes them the same way). Contour error: host/machine/job's measure (the "
          "distance of the table's true XY position from the programmed path, samples whose command is "
          "on a rapid left out); encoder: the same of the encoder counts, as `motionctl run` reports it. "
          "Feed-forward `fitted`: FF1 = 1/Kg and FF2 = tau/Kg from the axis model, each where a one-count "
          "pulse of it fits the output (FF1/Ts <= out_limit, FF2/Ts^2 <= out_limit/8); the column says "
          "what was applied. One count = "
       << fmt(1e6 / cpm, 2) << " um; the quantization floor is 1/sqrt(12) = " << fmt(floor_counts, 3)
       << " count RMS.\n\n"
       << "| platform | Ts | feed-forward | RMS contour (um) | RMS contour (counts) | max contour (um) | max "
          "contour (counts) | RMS follow x (um) | RMS follow y (um) | max follow (um) | encoder RMS contour "
          "(counts) | queue ran dry | tracking |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const std::string& ff : ff_order)
      for (const std::string& p : platform_order) {
        const RunResult* r = job_find(p, ff);
        if (!r) continue;
        md << "| " << p << " | " << fmt(r->gains.ts * 1e6, 2) << " us | " << ff_applied(*r) << " | "
           << um(r->contour.rms) << " | " << counts(r->contour.rms) << " | " << um(r->contour.max) << " | "
           << counts(r->contour.max) << " | " << um(r->follow[0].rms) << " | " << um(r->follow[1].rms)
           << " | " << um(std::max(r->follow[0].max, r->follow[1].max)) << " | "
           << counts(r->measured_contour.rms) << " | " << (r->underrun ? "**yes**" : "no") << " | "
           << (r->tracking ? "yes" : "**no**") << " |\n";
      }
    md << "\n";
    // The headline: each FPGA Ts without and with, against the floor.
    std::string reading;
    for (const std::string& p : platform_order) {
      const RunResult *off = job_find(p, "none"), *on = job_find(p, "fitted");
      if (p.rfind("fpga", 0) != 0 || !off || !on) continue;
      reading += std::string(reading.empty() ? "" : "; ") + p + ": " + counts(off->contour.rms) + " -> " +
                 counts(on->contour.rms) + " count (" + ff_applied(*on) + ", " +
                 fmt(on->contour.rms * cpm / floor_counts, 2) + "x the floor)";
    }
    if (!reading.empty())
      md << "Reading, RMS contour error without -> with feed-forward: " << reading
         << ". The quantization floor is " << fmt(floor_counts, 3) << " count.\n\n";
  }

  // The README's table (scripts/bench_readme.sh copies it there): the circle
  // under the tuned gains, every platform.
  if (std::count(scenario_order.begin(), scenario_order.end(), "circle") &&
      std::count(policies.begin(), policies.end(), std::string("tuned"))) {
    std::string head = "|", rule = "|", row = "|";
    for (const std::string& p : platform_order) {
      const RunResult* r = find(p, "circle", "tuned");
      if (!r) continue;
      head += " " + (p == "fpga-min" ? "fpga-" + fmt(r->gains.ts * 1e6, 2) + "us" : p) + " |";
      rule += "---|";
      row += " " + um(r->contour.rms) + " µm |";
    }
    double twin_sim = 0, twin_wall = 0, twin_cpu = 0;
    for (const RunResult& r : br.runs)
      if (r.engine != "host") {
        twin_sim += r.sim_s;
        twin_wall += r.wall_s;
        twin_cpu += r.cpu_s;
      }
    size_t same = 0;
    for (const RtlCheck& c : br.rtl_checks) same += c.same_outputs;
    md << "<!-- README table -->\n" << head << "\n" << rule << "\n" << row << "\n\n";
    if (!jobs.empty()) {
      // The job: RMS contour error in counts, a row per feed-forward.
      std::string jhead = "| job, RMS contour error |", jrule = "|---|";
      std::vector<std::string> jp;
      for (const std::string& p : platform_order)
        if (job_find(p, ff_order.front())) {
          jp.push_back(p);
          jhead += " " + p + " |";
          jrule += "---|";
        }
      md << jhead << "\n" << jrule << "\n";
      for (const std::string& ff : ff_order) {
        md << "| feed-forward " << ff << " |";
        for (const std::string& p : jp) {
          const RunResult* r = job_find(p, ff);
          md << " " << (r ? um(r->contour.rms) + " µm = " + counts(r->contour.rms) + " count" : "") << " |";
        }
        md << "\n";
      }
      md << "\n";
    }
    md << "The full benchmark took " << fmt(br.wall_s, 1) << " s with " << o.jobs << " jobs; its FPGA runs "
       << "went at " << fmt(twin_wall > 0 ? twin_sim / twin_wall : 0, 1) << "x real time on the "
       << engine_name(o.engine) << " engine (" << fmt(twin_cpu > 0 ? twin_sim / twin_cpu : 0, 1)
       << "x on CPU time)";
    if (!br.rtl_checks.empty())
      md << ", and " << same << " of " << br.rtl_checks.size()
         << " runs repeated on the Verilated RTL gave the same controller outputs, sample for sample";
    md << (o.quick ? " (quick run: not for comparison)" : "") << ".\n<!-- end of README table -->\n\n";
  }

  // The RTL check: the same runs on the Verilated core.
  if (!br.rtl_checks.empty()) {
    md << "## The twin against the RTL\n\nThe tables above ran on the C++ twin of the core (hls/). These "
          "runs were repeated on the Verilated RTL in the same benchmark:\n\n"
          "| platform | scenario | policy | error, twin (um) | error, RTL (um) | controller outputs |\n"
          "|---|---|---|---|---|---|\n";
    for (const RtlCheck& c : br.rtl_checks) {
      const RunResult& t = br.runs[c.run];
      const auto err = [&](const RunResult& r) {
        return r.scenario == "step" ? r.follow[0].rms : r.contour.rms;
      };
      md << "| " << t.platform << " | " << t.scenario << " | " << t.policy << " | " << um(err(t)) << " | "
         << um(err(c.rtl)) << " | "
         << (c.same_outputs ? "identical (" + std::to_string(t.sample_u[0].size()) + " samples)"
                            : std::string("**differ**"))
         << " |\n";
    }
    md << "\n(error: RMS following error of x for the step, RMS contour error for paths.)\n\n";
  }

  // Speed.
  md << "## Simulation speed\n\nWall time, and CPU time (the machine may be shared: the tables' runs go "
     << o.jobs
     << " at a time, the RTL check's one at a time after them, and other work may run beside "
        "them).\n\n| platform | engine | simulated s | wall s | x real "
        "time | CPU s | x real time on CPU time |\n|---|---|---|---|---|---|---|\n";
  struct Sum {
    double sim = 0, wall = 0, cpu = 0;
  };
  std::map<std::string, Sum> speed;
  const auto add_speed = [&](const RunResult& r) {
    Sum& e = speed[r.platform + " | " + r.engine];
    e.sim += r.sim_s;
    e.wall += r.wall_s;
    e.cpu += r.cpu_s;
  };
  for (const RunResult& r : br.runs) add_speed(r);
  for (const RtlCheck& c : br.rtl_checks) add_speed(c.rtl);
  for (const std::string& p : platform_order)
    for (const auto& [k, v] : speed)
      if (k.rfind(p + " |", 0) == 0)
        md << "| " << k << " | " << fmt(v.sim, 2) << " | " << fmt(v.wall, 2) << " | "
           << fmt(v.sim / v.wall, 3) << " | " << fmt(v.cpu, 2) << " | "
           << fmt(v.cpu > 0 ? v.sim / v.cpu : 0, 3) << " |\n";
  // The RTL runs against the bare model, on CPU time: the check's each
  // against the bare loop measured around it, a whole RTL table's against
  // the kernel probe's. bare_cpu: the CPU time the runs would have taken at
  // the bare loop's speed.
  double rtl_sim = 0, rtl_cpu = 0, bare_cpu = 0;
  const auto against = [&](const RunResult& r, double bare) {
    if (bare <= 0) return;
    rtl_sim += r.sim_s;
    rtl_cpu += r.cpu_s;
    bare_cpu += r.sim_s / bare;
  };
  for (const RtlCheck& c : br.rtl_checks) against(c.rtl, c.bare_speed);
  for (const RunResult& r : br.runs)
    if (r.engine == "rtl") against(r, br.probe.bare_speed);
  if (!br.other_speeds.empty()) {
    md << "\n| workload | engine | simulated s | wall s | x real time | CPU s | x real time on CPU time "
          "|\n|---|---|---|---|---|---|---|\n";
    for (const SpeedRow& r : br.other_speeds)
      md << "| " << r.what << " | " << r.engine << " | " << fmt(r.sim_s, 3) << " | " << fmt(r.wall_s, 2)
         << " | " << fmt(r.wall_s > 0 ? r.sim_s / r.wall_s : 0, 3) << " | " << fmt(r.cpu_s, 2) << " | "
         << fmt(r.cpu_s > 0 ? r.sim_s / r.cpu_s : 0, 3) << " |\n";
  }
  // The goal's own case: a row above sums every scenario, and the long
  // job spreads each run's fixed cost thinner than the circle does.
  double goal_sim = 0, goal_wall = 0;
  for (const RunResult& r : br.runs)
    if (r.platform == "fpga-100us" && r.scenario == "circle" && r.engine == "twin") {
      goal_sim += r.sim_s;
      goal_wall += r.wall_s;
    }
  if (goal_wall > 0)
    md << "\nThe goal's case, the two-axis circle at 100 us on the twin: " << fmt(goal_sim / goal_wall, 1)
       << "x real time on wall time (" << fmt(goal_sim, 2) << " s simulated in " << fmt(goal_wall, 3)
       << " s, the runs " << o.jobs << " at a time).";
  if (!br.goal_alone_wall_s.empty()) {
    std::vector<double> w = br.goal_alone_wall_s;
    std::sort(w.begin(), w.end());
    const double sim = br.goal_alone_sim_s, med = w[w.size() / 2];
    md << " Run alone after the pool, " << w.size() << " times (same gains, nothing else of the benchmark "
       << "running): " << fmt(sim, 3) << " s simulated in " << fmt(w.front(), 4) << " to " << fmt(w.back(), 4)
       << " s, " << fmt(sim / med, 1) << "x real time at the median (" << fmt(sim / w.front(), 1)
       << "x at the fastest).";
    std::vector<double> su = br.goal_alone_setup_s;  // pushed with each wall time
    std::sort(su.begin(), su.end());
    md << " Of each run, the set-up (the machine, its trace and the model built before the kernel starts) "
          "took "
       << fmt(su[su.size() / 2] * 1e3, 2) << " ms at the median.";
  }
  md << "\n";
  md << "\nGoals: the twin co-simulation of the two-axis loop at least 100x real time; the RTL "
        "co-simulation at least 75 % of the speed of the bare Verilated core measured in the same run; the "
        "virtual board (`motionctl sim serve --speed max`, measured in process under a host session) at "
        "least 10x on the twin. "
        "`motionctl bench --engine rtl` runs every table on the RTL. The whole benchmark took "
     << fmt(br.wall_s, 1) << " s of wall time with " << o.jobs << " jobs.\n\n";
  if (rtl_cpu > 0)
    md << "On CPU time: the RTL co-simulations above (plant, harness and SystemC included) ran at "
       << fmt(rtl_sim / rtl_cpu, 4) << "x real time, " << fmt(100 * bare_cpu / rtl_cpu, 0)
       << " % of the speed of the Verilated core alone, clocked in a bare C++ loop with its inputs held ("
       << fmt(rtl_sim / bare_cpu, 4) << "x), measured in this run "
       << (br.rtl_checks.empty() ? "after them" : "just before and just after each of them, each alone")
       << ".\n\n";
  if (br.probe.probe_sim_s > 0)
    md << "SystemC kernel choice (probe of " << br.probe.probe_sim_s * 1e3
       << " ms of core time, no plant): the "
       << "Verilated core as a module clocked by an sc_clock runs at " << fmt(br.probe.clocked_speed, 4)
       << "x real time; stepped inside one process that synchronizes every 100 us (temporal decoupling) at "
       << fmt(br.probe.decoupled_speed, 4) << "x. The co-simulation uses the second (docs/decisions.md).\n\n";
  md << "Files: results.csv (one row per platform x scenario x policy), data/*.dat (traces), plots/*.png.\n";
  write_file(dir / "report.md", md.str());
  written.push_back((dir / "report.md").string());
  if (!o.plots) return written;

  // Plots.
  const auto dat = [&](const RunResult& r) { return (dir / "data" / (tag(r) + ".dat")).string(); };
  for (const std::string& s : scenario_order)
    for (const char* pol : policies) {
      const fs::path png = dir / "plots" / ("following_" + s + "_" + pol + ".png");
      std::ostringstream gp;
      gp << "set terminal pngcairo size 1000,600\nset output '" << png.string() << "'\n"
         << "set title 'Following error, x axis: " << s << ", " << pol << " gains'\nset xlabel 'time (s)'\n"
         << "set ylabel 'command - position (um)'\nset grid\nset key outside right\nplot ";
      bool first = true;
      for (const std::string& p : platform_order) {
        const RunResult* r = find(p, s, pol);
        if (!r) continue;
        gp << (first ? "" : ", ") << "'" << dat(*r) << "' using 1:6 with lines title '" << p << "'";
        first = false;
      }
      gp << "\n";
      write_file(dir / "plots" / ("following_" + s + "_" + pol + ".gp"), gp.str());
      run_gnuplot(dir / "plots" / ("following_" + s + "_" + pol + ".gp"));
      written.push_back(png.string());
    }
  if (std::count(scenario_order.begin(), scenario_order.end(), "circle")) {
    // The circle's radial error is microns on millimetres: magnify it.
    const double r0 = find_scenario("circle", o.quick).size_m;
    const double mag = 20;
    for (const char* pol : policies) {
      const fs::path png = dir / "plots" / (std::string("circle_xy_") + pol + ".png");
      std::ostringstream gp;
      gp << "set terminal pngcairo size 900,900\nset output '" << png.string() << "'\nset size square\n"
         << "set title 'Circle R " << r0 * 1e3 << " mm, " << pol << " gains: radial error magnified x" << mag
         << "'\nset xlabel 'x (mm)'\nset ylabel 'y (mm)'\nset grid\nset key outside right\n"
         << "cx = " << -r0 << "\nR = " << r0 << "\nM = " << mag << "\n"
         << "rad(x,y) = sqrt((x-cx)**2 + y**2)\n"
         << "mx(x,y) = (cx + (x-cx) * (R + M*(rad(x,y)-R)) / rad(x,y)) * 1e3\n"
         << "my(x,y) = (y * (R + M*(rad(x,y)-R)) / rad(x,y)) * 1e3\nplot ";
      gp << "'" << dat(*find(platform_order.front(), "circle", pol))
         << "' using (mx($2,$3)):(my($2,$3)) with lines lw 2 "
         << "dt 2 title 'command'";
      for (const std::string& p : platform_order) {
        const RunResult* r = find(p, "circle", pol);
        if (r) gp << ", '" << dat(*r) << "' using (mx($4,$5)):(my($4,$5)) with lines title '" << p << "'";
      }
      gp << "\n";
      write_file(dir / "plots" / (std::string("circle_xy_") + pol + ".gp"), gp.str());
      run_gnuplot(dir / "plots" / (std::string("circle_xy_") + pol + ".gp"));
      written.push_back(png.string());
    }
  }
  {
    // Contour error against Ts: FPGA platforms as lines, the host as points.
    std::vector<const RunResult*> rows;
    for (const RunResult& r : br.runs)
      if (r.scenario != "step" && r.scenario != "job") rows.push_back(&r);
    std::sort(rows.begin(), rows.end(), [](const RunResult* a, const RunResult* b) {
      return std::tie(a->policy, a->scenario, a->gains.ts) < std::tie(b->policy, b->scenario, b->gains.ts);
    });
    std::ostringstream d;
    d << "# policy scenario platform ts_s rms_um host\n";
    for (const RunResult* r : rows)
      d << r->policy << ' ' << r->scenario << ' ' << r->platform << ' ' << r->gains.ts << ' '
        << r->contour.rms * 1e6 << ' ' << (r->platform.rfind("host", 0) == 0 ? 1 : 0) << '\n';
    write_file(dir / "data" / "contour_vs_ts.dat", d.str());
    const fs::path png = dir / "plots" / "contour_vs_ts.png";
    std::ostringstream gp;
    gp << "set terminal pngcairo size 1000,600\nset output '" << png.string() << "'\nset logscale xy\n"
       << "set title 'RMS contour error against sample period'\nset xlabel 'Ts (s)'\nset ylabel 'RMS contour "
          "error (um)'\n"
       << "set grid\nset key outside right\nf = '" << (dir / "data" / "contour_vs_ts.dat").string()
       << "'\nplot ";
    bool first = true;
    for (const char* pol : policies)
      for (const std::string& s : scenario_order) {
        if (s == "step") continue;
        const std::string sel = "(strcol(1) eq '" + std::string(pol) + "' && strcol(2) eq '" + s + "'";
        gp << (first ? "" : ", ") << "f using " << sel
           << " && $6 == 0 ? $4 : NaN):5 with linespoints title 'FPGA " << s << " " << pol << "', f using "
           << sel << " && $6 == 1 ? $4 : NaN):5 with points pt 7 ps 2 title 'host " << s << " " << pol << "'";
        first = false;
      }
    gp << "\n";
    write_file(dir / "plots" / "contour_vs_ts.gp", gp.str());
    if (!first) {
      run_gnuplot(dir / "plots" / "contour_vs_ts.gp");
      written.push_back(png.string());
    }
  }
  if (!jobs.empty()) {
    // The job's RMS contour error against Ts, in counts, with the floor.
    std::vector<const RunResult*> rows = jobs;
    std::sort(rows.begin(), rows.end(), [](const RunResult* a, const RunResult* b) {
      return std::tie(a->feedforward, a->gains.ts) < std::tie(b->feedforward, b->gains.ts);
    });
    std::ostringstream d;
    d << "# feedforward platform ts_s rms_counts max_counts host\n";
    for (const RunResult* r : rows)
      d << r->feedforward << ' ' << r->platform << ' ' << r->gains.ts << ' ' << r->contour.rms * cpm << ' '
        << r->contour.max * cpm << ' ' << (r->platform.rfind("host", 0) == 0 ? 1 : 0) << '\n';
    const fs::path data = dir / "data" / "job_contour_vs_ts.dat";
    write_file(data, d.str());
    const fs::path png = dir / "plots" / "job_contour_vs_ts.png";
    std::ostringstream gp;
    gp << "set terminal pngcairo size 1000,600\nset output '" << png.string() << "'\nset logscale xy\n"
       << "set title 'Job: RMS contour error against sample period, tuned gains'\nset xlabel 'Ts (s)'\n"
       << "set ylabel 'RMS contour error (encoder counts)'\nset grid\nset key outside right\nf = '"
       << data.string() << "'\nplot " << floor_counts
       << " with lines dt 2 lc rgb 'gray' title 'quantization floor "
       << "1/sqrt(12)'";
    for (const std::string& ff : ff_order) {
      const std::string sel = "(strcol(1) eq '" + ff + "'";
      gp << ", f using " << sel << " && $6 == 0 ? $3 : NaN):4 with linespoints title 'FPGA, feed-forward "
         << ff << "', f using " << sel
         << " && $6 == 1 ? $3 : NaN):4 with points pt 7 ps 2 title 'host, feed-forward " << ff << "'";
    }
    gp << "\n";
    write_file(dir / "plots" / "job_contour_vs_ts.gp", gp.str());
    run_gnuplot(dir / "plots" / "job_contour_vs_ts.gp");
    written.push_back(png.string());

    // Along the path: the contour error against time at the shortest FPGA
    // Ts and at 1 ms, without and with.
    std::vector<const RunResult*> shown;
    std::string shortest;
    for (const std::string& p : platform_order)
      if (p.rfind("fpga", 0) == 0 && job_find(p, ff_order.front())) shortest = p;
    for (const std::string& p : {std::string("fpga-1ms"), shortest})
      for (const std::string& ff : ff_order)
        if (const RunResult* r = job_find(p, ff); r && !std::count(shown.begin(), shown.end(), r))
          shown.push_back(r);
    if (!shown.empty()) {
      const fs::path path_png = dir / "plots" / "job_contour_path.png";
      std::ostringstream pg;
      pg << "set terminal pngcairo size 1200,600\nset output '" << path_png.string() << "'\n"
         << "set title 'Job: contour error along the path (rapids left out), tuned gains'\n"
         << "set xlabel 'time (s)'\nset ylabel 'contour error (um)'\nset grid\nset key outside right\nplot ";
      for (size_t k = 0; k < shown.size(); ++k) {
        const RunResult& r = *shown[k];
        std::ostringstream e;
        e << "# t_s contour_um (NaN: the command on a rapid)\n";
        for (size_t i = 0; i < r.contour_each.size(); ++i)
          e << r.t[i] << ' '
            << (std::isnan(r.contour_each[i]) ? std::string("NaN") : fmt(r.contour_each[i] * 1e6, 4)) << '\n';
        const fs::path f = dir / "data" / ("job_contour_" + tag(r) + ".dat");
        write_file(f, e.str());
        pg << (k ? ", " : "") << "'" << f.string() << "' using 1:2 with lines title '" << r.platform
           << ", feed-forward " << ff_applied(r) << "'";
      }
      pg << "\n";
      write_file(dir / "plots" / "job_contour_path.gp", pg.str());
      run_gnuplot(dir / "plots" / "job_contour_path.gp");
      written.push_back(path_png.string());
    }
  }
  return written;
}

}  // namespace mc::sim
