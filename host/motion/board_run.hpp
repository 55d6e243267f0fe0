// Moves on the board: a straight move split into segments the core
// accepts, and running planned segments to completion.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::host {

// Queues what the board's queue takes of segs[sent..] (one frame: up to six
// segments); returns the new count sent.
size_t send_segments(BoardLink& l, const std::vector<PlannedSegment>& segs, size_t sent);

// Queues the segments (waiting while the queue is full), then polls until
// the interpolator has finished them, keeping the watchdog fed. Throws
// BoardError when a fault stops the motion. progress(done, total).
void run_segments(BoardLink& l, const std::vector<PlannedSegment>& segs,
                  const std::function<void(int, int)>& progress = {});

// A straight move split into segments the core accepts.
std::vector<PlannedSegment> plan_move(const Vec3& from, const Vec3& to, double feed_counts_s, double clk_hz);

struct MoveResult {
  bool moved = false;            // false: the target was where the axes are
  Vec3 from{}, to{};             // interpolator counts
  std::array<int32_t, 3> pos{};  // encoder counts after the move
};
// Arms the drives, moves in a straight line from where the interpolator is
// to target(from) at feed_mm_min along the path, and waits until done.
// counts_per_m: each axis's scale (0: no such axis); the first moving axis
// sets the path's scale, as the axes share one in a sane machine.
MoveResult move_axes(BoardLink& l, const std::function<Vec3(const Vec3&)>& target, double feed_mm_min,
                     const std::array<double, 3>& counts_per_m, const Note& note);

}  // namespace mc::host
