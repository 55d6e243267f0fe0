// motionctl jitter: measure how late a periodic loop wakes on this machine.
//
// The loop a PC motion program runs: sleep until an absolute deadline
// k * period (clock_nanosleep, CLOCK_MONOTONIC, TIMER_ABSTIME), wake, note the
// time. Lateness = wake - deadline. A wake more than one period late is an
// overrun; the next deadline is then already past and the loop runs at once,
// as the real program would. The result is a histogram file with the machine's
// provenance (jitter_record.hpp), which the co-simulation samples.
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "errors.hpp"
#include "jitter_record.hpp"
#include "units.hpp"

#ifndef MC_VERSION
#define MC_VERSION "unknown"
#endif

namespace mc::host::cli {
namespace {

// Memory for the samples stays bounded (80 MB); a longer run wants a larger period.
constexpr double kMaxSamples = 1e7;

struct JitterOptions {
  std::string period = "10ms", duration = "30s", out;
  bool fifo = false, json = false;
  int priority = 80;
};

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_signal(int) {
  g_stop = 1;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

std::string read_first_line(const char* path) {
  std::ifstream f(path);
  std::string line;
  std::getline(f, line);
  return trim(line);
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  for (std::string line; std::getline(f, line);) {
    if (line.rfind("model name", 0) == 0) {
      const size_t c = line.find(':');
      if (c != std::string::npos) return trim(line.substr(c + 1));
    }
  }
  return "unknown";
}

bool cpu_flag(const std::string& flag) {
  std::ifstream f("/proc/cpuinfo");
  for (std::string line; std::getline(f, line);) {
    if (line.rfind("flags", 0) == 0) return (line + " ").find(" " + flag + " ") != std::string::npos;
  }
  return false;
}

std::string run_quiet(const char* cmd) {
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(cmd, "r"), &pclose);
  if (!p) return "";
  char buf[256];
  std::string s;
  while (std::fgets(buf, sizeof buf, p.get())) s += buf;
  return trim(s);
}

// Every hint we can find, as evidence rather than a verdict: a reader of the
// file decides how much the numbers say about a dedicated PC.
std::string virtualization() {
  std::string v;
  const auto add = [&](const std::string& s) { v += (v.empty() ? "" : "; ") + s; };
  const std::string sd = run_quiet("systemd-detect-virt 2>/dev/null");
  if (!sd.empty()) add("systemd-detect-virt: " + sd);
  add(std::string("cpu flag hypervisor: ") + (cpu_flag("hypervisor") ? "yes" : "no"));
  const std::string hv = read_first_line("/sys/hypervisor/type");
  if (!hv.empty()) add("/sys/hypervisor/type: " + hv);
  if (access("/.dockerenv", F_OK) == 0) add("/.dockerenv present");
  std::ifstream cg("/proc/1/cgroup");
  for (std::string line; std::getline(cg, line);) {
    for (const char* k : {"docker", "lxc", "kubepods", "containerd"}) {
      if (line.find(k) != std::string::npos) {
        add(std::string("/proc/1/cgroup mentions ") + k);
        return v;
      }
    }
  }
  return v;
}

std::string kernel() {
  utsname u{};
  if (uname(&u) != 0) return "unknown";
  return std::string(u.sysname) + " " + u.release + " " + u.version + " " + u.machine;
}

std::string hostname() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string fmt_us(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

// The policy actually in force, as the kernel reports it.
std::string scheduling(bool fifo) {
  if (fifo) {
    sched_param sp{};
    const int pol = sched_getscheduler(0);
    sched_getparam(0, &sp);
    return std::string(pol == SCHED_FIFO ? "SCHED_FIFO" : "other") + " priority " +
           std::to_string(sp.sched_priority);
  }
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, 0);
  return "SCHED_OTHER nice " + std::to_string(nice);
}

void enter_fifo(int priority) {
  sched_param sp{};
  sp.sched_priority = priority;
  if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
    const int err = errno;
    throw std::runtime_error("--fifo: cannot switch to SCHED_FIFO priority " + std::to_string(priority) +
                             ": " + std::strerror(err) +
                             (err == EPERM
                                  ? " (needs root, CAP_SYS_NICE or an rtprio limit; run without --fifo "
                                    "to measure the default policy)"
                                  : ""));
  }
}

int64_t to_ns(const timespec& t) {
  return int64_t(t.tv_sec) * 1000000000 + t.tv_nsec;
}
timespec from_ns(int64_t ns) {
  timespec t{};
  t.tv_sec = time_t(ns / 1000000000);
  t.tv_nsec = long(ns % 1000000000);
  return t;
}

struct Recording {
  std::vector<int64_t> lateness_ns;
  bool interrupted = false;
};

Recording record(int64_t period_ns, uint64_t n, bool progress) {
  Recording r;
  r.lateness_ns.reserve(n);
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const int64_t t0 = to_ns(now);
  const int64_t report_every = std::max<int64_t>(1, 1000000000 / period_ns);
  for (uint64_t k = 1; k <= n; ++k) {
    const int64_t deadline = t0 + int64_t(k) * period_ns;
    const timespec d = from_ns(deadline);
    int rc;
    while ((rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &d, nullptr)) == EINTR && !g_stop) {
    }
    if (g_stop) {
      r.interrupted = true;
      break;
    }
    if (rc != 0) throw std::runtime_error(std::string("clock_nanosleep failed: ") + std::strerror(rc));
    clock_gettime(CLOCK_MONOTONIC, &now);
    r.lateness_ns.push_back(to_ns(now) - deadline);
    if (progress && int64_t(k) % report_every == 0) {
      std::fprintf(stderr, "\rrecording: %.0f of %.0f s, %llu samples", double(k) * double(period_ns) / 1e9,
                   double(n) * double(period_ns) / 1e9, (unsigned long long)k);
      std::fflush(stderr);
    }
  }
  if (progress) std::fprintf(stderr, "\r\033[K");
  return r;
}

void run(const JitterOptions& o) {
  const double period = parse_duration(o.period, "--period");
  const double duration = parse_duration(o.duration, "--duration");
  if (period < 1e-6) throw InputError("--period", quote(o.period), "at least 1us");
  if (duration < period) throw InputError("--duration", quote(o.duration), "at least one --period");
  const double nd = std::floor(duration / period + 1e-9);
  if (nd > kMaxSamples) {
    throw InputError("--duration", quote(o.duration),
                     "at most 1e7 periods (" + num(kMaxSamples * period) + " s)",
                     "too many samples to keep in memory");
  }
  if (o.fifo && (o.priority < 1 || o.priority > 99)) {
    throw InputError("--priority", std::to_string(o.priority), "1..99");
  }
  if (o.out.empty()) throw InputError("--out", "\"\"", "a file path");
  const auto n = uint64_t(nd);
  const auto period_ns = int64_t(std::llround(period * 1e9));

  // Before the long wait: a bad --out or a refused --fifo fails at once.
  AtomicFile out(o.out);
  if (o.fifo) enter_fifo(o.priority);

  std::string command =
      "motionctl jitter --period " + o.period + " --duration " + o.duration + " --out " + o.out;
  if (o.fifo) command += " --fifo --priority " + std::to_string(o.priority);
  std::vector<std::pair<std::string, std::string>> prov = {
      {"tool", std::string("motionctl ") + MC_VERSION + " jitter: wake-up lateness of a periodic loop"},
      {"command", command},
      {"hostname", hostname()},
      {"kernel", kernel()},
      {"cpu_model", cpu_model()},
      {"cpus_online", std::to_string(sysconf(_SC_NPROCESSORS_ONLN))},
      {"virtualization", virtualization()},
      {"loadavg_at_start", read_first_line("/proc/loadavg")},
      {"scheduling", scheduling(o.fifo)},
      // The kernel may defer a SCHED_OTHER wake by up to this much to batch timers.
      {"timer_slack_ns", std::to_string(prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0))},
      {"clock",
       "clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) on deadlines t0 + k*period; "
       "lateness = clock_gettime(CLOCK_MONOTONIC) after the wake - deadline"},
      {"date_utc", utc_now()},
  };

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  struct sigaction old_int {
  }, old_term{};
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);
  const Recording rec = record(period_ns, n, isatty(STDERR_FILENO) == 1);
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  if (rec.interrupted && rec.lateness_ns.empty()) {
    throw std::runtime_error("interrupted before the first period ended; nothing recorded, " + quote(o.out) +
                             " not written");
  }

  const LatencyStats s = latency_stats(rec.lateness_ns, period_ns);
  prov.insert(prov.end(), {
                              {"period_s", num(period)},
                              {"duration_s", num(double(s.samples) * period)},
                              {"samples", std::to_string(s.samples)},
                              {"interrupted", rec.interrupted ? "yes, after " + std::to_string(s.samples) +
                                                                    " of " + std::to_string(n) + " periods"
                                                              : "no"},
                              {"overruns", std::to_string(s.overruns) + " (wakes more than one period late)"},
                              {"lateness_us_min", fmt_us(s.min_us)},
                              {"lateness_us_mean", fmt_us(s.mean_us)},
                              {"lateness_us_p50", fmt_us(s.p50_us)},
                              {"lateness_us_p99", fmt_us(s.p99_us)},
                              {"lateness_us_p99.9", fmt_us(s.p999_us)},
                              {"lateness_us_max", fmt_us(s.max_us)},
                          });
  out.commit(jitter_csv(prov, latency_histogram(rec.lateness_ns)));

  if (o.json) {
    nlohmann::ordered_json j;
    j["out"] = o.out;
    j["period_s"] = period;
    j["samples"] = s.samples;
    j["interrupted"] = rec.interrupted;
    j["overruns"] = s.overruns;
    j["lateness_us"] = {{"min", s.min_us}, {"mean", s.mean_us},  {"p50", s.p50_us},
                        {"p99", s.p99_us}, {"p99.9", s.p999_us}, {"max", s.max_us}};
    nlohmann::ordered_json p = nlohmann::ordered_json::object();
    for (const auto& [k, v] : prov) p[k] = v;
    j["provenance"] = p;
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << "wake-up lateness, period " << format_duration(period) << ", " << s.samples << " samples ("
              << scheduling(o.fifo) << ")\n"
              << "  min " << fmt_us(s.min_us) << " us   mean " << fmt_us(s.mean_us) << " us   p50 "
              << fmt_us(s.p50_us) << " us   p99 " << fmt_us(s.p99_us) << " us   p99.9 " << fmt_us(s.p999_us)
              << " us   max " << fmt_us(s.max_us) << " us\n"
              << "  overruns (later than one period): " << s.overruns << "\n"
              << "  histogram written to " << o.out << "\n";
  }
  if (rec.interrupted) {
    throw std::runtime_error("interrupted after " + std::to_string(s.samples) + " of " + std::to_string(n) +
                             " periods; the samples so far are in " + quote(o.out));
  }
}

}  // namespace

void add_jitter_command(CLI::App& app) {
  auto opt = std::make_shared<JitterOptions>();
  CLI::App* sub =
      app.add_subcommand("jitter", "Record the wake-up jitter of a periodic loop on this machine");
  sub->footer(
      "Sleeps to absolute deadlines k*period with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) and\n"
      "records how late each wake is. Writes a histogram (CSV with '#' provenance lines) that the\n"
      "co-simulation's host loop samples. Ctrl-C stops early and keeps what was recorded.");
  sub->add_option("--period", opt->period, "Loop period (default 10ms)")->type_name("TIME");
  sub->add_option("--duration", opt->duration, "How long to record (default 30s)")->type_name("TIME");
  sub->add_option("--out", opt->out, "Histogram file to write (replaced atomically)")
      ->required()
      ->type_name("FILE");
  sub->add_flag("--fifo", opt->fifo, "Run under SCHED_FIFO (needs privileges; fails if refused)");
  sub->add_option("--priority", opt->priority, "SCHED_FIFO priority 1..99 with --fifo (default 80)")
      ->type_name("N");
  sub->add_flag("--json", opt->json, "Print the summary as one JSON object");
  sub->callback([opt] { run(*opt); });
}

}  // namespace mc::host::cli
