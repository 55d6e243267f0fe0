#include "host/control/step_metrics.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "host/base/errors.hpp"

namespace mc::host {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The time at which x first reaches level (x rising through it), linearly
// interpolated between samples i-1 and i; NaN if it never does. Starts at
// sample `from`.
double first_reach(std::span<const double> t, std::span<const double> x, size_t from, double level) {
  if (x[from] >= level) return t[from];
  for (size_t i = from + 1; i < x.size(); ++i) {
    if (x[i] >= level) {
      const double f = (level - x[i - 1]) / (x[i] - x[i - 1]);
      return t[i - 1] + f * (t[i] - t[i - 1]);
    }
  }
  return kNaN;
}

}  // namespace

StepMetrics step_metrics(std::span<const double> t, std::span<const double> y, double y0, double step,
                         double t0, double band) {
  if (t.size() != y.size())
    throw InputError("step capture",
                     std::to_string(t.size()) + " times, " + std::to_string(y.size()) + " values",
                     "as many times as values");
  if (!std::isfinite(step) || step == 0)
    throw InputError("step size", format_number(step), "a finite nonzero step");
  if (!(band > 0 && band < 1)) throw InputError("settling band", format_number(band), "a fraction in (0, 1)");
  if (!std::isfinite(y0) || !std::isfinite(t0))
    throw InputError("step start", format_number(y0) + " at " + format_number(t0), "a finite level and time");
  for (size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(y[i]))
      throw InputError("step capture sample " + std::to_string(i),
                       format_number(y[i]) + " at " + format_number(t[i]), "finite times and values");
    if (i > 0 && !(t[i] > t[i - 1]))
      throw InputError("step capture time " + std::to_string(i), format_number(t[i]),
                       "strictly increasing times (previous " + format_number(t[i - 1]) + ")");
  }
  size_t first = 0;
  while (first < t.size() && t[first] < t0) ++first;
  if (t.size() - first < 2)
    throw InputError("step capture", std::to_string(t.size() - first) + " samples at or after t0",
                     "at least 2 samples from the step on");

  // Normalized to a unit step: one code path for either sign of S.
  std::vector<double> yn(y.size());
  for (size_t i = 0; i < y.size(); ++i) yn[i] = (y[i] - y0) / step;

  StepMetrics m{};
  const double t10 = first_reach(t, yn, first, 0.1);
  const double t90 = std::isnan(t10) ? kNaN : first_reach(t, yn, first, 0.9);
  m.rose = !std::isnan(t90);
  m.rise_s = m.rose ? t90 - t10 : kNaN;

  size_t ipeak = first;
  for (size_t i = first; i < yn.size(); ++i)
    if (yn[i] > yn[ipeak]) ipeak = i;
  m.overshoot_pct = yn[ipeak] > 1 ? 100 * (yn[ipeak] - 1) : 0.0;
  m.peak_s = t[ipeak] - t0;

  const auto outside = [&](size_t i) { return std::fabs(yn[i] - 1) > band; };
  const size_t last = yn.size() - 1;
  m.settled = !outside(last);
  if (!m.settled) {
    m.settling_s = kNaN;
  } else {
    size_t out = last;
    while (out > first && !outside(out - 1)) --out;
    if (out == first && !outside(first)) {
      m.settling_s = t[first] - t0;  // inside from the first sample on
    } else {
      // out - 1 is the last sample outside: interpolate to the band's edge.
      const size_t o = out - 1;
      const double edge = yn[o] > 1 ? 1 + band : 1 - band;
      const double f = (edge - yn[o]) / (yn[out] - yn[o]);
      m.settling_s = t[o] + f * (t[out] - t[o]) - t0;
    }
  }

  const size_t n = yn.size() - first;
  const size_t tail = n / 10 > 0 ? n / 10 : 1;
  double sum = 0;
  for (size_t i = yn.size() - tail; i < yn.size(); ++i) sum += 1 - yn[i];
  m.ss_error = step * sum / double(tail);

  double iae = 0;
  for (size_t i = first + 1; i < yn.size(); ++i)
    iae += 0.5 * (std::fabs(1 - yn[i - 1]) + std::fabs(1 - yn[i])) * (t[i] - t[i - 1]);
  m.iae = std::fabs(step) * iae;
  return m;
}

}  // namespace mc::host
