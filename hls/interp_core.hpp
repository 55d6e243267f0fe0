// interp_core twin: the interpolator, clock by clock. Mirrors rtl/interp_core.v.
//
// How to drive it (the same as the RTL):
// - Queue segments (hls/interp_seg.hpp) a word at a time with wr. A segment is
//   admitted whole or not at all: if the FIFO lacks room for all SEG_WORDS
//   words when its first word arrives, the whole segment is dropped and
//   ovf() set, so the queue can never fall out of step. The host checks
//   count() before writing.
// - The core loads the oldest segment (SEG_WORDS + 1 clocks), prepares it
//   (PREP_STEPS clocks) and runs it: the feed generator fires iterations,
//   each moving the position command pos() by at most one count per axis. The
//   next segment follows at once, with the phase of the feed generator carried
//   over, so a queue of segments runs without a stop (a pause of at most
//   JUNCTION clocks between two steps, iterations that fall due meanwhile are
//   kept, up to three).
// - When a segment ends, the queue holds no whole segment and that segment
//   was not marked last, underrun() is set: the position holds (it never
//   jumps) and motion resumes when segments arrive.
// - hold pauses the feed (feed hold); abort stops at once and empties the
//   queue; set loads the position of the axes it names, taken only while
//   idle; clr clears the sticky flags.
//
// Structure: a serial engine. One 32-bit ALU, out = A + (B ^ inv) + cin, with
// A from read port a and B from read port b or the FIFO word, runs a fixed
// schedule over a 16-word state RAM (block RAM with two read ports and one
// write port; reads are registered, so each step's addresses are issued the
// step before, and no step uses a word read in the clock it is written). A tick
// of TICK = 2^TICK_LOG2 clocks advances the feed phase once and runs at most
// one iteration, so the iteration rate is at most f_clk / TICK. The phase
// keeps the meaning of the segment's rate word (iterations per clock *
// 2^PH_W): adding inc once per tick into an accumulator of PH_W - TICK_LOG2
// bits carries exactly when the PH_W-bit accumulator, advanced by inc every
// clock, would have carried during that tick.
//
// RAM words (V[i] = word i of the segment as loaded, except as noted):
//   0 zero (cleared after reset)      1 N, counted down: iterations left
//   2 inc[31:0] (arcs: +-k per step)  3 {k[47:32], inc[47:32]}
//   4..6 line: 2|d| (doubled in PREP); arc: x, y, xe
//   7..9 line: g per axis; arc: ye, D, k[31:0]
//   11, 12 feed phase [31:0], [PH_W-TICK_LOG2-1:32]
//   13 k[47:32]  14 2N  15 arc: D + mx*x
// The line's error term is kept as g = 2N - E (hls/line_interp.hpp has E):
// an axis steps when g - 2|d| <= 0, and g then gains 2N.
//
// Schedule. After reset (IDLE) V0, V11, V12 are cleared. LOAD writes the
// words through the ALU (V0 + FIFO word). PREP:
//   0 V13 = V3 >> 16            1 V14 = V1 + V1
//   2..4 line: V4+i += V4+i     5..7 line: V7+i = V1 + !neg_i
// RUN, tick step u:
//   0 V11 += V2 (carry)         1 V12 += V3 + carry; fire on a carry out of
//                                 the accumulator's top bit
//   2 V15 = D + mx*x            3 xeq = (x - xe == 0)   4 yeq = (y - ye == 0)
//   5 S = V15 + my*y: end the segment, iterate (go) or wait; the arc's move
//   6 go: V1 -= 1
//   line 7..9  g_i -= 2|d_i|, step_i = (g_i <= 0)
//        10..12 if step_i: g_i += 2N
//   arc  7 D += m*c              8 c += m (c = x or y)
//        9 inc_lo +-= k_lo       10 D += m*c (the new c): D + 2mc + 1 in all
//       11 inc_hi +-= k_hi + carry
//   13 go: the position moves.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>

#include "interp_seg.hpp"
#include "mc_fixed.hpp"
#include "seg_fifo.hpp"

namespace mc {

struct InterpIn {
  bool operator==(const InterpIn&) const = default;
  bool wr = false;
  uint32_t wdata = 0;
  bool abort = false;
  bool hold = false;
  bool clr = false;
  uint8_t set = 0;  // a strobe per axis: bit a loads set_pos[a]
  int32_t set_pos[3] = {};
  uint8_t jog = 0;  // a strobe per axis: bit a moves axis a one count while idle (set wins)
  bool jog_neg = false;
};

template <int FIFO_AW = 9>
class InterpCore {
  static_assert(FIFO_AW >= 4 && FIFO_AW <= 12, "interp_core: FIFO_AW must be 4..12");

 public:
  bool operator==(const InterpCore&) const = default;
  static constexpr int ST_IDLE = 0, ST_LOAD = 1, ST_PREP = 2, ST_RUN = 3;
  static constexpr int DEPTH = 1 << FIFO_AW;
  static constexpr int TICK = 1 << seg::TICK_LOG2;  // clocks per iteration, at most one
  static constexpr int PREP_STEPS = 8;
  static constexpr int INIT_STEPS = 5;  // after reset: equalize, read, clear three words
  // Longest pause between two steps across a junction, with an iteration
  // due: from the step that moves (tick step 13) to the end test at the next
  // tick's step 5, then IDLE, LOAD, PREP, and steps 0..13 of the first tick.
  static constexpr int STEP_MOVE = 13, STEP_DECIDE = 5;
  static constexpr int JUNCTION =
      (TICK - STEP_MOVE + STEP_DECIDE) + 1 + (seg::SEG_WORDS + 1) + PREP_STEPS + STEP_MOVE + 1;

  void reset() {
    fifo_.reset();
    st_ = ST_IDLE;
    sq_ = 0;
    ic_ = 0;
    widx_ = ridx_ = 0;
    rv_ = false;
    wi_ = 0;
    drop_ = false;
    pend_ = 0;
    go_ = false;
    for (int32_t& p : pos_) p = 0;
    underrun_ = ovf_ = false;
    seg_cnt_ = 0;
    calm_ = calm_seen_ = tick_strobe_ = false;
  }

  // One clock edge.
  void clock(const InterpIn& in) { clock_as<false>(in); }

  // The fast-forwards below clock a running segment with no input many
  // times: the same edge, compiled for that case and each tick step.
  void clock_running() {
    static constexpr auto kSteps = running_steps(std::make_index_sequence<TICK>{});
    (this->*kSteps[size_t(sq_)])(kNone);
  }

 private:
  static constexpr InterpIn kNone{};
  template <size_t... S>
  static constexpr auto running_steps(std::index_sequence<S...>) {
    return std::array<void (InterpCore::*)(const InterpIn&), TICK>{&InterpCore::clock_as<true, int(S)>...};
  }
  bool ending_as(int st, int u) const {
    const bool final_q = ncross_ == nq_;
    return st == ST_RUN && u == 5 && (!nz_ || (type_ == seg::T_ARC && final_q && xeq_ && yeq_));
  }
  // RUNNING: a running segment, no input; STEP: the tick step sq_ (-1:
  // read it).
  template <bool RUNNING, int STEP = -1>
  void clock_as(const InterpIn& in_arg) {
    const InterpIn& in = RUNNING ? kNone : in_arg;
    const int st = RUNNING ? int(ST_RUN) : st_;
    // --- Combinational values from the current state ---
    const int count = fifo_.count();
    const uint32_t fd = fifo_.rdata();
    const int ridx = ridx_;
    const bool line = type_ == seg::T_LINE, arc = type_ == seg::T_ARC;
    const bool rd = st == ST_LOAD && widx_ < seg::SEG_WORDS && !in.abort;
    const bool ld = rv_ && !in.abort;
    const bool drop_n = wi_ == 0 ? DEPTH - count < seg::SEG_WORDS : drop_;
    const bool push = in.wr && !in.abort && !drop_n;
    const auto [mxn, myn, xo] = quadrant();
    const bool final_q = ncross_ == nq_;
    const int c_addr = movex_ ? 4 : 5;
    const bool xlock = final_q && xeq_, ylock = final_q && yeq_;
    // The end of the segment, decided at tick step 5 (flags of this tick).
    const int u = STEP >= 0 ? STEP : sq_;
    const bool fin = ending_as(st, u);

    // The operation of this clock.
    Op op;
    if (st == ST_IDLE) {
      // After reset: the RTL's two RAM copies of V1 made equal, then
      // V1 - V1 = 0 into the zero word and the phase.
      if (ic_ != 1 && ic_ < INIT_STEPS) op = alu(true, 1, kInitAddr[ic_], W_BOTH);
    } else if (st == ST_LOAD) {
      if (ld && ridx != seg::W_HDR) op = Op{true, false, 0, ridx, W_BOTH};  // V0 + word
    } else if (st == ST_PREP) {
      if (u == 0) op = alu(false, 0, 13, W_SWAP);
      if (u == 1) op = alu(false, 0, 14, W_BOTH);
      if (u >= 2 && u <= 4) op = alu(false, 0, 2 + u, line ? W_BOTH : W_NONE);
      if (u >= 5) op = alu(false, ((neg_ >> (u - 5)) & 1) ? 0 : 1, 2 + u, line ? W_BOTH : W_NONE);
    } else {
      if (u == 0) op = alu(false, 0, 11, (!in.hold && !in.abort) ? W_BOTH : W_NONE);
      if (u == 1) op = alu(false, carry_, 12, fen_ ? W_MASK : W_NONE);
      if (u == 2) op = alu(mxn, mxn, 15, W_BOTH);
      if (u == 3 || u == 4) op = alu(true, 1, 0, W_NONE);
      if (u == 5) op = alu(myn, myn, 0, W_NONE);
      if (u == 6) op = alu(true, 0, 1, go_ ? W_BOTH : W_NONE);
      if (line && u >= 7 && u <= 9) op = alu(true, 1, u, go_ ? W_BOTH : W_NONE);
      if (line && u >= 10 && u <= 12)  // & 3 as at steps 7..9 below
        op = alu(false, 0, u - 3, go_ && ((lmv_ >> ((u - 10) & 3)) & 1) ? W_BOTH : W_NONE);
      if (arc) {
        const bool dn = !outw_;  // inward: inc -= k
        if (u == 7 || u == 10) op = alu(neg_m_, neg_m_, 8, go_ ? W_BOTH : W_NONE);
        if (u == 8) op = alu(neg_m_, !neg_m_, c_addr, go_ ? W_BOTH : W_NONE);
        if (u == 9) op = alu(dn, dn, 2, go_ ? W_BOTH : W_NONE);
        if (u == 11) op = alu(dn, carry_, 3, go_ ? W_LO : W_NONE);
      }
    }
    // The ALU.
    const uint32_t a = ra_;
    const uint32_t b = (op.bfd ? fd : rb_) ^ (op.binv ? 0xFFFFFFFFu : 0);
    const uint64_t sum = uint64_t(a) + b + op.cin;
    const uint32_t out = uint32_t(sum);
    const bool cout = (sum >> 32) & 1;
    const bool zero = out == 0, sign = out >> 31;
    const bool c16 = ((out ^ a ^ b) >> 16) & 1;                      // carry into bit 16
    constexpr int PHB = 16 - seg::TICK_LOG2;                         // accumulator bits in V12
    const uint32_t mask_hi = ((1u << 16) - 1) & ~((1u << PHB) - 1);  // carries out of the accumulator
    const bool fire = st == ST_RUN && u == 1 && fen_ && (c16 || (out & mask_hi) != 0);

    // --- Next state ---
    if (in.clr) underrun_ = ovf_ = false;
    if (in.wr && !in.abort) {
      drop_ = drop_n;
      wi_ = wi_ == seg::SEG_WORDS - 1 ? 0 : wi_ + 1;
      if (drop_n) ovf_ = true;
    }

    // The state RAM: reads of this edge see the old contents.
    const Addr next = next_addr(st, u, c_addr);
    const uint32_t ra_n = mem_[next.a], rb_n = mem_[next.b];
    if (op.we != W_NONE) {
      uint32_t& w = mem_[op.wa];
      if (op.we == W_BOTH) w = out;
      if (op.we == W_LO) w = (w & 0xFFFF0000u) | (out & 0xFFFFu);
      if (op.we == W_MASK) w = (w & 0xFFFF0000u) | (out & 0xFFFFu & ~mask_hi);
      if (op.we == W_SWAP) w = (w & 0xFFFF0000u) | (out >> 16);
    }
    ra_ = ra_n;
    rb_ = rb_n;
    ra_addr_ = uint8_t(next.a);
    rb_addr_ = uint8_t(next.b);

    if (ld) {
      if (ridx == seg::W_HDR) {
        type_ = (fd >> seg::H_TYPE_LSB) & 3;
        last_ = (fd >> seg::H_LAST) & 1;
        ccw_ = (fd >> seg::H_CCW) & 1;
        plane_ = (fd >> seg::H_PLANE_LSB) & 3;
        nq_ = (fd >> seg::H_NQ_LSB) & 7;
        neg_ = (fd >> seg::H_NEG_LSB) & 7;
        ncross_ = 0;
      }
      if (ridx == seg::W_N) nz_ = !zero;
      if (ridx == seg::W_A) {
        xz_ = zero;
        xn_ = sign;
      }
      if (ridx == seg::W_B) {
        yz_ = zero;
        yn_ = sign;
      }
    }
    if (st == ST_RUN) {
      if (u == 0) fen_ = !in.hold && !in.abort;
      if (u == 0 || u == 9) carry_ = cout;
      if (u == 9) carry9_ = cout;
      if (u == 1 && fire) pend_ = pend_ == 3 ? 3 : pend_ + 1;
      if (u == 3) xeq_ = zero;
      if (u == 4) yeq_ = zero;
      if (line && u >= 7 && u <= 9) {
        // (& 3: the axis, and no negative shift in the other steps' instantiations)
        const int ax = (u - 7) & 3;
        lmv_ = (lmv_ & ~(1 << ax)) | int(sign || zero) << ax;
      }
      if (u == 6 && go_) nz_ = !zero;
      if (arc && u == 8 && go_) {
        if (movex_) {
          xz_ = zero;
          xn_ = sign;
        } else {
          yz_ = zero;
          yn_ = sign;
        }
        if (!outw_ && zero) ncross_ = (ncross_ + 1) & 7;
      }
      if (u == 13 && go_) {
        move();
      }
      if (u == 5) {
        const bool movex = xlock ? false : (ylock ? true : (sign == xo));
        movex_ = movex;
        neg_m_ = movex ? mxn : myn;
        outw_ = movex == xo;
        if (!fin) {
          go_ = pend_ != 0 && !in.hold && !in.abort;
          if (go_) --pend_;
        }
      }
    }

    fifo_.clock(in.abort, push, in.wdata, rd);
    rv_ = rd;
    ridx_ = widx_;

    switch (st) {
      case ST_IDLE:
        for (int ax = 0; ax < 3; ++ax)
          if (in.set >> ax & 1)
            pos_[ax] = in.set_pos[ax];
          else if (in.jog >> ax & 1)
            pos_[ax] = sat32(i128(pos_[ax]) + (in.jog_neg ? -1 : 1));
        if (!in.set && ic_ == INIT_STEPS && count >= seg::SEG_WORDS) {
          st_ = ST_LOAD;
          widx_ = 0;
        }
        if (ic_ < INIT_STEPS) ++ic_;
        break;
      case ST_LOAD:
        if (rd) ++widx_;
        if (ld && ridx == seg::SEG_WORDS - 1) {
          st_ = ST_PREP;
          sq_ = 0;
        }
        break;
      case ST_PREP:
        if (sq_ == PREP_STEPS - 1) st_ = ST_RUN;
        sq_ = sq_ == PREP_STEPS - 1 ? 0 : sq_ + 1;
        break;
      default:
        sq_ = (u + 1) & (TICK - 1);
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
      go_ = false;
    }
    // Calm: a whole running tick went by with no input, no iteration fired
    // and none moving. Such a tick writes only what it computes from words
    // that only an iteration or a load changes (V15, the end and direction
    // flags, the line's step flags, the carry of step 9), each before it
    // reads it, besides the feed phase: so the next ticks repeat it, adding
    // inc to the phase, until one fires (run_quiet).
    // RunSkipEqualsClocks holds this to clocking every tick.
    const bool strobe = in.wr || in.abort || in.hold || in.clr || in.set || fire || go_;
    if (st_ != ST_RUN || strobe) {
      calm_ = false;
      tick_strobe_ = st_ == ST_RUN;
    }
    if (st_ == ST_RUN && sq_ == 0) {
      calm_ = !tick_strobe_ && pend_ == 0 && !go_ && calm_seen_;
      calm_seen_ = true;
      tick_strobe_ = false;
    } else if (st_ != ST_RUN) {
      calm_seen_ = false;
    }
  }

 public:
  // Up to n clocks with no input while a segment runs, calm stretches at
  // once (skip_run), stopping before the clock that would end the segment
  // (the caller clocks that one, and what follows, itself). The last clock
  // done never moves the position, so pos() after the call is also what
  // the last clock showed. Returns the clocks done; moved(i) is called
  // after the i-th clock of the call (from 1) when that clock moved the
  // position (pos() is then the new one).
  template <typename Moved>
  uint32_t run_for(uint32_t n, Moved&& moved) {
    return run(n, moved, true);
  }
  uint32_t run_for(uint32_t n) {
    return run_for(n, [](uint32_t) {});
  }
  // At least this many clocks go by before the running segment can end:
  // it ends at a tick's step 5 once N, counted down by one iteration a
  // tick at most, is 0, or (an arc) once x and y both equal the end point,
  // which an iteration brings at most one count nearer. Two ticks of slack
  // for where in its tick and its pending iterations the engine stands.
  uint32_t end_bound() const {
    if (st_ != ST_RUN || !nz_) return 0;
    uint64_t iters = mem_[1];
    if (type_ == seg::T_ARC) {
      const int64_t dx = int64_t(int32_t(mem_[4])) - int32_t(mem_[6]);
      const int64_t dy = int64_t(int32_t(mem_[5])) - int32_t(mem_[7]);
      iters = std::min<uint64_t>(iters, uint64_t(dx < 0 ? -dx : dx) + uint64_t(dy < 0 ? -dy : dy));
    }
    const uint64_t slack = 2 + 3;  // ticks: the current one and the next, and up to three pending
    return iters > slack ? uint32_t(std::min<uint64_t>((iters - slack) * TICK, 0xFFFFFFFFu)) : 0;
  }
  // Up to n clocks with no input while a segment runs, stopping only before
  // the clock that would end it (the last clock may move the position).
  uint32_t run_to_end(uint32_t n) {
    return run(
        n, [](uint32_t) {}, false);
  }
  // The current clock ends the running segment (its end test, at tick step 5).
  bool ending() const { return ending_as(st_, sq_); }

  // Running fast-forward. After a calm tick (clock() says why), with no
  // iteration pending: each further tick that fires no iteration only adds
  // inc to the phase (the phase being the one thing such a tick reads that
  // changes). run_quiet(in) says how many clocks from
  // here, with these inputs, fire nothing (0: not so); skip_run(n) does
  // n <= that many by arithmetic (calm_advance), whole ticks and parts of
  // one alike; only a clock between the phase's two adds is clocked.
  uint32_t run_quiet(const InterpIn& in) const {
    // At step 1 this tick's iteration is still to be decided.
    if (!calm_ || st_ != ST_RUN || sq_ == 1 || pend_ != 0 || go_ || in.wr || in.abort || in.hold || in.clr ||
        in.set)
      return 0;
    const uint32_t head = uint32_t(TICK - sq_) % TICK;
    constexpr uint64_t kAcc = uint64_t(1) << 44;  // the phase accumulator: V12[11:0] : V11
    const uint64_t acc = uint64_t(mem_[12] & 0xFFFu) << 32 | mem_[11];
    const uint64_t inc = uint64_t(mem_[3] & 0xFFFFu) << 32 | mem_[2];
    if (inc >= kAcc) return 0;
    // Ticks j = 1..m fire nothing while acc + j inc < 2^44; the clock after
    // them (step 0 of the tick that fires) adds to the phase only.
    const uint64_t m = inc == 0 ? uint64_t(1) << 26 : (kAcc - 1 - acc) / inc;
    return head + uint32_t(std::min<uint64_t>(m, uint64_t(1) << 26) * TICK + 1);
  }
  void skip_run(uint32_t n) {
    // Between the phase's two adds (steps 0 and 1) the accumulator is split
    // across V11 and V12 with the carry in flight: that clock is clocked.
    if (n > 0 && sq_ == 1) {
      clock_running();
      --n;
    }
    const bool split_end = n > 0 && ((sq_ + n) & (TICK - 1)) == 1;
    calm_advance(split_end ? n - 1 : n);
    if (split_end) clock_running();
  }

  // Fast-forward: idle with less than a segment queued and no input, the
  // core settles within two clocks and then stands still; skip(n) is n such
  // clocks.
  bool quiet(const InterpIn& in) const {
    return st_ == ST_IDLE && ic_ == INIT_STEPS && !rv_ && fifo_.count() < seg::SEG_WORDS && !in.wr &&
           !in.abort && !in.clr && !in.set && !in.jog;
  }
  void skip(uint32_t n) {
    for (uint32_t i = 0; i < n && i < 2; ++i) clock(InterpIn{});
  }

  int32_t pos(int a) const { return pos_[a]; }
  bool busy() const { return st_ != ST_IDLE; }
  int state() const { return st_; }
  // The PREP step or running tick's step of the current clock.
  int step() const { return sq_; }
  bool underrun() const { return underrun_; }
  bool ovf() const { return ovf_; }
  int seg_cnt() const { return seg_cnt_; }
  int count() const { return fifo_.count(); }
  // The feed phase, in units of 2^-PH_W iterations (its low TICK_LOG2 bits,
  // which a per-clock accumulator would hold, are always zero here).
  uint64_t phase() const {
    return ((uint64_t(mem_[12] & 0xFFFF) << 32 | mem_[11]) << seg::TICK_LOG2) & seg::PH_MASK;
  }

 private:
  enum { W_NONE, W_BOTH, W_LO, W_MASK, W_SWAP };
  // A is always read port a; B is read port b or the FIFO word.
  struct Op {
    bool operator==(const Op&) const = default;
    bool bfd = false, binv = false;  // B: the FIFO word (else read port b), inverted
    int cin = 0;
    int wa = 0;  // write address
    int we = W_NONE;
  };
  static Op alu(bool binv, int cin, int wa, int we) { return Op{false, binv, cin, wa, we}; }
  static constexpr int kInitAddr[INIT_STEPS] = {1, 0, 0, 11, 12};
  struct Addr {
    bool operator==(const Addr&) const = default;
    int a = 1, b = 1;
  };
  // The read addresses of the next clock's operation, by the current state
  // and step (the RTL's table).
  Addr next_addr(int st, int u, int c) const {
    const bool line = type_ == seg::T_LINE;
    if (st == ST_IDLE) return {1, 1};  // init: V - V = 0
    if (st == ST_LOAD) return {0, 3};
    if (st == ST_PREP) {
      switch (u) {
        case 0:
          return {1, 1};
        case 1:
          return {4, 4};
        case 2:
          return {5, 5};
        case 3:
          return {6, 6};
        case 7:
          return {11, 2};
        default:
          return {1, 0};
      }
    }
    switch (u) {
      case 15:
        return {11, 2};
      case 0:
        return {12, 3};
      case 1:
        return {8, 4};
      case 2:
        return {4, 6};
      case 3:
        return {5, 7};
      case 4:
        return {15, 5};
      case 6:
        return line ? Addr{7, 4} : Addr{8, c};
      case 7:
        return line ? Addr{8, 5} : Addr{c, 0};
      case 8:
        return line ? Addr{9, 6} : Addr{2, 9};
      case 9:
        return line ? Addr{7, 14} : Addr{8, c};
      case 10:
        return line ? Addr{8, 14} : Addr{3, 13};
      case 11:
        return {9, 14};
      default:
        return {1, 0};
    }
  }

  // run_for and run_to_end: still_last keeps the last clock from moving.
  template <typename Moved>
  uint32_t run(uint32_t n, Moved&& moved, bool still_last) {
    const InterpIn none{};
    uint32_t done = 0;
    while (done < n && st_ == ST_RUN) {
      if (const uint32_t q = run_quiet(none); q > 0) {
        const uint32_t m = std::min(q, n - done);
        skip_run(m);
        done += m;
        continue;
      }
      // The rest of a tick at once where it all fits and does not end the
      // segment: the tick that fires an iteration, and the one after it.
      if (const uint32_t k = uint32_t(TICK - sq_); n - done >= k && finish_tick(done, moved)) {
        done += k;
        continue;
      }
      // Else (a tick cut short by n, or one that ends the segment) clock by
      // clock.
      if (!run_step(n, done, moved, still_last)) break;
    }
    return done;
  }
  // One clock of run(): false, and not done, when it is the one that would
  // end the segment or, still_last, a last clock that moves.
  template <typename Moved>
  bool run_step(uint32_t n, uint32_t& done, Moved& moved, bool still_last) {
    const bool moves = sq_ == STEP_MOVE && go_ && move_axes().first != 0;
    if (ending() || (still_last && done + 1 == n && moves)) return false;
    clock_running();
    ++done;
    if (moves) moved(done);
    return true;
  }

  // The axes the going iteration moves at step 13 (bit a), and which of
  // them towards minus (a dwell's moves none).
  std::pair<int, int> move_axes() const {
    if (type_ == seg::T_LINE) return {lmv_, neg_};
    if (type_ != seg::T_ARC) return {0, 0};
    const int mv = 1 << seg::PLANE_AXES[plane_][movex_ ? 0 : 1];
    return {mv, neg_m_ ? mv : 0};
  }
  // Step 13 of an iteration: the position moves.
  void move() {
    const auto [mv, neg] = move_axes();
    for (int ax = 0; ax < 3; ++ax)
      if ((mv >> ax) & 1) pos_[ax] = sat32(int64_t(pos_[ax]) + (((neg >> ax) & 1) ? -1 : 1));
    go_ = false;
  }
  // The arc's quadrant, from the signs of x and y: the directions of the
  // two moves it allows (towards minus when set), and whether the x move is
  // outward.
  struct Quadrant {
    bool mxn, myn, xo;
  };
  Quadrant quadrant() const {
    const bool xp = !xn_ && !xz_, yp = !yn_ && !yz_;
    const bool q1 = ccw_ ? (xp && !yn_) : (!xn_ && yp);
    const bool q2 = ccw_ ? (!xp && yp) : (xn_ && !yn_);
    const bool q4 = ccw_ ? (!xn_ && yn_) : (xp && !yp);
    const bool upper = q1 || q2, right = q1 || q4;
    const bool mxn = upper == ccw_;
    return {mxn, right != ccw_, xz_ || (xn_ == mxn)};
  }

 public:
  // The clocks from step sq_ to the end of a running tick, with no input,
  // at once: the schedule of the header step by step, each ALU operation
  // on the words its read ports hold (within a running tick a port always
  // holds the word it addresses: no step reads a word in the clock it is
  // written), the flags as the edge sets them. False, and nothing done,
  // where the tick's step 5 would end the segment. moved(done + i) as
  // run() calls it, i the clock of the tick that moved the position.
  // FinishTickEqualsClocks holds it to clock().
  template <typename Moved>
  bool finish_tick(uint32_t done, Moved&& moved) {
    if (st_ != ST_RUN) return false;
    const int s = sq_;
    const bool line = type_ == seg::T_LINE, arc = type_ == seg::T_ARC;
    uint32_t* const v = mem_;
    if (s <= STEP_DECIDE) {
      const bool xeq = s <= 3 ? v[4] == v[6] : xeq_, yeq = s <= 4 ? v[5] == v[7] : yeq_;
      if (!nz_ || (arc && ncross_ == nq_ && xeq && yeq)) return false;
    }
    const auto add = [](uint32_t a, uint32_t b, bool neg) { return neg ? a - b : a + b; };
    // A strobe in a clock of the tick (an iteration fired or going): an
    // iteration already going stays so to step 13, but for step 5 deciding
    // anew.
    bool strobe = tick_strobe_ || (go_ && s != STEP_DECIDE && s != STEP_MOVE);
    if (s == 0) {
      const uint64_t sum = uint64_t(v[11]) + v[2];
      v[11] = uint32_t(sum);
      carry_ = (sum >> 32) & 1;
      fen_ = true;
    }
    if (s <= 1 && fen_) {
      constexpr int PHB = 16 - seg::TICK_LOG2;
      constexpr uint32_t mask_hi = ((1u << 16) - 1) & ~((1u << PHB) - 1);
      const uint32_t a = v[12], b = v[3], out = a + b + uint32_t(carry_);
      v[12] = (a & 0xFFFF0000u) | (out & 0xFFFFu & ~mask_hi);
      if ((((out ^ a ^ b) >> 16) & 1) || (out & mask_hi) != 0) {
        pend_ = pend_ == 3 ? 3 : pend_ + 1;
        strobe = true;
      }
    }
    const Quadrant q = quadrant();
    if (s <= 2) v[15] = add(v[8], v[4], q.mxn);
    if (s <= 3) xeq_ = v[4] == v[6];
    if (s <= 4) yeq_ = v[5] == v[7];
    if (s <= STEP_DECIDE) {
      const bool sign = add(v[15], v[5], q.myn) >> 31;
      const bool final_q = ncross_ == nq_;
      const bool movex = final_q && xeq_ ? false : (final_q && yeq_ ? true : sign == q.xo);
      movex_ = movex;
      neg_m_ = movex ? q.mxn : q.myn;
      outw_ = movex == q.xo;
      go_ = pend_ != 0;
      if (go_) {
        --pend_;
        strobe = true;
      }
    }
    const bool go = go_;
    if (s <= 6 && go) {
      --v[1];
      nz_ = v[1] != 0;
    }
    const int c = movex_ ? 4 : 5;
    const bool dn = !outw_;
    if (line) {
      for (int ax = 0; ax < 3; ++ax) {
        if (s > 7 + ax) continue;
        const uint32_t out = v[7 + ax] - v[4 + ax];
        lmv_ = (lmv_ & ~(1 << ax)) | int(int32_t(out) <= 0) << ax;
        if (ax == 2) carry_ = carry9_ = v[9] >= v[6];
        if (go) v[7 + ax] = out;
      }
      for (int ax = 0; ax < 3; ++ax)
        if (s <= 10 + ax && go && ((lmv_ >> ax) & 1)) v[7 + ax] += v[14];
    } else {
      if (arc && s <= 7 && go) v[8] = add(v[8], v[c], neg_m_);
      if (arc && s <= 8 && go) {
        const uint32_t out = neg_m_ ? v[c] - 1 : v[c] + 1;
        v[c] = out;
        (movex_ ? xz_ : yz_) = out == 0;
        (movex_ ? xn_ : yn_) = out >> 31;
        if (!outw_ && out == 0) ncross_ = (ncross_ + 1) & 7;
      }
      if (s <= 9) {
        // A dwell adds, as the ALU does with no operation.
        const bool sub = arc && dn;
        const uint32_t out = add(v[2], v[9], sub);
        carry_ = carry9_ = sub ? v[2] >= v[9] : out < v[2];
        if (arc && go) v[2] = out;
      }
      if (arc && s <= 10 && go) v[8] = add(v[8], v[c], neg_m_);
      if (arc && s <= 11 && go) {
        const uint32_t out = v[3] + (dn ? ~v[13] : v[13]) + uint32_t(carry_);
        v[3] = (v[3] & 0xFFFF0000u) | (out & 0xFFFFu);
      }
    }
    const bool moving = go && move_axes().first != 0;
    if (s <= STEP_MOVE && go) {
      move();
    }
    // The read ports as step 15 addresses them; the calm flags at the
    // tick's end.
    ra_ = v[11];
    rb_ = v[2];
    ra_addr_ = 11;
    rb_addr_ = 2;
    rv_ = false;
    ridx_ = widx_;
    sq_ = 0;
    calm_ = !strobe && pend_ == 0 && !go_ && calm_seen_;
    calm_seen_ = true;
    tick_strobe_ = false;
    if (s <= STEP_MOVE && go && moving) moved(done + uint32_t(STEP_MOVE - s + 1));
    return true;
  }

 private:
  // n calm clocks at once, from and to a step other than 1 (skip_run).
  // A calm tick rewrites every word and flag with the value it holds, but
  // for the phase (steps 0 and 1) and the carry (set at steps 0 and 9): so
  // the state after them is the phase advanced once per step 0 passed, the
  // carry of the last setter passed, and the read ports as step s1 - 1
  // addressed them (no write of a calm clock changes what they read).
  void calm_advance(uint32_t n) {
    if (n == 0) return;
    const uint32_t s0 = uint32_t(sq_), s1 = (s0 + n) & (TICK - 1);
    // Clocks at step 0 and at step 9 among steps s0 .. s0 + n - 1.
    const auto passes = [&](uint32_t step) {
      return (s0 + n + (TICK - 1 - step)) / TICK - (s0 + (TICK - 1 - step)) / TICK;
    };
    const uint32_t ticks = passes(0);
    if (ticks > 0) {
      const uint64_t acc = uint64_t(mem_[12] & 0xFFFu) << 32 | mem_[11];
      const uint64_t inc = uint64_t(mem_[3] & 0xFFFFu) << 32 | mem_[2];
      const uint64_t now = acc + uint64_t(ticks) * inc, before = now - inc;
      mem_[11] = uint32_t(now);
      mem_[12] = (mem_[12] & 0xFFFF0000u) | uint32_t(now >> 32);
      if (s1 >= 2 && s1 <= 9) carry_ = ((before & 0xFFFFFFFFu) + (inc & 0xFFFFFFFFu)) >> 32;
    }
    if ((s1 == 0 || s1 > 9) && passes(9) > 0) carry_ = carry9_;
    // The ports as the clock before s1 addressed them.
    const Addr a = next_addr(st_, int(s1 + TICK - 1) & (TICK - 1), movex_ ? 4 : 5);
    sq_ = int(s1);
    ra_ = mem_[a.a];
    rb_ = mem_[a.b];
    ra_addr_ = uint8_t(a.a);
    rb_addr_ = uint8_t(a.b);
  }

  SegFifo<FIFO_AW> fifo_;
  uint32_t mem_[16] = {};
  uint32_t ra_ = 0, rb_ = 0;
  uint8_t ra_addr_ = 1, rb_addr_ = 1;  // where ra_ and rb_ were read
  // run_quiet: the last tick was calm; a whole tick has run since the
  // segment started; a strobe came during this tick.
  bool calm_ = false, calm_seen_ = false, tick_strobe_ = false;
  int st_ = ST_IDLE;
  int sq_ = 0;  // PREP step or RUN tick step
  int ic_ = 0;  // init steps done after reset
  int widx_ = 0, ridx_ = 0;
  bool rv_ = false;
  int wi_ = 0;
  bool drop_ = false;
  int pend_ = 0;
  bool go_ = false, fen_ = false, carry_ = false;
  // The carry step 9 set last (not a register of the RTL: carry_ holds it
  // from step 9 to step 0), for calm_advance().
  bool carry9_ = false;
  // segment header
  int type_ = 0, plane_ = 0, nq_ = 0, neg_ = 0;
  bool last_ = false, ccw_ = false;
  // flags of the running segment
  bool nz_ = false, xz_ = false, xn_ = false, yz_ = false, yn_ = false, xeq_ = false, yeq_ = false;
  int ncross_ = 0;
  int lmv_ = 0;  // line: axes that step this iteration
  bool movex_ = false, neg_m_ = false, outw_ = false;
  int32_t pos_[3] = {};
  bool underrun_ = false, ovf_ = false;
  int seg_cnt_ = 0;
};

}  // namespace mc
