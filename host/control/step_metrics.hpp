// Step-response metrics for `motionctl step` and for the predictions of
// `motionctl tune`: rise time, overshoot, 2 % settling time, steady-state
// error and IAE of a sampled response y(t) to a step of size S applied at t0
// from the level y0. Any consistent units (counts and seconds on the host).
//
// A metric the response never reaches is NaN with its flag false (rose,
// settled), never a number that looks like a measurement: a loop that does not
// reach 90 % of the step has no rise time, one that is still outside the band
// at the end of the capture has no settling time.
#pragma once

#include <span>
#include <vector>

namespace mc::host {

struct StepMetrics {
  double rise_s;         // 10 % to 90 % of S, first crossings, interpolated; NaN unless rose
  double overshoot_pct;  // (peak - S) / S * 100 after t0, 0 when the response never passes S
  double peak_s;         // time of the peak after t0 (of the largest y - y0 in the direction of S)
  double settling_s;     // after t0, when the response last entered the band; NaN unless settled
  double ss_error;       // mean of S - (y - y0) over the last 10 % of the samples after t0
  double iae;            // integral of |S - (y - y0)| dt from t0, trapezoid
  bool rose;             // reached 90 % of S
  bool settled;          // inside the band at the end of the capture
};

// t strictly increasing, the same length as y, at least two samples at or
// after t0; step nonzero (either sign); band a fraction of |S| in (0, 1).
// Samples before t0 are ignored. Throws InputError otherwise.
StepMetrics step_metrics(std::span<const double> t, std::span<const double> y, double y0, double step,
                         double t0, double band = 0.02);

}  // namespace mc::host
