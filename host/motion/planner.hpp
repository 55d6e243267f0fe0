// The path planner: from the interpreter's canonical calls (machine mm) to
// the segments the board runs (counts), with feed ramps that respect every
// axis's rate and acceleration limit, cornering speeds from the junction
// deviation, and look-ahead over the whole program.
//
// The core runs each segment at one constant feed (it has no ramp of its
// own, docs/decisions.md "Feed ramps on the host"), so a ramp is a staircase
// of short constant-feed pieces whose boundaries lie on whole counts and whose
// durations come from the exact trapezoid: the average of the commanded
// velocity over any window of `accel_window_s` follows the ramp, and the
// position at each boundary is the ideal one rounded to a count.
//
// Three steps, each usable alone:
//   1. to_moves(): calls -> Moves (lines and arcs the core can run whole; a
//      helix or an arc on axes of unequal scale becomes chords), with the
//      travel and rate checks;
//   2. plan_speeds(): junction speeds, the backward and forward passes;
//   3. chop(): Moves -> Pieces (segments with their planned times).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "host/gcode/canon.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::host {

using Vec3d = gcode::Vec3;  // machine mm

struct AxisLimits {
  bool present = false;
  double counts_per_mm = 0;
  double max_rate_mm_s = 0;
  double max_accel_mm_s2 = 0;
  double min_mm = 0, max_mm = 0;  // travel, machine coordinates
  // The board count at machine zero (the board's ORIGIN once homed, else 0:
  // machine coordinates count from where the axis was at power-up).
  int64_t origin = 0;
};

struct PlannerConfig {
  std::array<AxisLimits, 3> axes{};
  double junction_deviation_mm = 0.01;  // cornering (G64 P overrides it)
  double arc_tolerance_mm = 0.002;      // chord error when an arc becomes lines
  double ramp_piece_s = 0.004;          // longest constant-feed piece of a ramp
  double max_piece_s = 0.05;            // longest piece at all: a feed hold waits for at most the queue
  double accel_window_s = 0.02;         // acceleration limits hold over this average
  double clock_hz = kDefaultClockHz;
};

// One motion of the program, or a stop the machine makes standing still.
struct Move {
  enum class Kind { line, arc, dwell, action };
  Kind kind = Kind::line;
  int line = 0;  // source line
  bool rapid = false;
  Vec3d start{}, end{};
  // Arcs: planar, about `centre` (its normal coordinate is the start's).
  Vec3d centre{};
  gcode::Plane plane = gcode::Plane::xy;
  bool clockwise = false;
  double radius = 0, sweep = 0;  // mm, rad (> 0)
  double length = 0;             // path length, mm
  double dwell_s = 0;
  // action: what runs while the machine stands (spindle, coolant, M0/M1,
  // M6, M2/M30); the streamer waits for the queue to drain first.
  std::optional<gcode::CanonOp> action;
  bool exact_stop = false;   // G61/G61.1: stop at the end of this move
  bool no_override = false;  // a jog: the feed override does not apply (Grbl)
  double deviation_mm = 0;   // the junction deviation at its start
  // Limits (mm/s, mm/s^2) and the planned speeds at its ends.
  double v_nominal = 0;
  double accel = 0;
  double v_entry_max = 0;
  double v_entry = 0, v_exit = 0;
  bool is_motion() const { return kind == Kind::line || kind == Kind::arc; }
};

// The unit tangent of a motion move at its start (at_end = false) or end.
Vec3d tangent(const Move& m, bool at_end);
// The point of a motion move at path distance s (0..length) from its start.
Vec3d point_at(const Move& m, double s);
// The distance from p to the move's path (lines and arcs; 0-length moves: to the point).
double distance_to(const Move& m, const Vec3d& p);

// Turns calls into moves starting at `start` (machine mm). Throws InputError
// naming the line ("FILE:LINE" when `file` is given) for a point outside the
// travel, a move of an absent axis, a probe (G38.x is run by the probing
// cycle, not by a job) or a feed of 0.
std::vector<Move> to_moves(const std::vector<gcode::CanonCall>& calls, const Vec3d& start,
                           const PlannerConfig& cfg, const std::string& file = "");

// Nominal speeds, accelerations and junction limits, then the passes: every
// move gets the entry and exit speeds of the fastest profile that starts and
// ends at rest and stays within every limit. feed_scale and rapid_scale are
// the overrides (1 = 100 %). v_start: the speed the first move starts at
// (mm/s) when the machine is already moving there (replanning the rest of a
// queue from the last segment sent); it must be one the first move can
// still stop from.
void plan_speeds(std::vector<Move>& moves, const PlannerConfig& cfg, double feed_scale = 1.0,
                 double rapid_scale = 1.0, double v_start = 0);

// The time a move takes with its planned entry and exit speeds (s).
double move_time(const Move& m);

// What the board runs: one segment, or a stop for an action.
struct Piece {
  int move = 0;         // index into the moves
  bool action = false;  // true: no segment; drain the queue, then run moves[move].action
  PlannedSegment seg;   // in counts (seg.duration is its planned time)
  double t_end = 0;     // planned time at its end since the job's start (s)
};

// Chops every move into pieces; `start_counts` is the board's position in
// counts, which must be `moves.front().start` rounded. Arcs the core cannot
// take whole (a rounding that leaves the end off the circle) become chords.
std::vector<Piece> chop(const std::vector<Move>& moves, const PlannerConfig& cfg);
// The same from the board position `start_counts` (moves.front().start
// rounded) and planned time t0: the rest of a queue after what was sent.
std::vector<Piece> chop_from(const std::vector<Move>& moves, const PlannerConfig& cfg,
                             const Vec3& start_counts, double t0);

// The part of a motion move between path distances s_from and s_to.
Move sub_move(const Move& m, double s_from, double s_to);
// Where pieces[k] ends on its move: the path distance from the move's start
// and the planned speed there (mm, mm/s).
struct PathPoint {
  size_t move = 0;
  double s = 0, v = 0;
};
PathPoint piece_end(const std::vector<Move>& moves, const Piece& piece, const PlannerConfig& cfg);

// Machine mm -> board counts, rounded per axis, and back (absent axes 0):
// positions, so each axis's origin is added or taken off.
Vec3 to_counts(const Vec3d& p, const PlannerConfig& cfg);
Vec3d to_mm(const Vec3& c, const PlannerConfig& cfg);

// The highest acceleration of each axis in the command the pieces make
// (mm/s^2): the second difference of the position over accel_window_s,
// sampled every window/8 (the command is piecewise linear: its
// instantaneous acceleration is a series of impulses).
// `when`: the planned time of each axis's peak.
std::array<double, 3> peak_accel(const std::vector<Piece>& pieces, const PlannerConfig& cfg,
                                 std::array<double, 3>* when = nullptr);

// The parts of `moves` (planned) that carry the machine from `at` along the
// path while it slows at each move's limit to v_to (0: a stop), with their
// entry and exit speeds set; `source`: the move each part comes from. Ends
// early where the path leaves motion moves (then at that move's end).
std::vector<Move> slow_down(const std::vector<Move>& moves, const PathPoint& at, double v_to,
                            std::vector<size_t>* source = nullptr);

// The pieces that bring the machine to rest from the end of pieces[k]
// (whose exit speed is the one planned there), along the rest of the path,
// decelerating at the limit: feed hold and Ctrl-C. Empty when it already is.
std::vector<Piece> stop_after(const std::vector<Move>& moves, const std::vector<Piece>& pieces, size_t k,
                              const PlannerConfig& cfg);

struct PlanSummary {
  int moves = 0, arcs = 0, dwells = 0, actions = 0;
  size_t pieces = 0;
  double time_s = 0;     // planned, from the pieces
  double length_mm = 0;  // path length of feed and arc moves
  double rapid_mm = 0;   // of rapid moves
  Vec3d min{}, max{};    // bounding box of every point the path reaches
  std::array<double, 3> peak_accel{};
};
PlanSummary summarize(const std::vector<Move>& moves, const std::vector<Piece>& pieces,
                      const PlannerConfig& cfg);

}  // namespace mc::host
