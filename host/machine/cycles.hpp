// The machine cycles a job starts with, on the board's latches: homing
// (seek the switch, back off, locate it slowly, set machine zero there) and
// probing (move until the probe changes, report where it did).
//
// Both run as state machines that never wait: poll() does one round of the
// link and returns whether the cycle is over, so the Grbl server keeps
// answering `?` while an axis homes, and a command line tool loops on it.
// The board does the timing-critical part: the switch or probe edge latches
// every selected axis's position in the clock it happens and stops the
// interpolator (LATCH.stop), whatever the link's latency; the host only
// reads the latched positions back (docs/board.md, "Probe and home
// switches").
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/machine_config.hpp"
#include "host/motion/interp_plan.hpp"
#include "host/motion/planner.hpp"

namespace mc::machine {

// A cycle that could not finish, with Grbl's alarm code for it: 4 the probe
// was already in the state the move looks for, 5 no contact (G38.2, G38.4),
// 8 a switch stayed closed after pulling off, 9 no switch within the
// search distance. The drives stay armed; the axes stand where the cycle
// stopped them.
class CycleError : public std::runtime_error {
 public:
  CycleError(int grbl_alarm, const std::string& what) : std::runtime_error(what), alarm_(grbl_alarm) {}
  int grbl_alarm() const { return alarm_; }

 private:
  int alarm_;
};

// One straight move that a switch or the probe may cut short: queued as
// segments, with LATCH set so that the edge latches the axes and stops the
// interpolator. Once over, the command is resynchronised with the board
// (the stop flushed the queue), so the next move starts where the axes'
// command stands.
class LatchedMove {
 public:
  enum class Source { none, home, probe };
  struct Spec {
    mc::host::Vec3 from{}, to{};  // board counts
    double feed_counts_s = 0;     // along the path in counts
    Source source = Source::none;
    unsigned latch_axes = 0;   // home: the axes whose switches latch; probe: the axes latched
    bool probe_inv = false;    // probe: latch when the contact opens (G38.4, G38.5)
    unsigned moving_axes = 0;  // set by the constructor: the axes from and to differ on
  };
  LatchedMove(mc::host::BoardLink& l, const Spec& s);
  // Sends what the queue takes; true once the interpolator stands (at the
  // end, or stopped by a latch) and the moving axes have caught up with it
  // (within 2 counts, or 0.5 s). BoardError when a fault stops the motion.
  bool poll();
  // After poll() returned true: the axes that latched, their latched
  // positions (board counts), and where the command stands.
  unsigned latched() const { return latched_; }
  const mc::host::Vec3& latch_position() const { return latch_pos_; }
  const mc::host::Vec3& end() const { return end_; }

 private:
  mc::host::BoardLink& l_;
  Spec s_;
  std::vector<mc::host::PlannedSegment> segs_;
  size_t sent_ = 0;
  uint32_t segs0_ = 0;
  bool done_ = false, settling_ = false;
  std::chrono::steady_clock::time_point settle_until_{};
  unsigned latched_ = 0;
  mc::host::Vec3 latch_pos_{}, end_{};
};

// One axis's homing, in board units (machine_config.hpp's [axis.N.home] with
// any of Grbl's $23..$27 applied).
struct HomeAxis {
  int axis = 0;
  int direction = 1;     // the side the switch is on: +1 the + end
  double switch_mm = 0;  // machine coordinate where the switch closes: machine zero follows from it
  double seek_mm_min = 500, locate_mm_min = 25, pull_off_mm = 1;
  int order = 0;
};
struct HomingPlan {
  std::vector<std::vector<HomeAxis>> passes;  // lowest order first; one pass homes its axes together
  double search_mm[3] = {0, 0, 0};            // the seek gives up after this (1.5 x the travel, as Grbl)
};
// The plan for the axes in `mask` (bit 0 X): every one needs its [home]
// table, else InputError naming the axis and the file.
HomingPlan homing_plan(const MachineConfig& m, unsigned mask);

// Homing, axis group by group: each switch is sought at seek speed (axes of
// a pass together, each at its own speed; one switch's latch stops all, the
// others go on), backed off by pull_off, located at locate speed, and its
// latched position becomes the axis's ORIGIN (machine coordinate switch_mm),
// after which the axis backs off again and is marked homed (HOMED). The
// limit faults of the homed axes are off during the cycle (their switches
// are the limit inputs) and restored after it, as is LATCH. The constructor
// readies the board as a job does (ready_board(): gains, armed, PIDs and
// following-error limits on), once those limits are off: an axis that
// powered up on its switch has its limit fault latched, and homing is how
// it gets off it.
class HomingCycle {
 public:
  HomingCycle(mc::host::BoardLink& l, const MachineConfig& m, HomingPlan plan,
              const mc::host::Note& note = {});
  // One round; true when every pass is done. CycleError, BoardError: the
  // cycle failed (SAFETY and LATCH are restored first).
  bool poll();
  // Stops the motion at once (a sender's reset): SAFETY and LATCH restored,
  // the axes not yet located stay unhomed.
  void abort();
  // After completion: the origins set (board counts, per axis).
  const mc::host::Vec3& origin() const { return origin_; }

 private:
  enum class Phase { clear, seek, pull_off, locate, park, done };
  // How far a move goes: the search distance, 5 x the pull-off (Grbl's
  // locate scalar), the pull-off.
  enum class Reach { search, locate, pull_off };
  void start_phase(Phase p);
  // sign +1: towards the switches; locate: at the locate speeds.
  void start_move(const std::vector<const HomeAxis*>& axes, int sign, Reach reach, bool locate,
                  LatchedMove::Source src);
  void fail(int alarm, const std::string& what);
  void restore();
  bool switch_closed(int a);
  double cpmm(int a) const;

  mc::host::BoardLink& l_;
  const MachineConfig& m_;
  HomingPlan plan_;
  uint32_t safety0_ = 0, latch0_ = 0;
  size_t pass_ = 0;
  Phase phase_ = Phase::clear;
  std::optional<LatchedMove> move_;
  unsigned pending_ = 0;  // axes of the pass still to latch in this phase
  mc::host::Vec3 at_{};   // the command, board counts
  mc::host::Vec3 latch_{}, origin_{};
  bool restored_ = false;
};

// Runs a homing cycle to the end, keeping the link alive: motionctl home.
// Returns the origins set.
mc::host::Vec3 home_axes(mc::host::BoardLink& l, const MachineConfig& m, unsigned mask,
                         const mc::host::Note& note = {});

// A probing move (G38.2..G38.5): from `from` towards `to` (board counts) at
// feed, until the probe closes (toward) or opens (away). The probe latches
// every axis at once. CycleError 4 when the probe already is in the state
// the move looks for; no contact is not an error here (G38.3/G38.5 accept
// it): contact() says.
class ProbeCycle {
 public:
  ProbeCycle(mc::host::BoardLink& l, const mc::host::Vec3& from, const mc::host::Vec3& to,
             double feed_counts_s, bool toward, unsigned axes);
  bool poll();
  void abort();
  bool contact() const { return move_.latched() != 0; }
  // Where the probe changed (the latched positions), else where the move ended.
  mc::host::Vec3 position() const { return contact() ? move_.latch_position() : move_.end(); }
  // Where the command stands now.
  const mc::host::Vec3& end() const { return move_.end(); }

 private:
  mc::host::BoardLink& l_;
  uint32_t latch0_;
  LatchedMove move_;
  bool restored_ = false;
};

// The feed along a straight move from `from` to `to` (board counts) that a
// cycle's LatchedMove takes, counts per second: feed_mm_min along the path
// in mm, lowered until no axis exceeds its max rate in `cfg`.
double path_feed_counts_s(const mc::host::Vec3& from, const mc::host::Vec3& to, double feed_mm_min,
                          const mc::host::PlannerConfig& cfg);

// The probe input as the board filters it (IO_STAT), active high.
bool probe_closed(mc::host::BoardLink& l);

// Waits board time on the link (its poll; the in-process virtual board
// advances), the way every loop here waits for the motion.
void wait_on_link(mc::host::BoardLink& l);

}  // namespace mc::machine
