// Streaming a planned job to the board: the queue is kept fed by how much
// planned time it holds (never by a fixed count, never past FULL), the
// board's telemetry is collected as it comes, and an interrupt replans the
// rest of the path into a stop at the acceleration limit.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/motion/planner.hpp"

namespace mc::host {

struct StreamOptions {
  double queue_ahead_s = 0.25;   // planned time kept queued
  unsigned telemetry_axes = 0;   // mask of axes to record (0: no telemetry)
  uint32_t telemetry_decim = 0;  // every Nth PID sample (0: chosen from the link's speed)
  double ts_s = 1e-4;            // the PID sample period, for the choice above
  // Called with the index of the piece the board is running (as far as the
  // host knows) whenever that changes.
  std::function<void(size_t)> progress;
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
// the first piece's start. Throws BoardError naming the source line when a
// fault stops the motion; LinkError when the board stops answering.
StreamResult stream_job(BoardLink& l, const std::vector<Move>& moves, const std::vector<Piece>& pieces,
                        const PlannerConfig& cfg, const StreamOptions& o);

}  // namespace mc::host
