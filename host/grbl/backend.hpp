// What the Grbl front end needs from a machine: the interface between the
// protocol engine (protocol.hpp), which speaks Grbl 1.1 to a sender, and
// whatever moves: the board through the planner, or the dry-run model
// (dry_run_backend.hpp).
//
// The engine calls it from one thread, never blocks on it, and polls it:
//  - a line's canonical calls go in with submit() once ready() says there is
//    room (Grbl answers `ok` when the line is in the planner, so a full queue
//    is the sender's flow control);
//  - feed hold, cycle start, jog cancel, soft reset and overrides are
//    real-time commands: they act on what is already queued;
//  - status() is read for every `?`, drained() for the lines whose `ok`
//    waits for the queue (G4, probes, M0/M2/M30, offset changes), and
//    poll_event() for what happens by itself (alarms, probe results).
//
// Positions are machine millimetres, feeds mm/min, as the interpreter's
// canonical calls (host/gcode/canon.hpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "host/gcode/canon.hpp"

namespace mc::grbl {

struct Settings;

// What the machine is doing, as the engine combines it with its own states
// (Alarm, Check, Sleep) into Grbl's state word.
enum class Motion {
  idle,     // nothing queued, stopped: "Idle"
  run,      // executing or about to execute queued lines: "Run"
  holding,  // decelerating after feed_hold(): "Hold:1"
  held,     // stopped in a hold, the queue kept: "Hold:0" (cycle_start() resumes)
  jog,      // executing a jog: "Jog"
  homing,   // a homing cycle: "Home"
};

// Input pins as Grbl's Pn: field lists them.
struct Pins {
  bool probe = false;
  bool limit[3] = {false, false, false};
  bool door = false, hold = false, start = false, reset = false;
};

struct Status {
  Motion motion = Motion::idle;
  gcode::Vec3 position{};  // machine position, mm
  double feed_mm_min = 0;  // current path speed
  double spindle_rpm = 0;  // current spindle speed
  int spindle = 0;         // 1 clockwise, -1 counterclockwise, 0 off
  bool flood = false, mist = false;
  int blocks_free = 0;  // planner blocks free (Bf's first number)
  int line_number = 0;  // N word of the line executing, 0: none
  Pins pins;
  // The handwheel while it jogs an axis: "X,10" (axis, counts a detent) for
  // the HW: field, "" otherwise.
  std::string handwheel;
};

// Feed, rapid and spindle overrides in percent (Grbl's Ov: field). The
// backend applies them by re-planning from where the machine is.
struct Overrides {
  int feed = 100, rapid = 100, spindle = 100;
  bool operator==(const Overrides& o) const {
    return feed == o.feed && rapid == o.rapid && spindle == o.spindle;
  }
};

// One line's work: its calls in order. `id` counts submitted lines from 1
// (it never repeats, across resets too); `line_number` is the line's N word
// (0: none) for Ln:. A jog's calls are one StraightFeed; jogs ignore the
// feed override and are cancelled by jog_cancel().
struct Submission {
  uint64_t id = 0;
  int line_number = 0;
  bool jog = false;
  std::vector<gcode::CanonCall> calls;
};

// The machine stopped by itself. Grbl's ALARM codes: 1 hard limit, 3 abort
// during a cycle, 4/5 probe, 6..10 homing. Board faults (following error,
// watchdog, e-stop) are code 3 with a message naming the fault; critical
// ones (hard limit, e-stop) need a soft reset before anything else runs.
struct AlarmEvent {
  int code = 3;
  std::string message;  // "" or the fault, shown as [MSG:...]
  bool critical = false;
};
// A probe move (StraightProbe) ended: where it stopped and whether the probe
// input changed as the mode asked. It comes before drained() turns true.
struct ProbeEvent {
  gcode::Vec3 position{};
  bool contact = false;
};
// A note for the operator, shown as [MSG:...].
struct MessageEvent {
  std::string text;
};
using Event = std::variant<AlarmEvent, ProbeEvent, MessageEvent>;

class Backend {
 public:
  virtual ~Backend() = default;

  // Settings changed ($N=value) or were loaded: max rates, accelerations,
  // junction deviation, arc tolerance, counts per mm.
  virtual void configure(const Settings& settings) = 0;

  // True when submit() may be called: the planner has room for a line.
  virtual bool ready() const = 0;
  virtual void submit(Submission line) = 0;
  // Nothing queued, nothing moving, every dwell done.
  virtual bool drained() const = 0;

  virtual void feed_hold() = 0;    // decelerate and stop on the path, keep the queue
  virtual void cycle_start() = 0;  // resume from a hold
  virtual void jog_cancel() = 0;   // stop a jog and drop the queued jogs
  // Stop now, drop the queue, spindle and coolant off; the position is
  // whatever the machine reached.
  virtual void soft_reset() = 0;
  virtual void set_overrides(const Overrides& o) = 0;

  virtual Status status() const = 0;
  // The total number of planner blocks (Bf's first number when empty).
  virtual int planner_blocks() const = 0;
  virtual std::optional<Event> poll_event() = 0;

  // Starts a homing cycle of the axes in `axis_mask` (bit 0 X); returns a
  // Grbl status code: 0 when it started (motion() then reports homing), 5
  // "setting disabled" when the machine cannot home.
  virtual int home(unsigned axis_mask) = 0;

  // Bed levelling ($LEV): the height map the machine was given, as `$LEV`
  // reports it ("" when it has none), and whether the lines after now are
  // levelled with it. set_levelling() returns a Grbl status code: 0, or 5
  // "setting disabled" when there is no map.
  virtual std::string height_map() const { return ""; }
  virtual bool levelling() const { return false; }
  virtual int set_levelling(bool on) { return on ? 5 : 0; }

  // The handwheel ($MPG, not Grbl's): the selection as $MPG reports it
  // ("X10", "OFF"), "" when the machine has none. set_mpg() takes "X10",
  // "Y1", "Z100" or "0" (off) and returns a Grbl status code: 0, 3 a bad
  // selection, 5 no handwheel. The wheel jogs only while nothing else runs.
  virtual std::string mpg() const { return ""; }
  virtual int set_mpg(const std::string& selection) { return selection == "0" ? 0 : 5; }
};

}  // namespace mc::grbl
