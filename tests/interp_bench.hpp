// Test support for the interpolator: random segments planned on the host, and
// a checker that watches a position-command stream (from the twin or from the
// Verilated RTL) and asserts the path properties segment by segment:
//   - lines are 8-connected (26 in 3-D): each iteration moves each axis by at
//     most one count and the major axis by exactly one;
//   - arcs are 4-connected: one plane axis moves one count, the third not at
//     all, and every point is within one step of the true circle;
//   - the step count equals the formula (line: max|d|; arc: per quadrant
//     |dx| + |dy|), and the segment ends exactly on its end point;
//   - segments run in the order queued, none lost, none repeated;
//   - every point is the one the reference engines visit (host::walk runs
//     hls/line_interp.hpp and hls/arc_interp.hpp, the per-iteration models the
//     serial engine of interp_core replaced), so the path is exactly the old
//     one, step for step.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <deque>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "host/base/errors.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::test {

using host::PlannedSegment;
using host::Vec3;

constexpr double kClk = host::kDefaultClockHz;
const double kMaxRate = host::max_iteration_rate(kClk);  // iterations/s

struct SegGen {
  std::mt19937_64 rng;
  int64_t max_line = 300;  // counts per axis
  int64_t max_radius = 200;
  double min_rate = 0.15;  // peak iteration rate, fraction of the core's highest
  double max_rate = 0.6;
  bool dwells = true;
  bool planes = true;

  explicit SegGen(uint64_t seed) : rng(seed) {}

  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  int64_t irange(int64_t a, int64_t b) { return std::uniform_int_distribution<int64_t>(a, b)(rng); }

  PlannedSegment line(const Vec3& at) {
    Vec3 to = at;
    const int kind = int(irange(0, 3));  // 0: 3-D, 1: XY, 2: one axis, 3: short
    for (int a = 0; a < 3; ++a) {
      int64_t d = irange(-max_line, max_line);
      if (kind == 1 && a == 2) d = 0;
      if (kind == 2 && a != 0) d = 0;
      if (kind == 3) d = irange(-2, 2);
      to[size_t(a)] += d;
    }
    // Plan once for the geometry, then again at the feed that gives the
    // iteration rate drawn.
    const PlannedSegment g = host::plan_line(at, to, 1000.0, kClk);
    if (g.seg.n == 0) return g;
    const double f = uni(min_rate, max_rate) * kMaxRate;
    return host::plan_line(at, to, f * g.length / double(g.seg.n), kClk);
  }

  PlannedSegment arc(const Vec3& at) {
    for (;;) {
      const int plane = planes ? int(irange(0, 2)) : seg::PLANE_XY;
      const int ax = seg::PLANE_AXES[plane][0], ay = seg::PLANE_AXES[plane][1];
      // Radius log-uniform so that small circles (where the lattice matters
      // most) are well represented.
      const double r = std::exp(uni(0.0, std::log(double(max_radius))));
      const double a0 = uni(0, 2 * M_PI), a1 = uni(0, 2 * M_PI);
      const int64_t x0 = std::llround(r * std::cos(a0)), y0 = std::llround(r * std::sin(a0));
      if (x0 == 0 && y0 == 0) continue;
      const double rr = std::sqrt(double(x0 * x0 + y0 * y0));
      const bool full = irange(0, 9) == 0;
      const int64_t xe = full ? x0 : std::llround(rr * std::cos(a1));
      const int64_t ye = full ? y0 : std::llround(rr * std::sin(a1));
      const std::array<int64_t, 2> c{at[size_t(ax)] - x0, at[size_t(ay)] - y0};
      Vec3 to = at;
      to[size_t(ax)] = c[0] + xe;
      to[size_t(ay)] = c[1] + ye;
      // Peak rate feed*sqrt(2) at 45 degrees.
      const double feed = uni(min_rate, max_rate) * kMaxRate / std::sqrt(2.0);
      try {
        return host::plan_arc(at, to, c, irange(0, 1) == 1, feed, plane, kClk);
      } catch (const host::InputError&) {
        // An end point rounded onto the wrong side of the walk: draw again.
      }
    }
  }

  PlannedSegment dwell(const Vec3& at) { return host::plan_dwell(at, uni(0, 3e-4), kClk); }

  PlannedSegment any(const Vec3& at) {
    const int k = int(irange(0, 9));
    if (dwells && k == 0) return dwell(at);
    return k <= 4 ? line(at) : arc(at);
  }
};

// Watches pos/seg_cnt every cycle; the expected segments are queued with
// expect() in the order they were admitted to the core.
class PathChecker {
 public:
  explicit PathChecker(const Vec3& start) : pos_(start) {}

  void expect(const PlannedSegment& s) {
    q_.push_back(s);
    std::vector<Vec3> pts;
    host::walk(s, [&](const Vec3& v) { pts.push_back(v); });
    ref_.push_back(std::move(pts));
  }
  int checked() const { return checked_; }
  int64_t steps() const { return total_steps_; }
  size_t pending() const { return q_.size(); }
  bool failed() const { return failures_ > 0; }

  void observe(const Vec3& pos, int seg_cnt) {
    if (failures_ > 5) return;  // one bug, one report: stop after a few
    if (pos != pos_) on_move(pos);
    if (seg_cnt != last_cnt_) {
      if (((last_cnt_ + 1) & 0xFFFF) != seg_cnt)
        fail("segment count jumped from " + std::to_string(last_cnt_));
      last_cnt_ = seg_cnt;
      on_segment_end();
    }
  }

 private:
  std::string where() const {
    std::ostringstream os;
    os << "segment #" << checked_ << " at step " << steps_ << ", pos (" << pos_[0] << ", " << pos_[1] << ", "
       << pos_[2] << ")";
    if (!q_.empty()) {
      const PlannedSegment& s = q_.front();
      os << ", type " << s.seg.type << " from (" << s.start[0] << ", " << s.start[1] << ", " << s.start[2]
         << ") to (" << s.end[0] << ", " << s.end[1] << ", " << s.end[2] << ") n " << s.seg.n;
    }
    return os.str();
  }
  void fail(const std::string& what) {
    ++failures_;
    ADD_FAILURE() << what << " [" << where() << "]";
  }

  void on_move(const Vec3& to) {
    if (q_.empty()) {
      fail("the position moved with no segment queued");
      pos_ = to;
      return;
    }
    const PlannedSegment& s = q_.front();
    int moved = 0;
    for (int a = 0; a < 3; ++a) {
      const int64_t d = to[size_t(a)] - pos_[size_t(a)];
      if (d < -1 || d > 1) fail("axis " + std::to_string(a) + " jumped by " + std::to_string(d));
      moved += d != 0;
    }
    if (s.seg.type == seg::T_DWELL) fail("a dwell moved");
    if (s.seg.type != seg::T_DWELL) {
      const std::vector<Vec3>& ref = ref_.front();
      const size_t k = size_t(steps_) + 1;
      if (k >= ref.size())
        fail("more steps than the reference path");
      else if (ref[k] != to)
        fail("step " + std::to_string(k) + " differs from the reference path");
    }
    if (s.seg.type == seg::T_LINE) {
      // Bresenham: the minor axes sit within half a count of the ideal line.
      ++steps_;
      const double k = double(steps_) / double(s.seg.n);
      for (int a = 0; a < 3; ++a) {
        const double ideal = double(s.start[size_t(a)]) + k * double(s.end[size_t(a)] - s.start[size_t(a)]);
        if (std::fabs(double(to[size_t(a)]) - ideal) > 0.5 + 1e-9)
          fail("line point off the ideal line by more than half a count on axis " + std::to_string(a));
      }
    }
    if (s.seg.type == seg::T_ARC) {
      ++steps_;
      if (moved != 1) fail("arc step moved " + std::to_string(moved) + " axes");
      const int ax = seg::PLANE_AXES[s.seg.plane][0], ay = seg::PLANE_AXES[s.seg.plane][1], az = 3 - ax - ay;
      if (to[size_t(az)] != s.start[size_t(az)]) fail("arc moved the axis normal to its plane");
      const double cx = double(s.start[size_t(ax)] - s.seg.x0), cy = double(s.start[size_t(ay)] - s.seg.y0);
      const double r0 = std::sqrt(double(s.seg.x0) * s.seg.x0 + double(s.seg.y0) * s.seg.y0 - s.seg.d0);
      const double r = std::hypot(double(to[size_t(ax)]) - cx, double(to[size_t(ay)]) - cy);
      if (std::fabs(r - r0) > 1.0) fail("arc point " + std::to_string(r - r0) + " steps off the circle");
    }
    pos_ = to;
  }

  void on_segment_end() {
    if (q_.empty()) {
      fail("a segment ended that was never admitted");
      return;
    }
    const PlannedSegment& s = q_.front();
    if (pos_ != s.end) fail("segment ended off its end point");
    if (s.seg.type != seg::T_DWELL && steps_ != int64_t(s.seg.n))
      fail("segment took " + std::to_string(steps_) + " steps, the formula says " + std::to_string(s.seg.n));
    total_steps_ += steps_;
    steps_ = 0;
    ++checked_;
    q_.pop_front();
    ref_.pop_front();
  }

  std::deque<PlannedSegment> q_;
  std::deque<std::vector<Vec3>> ref_;  // each segment's points, from host::walk
  Vec3 pos_;
  int last_cnt_ = 0;
  int64_t steps_ = 0, total_steps_ = 0;
  int checked_ = 0;
  int failures_ = 0;
};

}  // namespace mc::test
