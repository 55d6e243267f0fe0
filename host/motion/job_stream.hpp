// Streaming planned motion to the board: the queue is kept fed by how much
// planned time it holds (never by a fixed count, never past FULL), and what
// has not been sent yet stays a plan that can change: moves appended as they
// arrive (a Grbl sender's lines), a feed hold or a stop (the rest of the
// path replanned into a stop at the acceleration limit), a resume, overrides
// (the rest replanned from the last segment sent). JobStreamer does that one
// link round at a time without blocking, so a server loop can call it
// between its own work; stream_job() runs a whole job with it (motionctl run).
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/motion/planner.hpp"

namespace mc::host {

// The incremental streamer. Moves go in machine mm (to_moves, starting at
// end()); the board's interpolator must stand at `at` (counts) and the
// drives be armed. Everything queued always ends at rest: the plan looks
// ahead over all of it, and the board never runs past what was planned.
class JobStreamer {
 public:
  JobStreamer(BoardLink& l, const PlannerConfig& cfg, const Vec3& at, double queue_ahead_s = 0.25);

  // A job planned whole (plan_speeds, chop from `at`), taken as it is.
  // Only while nothing is queued.
  void load(const std::vector<Move>& moves, const std::vector<Piece>& pieces);
  // Appends moves starting at end(); the part not sent yet is replanned.
  void append(const std::vector<Move>& moves);
  // Where the queued moves end (mm): the start of the next append.
  Vec3d end() const;

  // One round of the link: what the board has done, then as many segments
  // as keep queue_ahead_s of planned time queued; an action runs (on_action)
  // once everything before it has been executed. Throws BoardError naming
  // the line when a fault stops the motion (nothing queued is kept), and
  // LinkError when the board stops answering.
  void poll();

  // Feed hold: decelerate along the path at the limit after what the board
  // has queued and keep the rest; resume() continues from the stop.
  void hold();
  void resume();
  // Decelerate as for a hold, then drop everything after the stop.
  void stop();
  // Stops the interpolator at once and drops everything; the command stays
  // where it was. Returns that position (counts).
  Vec3 abort();
  // Drops everything without touching the board, whose interpolator now
  // stands at `at` (re-armed after a fault).
  void restart(const Vec3& at);
  // Feed and rapid overrides (1 = 100 %), from the last segment sent on.
  void set_overrides(double feed, double rapid);
  // New limits for what is appended from now on.
  void set_config(const PlannerConfig& cfg) { cfg_ = cfg; }

  enum class State { idle, run, holding, held };
  State state() const;
  // Nothing left to send and the board has executed all of it.
  bool drained() const;
  // The segment the board is executing, or the next one to send; none when
  // drained. t_end: its planned end since the start.
  struct Running {
    int line = 0;
    bool jog = false;  // a move without the feed override
    double t_end = 0;
    double feed_mm_s = 0;  // the segment's path speed
  };
  std::optional<Running> current() const;
  // The end of the last segment sent (counts): where the interpolator
  // stands once drained.
  Vec3 command_end() const;
  // The latched FAULT bits that stopped the last poll() (0: none).
  uint32_t fault() const { return fault_; }

  // Called with each action move when its turn comes.
  std::function<void(const Move&)> on_action;

  int underruns() const { return underruns_; }
  size_t segments() const { return segments_; }
  double planned_s() const { return t_sent_; }  // planned time up to the end of what was sent
  // The line of the last segment sent (0: none).
  int last_line() const { return last_line_; }

 private:
  struct Sent {
    Move move;  // the planned move the piece belongs to
    Piece piece;
  };
  struct Flight {
    Running what;
    double t_start = 0;
  };
  // Folds what was sent into the boundary: orig_ then starts where the last
  // piece sent ended.
  void rebase();
  // Plans orig_ from the boundary and chops it.
  void replan();
  void send();
  void record(const Piece& p, const Move& m);
  void drop_queue();

  BoardLink& l_;
  PlannerConfig cfg_;
  double ahead_s_;
  double feed_ = 1, rapid_ = 1;
  // The boundary: where the last piece sent ends (counts, planned time,
  // speed), and the moves after it, as queued (orig_) and planned (plan_).
  Vec3 at_{};
  double t_ = 0, v_ = 0;
  std::vector<Move> orig_, plan_;
  std::vector<Piece> pieces_;  // to send, from pieces_[next_]
  size_t next_ = 0;
  // pieces_ follow plan_, which follows orig_; false while a stop's tail is
  // being sent (orig_ then starts after it).
  bool attached_ = true;
  bool hold_ = false;
  std::optional<Sent> last_;   // the last piece sent from an attached plan, not yet rebased
  std::deque<Flight> flight_;  // sent, not executed yet
  uint32_t segs_base_ = 0;     // IP_SEGS when the count started
  uint64_t sent_ = 0, done_ = 0;
  bool busy_ = false;
  int underruns_ = 0;
  size_t segments_ = 0;
  int last_line_ = 0;
  double t_sent_ = 0;
  uint32_t fault_ = 0;
};

struct StreamOptions {
  double queue_ahead_s = 0.25;   // planned time kept queued
  unsigned telemetry_axes = 0;   // mask of axes to record (0: no telemetry)
  uint32_t telemetry_decim = 0;  // every Nth PID sample (0: chosen from the link's speed)
  double ts_s = 1e-4;            // the PID sample period, for the choice above
  // Called with the planned time and source line of the segment the board
  // is running (as far as the host knows) whenever that changes.
  std::function<void(double, int)> progress;
  // Runs an action (spindle, coolant, M0, M6, M2) once the queue has drained.
  std::function<void(const Move&)> action;
  // Set from a signal handler: decelerate to a stop along the path and end.
  const std::atomic<bool>* stop = nullptr;
};

// One telemetry sample of every recorded axis (counts).
struct JobSample {
  int64_t n = 0;  // PID sample count, unwrapped
  std::array<int32_t, 3> pos{}, cmd{};
};

struct StreamResult {
  std::vector<JobSample> samples;
  int64_t gaps = 0;         // telemetry frames that skipped samples
  int underruns = 0;        // times the board's queue ran dry while moving
  size_t segments = 0;      // segments the board ran
  bool stopped = false;     // ended by `stop`, part-way
  int stopped_at_line = 0;  // the source line it stopped on
  double planned_s = 0;     // planned time of what ran
};

// Runs `pieces` (from chop()) on an armed board whose interpolator stands at
// the first piece's start, with a JobStreamer. Throws BoardError naming the
// source line when a fault stops the motion; LinkError when the board stops
// answering.
StreamResult stream_job(BoardLink& l, const std::vector<Move>& moves, const std::vector<Piece>& pieces,
                        const PlannerConfig& cfg, const StreamOptions& o);

}  // namespace mc::host
