#include "host/control/jitter_host.hpp"

#include <sched.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace mc::host {
namespace {

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

int64_t to_ns(const timespec& t) {
  return int64_t(t.tv_sec) * 1000000000 + t.tv_nsec;
}
timespec from_ns(int64_t ns) {
  timespec t{};
  t.tv_sec = time_t(ns / 1000000000);
  t.tv_nsec = long(ns % 1000000000);
  return t;
}

}  // namespace

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

Recording record_lateness(int64_t period_ns, uint64_t n, const volatile std::sig_atomic_t& stop,
                          const std::function<void(uint64_t, uint64_t)>& progress) {
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
    while ((rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &d, nullptr)) == EINTR && !stop) {
    }
    if (stop) {
      r.interrupted = true;
      break;
    }
    if (rc != 0) throw std::runtime_error(std::string("clock_nanosleep failed: ") + std::strerror(rc));
    clock_gettime(CLOCK_MONOTONIC, &now);
    r.lateness_ns.push_back(to_ns(now) - deadline);
    if (progress && int64_t(k) % report_every == 0) progress(k, n);
  }
  return r;
}

std::string load_average() {
  return read_first_line("/proc/loadavg");
}

}  // namespace mc::host
