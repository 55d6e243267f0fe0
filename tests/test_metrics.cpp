// Tracking metrics against analytic cases (step metrics: test_step_metrics.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "host/control/metrics.hpp"

namespace mc::host {
namespace {

struct Trace {
  std::vector<double> t, y;
};

template <typename F>
Trace sample(F f, double t_end, double dt) {
  Trace r;
  const auto n = size_t(std::llround(t_end / dt));
  for (size_t i = 0; i <= n; ++i) {
    r.t.push_back(double(i) * dt);
    r.y.push_back(f(double(i) * dt));
  }
  return r;
}

TEST(Metrics, FollowingErrorOfASinusoid) {
  const double a = 3e-5;
  const Trace cmd = sample([&](double t) { return a * std::sin(2 * M_PI * 5 * t); }, 1.0, 1e-4);
  const std::vector<double> actual(cmd.t.size(), 0.0);
  const ErrorStats e = following_error(cmd.t, cmd.y, actual, 0, 1.0 - 1e-9);  // whole periods
  EXPECT_NEAR(e.rms, a / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(e.max, a, 1e-12);
  EXPECT_EQ(e.n, 10000u);
  // The window: half a period of |sin| from t = 0.
  const ErrorStats w = following_error(cmd.t, cmd.y, actual, 0.0, 0.1 - 1e-9);
  EXPECT_EQ(w.n, 1000u);
  const std::vector<double> one{0.0};
  EXPECT_THROW(following_error(cmd.t, cmd.y, one), std::invalid_argument);
}

TEST(Metrics, ContourErrorFromLines) {
  const Segment s{{0, 0}, {3, 4}};  // unit normal (-0.8, 0.6)
  EXPECT_NEAR(distance(s, {1.5 - 0.8 * 0.1, 2 + 0.6 * 0.1}), 0.1, 1e-12);
  EXPECT_NEAR(distance(s, {-0.3, -0.4}), 0.5, 1e-12);  // before the start: to the end point
  EXPECT_NEAR(distance(s, {6, 8}), 5, 1e-12);
  EXPECT_NEAR(distance(Segment{{1, 1}, {1, 1}}, {4, 5}), 5, 1e-12);
  // Points at alternating distances 1e-6 and 3e-6 either side of the line.
  std::vector<Point2> pts;
  for (int i = 0; i < 100; ++i) {
    const double d = (i % 2 ? 3e-6 : 1e-6) * (i % 3 ? 1 : -1);
    pts.push_back({0.03 * i - 0.8 * d, 0.04 * i + 0.6 * d});
  }
  const ErrorStats e = contour_error(pts, {s});
  EXPECT_NEAR(e.rms, std::sqrt((1e-12 + 9e-12) / 2), 1e-15);
  EXPECT_NEAR(e.max, 3e-6, 1e-15);
}

TEST(Metrics, ContourErrorFromCirclesAndArcs) {
  const Arc circle{{1, 2}, 0.5, 0, 2 * M_PI};
  for (int i = 0; i < 36; ++i) {
    const double th = i * M_PI / 18, r = 0.5 + (i % 2 ? 1e-4 : -2e-4);
    EXPECT_NEAR(distance(circle, {1 + r * std::cos(th), 2 + r * std::sin(th)}), i % 2 ? 1e-4 : 2e-4, 1e-12);
  }
  EXPECT_NEAR(distance(circle, {1, 2}), 0.5, 1e-12);
  // Quarter arc from 0 to pi/2, counter-clockwise, about the origin, r = 1.
  const Arc q{{0, 0}, 1, 0, M_PI / 2};
  EXPECT_NEAR(distance(q, {0.9 * std::cos(0.3), 0.9 * std::sin(0.3)}), 0.1, 1e-12);
  EXPECT_NEAR(distance(q, {-1, 0}), std::sqrt(2.0), 1e-12);  // outside the span: nearer end (0, 1)
  EXPECT_NEAR(distance(q, {0, -2}), std::sqrt(5.0), 1e-12);  // nearer end (1, 0)
  // The same quarter traced clockwise from pi/2: the same set of points.
  const Arc qcw{{0, 0}, 1, M_PI / 2, -M_PI / 2};
  EXPECT_NEAR(distance(qcw, {0.9 * std::cos(0.3), 0.9 * std::sin(0.3)}), 0.1, 1e-12);
  EXPECT_NEAR(distance(qcw, {-1, 0}), std::sqrt(2.0), 1e-12);
  // A path of two pieces: the nearer one counts.
  const std::vector<PathPiece> path{Segment{{-2, 0}, {0, 0}}, q};
  EXPECT_NEAR(distance(path, {-1, 0.25}), 0.25, 1e-12);
  EXPECT_THROW(contour_error({}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace mc::host
