// interp_core twin: the interpolator, clock by clock. Mirrors rtl/interp_core.v.
//
// How to drive it (the same as the RTL):
// - Queue segments (hls/interp_seg.hpp) a word at a time with wr. A segment is
//   admitted whole or not at all: if the FIFO lacks room for all SEG_WORDS
//   words when its first word arrives, the whole segment is dropped and
//   ovf() set, so the queue can never fall out of step. The host checks
//   count() before writing.
// - The core loads the oldest segment (SEG_WORDS + 1 clocks) and runs it: the
//   feed generator fires iterations, each moving the position command pos()
//   by at most one count per axis. The next segment follows at once, with
//   the phase of the feed generator carried over, so a queue of segments
//   runs without a stop (a pause of about SEG_WORDS clocks at each junction,
//   ~1 us at 12 MHz, and iterations that fall due meanwhile are kept, up to
//   three).
// - When a segment ends, the queue holds no whole segment and that segment
//   was not marked last, underrun() is set: the position holds (it never
//   jumps) and motion resumes when segments arrive.
// - hold pauses the feed (feed hold); abort stops at once and empties the
//   queue; set loads the position, taken only while idle; clr clears the
//   sticky flags.
#pragma once

#include <cstdint>

#include "arc_interp.hpp"
#include "feed_gen.hpp"
#include "interp_seg.hpp"
#include "line_interp.hpp"
#include "mc_fixed.hpp"
#include "seg_fifo.hpp"

namespace mc {

struct InterpIn {
  bool wr = false;
  uint32_t wdata = 0;
  bool abort = false;
  bool hold = false;
  bool clr = false;
  bool set = false;
  int32_t set_pos[3] = {};
};

template <int FIFO_AW = 9>
class InterpCore {
  static_assert(FIFO_AW >= 4 && FIFO_AW <= 12, "interp_core: FIFO_AW must be 4..12");

 public:
  static constexpr int ST_IDLE = 0, ST_LOAD = 1, ST_RUN = 2;
  static constexpr int DEPTH = 1 << FIFO_AW;

  void reset() {
    fifo_.reset();
    feed_.reset();
    st_ = ST_IDLE;
    widx_ = ridx_ = 0;
    rv_ = false;
    wi_ = 0;
    drop_ = false;
    pend_ = 0;
    for (int32_t& p : pos_) p = 0;
    underrun_ = ovf_ = false;
    seg_cnt_ = 0;
  }

  // One clock edge.
  void clock(const InterpIn& in) {
    // --- Combinational values from the current state ---
    const int ridx = ridx_;
    const bool fire = feed_.fire();
    const int count = fifo_.count();
    const bool running = st_ == ST_RUN;
    // An arc's decision is registered (see hls/arc_interp.hpp): valid when ready.
    const bool arc = type_ == seg::T_ARC;
    const bool fin = n_left_ == 0 || (arc && arc_.ready() && arc_.fin());
    const bool it = running && !fin && pend_ != 0 && !in.hold && !in.abort && (!arc || arc_.ready());
    const ArcStep as = arc_.step();
    const int lmv = line_.moves();
    int mv = 0, neg = 0;  // bit a: axis a moves / moves negative
    if (it && type_ == seg::T_LINE) {
      mv = lmv;
      neg = line_.neg();
    } else if (it && type_ == seg::T_ARC) {
      const int a = seg::PLANE_AXES[plane_][as.movex ? 0 : 1];
      mv = 1 << a;
      neg = as.dir < 0 ? mv : 0;
    }
    const bool rd = st_ == ST_LOAD && widx_ < seg::SEG_WORDS && !in.abort;
    const bool ld = rv_ && !in.abort;
    const uint32_t ldata = fifo_.rdata();
    // Writer: a segment is admitted whole or not at all.
    const int free = DEPTH - count;
    const bool drop_n = wi_ == 0 ? free < seg::SEG_WORDS : drop_;
    const bool push = in.wr && !in.abort && !drop_n;

    // --- Next state ---
    // Sticky flags: cleared first, so an event in the same cycle wins.
    if (in.clr) underrun_ = ovf_ = false;
    if (in.wr && !in.abort) {
      drop_ = drop_n;
      wi_ = wi_ == seg::SEG_WORDS - 1 ? 0 : wi_ + 1;
      if (drop_n) ovf_ = true;
    }

    feed_.clock(ld, ridx, ldata, running && !in.hold && !in.abort, it && type_ == seg::T_ARC, as.outward);
    if (ld) {
      line_.load(ridx, ldata);
      arc_.load(ridx, ldata);
      if (ridx == seg::W_HDR) {
        type_ = (ldata >> seg::H_TYPE_LSB) & 3;
        last_ = (ldata >> seg::H_LAST) & 1;
        plane_ = (ldata >> seg::H_PLANE_LSB) & 3;
      }
      if (ridx == seg::W_N) n_left_ = ldata & seg::N_MASK;
    }
    if (it) {
      if (type_ == seg::T_LINE) line_.iterate(lmv);
      if (arc) arc_.iterate(as);
      n_left_ = (n_left_ - 1) & seg::N_MASK;
      for (int a = 0; a < 3; ++a)
        if ((mv >> a) & 1) pos_[a] = sat32(i128(pos_[a]) + (((neg >> a) & 1) ? -1 : 1));
    }
    if (!ld && !(it && arc)) arc_.settle();
    const int pend_n = pend_ + int(fire) - int(it);
    pend_ = pend_n > 3 ? 3 : pend_n;

    fifo_.clock(in.abort, push, in.wdata, rd);
    rv_ = rd;
    ridx_ = widx_;

    switch (st_) {
      case ST_IDLE:
        if (in.set) {
          for (int a = 0; a < 3; ++a) pos_[a] = in.set_pos[a];
        } else if (count >= seg::SEG_WORDS) {
          st_ = ST_LOAD;
          widx_ = 0;
        }
        break;
      case ST_LOAD:
        if (rd) ++widx_;
        if (ld && ridx == seg::SEG_WORDS - 1) st_ = ST_RUN;
        break;
      default:
        if (fin) {
          st_ = ST_IDLE;
          seg_cnt_ = (seg_cnt_ + 1) & 0xFFFF;
          if (!last_ && count < seg::SEG_WORDS) underrun_ = true;
        }
        break;
    }
    if (in.abort) {
      st_ = ST_IDLE;
      rv_ = false;
      wi_ = 0;
      drop_ = false;
      pend_ = 0;
    }
  }

  // Fast-forward: idle with less than a segment queued and no input, the
  // core settles within two clocks and then stands still; skip(n) is n such
  // clocks.
  bool quiet(const InterpIn& in) const {
    return st_ == ST_IDLE && !rv_ && fifo_.count() < seg::SEG_WORDS && !in.wr && !in.abort && !in.clr &&
           !in.set;
  }
  void skip(uint32_t n) {
    for (uint32_t i = 0; i < n && i < 2; ++i) clock(InterpIn{});
  }

  int32_t pos(int a) const { return pos_[a]; }
  bool busy() const { return st_ != ST_IDLE; }
  int state() const { return st_; }
  bool underrun() const { return underrun_; }
  bool ovf() const { return ovf_; }
  int seg_cnt() const { return seg_cnt_; }
  int count() const { return fifo_.count(); }
  const FeedGen& feed() const { return feed_; }
  const ArcInterp& arc() const { return arc_; }

 private:
  SegFifo<FIFO_AW> fifo_;
  FeedGen feed_;
  LineInterp line_;
  ArcInterp arc_;
  int st_ = ST_IDLE;
  int widx_ = 0, ridx_ = 0;
  bool rv_ = false;
  int wi_ = 0;
  bool drop_ = false;
  int pend_ = 0;
  int type_ = 0, plane_ = 0;
  bool last_ = false;
  uint32_t n_left_ = 0;
  int32_t pos_[3] = {};
  bool underrun_ = false, ovf_ = false;
  int seg_cnt_ = 0;
};

}  // namespace mc
