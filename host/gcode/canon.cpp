#include "host/gcode/canon.hpp"

#include <cmath>
#include <sstream>

namespace mc::gcode {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// Shortest text that gives the value back to 1e-9 mm.
std::string num(double v) {
  if (std::fabs(v) < 5e-10) v = 0.0;
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string vec(const Vec3& v) {
  return "(" + num(v[0]) + "," + num(v[1]) + "," + num(v[2]) + ")";
}

int plane_code(Plane p) {
  switch (p) {
    case Plane::xy:
      return 17;
    case Plane::xz:
      return 18;
    case Plane::yz:
      return 19;
  }
  return 17;
}

const char* probe_code(ProbeMode m) {
  switch (m) {
    case ProbeMode::toward_error:
      return "G38.2";
    case ProbeMode::toward:
      return "G38.3";
    case ProbeMode::away_error:
      return "G38.4";
    case ProbeMode::away:
      return "G38.5";
  }
  return "G38.2";
}

const char* stop_code(StopKind k) {
  switch (k) {
    case StopKind::pause:
      return "M0";
    case StopKind::optional_pause:
      return "M1";
    case StopKind::end:
      return "M2";
    case StopKind::end_rewind:
      return "M30";
  }
  return "M0";
}

const char* path_code(PathMode m) {
  switch (m) {
    case PathMode::exact_path:
      return "G61";
    case PathMode::exact_stop:
      return "G61.1";
    case PathMode::continuous:
      return "G64";
  }
  return "G64";
}

struct Printer {
  std::string operator()(const StraightTraverse& c) const { return "STRAIGHT_TRAVERSE end=" + vec(c.end); }
  std::string operator()(const StraightFeed& c) const {
    return "STRAIGHT_FEED end=" + vec(c.end) + " feed=" + num(c.feed_mm_min);
  }
  std::string operator()(const ArcFeed& c) const {
    return "ARC_FEED end=" + vec(c.end) + " centre=" + vec(c.centre) +
           " plane=" + std::to_string(plane_code(c.plane)) + (c.clockwise ? " cw" : " ccw") +
           " turns=" + std::to_string(c.turns) + " feed=" + num(c.feed_mm_min);
  }
  std::string operator()(const Dwell& c) const { return "DWELL " + num(c.seconds) + " s"; }
  std::string operator()(const StraightProbe& c) const {
    return std::string("STRAIGHT_PROBE ") + probe_code(c.mode) + " end=" + vec(c.end) +
           " feed=" + num(c.feed_mm_min);
  }
  std::string operator()(const SetSpindleSpeed& c) const { return "SET_SPINDLE_SPEED " + num(c.rpm); }
  std::string operator()(const StartSpindle& c) const {
    return std::string("START_SPINDLE ") + (c.clockwise ? "cw " : "ccw ") + num(c.rpm);
  }
  std::string operator()(const StopSpindle& /*c*/) const { return "STOP_SPINDLE"; }
  std::string operator()(const SetCoolant& c) const {
    return std::string("SET_COOLANT mist=") + (c.mist ? "on" : "off") + " flood=" + (c.flood ? "on" : "off");
  }
  std::string operator()(const SelectTool& c) const { return "SELECT_TOOL " + std::to_string(c.tool); }
  std::string operator()(const ChangeTool& c) const { return "CHANGE_TOOL " + std::to_string(c.tool); }
  std::string operator()(const ProgramStop& c) const {
    return std::string("PROGRAM_STOP ") + stop_code(c.kind);
  }
  std::string operator()(const SetFeedMode& c) const {
    return std::string("SET_FEED_MODE ") + (c.mode == FeedMode::inverse_time ? "G93" : "G94");
  }
  std::string operator()(const SetPathMode& c) const {
    return std::string("SET_PATH_MODE ") + path_code(c.mode) + " tolerance=" + num(c.tolerance_mm);
  }
};

}  // namespace

PlaneAxes plane_axes(Plane plane) {
  switch (plane) {
    case Plane::xy:
      return {0, 1, 2};
    case Plane::xz:
      return {2, 0, 1};
    case Plane::yz:
      return {1, 2, 0};
  }
  return {0, 1, 2};
}

bool is_motion(const CanonOp& op) {
  return std::holds_alternative<StraightTraverse>(op) || std::holds_alternative<StraightFeed>(op) ||
         std::holds_alternative<ArcFeed>(op) || std::holds_alternative<StraightProbe>(op);
}

double arc_sweep(const Vec3& start, const ArcFeed& arc) {
  const PlaneAxes ax = plane_axes(arc.plane);
  const double a0 =
      std::atan2(start[ax.second] - arc.centre[ax.second], start[ax.first] - arc.centre[ax.first]);
  const double a1 =
      std::atan2(arc.end[ax.second] - arc.centre[ax.second], arc.end[ax.first] - arc.centre[ax.first]);
  double sweep = arc.clockwise ? a0 - a1 : a1 - a0;
  while (sweep <= 0.0) sweep += kTwoPi;
  // An end that is the start (to rounding) is a full circle, not a zero arc.
  const double chord = std::hypot(arc.end[ax.first] - start[ax.first], arc.end[ax.second] - start[ax.second]);
  if (chord < 1e-9) sweep = kTwoPi;
  return sweep + kTwoPi * (arc.turns - 1);
}

double arc_length(const Vec3& start, const ArcFeed& arc) {
  const PlaneAxes ax = plane_axes(arc.plane);
  const double r =
      std::hypot(start[ax.first] - arc.centre[ax.first], start[ax.second] - arc.centre[ax.second]);
  return std::hypot(r * arc_sweep(start, arc), arc.end[ax.normal] - start[ax.normal]);
}

std::string to_string(const CanonCall& call) {
  return std::to_string(call.line) + " " + std::visit(Printer{}, call.op);
}

}  // namespace mc::gcode
