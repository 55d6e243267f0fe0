#include "host/motion/planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

#include "host/base/errors.hpp"

namespace mc::host {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
constexpr char kAxisName[] = "XYZ";
// The core takes at most 2^26 - 1 counts per line segment; cruise pieces
// longer than this are split.
constexpr int64_t kSegMax = (int64_t(1) << seg::N_W) / 2;
// Stay a little below the core's top iteration rate.
constexpr double kRateMargin = 0.95;
// How an axis's acceleration limit is shared. The command is a staircase of
// constant-feed pieces and its acceleration is measured as the average over
// accel_window_s (peak_accel). Within one window an axis can see a ramp on
// each side of a junction plus the velocity steps of the junctions in it, so
// ramps and arcs get kRampShare of the limit and the steps at junctions
// kCornerShare; 2 % of the ramps' share is kept back for the staircase's
// chord error and the rounding to counts (test_planner measures the sum on
// random programs).
constexpr double kCornerShare = 0.25;
constexpr double kAccelMargin = 0.98 * (1 - kCornerShare);

Vec3d sub(const Vec3d& a, const Vec3d& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
double dot(const Vec3d& a, const Vec3d& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
double norm(const Vec3d& a) {
  return std::sqrt(dot(a, a));
}

std::string line_ref(const std::string& file, int line) {
  return file.empty() ? "line " + std::to_string(line) : file + ":" + std::to_string(line);
}

// In-plane angle of p about the arc's centre.
double angle_of(const Move& m, const Vec3d& p) {
  const gcode::PlaneAxes ax = gcode::plane_axes(m.plane);
  return std::atan2(p[size_t(ax.second)] - m.centre[size_t(ax.second)],
                    p[size_t(ax.first)] - m.centre[size_t(ax.first)]);
}
double radius_of(const Move& m, const Vec3d& p) {
  const gcode::PlaneAxes ax = gcode::plane_axes(m.plane);
  return std::hypot(p[size_t(ax.first)] - m.centre[size_t(ax.first)],
                    p[size_t(ax.second)] - m.centre[size_t(ax.second)]);
}
// The point of an arc at swept angle phi (0..sweep) from its start; the
// radius goes linearly from the start's to the end's, so that both ends are
// exact even when a program's end point is a little off the circle.
Vec3d arc_point(const Move& m, double phi) {
  const gcode::PlaneAxes ax = gcode::plane_axes(m.plane);
  const double a0 = angle_of(m, m.start);
  const double r0 = radius_of(m, m.start), r1 = radius_of(m, m.end);
  const double f = m.sweep > 0 ? phi / m.sweep : 0;
  const double r = r0 + (r1 - r0) * f;
  const double a = m.clockwise ? a0 - phi : a0 + phi;
  Vec3d p = m.start;
  p[size_t(ax.first)] = m.centre[size_t(ax.first)] + r * std::cos(a);
  p[size_t(ax.second)] = m.centre[size_t(ax.second)] + r * std::sin(a);
  p[size_t(ax.normal)] = m.start[size_t(ax.normal)];
  return p;
}
// The swept angle of p along the arc, from its start (0..2 pi + turns).
double swept_to(const Move& m, const Vec3d& p, double near_phi) {
  const double a0 = angle_of(m, m.start);
  double d = m.clockwise ? a0 - angle_of(m, p) : angle_of(m, p) - a0;
  // The branch nearest the angle expected there.
  d += 2 * kPi * std::round((near_phi - d) / (2 * kPi));
  return d;
}

// Expands [lo, hi] to hold every point of a motion move.
void extend_box(const Move& m, Vec3d& lo, Vec3d& hi) {
  auto add = [&](const Vec3d& p) {
    for (size_t k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  };
  add(m.start);
  add(m.end);
  if (m.kind != Move::Kind::arc) return;
  // The arc's extremes lie where it crosses the plane's axis directions.
  const double a0 = angle_of(m, m.start);
  for (int q = -8; q <= 8; ++q) {
    const double a = q * kPi / 2;
    const double phi = m.clockwise ? a0 - a : a - a0;
    if (phi > 0 && phi < m.sweep) add(arc_point(m, phi));
  }
}

struct Profile {
  double v0, vc, v1, a, len;
  double ta, tc, tb, sa, sb;
};
Profile profile(const Move& m) {
  Profile p{};
  p.v0 = m.v_entry;
  p.v1 = m.v_exit;
  p.a = m.accel;
  p.len = m.length;
  p.vc = std::min(m.v_nominal, std::sqrt((2 * p.a * p.len + p.v0 * p.v0 + p.v1 * p.v1) / 2));
  p.vc = std::max({p.vc, p.v0, p.v1});
  p.sa = (p.vc * p.vc - p.v0 * p.v0) / (2 * p.a);
  p.sb = (p.vc * p.vc - p.v1 * p.v1) / (2 * p.a);
  // Rounding can leave the ramps a hair longer than the move.
  const double over = p.sa + p.sb - p.len;
  if (over > 0) {
    p.sa = std::max(0.0, p.sa - over / 2);
    p.sb = std::max(0.0, p.len - p.sa);
  }
  p.ta = (p.vc - p.v0) / p.a;
  p.tb = (p.vc - p.v1) / p.a;
  p.tc = p.vc > 0 ? std::max(0.0, p.len - p.sa - p.sb) / p.vc : 0;
  return p;
}
double total_time(const Profile& p) {
  return p.ta + p.tc + p.tb;
}
// Distance at time t and time at distance s along the profile.
double s_at(const Profile& p, double t) {
  if (t <= 0) return 0;
  if (t < p.ta) return p.v0 * t + 0.5 * p.a * t * t;
  t -= p.ta;
  if (t < p.tc) return p.sa + p.vc * t;
  t -= p.tc;
  t = std::min(t, p.tb);
  return std::min(p.len, p.sa + p.vc * p.tc + p.vc * t - 0.5 * p.a * t * t);
}
double t_at(const Profile& p, double s) {
  s = std::clamp(s, 0.0, p.len);
  // Solve v0 t + a t^2 / 2 = s (and its mirror) the stable way.
  auto ramp_up = [](double v0, double a, double d) {
    const double disc = std::sqrt(std::max(0.0, v0 * v0 + 2 * a * d));
    return v0 + disc > 0 ? 2 * d / (v0 + disc) : 0.0;
  };
  if (s < p.sa) return ramp_up(p.v0, p.a, s);
  const double sc = p.len - p.sa - p.sb;
  if (s < p.sa + sc) return p.ta + (p.vc > 0 ? (s - p.sa) / p.vc : 0);
  // Decelerating: the time left to the end, from the end's side.
  const double left = std::max(0.0, p.len - s);
  return total_time(p) - ramp_up(p.v1, p.a, left);
}
double v_at(const Profile& p, double t) {
  if (t < p.ta) return p.v0 + p.a * t;
  if (t < p.ta + p.tc) return p.vc;
  return std::max(p.v1, p.vc - p.a * (t - p.ta - p.tc));
}

double core_rate_limit(const PlannerConfig& cfg) {
  return kRateMargin * max_iteration_rate(cfg.clock_hz);
}

}  // namespace

Vec3 to_counts(const Vec3d& p, const PlannerConfig& cfg) {
  Vec3 c{};
  for (size_t k = 0; k < 3; ++k)
    if (cfg.axes[k].present)
      c[k] = int64_t(std::llround(p[k] * cfg.axes[k].counts_per_mm)) + cfg.axes[k].origin;
  return c;
}

Vec3d to_mm(const Vec3& c, const PlannerConfig& cfg) {
  Vec3d p{};
  for (size_t k = 0; k < 3; ++k)
    if (cfg.axes[k].present) p[k] = double(c[k] - cfg.axes[k].origin) / cfg.axes[k].counts_per_mm;
  return p;
}

Vec3d tangent(const Move& m, bool at_end) {
  if (m.kind == Move::Kind::line) {
    Vec3d d = sub(m.end, m.start);
    const double l = norm(d);
    if (l > 0)
      for (double& v : d) v /= l;
    return d;
  }
  if (m.kind != Move::Kind::arc) return {};
  const gcode::PlaneAxes ax = gcode::plane_axes(m.plane);
  const Vec3d p = at_end ? m.end : m.start;
  const double rx = p[size_t(ax.first)] - m.centre[size_t(ax.first)];
  const double ry = p[size_t(ax.second)] - m.centre[size_t(ax.second)];
  const double r = std::hypot(rx, ry);
  Vec3d t{};
  // Counter-clockwise in (first, second): the radius turned by +90 degrees.
  const double s = m.clockwise ? -1 : 1;
  t[size_t(ax.first)] = -s * ry / r;
  t[size_t(ax.second)] = s * rx / r;
  return t;
}

Vec3d point_at(const Move& m, double s) {
  if (m.length <= 0) return m.start;
  s = std::clamp(s, 0.0, m.length);
  if (m.kind == Move::Kind::arc) return arc_point(m, m.sweep * s / m.length);
  Vec3d p;
  for (size_t k = 0; k < 3; ++k) p[k] = m.start[k] + (m.end[k] - m.start[k]) * s / m.length;
  return p;
}

double distance_to(const Move& m, const Vec3d& p) {
  if (m.kind == Move::Kind::arc) {
    const gcode::PlaneAxes ax = gcode::plane_axes(m.plane);
    const double phi = swept_to(m, p, m.sweep / 2);
    if (phi >= 0 && phi <= m.sweep) {
      const double r = m.radius + (radius_of(m, m.end) - m.radius) * phi / m.sweep;
      return std::hypot(radius_of(m, p) - r, p[size_t(ax.normal)] - m.start[size_t(ax.normal)]);
    }
    return std::min(norm(sub(p, m.start)), norm(sub(p, m.end)));
  }
  const Vec3d d = sub(m.end, m.start);
  const double l2 = dot(d, d);
  double f = l2 > 0 ? dot(sub(p, m.start), d) / l2 : 0;
  f = std::clamp(f, 0.0, 1.0);
  Vec3d q;
  for (size_t k = 0; k < 3; ++k) q[k] = m.start[k] + f * d[k];
  return norm(sub(p, q));
}

std::vector<Move> to_moves(const std::vector<gcode::CanonCall>& calls, const Vec3d& start,
                           const PlannerConfig& cfg, const std::string& file) {
  std::vector<Move> out;
  Vec3d at = start;
  bool exact = false;
  double deviation = cfg.junction_deviation_mm;

  auto check_axes = [&](int line, const Vec3d& from, const Vec3d& to) {
    for (size_t k = 0; k < 3; ++k)
      if (!cfg.axes[k].present && std::fabs(to[k] - from[k]) > 1e-9)
        throw InputError(line_ref(file, line) + ": " + std::string(1, kAxisName[k]),
                         format_number(to[k]) + " mm", "no motion on " + std::string(1, kAxisName[k]),
                         "the machine has no such axis");
  };
  auto check_travel = [&](const Move& m) {
    Vec3d lo = m.start, hi = m.start;
    extend_box(m, lo, hi);
    for (size_t k = 0; k < 3; ++k) {
      const AxisLimits& a = cfg.axes[k];
      if (!a.present) continue;
      const bool low = lo[k]<a.min_mm - 1e-9, high = hi[k]> a.max_mm + 1e-9;
      if (low || high)
        throw InputError(
            line_ref(file, m.line) + ": " + std::string(1, kAxisName[k]) + " (machine)",
            format_number(low ? lo[k] : hi[k]) + " mm",
            "within the travel " + format_number(a.min_mm) + " .. " + format_number(a.max_mm) + " mm",
            "outside the machine's travel");
    }
  };
  auto push = [&](Move m) {
    m.exact_stop = exact;
    m.deviation_mm = deviation;
    if (m.is_motion()) check_travel(m);
    out.push_back(m);
  };
  // A dwell or an action: the machine stands where it is.
  auto standing = [&](Move::Kind kind, int line) {
    Move m;
    m.kind = kind;
    m.line = line;
    m.start = m.end = at;
    return m;
  };
  auto line_move = [&](int line, const Vec3d& to, bool rapid, double feed_mm_s) {
    check_axes(line, at, to);
    Move m;
    m.kind = Move::Kind::line;
    m.line = line;
    m.rapid = rapid;
    m.start = at;
    m.end = to;
    m.length = norm(sub(to, at));
    m.v_nominal = feed_mm_s;
    at = to;
    if (m.length > 1e-9) push(m);
  };
  auto require_feed = [&](int line, double feed_mm_min) {
    if (!(feed_mm_min > 0) || !std::isfinite(feed_mm_min))
      throw InputError(line_ref(file, line) + ": F", format_number(feed_mm_min),
                       "a feed above 0 before G1/G2/G3", "no feed rate");
    return feed_mm_min / 60.0;
  };

  for (const gcode::CanonCall& c : calls) {
    std::visit(
        [&](const auto& op) {
          using T = std::decay_t<decltype(op)>;
          if constexpr (std::is_same_v<T, gcode::StraightTraverse>) {
            line_move(c.line, op.end, true, kInf);
          } else if constexpr (std::is_same_v<T, gcode::StraightFeed>) {
            line_move(c.line, op.end, false, require_feed(c.line, op.feed_mm_min));
          } else if constexpr (std::is_same_v<T, gcode::ArcFeed>) {
            const double feed = require_feed(c.line, op.feed_mm_min);
            check_axes(c.line, at, op.end);
            const gcode::PlaneAxes ax = gcode::plane_axes(op.plane);
            Move m;
            m.kind = Move::Kind::arc;
            m.line = c.line;
            m.start = at;
            m.end = op.end;
            m.centre = op.centre;
            m.centre[size_t(ax.normal)] = at[size_t(ax.normal)];
            m.plane = op.plane;
            m.clockwise = op.clockwise;
            m.radius = radius_of(m, at);
            m.sweep = gcode::arc_sweep(at, op);
            m.v_nominal = feed;
            const bool helix = std::fabs(op.end[size_t(ax.normal)] - at[size_t(ax.normal)]) > 1e-9;
            const AxisLimits& a1 = cfg.axes[size_t(ax.first)];
            const AxisLimits& a2 = cfg.axes[size_t(ax.second)];
            const bool whole = !helix && a1.present && a2.present && a1.counts_per_mm == a2.counts_per_mm;
            if (m.radius <= 0)
              throw InputError(line_ref(file, c.line) + ": arc", "radius 0", "a centre away from the start");
            if (whole) {
              m.length = m.radius * m.sweep;
              at = op.end;
              push(m);
              return;
            }
            // A helix or an arc on axes of unequal scale: chords within the
            // arc tolerance (the core's arcs are planar circles in counts).
            const double tol = std::min(cfg.arc_tolerance_mm, m.radius);
            const double step = 2 * std::acos(1 - tol / m.radius);
            const int n = std::max(1, int(std::ceil(m.sweep / step)));
            const double z0 = at[size_t(ax.normal)], z1 = op.end[size_t(ax.normal)];
            for (int i = 1; i <= n; ++i) {
              Vec3d p = i == n ? op.end : arc_point(m, m.sweep * i / n);
              if (i < n) p[size_t(ax.normal)] = z0 + (z1 - z0) * i / n;
              line_move(c.line, p, false, feed);
            }
          } else if constexpr (std::is_same_v<T, gcode::Dwell>) {
            Move m = standing(Move::Kind::dwell, c.line);
            m.dwell_s = op.seconds;
            push(m);
          } else if constexpr (std::is_same_v<T, gcode::StraightProbe>) {
            throw InputError(line_ref(file, c.line) + ": G38", "a probing move",
                             "no probing in a job: probe with the probing cycle (the machine-cycles work)",
                             "not supported in a job yet");
          } else if constexpr (std::is_same_v<T, gcode::SetPathMode>) {
            exact = op.mode != gcode::PathMode::continuous;
            deviation = op.tolerance_mm > 0 ? op.tolerance_mm : cfg.junction_deviation_mm;
          } else if constexpr (std::is_same_v<T, gcode::SelectTool> ||
                               std::is_same_v<T, gcode::SetFeedMode>) {
            // Nothing moves: T only selects, and the interpreter has turned
            // inverse-time feeds into speeds already.
          } else {
            Move m = standing(Move::Kind::action, c.line);
            m.action = c.op;
            push(m);
          }
        },
        c.op);
  }
  return out;
}

void plan_speeds(std::vector<Move>& moves, const PlannerConfig& cfg, double feed_scale, double rapid_scale,
                 double v_start) {
  const double rate_max = core_rate_limit(cfg);
  for (Move& m : moves) {
    if (!m.is_motion()) continue;
    double v = m.rapid ? kInf : m.v_nominal * (m.no_override ? 1.0 : feed_scale);
    double a = kInf;
    if (m.kind == Move::Kind::line) {
      const Vec3d u = tangent(m, false);
      double vr = kInf;
      for (size_t k = 0; k < 3; ++k) {
        const double c = std::fabs(u[k]);
        if (c < 1e-12) continue;
        const AxisLimits& ax = cfg.axes[k];
        vr = std::min(vr, ax.max_rate_mm_s / c);
        a = std::min(a, kAccelMargin * ax.max_accel_mm_s2 / c);
        v = std::min(v, rate_max / (c * ax.counts_per_mm));
      }
      v = std::min(v, m.rapid ? vr * rapid_scale : vr);
    } else {
      const gcode::PlaneAxes pa = gcode::plane_axes(m.plane);
      const AxisLimits& a1 = cfg.axes[size_t(pa.first)];
      const AxisLimits& a2 = cfg.axes[size_t(pa.second)];
      const double ac = kAccelMargin * std::min(a1.max_accel_mm_s2, a2.max_accel_mm_s2);
      // Centripetal within sqrt(3)/2 of the limit and tangential within half
      // of it: their sum stays within the limit on every axis.
      v = std::min({v, a1.max_rate_mm_s, a2.max_rate_mm_s, std::sqrt(0.8660254 * ac * m.radius),
                    rate_max / (std::sqrt(2.0) * a1.counts_per_mm)});
      a = ac / 2;
    }
    m.v_nominal = v;
    m.accel = a;
  }
  // Junction limits.
  const double window = cfg.accel_window_s;
  for (size_t i = 0; i < moves.size(); ++i) {
    Move& m = moves[i];
    if (!m.is_motion()) continue;
    m.v_entry_max = 0;
    if (i == 0) m.v_entry_max = v_start;
    if (i == 0 || !moves[i - 1].is_motion() || moves[i - 1].exact_stop) continue;
    const Move& p = moves[i - 1];
    const Vec3d u1 = tangent(p, true), u2 = tangent(m, false);
    const double cos_theta = -dot(u1, u2);
    double v;
    if (cos_theta > 0.999999) {
      v = 0;  // a reversal
    } else if (cos_theta < -0.999999) {
      v = kInf;  // straight on
    } else {
      // Grbl's junction deviation: the speed of a circle that touches both
      // moves and passes within `deviation` of the corner, at the
      // acceleration the junction's direction allows.
      Vec3d j = sub(u2, u1);
      const double jl = norm(j);
      double aj = kInf;
      for (size_t k = 0; k < 3; ++k)
        if (std::fabs(j[k]) > 1e-12 * jl)
          aj = std::min(aj, cfg.axes[k].max_accel_mm_s2 * jl / std::fabs(j[k]));
      const double sin_half = std::sqrt(0.5 * (1 - cos_theta));
      v = std::sqrt(aj * m.deviation_mm * sin_half / (1 - sin_half));
    }
    // The command's velocity steps at the corner, per axis: one step in a
    // window (moves longer than the window) or one every move (shorter
    // moves: then the steps add up like a centripetal acceleration) stays
    // within the axis's corner share.
    const double lmin = std::min(p.length, m.length);
    for (size_t k = 0; k < 3; ++k) {
      const double du = std::fabs(u2[k] - u1[k]);
      if (du <= 1e-12) continue;
      const double ak = kCornerShare * cfg.axes[k].max_accel_mm_s2;
      v = std::min({v, ak * window / du, std::sqrt(ak * lmin / du)});
    }
    m.v_entry_max = std::min({v, m.v_nominal, p.v_nominal});
  }
  // Backward: every move can still stop by the end of the program.
  double next_entry = 0;
  for (size_t i = moves.size(); i-- > 0;) {
    Move& m = moves[i];
    if (!m.is_motion()) {
      next_entry = 0;
      continue;
    }
    m.v_exit = m.exact_stop ? 0 : next_entry;
    m.v_entry = std::min(m.v_entry_max, std::sqrt(m.v_exit * m.v_exit + 2 * m.accel * m.length));
    next_entry = m.v_entry;
  }
  // Forward: and reach its entry speed from where it starts.
  double prev_exit = v_start;
  for (Move& m : moves) {
    if (!m.is_motion()) {
      prev_exit = 0;
      continue;
    }
    m.v_entry = std::min(m.v_entry, prev_exit);
    m.v_exit = std::min(m.v_exit, std::sqrt(m.v_entry * m.v_entry + 2 * m.accel * m.length));
    prev_exit = m.v_exit;
  }
}

double move_time(const Move& m) {
  if (m.kind == Move::Kind::dwell) return m.dwell_s;
  if (!m.is_motion()) return 0;
  return total_time(profile(m));
}

namespace {

// Builds the pieces of consecutive moves, carrying the rounded position.
class Chopper {
 public:
  Chopper(const PlannerConfig& cfg, const Vec3& at, double t) : cfg_(cfg), at_(at), t_(t) {}

  void add(const std::vector<Move>& moves, size_t i) {
    const Move& m = moves[i];
    switch (m.kind) {
      case Move::Kind::action: {
        Piece p;
        p.move = int(i);
        p.action = true;
        p.seg.start = p.seg.end = at_;
        p.t_end = t_;
        out_.push_back(p);
        return;
      }
      case Move::Kind::dwell: {
        if (m.dwell_s <= 0) return;
        Piece p;
        p.move = int(i);
        p.seg = plan_dwell(at_, m.dwell_s, cfg_.clock_hz);
        t_ += p.seg.duration;
        p.t_end = t_;
        out_.push_back(p);
        return;
      }
      case Move::Kind::line:
        add_motion(m, int(i), false);
        return;
      case Move::Kind::arc: {
        const size_t mark = out_.size();
        const Vec3 at = at_;
        const double t = t_;
        try {
          add_motion(m, int(i), false);
        } catch (const InputError&) {
          // The rounded points leave the core's circle: chords instead.
          out_.resize(mark);
          at_ = at;
          t_ = t;
          add_motion(m, int(i), true);
        }
        return;
      }
    }
  }

  std::vector<Piece>& pieces() { return out_; }

 private:
  // Boundaries: the ramps' equal-time steps, the arc's quarter turns (or its
  // chords), and splits of long cruises; each point rounded to counts and
  // timed by where the rounded point lies on the path.
  void add_motion(const Move& m, int index, bool chords) {
    const Profile pr = profile(m);
    const double total = total_time(pr);
    const double step = cfg_.ramp_piece_s;
    std::vector<double> ss;  // path distances of the boundaries, increasing
    // Pieces of exactly `step` from the ramp's start, the remainder last:
    // with a window a whole number of steps long, the chords' error is the
    // same at both ends of the window and drops out of the acceleration.
    auto ramp = [&](double t0, double t1) {
      const int n = std::max(1, int(std::ceil((t1 - t0) / step - 1e-9)));
      for (int k = 1; k < n; ++k) ss.push_back(s_at(pr, t0 + step * k));
      ss.push_back(s_at(pr, t1));
    };
    if (pr.ta > 0) ramp(0, pr.ta);
    if (pr.tc > 0) {
      const int n = std::max(1, int(std::ceil(pr.tc / cfg_.max_piece_s - 1e-9)));
      for (int k = 1; k <= n; ++k) ss.push_back(pr.sa + pr.vc * pr.tc * k / n);
    }
    if (pr.tb > 0) ramp(pr.ta + pr.tc, total);
    ss.push_back(m.length);
    // Finer boundaries where the geometry needs them.
    double max_ds = kInf;
    if (m.kind == Move::Kind::arc) {
      const double dphi =
          chords ? 2 * std::acos(1 - std::min(cfg_.arc_tolerance_mm, m.radius) / m.radius) : kPi / 2 - 1e-6;
      max_ds = m.length * dphi / m.sweep;
    }
    double cpm_max = 0;
    for (const AxisLimits& a : cfg_.axes)
      if (a.present) cpm_max = std::max(cpm_max, a.counts_per_mm);
    max_ds = std::min(max_ds, double(kSegMax) / cpm_max);
    std::vector<double> fine;
    double prev = 0;
    for (double s : ss) {
      const int n = std::max(1, int(std::ceil((s - prev) / max_ds - 1e-9)));
      for (int k = 1; k <= n; ++k) fine.push_back(prev + (s - prev) * k / n);
      prev = s;
    }
    const Vec3 end = to_counts(m.end, cfg_);
    double s_prev = 0, t_prev = 0;
    for (size_t b = 0; b < fine.size(); ++b) {
      const bool last = b + 1 == fine.size();
      const Vec3 c = last ? end : to_counts(point_at(m, fine[b]), cfg_);
      if (c == at_ && !last) continue;
      // Where the rounded point lies on the path, and so when the ideal
      // profile passes it.
      double s = m.length;
      if (!last) {
        const Vec3d q = to_mm(c, cfg_);
        if (m.kind == Move::Kind::arc)
          s = m.length * swept_to(m, q, m.sweep * fine[b] / m.length) / m.sweep;
        else
          s = dot(sub(q, m.start), tangent(m, false));
        s = std::clamp(s, s_prev, m.length);
      }
      const double t = last ? total : t_at(pr, s);
      const double dt = t - t_prev;
      if (c == at_) {  // the end rounds onto the last boundary: stretch that piece
        if (!out_.empty() && out_.back().move == index && dt > 0) stretch_last(dt);
        break;
      }
      if (!(dt > 1e-9)) continue;  // too close in time: merge with the next
      Piece p;
      p.move = index;
      if (m.kind == Move::Kind::arc && !chords) {
        const gcode::PlaneAxes pa = gcode::plane_axes(m.plane);
        const Vec3 cc = to_counts(m.centre, cfg_);
        const std::array<int64_t, 2> centre{cc[size_t(pa.first)], cc[size_t(pa.second)]};
        const int plane = m.plane == gcode::Plane::xy   ? seg::PLANE_XY
                          : m.plane == gcode::Plane::xz ? seg::PLANE_ZX
                                                        : seg::PLANE_YZ;
        const PlannedSegment probe = plan_arc(at_, c, centre, !m.clockwise, 1.0, plane, cfg_.clock_hz);
        p.seg = plan_arc(at_, c, centre, !m.clockwise, probe.length / dt, plane, cfg_.clock_hz);
      } else {
        const PlannedSegment probe = plan_line(at_, c, 1.0, cfg_.clock_hz);
        p.seg = plan_line(at_, c, probe.length / dt, cfg_.clock_hz);
      }
      t_ += dt;
      p.t_end = t_;
      out_.push_back(p);
      at_ = c;
      s_prev = s;
      t_prev = t;
    }
  }

  // Gives the last piece dt more seconds (same path, lower feed).
  void stretch_last(double dt) {
    Piece& p = out_.back();
    const double d = p.seg.duration + dt;
    const PlannedSegment& s = p.seg;
    if (s.seg.type == seg::T_ARC) {
      const int plane = s.seg.plane;
      const int ax = seg::PLANE_AXES[plane][0], ay = seg::PLANE_AXES[plane][1];
      const std::array<int64_t, 2> centre{s.start[size_t(ax)] - s.seg.x0, s.start[size_t(ay)] - s.seg.y0};
      p.seg = plan_arc(s.start, s.end, centre, s.seg.ccw, s.length / d, plane, cfg_.clock_hz);
    } else {
      p.seg = plan_line(s.start, s.end, s.length / d, cfg_.clock_hz);
    }
    t_ += dt;
    p.t_end = t_;
  }

  const PlannerConfig& cfg_;
  Vec3 at_;
  double t_;
  std::vector<Piece> out_;
};

// Marks the segment before every stop as the last of its run, so the board
// does not count the planned wait as an underrun.
void mark_stops(std::vector<Piece>& pieces) {
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (pieces[i].action) continue;
    const bool stop_next = i + 1 == pieces.size() || pieces[i + 1].action;
    pieces[i].seg.seg.last = stop_next;
  }
}

}  // namespace

std::vector<Piece> chop(const std::vector<Move>& moves, const PlannerConfig& cfg) {
  if (moves.empty()) return {};
  return chop_from(moves, cfg, to_counts(moves.front().start, cfg), 0);
}

std::vector<Piece> chop_from(const std::vector<Move>& moves, const PlannerConfig& cfg,
                             const Vec3& start_counts, double t0) {
  Chopper c(cfg, start_counts, t0);
  for (size_t i = 0; i < moves.size(); ++i) c.add(moves, i);
  mark_stops(c.pieces());
  return std::move(c.pieces());
}

Move sub_move(const Move& m, double s_from, double s_to) {
  Move part = m;
  part.start = point_at(m, s_from);
  part.end = point_at(m, s_to);
  part.length = std::max(0.0, s_to - s_from);
  if (m.kind == Move::Kind::arc && m.length > 0) {
    part.sweep = m.sweep * part.length / m.length;
    part.radius = radius_of(m, part.start);
  }
  return part;
}

PathPoint piece_end(const std::vector<Move>& moves, const Piece& piece, const PlannerConfig& cfg) {
  PathPoint p;
  p.move = size_t(piece.move);
  const Move& m = moves[p.move];
  if (!m.is_motion()) return p;
  const Vec3d q = to_mm(piece.seg.end, cfg);
  const double s = m.kind == Move::Kind::arc ? m.length * swept_to(m, q, m.sweep / 2) / m.sweep
                                             : dot(sub(q, m.start), tangent(m, false));
  p.s = std::clamp(s, 0.0, m.length);
  const Profile pr = profile(m);
  p.v = v_at(pr, t_at(pr, p.s));
  return p;
}

std::array<double, 3> peak_accel(const std::vector<Piece>& pieces, const PlannerConfig& cfg,
                                 std::array<double, 3>* when) {
  std::array<double, 3> peak{};
  // Knots of the piecewise-linear command: (time, counts).
  std::vector<double> kt;
  std::vector<Vec3> kp;
  const double w = cfg.accel_window_s, h = w / 8;
  for (const Piece& p : pieces) {
    if (p.action) continue;
    const double t0 = p.t_end - p.seg.duration;
    if (kt.empty()) {
      kt.push_back(t0);
      kp.push_back(p.seg.start);
    }
    if (p.seg.seg.type == seg::T_ARC) {
      // The core walks the circle at a constant tangential speed: knots
      // along it, much closer than the sampling step.
      const seg::Segment& a = p.seg.seg;
      const int ax = seg::PLANE_AXES[a.plane][0], ay = seg::PLANE_AXES[a.plane][1];
      const double cx = double(p.seg.start[size_t(ax)] - a.x0), cy = double(p.seg.start[size_t(ay)] - a.y0);
      const double a0 = std::atan2(double(a.y0), double(a.x0)), r = p.seg.arc.radius;
      const int n = std::max(2, int(std::ceil(p.seg.duration / (h / 4))));
      for (int i = 1; i < n; ++i) {
        const double f = double(i) / n, phi = a0 + (a.ccw ? 1 : -1) * p.seg.arc.sweep * f;
        Vec3 q = p.seg.start;
        q[size_t(ax)] = int64_t(std::llround(cx + r * std::cos(phi)));
        q[size_t(ay)] = int64_t(std::llround(cy + r * std::sin(phi)));
        kt.push_back(t0 + p.seg.duration * f);
        kp.push_back(q);
      }
    }
    kt.push_back(p.t_end);
    kp.push_back(p.seg.end);
  }
  if (kt.size() < 2) return peak;
  auto at = [&](double t, size_t& i, size_t k) {
    if (t <= kt.front()) return double(kp.front()[k]);
    if (t >= kt.back()) return double(kp.back()[k]);
    while (i + 1 < kt.size() && kt[i + 1] < t) ++i;
    const double f = kt[i + 1] > kt[i] ? (t - kt[i]) / (kt[i + 1] - kt[i]) : 1;
    return double(kp[i][k]) + f * double(kp[i + 1][k] - kp[i][k]);
  };
  for (size_t k = 0; k < 3; ++k) {
    if (!cfg.axes[k].present) continue;
    size_t i0 = 0, i1 = 0, i2 = 0;
    const auto steps = int64_t((kt.back() - kt.front()) / h);
    for (int64_t n = 0; n <= steps; ++n) {
      const double t = kt.front() + double(n) * h;
      const double a = (at(t + w, i2, k) - 2 * at(t, i1, k) + at(t - w, i0, k)) / (w * w);
      const double v = std::fabs(a) / cfg.axes[k].counts_per_mm;
      if (v > peak[k]) {
        peak[k] = v;
        if (when) (*when)[k] = t;
      }
    }
  }
  return peak;
}

std::vector<Move> slow_down(const std::vector<Move>& moves, const PathPoint& at, double v_to,
                            std::vector<size_t>* source) {
  std::vector<Move> out;
  size_t j = at.move;
  double v = at.v, s_from = at.s;
  while (v > v_to + 1e-9 && j < moves.size() && moves[j].is_motion()) {
    const Move& mj = moves[j];
    const double left = mj.length - s_from;
    const double need = (v * v - v_to * v_to) / (2 * mj.accel);
    const double s_to = need < left ? s_from + need : mj.length;
    Move part = sub_move(mj, s_from, s_to);
    part.v_entry = v;
    part.v_exit = need < left ? v_to : std::sqrt(std::max(0.0, v * v - 2 * mj.accel * left));
    part.v_nominal = v;
    if (part.length > 1e-9) {
      out.push_back(part);
      if (source) source->push_back(j);
    }
    v = part.v_exit;
    s_from = 0;
    ++j;
  }
  return out;
}

std::vector<Piece> stop_after(const std::vector<Move>& moves, const std::vector<Piece>& pieces, size_t k,
                              const PlannerConfig& cfg) {
  if (k >= pieces.size() || pieces[k].action || pieces[k].seg.seg.type == seg::T_DWELL) return {};
  const Piece& last = pieces[k];
  const PathPoint at = piece_end(moves, last, cfg);
  if (at.v <= 1e-9 || (k + 1 < pieces.size() && pieces[k + 1].action)) return {};
  // Decelerate at each move's limit along the rest of the path.
  std::vector<size_t> source;
  const std::vector<Move> tail = slow_down(moves, at, 0, &source);
  std::vector<Piece> out = chop_from(tail, cfg, last.seg.end, last.t_end);
  // Indices into `moves`, not into the tail.
  for (Piece& p : out) p.move = int(source[size_t(p.move)]);
  if (!out.empty()) out.back().seg.seg.last = true;
  return out;
}

PlanSummary summarize(const std::vector<Move>& moves, const std::vector<Piece>& pieces,
                      const PlannerConfig& cfg) {
  PlanSummary s;
  bool any = false;
  for (const Move& m : moves) {
    if (m.kind == Move::Kind::dwell) ++s.dwells;
    if (m.kind == Move::Kind::action) ++s.actions;
    if (!m.is_motion()) continue;
    ++s.moves;
    if (m.kind == Move::Kind::arc) ++s.arcs;
    (m.rapid ? s.rapid_mm : s.length_mm) += m.length;
    if (!any) s.min = s.max = m.start;
    any = true;
    extend_box(m, s.min, s.max);
  }
  s.pieces = pieces.size();
  s.time_s = pieces.empty() ? 0 : pieces.back().t_end;
  s.peak_accel = peak_accel(pieces, cfg);
  return s;
}

}  // namespace mc::host
