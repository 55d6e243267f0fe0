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
#include <functional>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/commands.hpp"
#include "host/control/jitter_host.hpp"
#include "host/control/jitter_record.hpp"

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
      {"loadavg_at_start", load_average()},
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
  std::function<void(uint64_t, uint64_t)> progress;
  if (isatty(STDERR_FILENO) == 1)
    progress = [period_ns](uint64_t k, uint64_t total) {
      std::fprintf(stderr, "\rrecording: %.0f of %.0f s, %llu samples", double(k) * double(period_ns) / 1e9,
                   double(total) * double(period_ns) / 1e9, (unsigned long long)k);
      std::fflush(stderr);
    };
  const Recording rec = record_lateness(period_ns, n, g_stop, progress);
  if (progress) std::fprintf(stderr, "\r\033[K");
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
