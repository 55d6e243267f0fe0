// seg_fifo twin: the interpolator's command FIFO, a synchronous first-in
// first-out queue of 32-bit words in block RAM. Mirrors rtl/seg_fifo.v.
//
// A read strobe takes the oldest word; it appears on rdata() after the clock
// edge (registered, as block RAM reads are); flush empties the queue. The
// user never writes when full nor reads when empty (interp_core admits a
// segment only when all of it fits and loads one only when all of it is
// queued), so, as in the RTL, nothing checks; keeping segments whole is the
// user's job too.
#pragma once

#include <cstdint>

namespace mc {

template <int AW>
class SegFifo {
 public:
  bool operator==(const SegFifo&) const = default;
  static constexpr int DEPTH = 1 << AW;

  void reset() { wp_ = rp_ = count_ = 0; }

  void clock(bool flush, bool wr, uint32_t wdata, bool rd) {
    if (flush) {
      reset();
      return;
    }
    const bool do_wr = wr, do_rd = rd;
    if (do_rd) {
      rdata_ = mem_[rp_];
      rp_ = (rp_ + 1) & (DEPTH - 1);
    }
    if (do_wr) {
      mem_[wp_] = wdata;
      wp_ = (wp_ + 1) & (DEPTH - 1);
    }
    count_ += int(do_wr) - int(do_rd);
  }

  uint32_t rdata() const { return rdata_; }
  int count() const { return count_; }

 private:
  uint32_t mem_[DEPTH] = {};
  int wp_ = 0, rp_ = 0, count_ = 0;
  uint32_t rdata_ = 0;
};

}  // namespace mc
