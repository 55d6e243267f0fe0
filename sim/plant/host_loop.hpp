// The paper's PC platform as an event model: "the same loop run as a 10 ms
// soft-real-time host loop". No plant dependency; the co-simulation calls it.
//
// What happens when (docs/hostloop.md):
//   - deadline k is at k * period (k = 0, 1, ...); the loop wakes at
//     deadline + a lateness drawn from a measured histogram (JitterSampler);
//   - at the wake the host reads the position and command as of that instant
//     and runs PidDouble with the NOMINAL Ts (the program cannot know how late
//     it woke, and a PC PID does not correct for it);
//   - the output reaches the drive io_latency later (USB DAQ round trip) and
//     stays until the next one arrives; the caller puts it through the DAC;
//   - a wake more than one period late is an overrun: the next deadline is
//     already past, so the loop runs again right away (kBackToBack_s after
//     the late wake), as a real loop on absolute deadlines does.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "host/control/pid_design.hpp"
#include "host/control/pid_double.hpp"
#include "sim/plant/jitter.hpp"

namespace mc::sim {

struct HostLoopConfig {
  mc::host::PidGains gains;  // gains.ts must equal period_s
  double period_s = 0.01;
  double io_latency_s = 0.001;
  double out_limit = 32767;  // drive units
};

class HostLoop {
 public:
  // The shortest time between two wakes when the loop is behind.
  static constexpr double kBackToBack_s = 1e-6;

  // Throws InputError: period <= 0, latency < 0, gains.ts != period_s, bad gains.
  HostLoop(const HostLoopConfig& cfg, JitterSampler sampler);

  // When the loop wakes next, seconds. Strictly increasing from wake to wake.
  double next_wake_s() const { return next_wake_; }
  // The wake at next_wake_s(): one PID sample on the inputs as of that
  // instant; its output takes effect io_latency later.
  void wake(double cmd_counts, double fb_counts);
  // The output in effect at t (drive units): the last one whose apply time
  // is <= t; 0 before the first.
  double output_at(double t) const;

  // The output the last wake computed (in effect from its apply time on).
  double last_output() const { return applied_.empty() ? 0.0 : applied_.back().second; }
  uint64_t wakes() const { return wakes_; }
  uint64_t overruns() const { return overruns_; }
  const mc::host::PidDouble& pid() const { return pid_; }

 private:
  void schedule();

  HostLoopConfig cfg_;
  JitterSampler sampler_;
  mc::host::PidDouble pid_;
  uint64_t k_ = 0;  // deadline of the next wake
  uint64_t wakes_ = 0, overruns_ = 0;
  double next_wake_ = 0;
  double last_wake_ = -1;
  std::vector<std::pair<double, double>> applied_;  // (apply time, output), times increasing
};

}  // namespace mc::sim
