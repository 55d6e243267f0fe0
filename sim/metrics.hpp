// Benchmark metrics: pure functions on sampled traces, doubles in metres and
// seconds (any consistent units work).
#pragma once

#include <cstddef>
#include <limits>
#include <variant>
#include <vector>

namespace mc::sim {

struct ErrorStats {
  double rms = 0, max = 0;
  size_t n = 0;  // samples that entered the statistics
};

// Following error of one axis: |cmd - actual| at each sample with t in
// [t0, t1]. The three vectors have the same length (else std::invalid_argument).
ErrorStats following_error(const std::vector<double>& t, const std::vector<double>& cmd,
                           const std::vector<double>& actual,
                           double t0 = -std::numeric_limits<double>::infinity(),
                           double t1 = std::numeric_limits<double>::infinity());

struct Point2 {
  double x = 0, y = 0;
};
struct Segment {
  Point2 a, b;
};
// Circle centre c, radius r; the arc starts at angle start_rad (from +x,
// counter-clockwise) and sweeps sweep_rad (negative: clockwise). |sweep| >=
// 2 pi is the full circle.
struct Arc {
  Point2 c;
  double r = 0, start_rad = 0, sweep_rad = 0;
};
using PathPiece = std::variant<Segment, Arc>;

// Point-to-segment distance (to the line between the ends, else the nearest end).
double distance(const Segment& s, Point2 p);
// | |p - c| - r | when p's angle lies within the arc's span, else the
// distance to the nearer end point.
double distance(const Arc& a, Point2 p);
// The distance to the nearest piece of a path.
double distance(const std::vector<PathPiece>& path, Point2 p);

// Contour error: RMS and max of the distance of each actual point from the
// ideal path (std::invalid_argument for an empty path).
ErrorStats contour_error(const std::vector<Point2>& actual, const std::vector<PathPiece>& path);

struct StepMetrics {
  double rise_time;           // 10 % to 90 % of the step, interpolated; NaN if never reached
  double overshoot_pct;       // (peak - S) / S * 100, 0 when it never exceeds S
  double settling_time;       // after t[0], last time outside the band; NaN if still outside at the end
  double steady_state_error;  // mean of S - y over the final 10 % of the samples
  double iae;                 // integral of |S - y| dt, trapezoid
};

// Step response y(t) to a step of size S (nonzero) applied at t[0]; the band
// is a fraction of |S| (2 % by default). At least two samples, t increasing.
StepMetrics step_metrics(const std::vector<double>& t, const std::vector<double>& y, double step,
                         double band = 0.02);

}  // namespace mc::sim
