// line_interp: Bresenham line in up to three axes, one iteration at a time:
// the reference for the path of rtl/interp_core.v's serial engine (which
// keeps g = 2N - E for each axis, see hls/interp_core.hpp), used by the host
// planner's walk() and by the tests that compare the core step for step.
//
// N = max |d| iterations; each iteration the major axis moves one count and
// every other axis moves when its error term overflows, so the path is
// 8-connected (26 in 3-D) and ends exactly on the target: after N iterations
// axis a has moved exactly |d_a| counts.
//
// Rounding is the one thing to get right for a path that retraces itself when
// run backwards. After k iterations axis a should sit at k*d/N rounded to the
// nearest count, with ties broken the same way in absolute coordinates
// whichever direction the axis runs (towards minus infinity here). In a
// doubled error term E (add 2d per iteration, step and subtract 2N when
// E + 2d - 2N >= 0) that is: E starts at N for an axis running towards minus
// and at N - 1 for one running towards plus. docs/numerics.md derives it.
#pragma once

#include <cstdint>

#include "interp_seg.hpp"

namespace mc {

class LineInterp {
 public:
  bool operator==(const LineInterp&) const = default;
  static constexpr int E_W = seg::N_W + 1;
  static constexpr uint32_t E_MASK = (uint32_t(1) << E_W) - 1;

  // A segment word streaming in from the FIFO.
  void load(int idx, uint32_t w) {
    if (idx == seg::W_HDR) neg_ = (w >> seg::H_NEG_LSB) & 7;
    if (idx == seg::W_N) {
      n_ = w & seg::N_MASK;
      for (int a = 0; a < 3; ++a) e_[a] = (n_ - (((neg_ >> a) & 1) ? 0 : 1)) & E_MASK;
    }
    if (idx >= seg::W_A && idx < seg::W_A + 3) d_[idx - seg::W_A] = w & seg::N_MASK;
  }

  // Which axes move in this iteration (bit a = axis a), from the state as it is.
  int moves() const {
    int mv = 0;
    for (int a = 0; a < 3; ++a)
      if (step_test(a)) mv |= 1 << a;
    return mv;
  }
  int neg() const { return neg_; }

  // Commit one iteration: mv is moves() of the current state.
  void iterate(int mv) {
    for (int a = 0; a < 3; ++a) {
      const int64_t s = int64_t(e_[a]) + 2 * int64_t(d_[a]);
      // E_W bits, as the RTL register: only a malformed segment (|d| > N)
      // ever reaches the top bit, and then both wrap alike.
      e_[a] = uint32_t(((mv >> a) & 1) ? s - 2 * int64_t(n_) : s) & E_MASK;
    }
  }

 private:
  bool step_test(int a) const {
    const int64_t t = int64_t(e_[a]) + 2 * int64_t(d_[a]) - 2 * int64_t(n_);
    return t >= 0;
  }

  uint32_t n_ = 0;
  uint32_t d_[3] = {};
  uint32_t e_[3] = {};  // doubled error term, 0..2N
  int neg_ = 0;
};

}  // namespace mc
