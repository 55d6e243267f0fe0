// This machine as a host control loop sees it: how late a periodic loop
// wakes (the loop a PC motion program runs: sleep until an absolute
// deadline k * period with clock_nanosleep on CLOCK_MONOTONIC, wake, note
// the time), the scheduling policy it ran under, and the provenance a
// jitter file records (jitter_record.hpp writes it).
#pragma once

#include <csignal>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mc::host {

struct Recording {
  std::vector<int64_t> lateness_ns;  // wake - deadline, one per period
  bool interrupted = false;          // `stop` was raised before the last period
};
// Runs n periods of period_ns. A wake more than one period late is an
// overrun; the next deadline is then already past and the loop runs at once,
// as the real program would. `stop` (set by a signal handler) ends the run
// early; progress(k, n) is called about once a second.
Recording record_lateness(int64_t period_ns, uint64_t n, const volatile std::sig_atomic_t& stop,
                          const std::function<void(uint64_t, uint64_t)>& progress);

// The scheduling policy in force, as the kernel reports it.
std::string scheduling(bool fifo);
// Switches this process to SCHED_FIFO; throws with the reason and the remedy.
void enter_fifo(int priority);

// Provenance: evidence, not a verdict (a reader decides how much the numbers
// say about a dedicated PC).
std::string cpu_model();
std::string virtualization();
std::string kernel();
std::string hostname();
std::string utc_now();
// /proc/loadavg as it reads now.
std::string load_average();

}  // namespace mc::host
