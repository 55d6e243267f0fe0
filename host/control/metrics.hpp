// Tracking metrics (the benchmark's and the board captures'): pure functions on sampled traces, doubles in
// metres and seconds (any consistent units work).
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <variant>
#include <vector>

namespace mc::host {

struct ErrorStats {
  double rms = 0, max = 0;
  size_t n = 0;  // samples that entered the statistics
};

// Following error of one axis: |cmd - actual| at each sample with t in
// [t0, t1]. The three vectors have the same length (else std::invalid_argument).
ErrorStats following_error(std::span<const double> t, std::span<const double> cmd,
                           std::span<const double> actual,
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

}  // namespace mc::host
