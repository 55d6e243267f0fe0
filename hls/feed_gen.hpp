// feed_gen twin: the feed-rate generator, a phase accumulator that fires one
// interpolation iteration each time it overflows. Mirrors rtl/feed_gen.v.
//
// Rate: f = inc / 2^PH_W iterations per clock, so a 48-bit accumulator gives
// a resolution of f_clk / 2^48 (4e-8 Hz at 12 MHz) and, being exact integer
// arithmetic, no drift however long the move: after n clocks exactly
// floor((ph0 + n*inc) / 2^PH_W) iterations have fired.
//
// For arcs the rate follows the tangent (see docs/numerics.md, "feed on a
// stairs circle"): inc = k * (|x| + |y|), kept exact without a multiplier by
// adding or subtracting k on every step, since each step changes |x| + |y| by
// exactly one.
//
// Loaded from the segment words as they stream out of the FIFO (W_INC_LO,
// W_INC_HI, W_K_LO, see hls/interp_seg.hpp).
#pragma once

#include <cstdint>

#include "interp_seg.hpp"

namespace mc {

class FeedGen {
 public:
  void reset() {
    ph_ = 0;
    fire_ = false;
  }

  // One clock edge. ld/idx/data: a segment word; run: accumulate this clock;
  // adj/up: an arc step was taken, outward (|x|+|y| grew) or inward.
  void clock(bool ld, int idx, uint32_t data, bool run, bool adj, bool up) {
    uint64_t ph_n = ph_, inc_n = inc_, k_n = k_;
    bool fire_n = false;
    if (run) {
      const uint64_t s = ph_ + inc_;
      fire_n = (s >> seg::PH_W) & 1;
      ph_n = s & seg::PH_MASK;
    }
    if (ld) {
      if (idx == seg::W_INC_LO) inc_n = (inc_ & ~uint64_t(0xFFFFFFFF)) | data;
      if (idx == seg::W_INC_HI) {
        inc_n = (inc_ & 0xFFFFFFFF) | uint64_t(data & 0xFFFF) << 32;
        k_n = (k_ & 0xFFFFFFFF) | uint64_t(data >> 16) << 32;
      }
      if (idx == seg::W_K_LO) k_n = (k_ & ~uint64_t(0xFFFFFFFF)) | data;
    } else if (adj) {
      inc_n = (up ? inc_ + k_ : inc_ - k_) & seg::PH_MASK;
    }
    ph_ = ph_n;
    inc_ = inc_n;
    k_ = k_n;
    fire_ = fire_n;
  }

  bool fire() const { return fire_; }
  uint64_t inc() const { return inc_; }
  uint64_t phase() const { return ph_; }

 private:
  uint64_t ph_ = 0;
  uint64_t inc_ = 0;
  uint64_t k_ = 0;
  bool fire_ = false;
};

}  // namespace mc
