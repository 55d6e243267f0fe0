#include "host/motion/board_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"

namespace mc::host {

namespace br = board::reg;
namespace bb = board::bits;

std::vector<PlannedSegment> plan_move(const Vec3& from, const Vec3& to, double feed, double clk_hz) {
  constexpr int64_t kMax = (int64_t(1) << seg::N_W) - 1;
  int64_t longest = 0;
  for (int a = 0; a < 3; ++a)
    longest = std::max<int64_t>(longest, std::llabs(to[size_t(a)] - from[size_t(a)]));
  const int64_t pieces = std::max<int64_t>(1, (longest + kMax - 1) / kMax);
  std::vector<PlannedSegment> v;
  Vec3 at = from;
  for (int64_t i = 1; i <= pieces; ++i) {
    Vec3 next;
    for (int a = 0; a < 3; ++a)
      next[size_t(a)] = from[size_t(a)] + (to[size_t(a)] - from[size_t(a)]) * i / pieces;
    if (next != at) v.push_back(plan_line(at, next, feed, clk_hz));
    at = next;
  }
  if (!v.empty()) v.back().seg.last = true;
  return v;
}

size_t send_segments(BoardLink& l, const std::vector<PlannedSegment>& segs, size_t sent) {
  if (sent >= segs.size()) return sent;
  std::vector<seg::Words> batch;
  for (size_t i = sent; i < segs.size() && batch.size() < 6; ++i) batch.push_back(seg::pack(segs[i].seg));
  return l.segments(batch) ? sent + batch.size() : sent;
}

void run_segments(BoardLink& l, const std::vector<PlannedSegment>& segs,
                  const std::function<void(int, int)>& progress) {
  using Clock = std::chrono::steady_clock;
  const uint32_t segs0 = l.read(br::IP_SEGS) & 0xFFFF;
  const int total = int(segs.size());
  // A virtual board may run slower than real time (a loaded machine, the
  // RTL engine): the limit only catches a board that stopped moving.
  double board_s = 0;
  for (const PlannedSegment& p : segs) board_s += p.duration;
  const auto deadline = Clock::now() + std::chrono::duration<double>(30 + 100 * board_s);
  size_t sent = 0;
  int last_done = -1;
  for (;;) {
    sent = send_segments(l, segs, sent);
    const uint32_t fault = l.read(br::FAULT);
    if (fault) throw BoardError("motion stopped by a fault: " + fault_names(fault));
    const int done = int((l.read(br::IP_SEGS) - segs0) & 0xFFFF);
    const bool busy = l.read(br::IP_STAT) & (1u << bb::IS_BUSY);
    if (done != last_done && progress) progress(done, total);
    last_done = done;
    if (sent == segs.size() && done >= total && !busy) return;
    if (Clock::now() > deadline)
      throw BoardError("the move did not finish in time (" + std::to_string(done) + " of " +
                       std::to_string(total) + " segments done)");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

MoveResult move_axes(BoardLink& l, const std::function<Vec3(const Vec3&)>& target, double feed_mm_min,
                     const std::array<double, 3>& counts_per_m, const Note& note) {
  MoveResult r;
  r.from = arm(l, note);
  r.to = target(r.from);
  double cpm = 0;
  for (int a = 0; a < 3; ++a)
    if (r.to[size_t(a)] != r.from[size_t(a)] && cpm == 0) cpm = counts_per_m[size_t(a)];
  if (cpm == 0) return r;
  const double clk = double(l.read(br::CLK_HZ));
  const std::vector<PlannedSegment> segs = plan_move(r.from, r.to, feed_mm_min / 60e3 * cpm, clk);
  double board_s = 0;
  for (const PlannedSegment& p : segs) board_s += p.duration;
  // Said once the first segments are on the board: from here an interrupted
  // command leaves the board moving until its watchdog stops it.
  bool said = false;
  run_segments(l, segs, [&](int, int total) {
    if (said || !note) return;
    said = true;
    char line[96];
    std::snprintf(line, sizeof line, "moving: %d segment%s, %.3g s of board time", total,
                  total == 1 ? "" : "s", board_s);
    note(line);
  });
  r.moved = true;
  for (int a = 0; a < 3; ++a)
    if (counts_per_m[size_t(a)] != 0) r.pos[size_t(a)] = int32_t(l.read(br::axis(a, br::AX_POS)));
  return r;
}

}  // namespace mc::host
