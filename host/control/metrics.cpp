#include "host/control/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mc::host {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

struct Accum {
  double s2 = 0, mx = 0;
  size_t n = 0;
  void add(double d) {
    s2 += d * d;
    mx = std::max(mx, d);
    ++n;
  }
  ErrorStats stats() const { return {n ? std::sqrt(s2 / double(n)) : 0.0, mx, n}; }
};

double hypot2(Point2 a, Point2 b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

}  // namespace

ErrorStats following_error(std::span<const double> t, std::span<const double> cmd,
                           std::span<const double> actual, double t0, double t1) {
  if (t.size() != cmd.size() || t.size() != actual.size()) {
    throw std::invalid_argument("following_error: t, cmd and actual differ in length (" +
                                std::to_string(t.size()) + ", " + std::to_string(cmd.size()) + ", " +
                                std::to_string(actual.size()) + ")");
  }
  Accum a;
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i] >= t0 && t[i] <= t1) a.add(std::abs(cmd[i] - actual[i]));
  }
  return a.stats();
}

double distance(const Segment& s, Point2 p) {
  const double dx = s.b.x - s.a.x, dy = s.b.y - s.a.y;
  const double len2 = dx * dx + dy * dy;
  if (len2 == 0) return hypot2(p, s.a);
  const double u = std::clamp(((p.x - s.a.x) * dx + (p.y - s.a.y) * dy) / len2, 0.0, 1.0);
  return hypot2(p, Point2{s.a.x + u * dx, s.a.y + u * dy});
}

double distance(const Arc& a, Point2 p) {
  const double radial = std::abs(hypot2(p, a.c) - a.r);
  if (std::abs(a.sweep_rad) >= kTwoPi) return radial;
  // Angle of p measured from the start in the sweep's direction, in [0, 2 pi).
  const double dir = a.sweep_rad < 0 ? -1.0 : 1.0;
  double rel = dir * (std::atan2(p.y - a.c.y, p.x - a.c.x) - a.start_rad);
  rel = std::fmod(rel, kTwoPi);
  if (rel < 0) rel += kTwoPi;
  if (p.x == a.c.x && p.y == a.c.y) return a.r;  // the centre: every point of the arc is r away
  if (rel <= std::abs(a.sweep_rad)) return radial;
  const double e = a.start_rad + a.sweep_rad;
  const Point2 s0{a.c.x + a.r * std::cos(a.start_rad), a.c.y + a.r * std::sin(a.start_rad)};
  const Point2 s1{a.c.x + a.r * std::cos(e), a.c.y + a.r * std::sin(e)};
  return std::min(hypot2(p, s0), hypot2(p, s1));
}

double distance(const std::vector<PathPiece>& path, Point2 p) {
  if (path.empty()) throw std::invalid_argument("contour error: empty path");
  double d = std::numeric_limits<double>::infinity();
  for (const PathPiece& piece : path)
    d = std::min(d, std::visit([&](const auto& x) { return distance(x, p); }, piece));
  return d;
}

ErrorStats contour_error(const std::vector<Point2>& actual, const std::vector<PathPiece>& path) {
  if (path.empty()) throw std::invalid_argument("contour error: empty path");
  Accum a;
  for (const Point2& p : actual) a.add(distance(path, p));
  return a.stats();
}

}  // namespace mc::host
