#include "host/motion/interp_plan.hpp"

#include <cmath>
#include <cstdlib>
#include <string>

#include "hls/arc_interp.hpp"
#include "hls/line_interp.hpp"
#include "host/base/errors.hpp"

namespace mc::host {
namespace {

constexpr double kTwoPowPh = 281474976710656.0;  // 2^PH_W
// The core runs at most one iteration per tick of 2^TICK_LOG2 clocks, so a
// rate word must stay below 2^(PH_W - TICK_LOG2).
constexpr double kIncMax = kTwoPowPh / double(1 << seg::TICK_LOG2);
constexpr int64_t kArcMax = (int64_t(1) << (seg::ARC_W - 1)) - 2;
constexpr int64_t kNMax = (int64_t(1) << seg::N_W) - 1;

std::string num(int64_t v) {
  return std::to_string(v);
}
std::string point(int64_t x, int64_t y) {
  return "(" + num(x) + ", " + num(y) + ")";
}

void check_feed(double feed) {
  if (!(feed > 0) || !std::isfinite(feed))
    throw InputError("feed", format_number(feed), "a positive number of counts per second");
}

}  // namespace

double max_iteration_rate(double clk_hz) {
  return clk_hz / double(1 << seg::TICK_LOG2);
}

namespace {

// Rate word for f iterations per second; 0 < inc < kIncMax.
uint64_t rate_word(double f, double clk_hz, const char* what) {
  const double inc = std::round(f / clk_hz * kTwoPowPh);
  if (inc >= kIncMax)
    throw InputError(what, format_number(f) + " iterations/s",
                     "less than " + format_number(max_iteration_rate(clk_hz)) +
                         " iterations/s (the core runs one iteration per " +
                         std::to_string(1 << seg::TICK_LOG2) + " clocks at most)",
                     "feed too high");
  if (inc < 1)
    throw InputError(what, format_number(f) + " iterations/s",
                     "at least " + format_number(clk_hz / kTwoPowPh) + " iterations/s", "feed too low");
  return uint64_t(inc);
}

// Where the walk leaves quadrant q.
std::array<int64_t, 2> quadrant_exit(int q, bool ccw, int64_t c) {
  static constexpr int CCW[4][2] = {{0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  static constexpr int CW[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
  const int(*t)[2] = ccw ? CCW : CW;
  return {t[q][0] * c, t[q][1] * c};
}

// e lies ahead of p (or is p) on a walk making the moves of m.
bool ahead(int64_t px, int64_t py, int64_t ex, int64_t ey, const ArcQuadrant& m) {
  return (ex - px) * m.mx >= 0 && (ey - py) * m.my >= 0;
}

}  // namespace

int64_t arc_axis_crossing(int64_t r2) {
  auto c = int64_t(std::sqrt(double(r2)));
  while (c * c > r2) --c;
  while ((c + 1) * (c + 1) <= r2) ++c;
  return r2 > c * c + c ? c + 1 : c;
}

ArcGeometry arc_geometry(int64_t x0, int64_t y0, int64_t xe, int64_t ye, bool ccw, int64_t r2) {
  ArcGeometry g;
  g.x0 = x0;
  g.y0 = y0;
  g.xe = xe;
  g.ye = ye;
  const int64_t lim = kArcMax;
  for (const int64_t v : {x0, y0, xe, ye}) {
    if (std::llabs(v) > lim)
      throw InputError("arc radius", num(std::llabs(v)) + " counts", "at most " + num(lim) + " counts",
                       "start or end too far from the centre");
  }
  g.r2 = r2 > 0 ? r2 : x0 * x0 + y0 * y0;
  if (g.r2 == 0) throw InputError("arc radius", "0", "a start point away from the centre", "zero radius");
  g.radius = std::sqrt(double(g.r2));
  g.d0 = x0 * x0 + y0 * y0 - g.r2;
  const double rs = std::sqrt(double(x0 * x0 + y0 * y0));
  if (std::fabs(rs - g.radius) > 1.0)
    throw InputError("arc start point", point(x0, y0) + " relative to the centre",
                     "a point within one step of the circle of radius " + format_number(g.radius),
                     "it is " + format_number(rs - g.radius) + " steps off the circle");
  const double re = std::sqrt(double(xe * xe + ye * ye));
  if (std::fabs(re - g.radius) > 1.0)
    throw InputError("arc end point", point(xe, ye) + " relative to the centre",
                     "a point within one step of the circle of radius " + format_number(g.radius),
                     "it is " + format_number(re - g.radius) + " steps off the circle");
  g.crossing = arc_axis_crossing(g.r2);
  const ArcQuadrant qs = arc_quadrant(x0, y0, ccw), qe = arc_quadrant(xe, ye, ccw);
  g.q0 = qs.q;
  g.qf = qe.q;
  const int k = ((ccw ? g.qf - g.q0 : g.q0 - g.qf) + 4) % 4;
  const bool same_point = x0 == xe && y0 == ye;
  g.nq = k != 0 ? k : ((!same_point && ahead(x0, y0, xe, ye, qs)) ? 0 : 4);

  // Steps: |dx| + |dy| over each quadrant piece the walk runs through.
  int64_t px = x0, py = y0;
  int q = g.q0;
  for (int i = 0; i < g.nq; ++i) {
    const auto ex = quadrant_exit(q, ccw, g.crossing);
    g.n += std::llabs(ex[0] - px) + std::llabs(ex[1] - py);
    px = ex[0];
    py = ex[1];
    q = (q + (ccw ? 1 : 3)) % 4;
  }
  if (!ahead(px, py, xe, ye, qe))
    throw InputError("arc end point", point(xe, ye) + " relative to the centre",
                     "a point the stairs path reaches from " + point(px, py) + " in its quadrant",
                     "it lies behind the path in one axis");
  g.n += std::llabs(xe - px) + std::llabs(ye - py);
  if (g.n > kNMax) throw InputError("arc steps", num(g.n), "at most " + num(kNMax));

  double a0 = std::atan2(double(y0), double(x0)), a1 = std::atan2(double(ye), double(xe));
  double sweep = ccw ? a1 - a0 : a0 - a1;
  while (sweep < 0) sweep += 2 * M_PI;
  if (g.nq == 4 && sweep < M_PI) sweep += 2 * M_PI;  // full circle (or nearly)
  g.sweep = sweep;
  return g;
}

PlannedSegment plan_line(const Vec3& from, const Vec3& to, double feed, double clk_hz) {
  check_feed(feed);
  PlannedSegment p;
  p.start = from;
  p.end = to;
  seg::Segment& s = p.seg;
  s.type = seg::T_LINE;
  double l2 = 0;
  int64_t n = 0;
  for (int a = 0; a < 3; ++a) {
    const int64_t d = to[a] - from[a];
    const int64_t m = std::llabs(d);
    if (m > kNMax)
      throw InputError("line move on axis " + std::string(1, "xyz"[a]), num(d) + " counts",
                       "at most " + num(kNMax) + " counts per segment", "split the move");
    s.d[a] = uint32_t(m);
    if (d < 0) s.neg |= 1 << a;
    n = m > n ? m : n;
    l2 += double(d) * double(d);
  }
  s.n = uint32_t(n);
  p.length = std::sqrt(l2);
  p.duration = p.length / feed;
  if (n > 0) {
    // N iterations over the length at the feed: f = feed * N / L.
    const double f = feed * double(n) / p.length;
    s.inc = rate_word(f, clk_hz, "line iteration rate");
    p.feed_rel_error = double(s.inc) / (f / clk_hz * kTwoPowPh) - 1;
  }
  return p;
}

PlannedSegment plan_arc(const Vec3& from, const Vec3& to, const std::array<int64_t, 2>& centre, bool ccw,
                        double feed, int plane, double clk_hz) {
  check_feed(feed);
  if (plane < 0 || plane > 2) throw InputError("arc plane", num(plane), "0 (XY), 1 (ZX) or 2 (YZ)");
  const int ax = seg::PLANE_AXES[plane][0], ay = seg::PLANE_AXES[plane][1], az = 3 - ax - ay;
  if (from[az] != to[az])
    throw InputError("arc end point", "axis " + std::string(1, "xyz"[az]) + " = " + num(to[az]),
                     num(from[az]) + ", the start's value (helical arcs are not supported)");
  const ArcGeometry g =
      arc_geometry(from[ax] - centre[0], from[ay] - centre[1], to[ax] - centre[0], to[ay] - centre[1], ccw);
  PlannedSegment p;
  p.start = from;
  p.end = to;
  p.arc = g;
  p.length = g.radius * g.sweep;
  p.duration = p.length / feed;
  seg::Segment& s = p.seg;
  s.type = seg::T_ARC;
  s.ccw = ccw;
  s.plane = plane;
  s.nq = g.nq;
  s.n = uint32_t(g.n);
  s.x0 = int32_t(g.x0);
  s.y0 = int32_t(g.y0);
  s.xe = int32_t(g.xe);
  s.ye = int32_t(g.ye);
  s.d0 = int32_t(g.d0);
  // Iteration rate f = feed * (|x| + |y|) / R, i.e. inc = k * (|x| + |y|).
  const double k = feed / (g.radius * clk_hz) * kTwoPowPh;
  const double kr = std::round(k);
  // The walk stays within one step of the circle, so |x| + |y| <= sqrt(2) (R + 1).
  const int64_t smax = int64_t(std::ceil(std::sqrt(2.0) * (g.radius + 1)));
  if (kr < 1)
    throw InputError(
        "feed", format_number(feed) + " counts/s",
        "at least " + format_number(0.5 * g.radius * clk_hz / kTwoPowPh) + " counts/s on this arc",
        "feed too low for the rate word");
  if (kr * double(smax) >= kIncMax)
    throw InputError("feed", format_number(feed) + " counts/s",
                     "less than " + format_number(max_iteration_rate(clk_hz) / std::sqrt(2.0)) +
                         " counts/s (at 45 degrees that is " + format_number(max_iteration_rate(clk_hz)) +
                         " iterations/s, one per " + std::to_string(1 << seg::TICK_LOG2) +
                         " clocks, the core's most)",
                     "feed too high");
  s.k = uint64_t(kr);
  s.inc = s.k * uint64_t(std::llabs(g.x0) + std::llabs(g.y0));
  p.feed_rel_error = kr / k - 1;
  return p;
}

PlannedSegment plan_dwell(const Vec3& at, double seconds, double clk_hz) {
  constexpr double kDwellRate = 1e4;  // iterations/s: 100 us resolution
  if (!(seconds >= 0) || !std::isfinite(seconds))
    throw InputError("dwell", format_number(seconds) + " s", "a duration of 0 s or more");
  PlannedSegment p;
  p.start = p.end = at;
  const double n = std::round(seconds * kDwellRate);
  if (n > double(kNMax))
    throw InputError("dwell", format_number(seconds) + " s",
                     "at most " + format_number(double(kNMax) / kDwellRate) + " s per segment");
  p.seg.type = seg::T_DWELL;
  p.seg.n = uint32_t(n);
  p.seg.inc = rate_word(kDwellRate, clk_hz, "dwell rate");
  p.duration = n / kDwellRate;
  return p;
}

void walk(const PlannedSegment& p, const std::function<void(const Vec3&)>& visit) {
  const seg::Words w = seg::pack(p.seg);
  Vec3 pos = p.start;
  visit(pos);
  if (p.seg.type == seg::T_LINE) {
    LineInterp li;
    for (int i = 0; i < seg::SEG_WORDS; ++i) li.load(i, w[size_t(i)]);
    for (uint32_t k = 0; k < p.seg.n; ++k) {
      const int mv = li.moves();
      for (int a = 0; a < 3; ++a)
        if ((mv >> a) & 1) pos[size_t(a)] += ((li.neg() >> a) & 1) ? -1 : 1;
      li.iterate(mv);
      visit(pos);
    }
  } else if (p.seg.type == seg::T_ARC) {
    ArcInterp ai;
    for (int i = 0; i < seg::SEG_WORDS; ++i) ai.load(i, w[size_t(i)]);
    const int* axes = seg::PLANE_AXES[p.seg.plane];
    for (uint32_t k = 0; k < p.seg.n && !ai.fin(); ++k) {
      const ArcStep st = ai.step();
      pos[size_t(axes[st.movex ? 0 : 1])] += st.dir;
      ai.iterate(st);
      visit(pos);
    }
  }
}

}  // namespace mc::host
