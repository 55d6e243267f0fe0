#include "sim/plant/host_loop.hpp"

#include <algorithm>
#include <cmath>

#include "host/base/errors.hpp"

namespace mc::sim {
namespace {

using mc::host::format_number;
using mc::host::InputError;

const HostLoopConfig& checked(const HostLoopConfig& c) {
  if (!(c.period_s > 0) || !std::isfinite(c.period_s)) {
    throw InputError("host loop period_s", format_number(c.period_s), "a finite number > 0");
  }
  if (!(c.io_latency_s >= 0) || !std::isfinite(c.io_latency_s)) {
    throw InputError("host loop io_latency_s", format_number(c.io_latency_s), "a finite number >= 0");
  }
  // One source of truth for Ts: the PID is designed at the loop's nominal period.
  if (std::abs(c.gains.ts - c.period_s) > 1e-12 * c.period_s) {
    throw InputError("host loop gains.ts", format_number(c.gains.ts),
                     "the loop's period_s = " + format_number(c.period_s));
  }
  return c;
}

}  // namespace

HostLoop::HostLoop(const HostLoopConfig& cfg, JitterSampler sampler)
    : cfg_(checked(cfg)), sampler_(std::move(sampler)), pid_(cfg.gains, cfg.out_limit) {
  schedule();
}

void HostLoop::schedule() {
  const double deadline = double(k_) * cfg_.period_s;
  const double late = sampler_.next_lateness_s();
  next_wake_ = std::max(deadline + late, last_wake_ + kBackToBack_s);
}

void HostLoop::wake(double cmd_counts, double fb_counts) {
  const double t = next_wake_;
  // As motionctl jitter counts them: more than one period after its deadline.
  if (t - double(k_) * cfg_.period_s > cfg_.period_s) ++overruns_;
  const double u = pid_.update(cmd_counts, fb_counts);
  applied_.emplace_back(t + cfg_.io_latency_s, u);
  ++wakes_;
  last_wake_ = t;
  ++k_;
  schedule();
}

double HostLoop::output_at(double t) const {
  const auto it = std::upper_bound(applied_.begin(), applied_.end(), t,
                                   [](double x, const std::pair<double, double>& a) { return x < a.first; });
  return it == applied_.begin() ? 0.0 : std::prev(it)->second;
}

}  // namespace mc::sim
