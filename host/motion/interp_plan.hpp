// Planning interpolator segments on the host: from a move in absolute counts
// and a feed to the segment words the core runs (hls/interp_seg.hpp), with the
// geometry checked first. The core itself trusts what it is given (it can
// never jump, but a malformed arc would not end where asked), so every check
// a user needs lives here, with a message that says what to fix.
//
// Feeds are in counts per second along the path, the clock in Hz.
#pragma once

#include <array>
#include <cstdint>
#include <functional>

#include "hls/interp_seg.hpp"

namespace mc::host {

using Vec3 = std::array<int64_t, 3>;

// The board clock (iCEBreaker's 12 MHz oscillator); configs may override.
constexpr double kDefaultClockHz = 12e6;

// Circle geometry of an arc, relative to its centre, as the core walks it.
struct ArcGeometry {
  int64_t x0 = 0, y0 = 0, xe = 0, ye = 0;
  int64_t d0 = 0;  // x0^2 + y0^2 - R^2
  int64_t r2 = 0;  // R^2, by default x0^2 + y0^2
  double radius = 0;
  int64_t crossing = 0;  // where the walk crosses each axis: (+-c, 0), (0, +-c)
  int q0 = 0, qf = 0;    // start and end quadrant, 0..3 = Q1..Q4
  int nq = 0;            // quadrant crossings before the final quadrant
  int64_t n = 0;         // steps, sum over quadrants of |dx| + |dy|
  double sweep = 0;      // swept angle, rad
};

struct PlannedSegment {
  seg::Segment seg;
  Vec3 start{};               // absolute counts
  Vec3 end{};                 // absolute counts
  double length = 0;          // path length of the ideal line/arc, counts
  double duration = 0;        // at the commanded feed, s
  double feed_rel_error = 0;  // quantization of the rate words, relative
  ArcGeometry arc;            // arcs only
};

// The axis crossing c of the stairs path of a circle of R^2 = r2: the integer
// with c(c-1) < r2 <= c(c+1).
int64_t arc_axis_crossing(int64_t r2);
// Checks and measures an arc (coordinates relative to the centre); throws
// InputError for a zero radius, an end point more than one step off the
// circle, one the walk cannot reach, or coordinates out of the core's range.
// r2 = 0: the start point defines the circle (what users mean by a centre);
// otherwise R^2 = r2 and the start must be a point of the walk of that circle
// (an arc run backwards from where another one ended, say).
ArcGeometry arc_geometry(int64_t x0, int64_t y0, int64_t xe, int64_t ye, bool ccw, int64_t r2 = 0);

// The highest iteration rate the core runs (one iteration per tick of
// 2^TICK_LOG2 clocks), iterations/s; the planners refuse feeds above it.
double max_iteration_rate(double clk_hz = kDefaultClockHz);

PlannedSegment plan_line(const Vec3& from, const Vec3& to, double feed, double clk_hz = kDefaultClockHz);
// plane: seg::PLANE_XY (x, y), PLANE_ZX (z, x) or PLANE_YZ (y, z); centre in
// absolute counts on that plane's two axes. The third axis must not change.
PlannedSegment plan_arc(const Vec3& from, const Vec3& to, const std::array<int64_t, 2>& centre, bool ccw,
                        double feed, int plane = seg::PLANE_XY, double clk_hz = kDefaultClockHz);
PlannedSegment plan_dwell(const Vec3& at, double seconds, double clk_hz = kDefaultClockHz);

// Every point the core visits for a planned segment, in order, starting with
// the start point: the twin's line and arc engines run step by step.
void walk(const PlannedSegment& p, const std::function<void(const Vec3&)>& visit);

}  // namespace mc::host
