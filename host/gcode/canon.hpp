// The interpreter's output: canonical machining calls in the spirit of
// LinuxCNC's canon interface, in MACHINE coordinates and millimetres. Work
// offsets (G54..G59.3), the G92 offset, the G43.1 tool length offset and G20
// inches are already applied, so a planner or a plotter needs no modal state.
#pragma once

#include <array>
#include <string>
#include <variant>
#include <vector>

namespace mc::gcode {

// X, Y, Z in mm; index 0, 1, 2 so the code can walk the axes of a plane.
using Vec3 = std::array<double, 3>;

enum class Plane { xy, xz, yz };                                  // G17, G18, G19
enum class FeedMode { units_per_minute, inverse_time };           // G94, G93
enum class PathMode { exact_stop, exact_path, continuous };       // G61.1, G61, G64
enum class ProbeMode { toward_error, toward, away_error, away };  // G38.2, G38.3, G38.4, G38.5
enum class StopKind { pause, optional_pause, end, end_rewind };   // M0, M1, M2, M30

// The two axes of a plane in LinuxCNC's order (G18 is Z then X, so that the
// arc's turning sense is the right-handed one) and the perpendicular axis.
struct PlaneAxes {
  int first;
  int second;
  int normal;
};
PlaneAxes plane_axes(Plane plane);

// G0 (and the rapid parts of G28/G30 and canned cycles).
struct StraightTraverse {
  Vec3 end;
};
// G1 and the feed parts of canned cycles. feed_mm_min is the path speed; in
// G93 it is the speed that makes the move last 1/F minutes.
struct StraightFeed {
  Vec3 end;
  double feed_mm_min;
};
// G2/G3. The arc turns about `centre` in `plane` (centre[normal] is the
// start's normal coordinate); the normal axis moves linearly from the start to
// end[normal] (a helix). turns >= 1: 1 is up to one revolution, P2 adds one
// full revolution, and so on. An arc whose end equals its start in the plane
// is a full circle.
struct ArcFeed {
  Vec3 end;
  Vec3 centre;
  Plane plane;
  bool clockwise;
  int turns;
  double feed_mm_min;
};
struct Dwell {
  double seconds;
};
// G38.x: moves toward `end` until the probe input changes; the real stop
// point is only known to the machine (Interpreter::set_machine_position).
struct StraightProbe {
  Vec3 end;
  ProbeMode mode;
  double feed_mm_min;
};
struct SetSpindleSpeed {
  double rpm;
};
struct StartSpindle {
  bool clockwise;
  double rpm;
};
struct StopSpindle {};
struct SetCoolant {
  bool mist;
  bool flood;
};
struct SelectTool {
  int tool;
};
// M6: stop the spindle and pause until the operator has put `tool` in.
struct ChangeTool {
  int tool;
};
// M0/M1 pause (resume with cycle start); M2/M30 end the program.
struct ProgramStop {
  StopKind kind;
};
struct SetFeedMode {
  FeedMode mode;
};
// G61/G61.1/G64 [P]: tolerance_mm is G64's P (0: none given).
struct SetPathMode {
  PathMode mode;
  double tolerance_mm;
};

using CanonOp =
    std::variant<StraightTraverse, StraightFeed, ArcFeed, Dwell, StraightProbe, SetSpindleSpeed, StartSpindle,
                 StopSpindle, SetCoolant, SelectTool, ChangeTool, ProgramStop, SetFeedMode, SetPathMode>;

struct CanonCall {
  int line;  // 1-based source line
  CanonOp op;
};

// True for the calls that move the machine (traverse, feed, arc, probe).
bool is_motion(const CanonOp& op);

// The angle an arc sweeps from `start` (radians, > 0): the in-plane angle in
// its direction (2 pi when the end is the start) plus 2 pi per extra turn.
double arc_sweep(const Vec3& start, const ArcFeed& arc);
// Its path length (mm): the helix over that sweep, from the start radius.
double arc_length(const Vec3& start, const ArcFeed& arc);

// One line per call, e.g. "12 ARC_FEED end=(1,2,0) centre=(0.5,2,0) plane=17 cw turns=1 feed=300".
std::string to_string(const CanonCall& call);

}  // namespace mc::gcode
