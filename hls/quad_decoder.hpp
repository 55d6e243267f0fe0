// quad_decoder twin: one quadrature encoder (A, B, index Z) to a 32-bit
// position, with glitch filters, error detection, an index latch and a
// velocity figure. Cycle for cycle the RTL (rtl/quad_decoder.v): step() is one
// clock edge, its registers carry the RTL's names and are updated in the
// RTL's order, and the outputs after each step equal the RTL's bit for bit.
// rtl/quad_decoder.v documents how to drive it; docs/encoder.md is the guide.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// Template parameters are the RTL's parameters (widths in bits).
#pragma once

#include <cstdint>

#include "mc_fixed.hpp"

namespace mc {

// Inputs of one clock: the RTL's ports without clk and the _i suffix.
struct QuadIn {
  bool operator==(const QuadIn&) const = default;
  bool rst = false;
  // configuration
  uint32_t filt_len = 0;  // clocks; only the low FILT_W bits reach the RTL
  bool dir_inv = false;
  bool idx_clr_en = false;
  // control strobes
  bool pos_load = false;
  int32_t pos_load_val = 0;
  bool idx_arm = false;
  bool idx_disarm = false;
  bool err_clr = false;
  bool sample = false;
  // encoder pins
  bool a = false;
  bool b = false;
  bool z = false;
  bool latch = false;  // synchronous strobe: latch as a Z edge would (a home switch, the probe)
};

// Outputs after a clock edge: the RTL's output ports without the _o suffix.
struct QuadOut {
  int32_t pos = 0;
  int32_t idx_pos = 0;
  bool idx_armed = false;
  bool idx_seen = false;
  bool err = false;
  uint32_t err_cnt = 0;
  int32_t vel = 0;  // sign-extended from VEL_W bits
  uint32_t age = 0;
  bool a = false;
  bool b = false;
  bool z = false;
  bool operator==(const QuadOut&) const = default;
};

// All ones in the low w bits (w <= 32).
constexpr uint32_t ones(int w) {
  return uint32_t((uint64_t(1) << w) - 1);
}

// IDX_RAM: the RTL's IDX_RAM parameter (the index latch in block RAM: its
// output a clock later, not reset); POS_LOAD: the RTL's POS_LOAD (false: no
// position load, pos_load ignored).
template <int FILT_W = 8, int ERR_W = 16, int VEL_W = 32, int AGE_W = 16, bool IDX_RAM = false,
          bool POS_LOAD = true>
class QuadDecoder {
  static_assert(FILT_W >= 1 && FILT_W <= 16, "quad_decoder: FILT_W must be 1..16");
  static_assert(ERR_W >= 2 && ERR_W <= 32, "quad_decoder: ERR_W must be 2..32");
  static_assert(VEL_W >= 2 && VEL_W <= 32, "quad_decoder: VEL_W must be 2..32");
  static_assert(AGE_W >= 2 && AGE_W <= 32, "quad_decoder: AGE_W must be 2..32");

 public:
  bool operator==(const QuadDecoder&) const = default;
  static constexpr int filt_w = FILT_W, err_w = ERR_W, vel_w = VEL_W, age_w = AGE_W;

  // The RTL's registers power up at random; its synchronous reset (held 3
  // clocks or more) brings every one to a value that depends only on the
  // pins. This puts the twin in the state of a reset with all pins low.
  QuadDecoder() = default;

  // One rising clock edge with these inputs. Channels: bit 0 = A, 1 = B, 2 = Z.
  QuadOut step(const QuadIn& in) {
    // Nonblocking: every right-hand side reads r, this clock's registers;
    // the next values go straight into r_ (n).
    const Regs r = r_;
    Regs& n = r_;
    const uint32_t pins = pins_of(in);
    const uint32_t len = in.filt_len & ones(FILT_W);

    // Synchronizers.
    n.meta = pins;
    n.sync = r.meta;

    // Glitch filters.
    const uint32_t differ = r.sync ^ r.filt;
    uint32_t pass = 0, drop = 0;
    for (int c = 0; c < 3; ++c) {
      const uint32_t seen = r.cnt[c] + 1;
      const bool d = (differ >> c) & 1;
      if (d && seen >= len) pass |= 1u << c;
      if (c < 2 && !d && r.cnt[c] != 0) drop |= 1u << c;
    }
    for (int c = 0; c < 3; ++c) {
      const bool d = (differ >> c) & 1, p = (pass >> c) & 1;
      n.cnt[c] = (in.rst || !d || p) ? 0 : (r.cnt[c] + 1) & ones(FILT_W);
    }
    n.filt = in.rst ? r.sync : r.filt ^ pass;

    const uint32_t sync_other = other_of(r.sync);
    for (int c = 0; c < 2; ++c) {
      const bool d = (differ >> c) & 1, p = (pass >> c) & 1;
      if (in.rst || !d || p) n.oth = (n.oth & ~(1u << c)) | (sync_other & (1u << c));
    }
    const bool straddle = (drop & (sync_other ^ r.oth)) != 0;

    // 4x decode.
    // The decision is registered once before the counters (RTL: the
    // filter's compare and the count would otherwise be one path).
    const bool a_mv = pass & 1, b_mv = (pass >> 1) & 1;
    n.step = !in.rst && a_mv != b_mv;
    n.fwd = !in.rst && fwd_now(r, a_mv);
    n.qerr = !in.rst && ((a_mv && b_mv) || straddle);
    n.z_rise = !in.rst && ((pass >> 2) & 1) && ((r.sync >> 2) & 1);
    const bool step = r.step;
    const bool up = r.fwd != in.dir_inv;
    const bool qerr = r.qerr;

    const bool dn = step && !up;
    const uint32_t pos_cnt = r.pos_o + (dn ? ~0u : uint32_t(step));
    const bool idx_hit = r.idx_armed_o && (r.z_rise || in.latch);

    // Reset, then load, then the index clear, then counting.
    n.pos_o = in.rst                       ? 0
              : POS_LOAD && in.pos_load    ? uint32_t(in.pos_load_val)
              : (idx_hit && in.idx_clr_en) ? 0
                                           : pos_cnt;

    if constexpr (IDX_RAM) {
      n.idx_pos_o = r.idx_mem[r.idx_w];
      if (idx_hit && !in.rst) {
        n.idx_mem[!r.idx_w] = pos_cnt;
        n.idx_w = !r.idx_w;
      }
    } else if (in.rst) {
      n.idx_pos_o = 0;
    } else if (idx_hit) {
      n.idx_pos_o = pos_cnt;
    }

    if (in.rst) {
      n.idx_armed_o = false;
      n.idx_seen_o = false;
    } else {
      if (in.idx_disarm || idx_hit)
        n.idx_armed_o = false;
      else if (in.idx_arm)
        n.idx_armed_o = true;
      if (idx_hit)
        n.idx_seen_o = true;
      else if (in.idx_arm)
        n.idx_seen_o = false;
    }

    if (in.rst) {
      n.err_o = false;
      n.err_cnt_o = 0;
    } else {
      n.err_o = (r.err_o && !in.err_clr) || qerr;
      if (in.err_clr)
        n.err_cnt_o = qerr ? 1 : 0;
      else
        n.err_cnt_o = r.err_cnt_o + ((qerr && r.err_cnt_o != ones(ERR_W)) ? 1 : 0);
    }

    // Per sample: the accumulator saturates (holds) at the VEL_W extremes.
    const int32_t vel_d = dn ? -1 : int32_t(step);
    const int64_t vel_sum = int64_t(r.vel_acc) + vel_d;
    const bool vel_ovf = sat(vel_sum, VEL_W) != vel_sum;
    if (in.rst) {
      n.vel_acc = 0;
      n.vel_o = 0;
    } else if (in.sample) {
      n.vel_acc = vel_d;
      n.vel_o = r.vel_acc;
    } else if (!vel_ovf) {
      n.vel_acc = int32_t(vel_sum);
    }

    if (in.rst) {
      n.age = ones(AGE_W);
      n.age_o = ones(AGE_W);
    } else {
      n.age = step ? 0 : r.age + (r.age != ones(AGE_W) ? 1 : 0);
      if (in.sample) n.age_o = r.age;
    }

    return out();
  }

  // Fast-forward, for long simulations: with these inputs held, no strobe
  // and the pins already through the synchronizers and filters, a clock
  // only ages the last edge; skip(n) is then n such clocks at once.
  bool quiet(const QuadIn& in) const { return !in.sample && quiet_but_sample(in); }
  void skip(uint32_t n) {
    r_.fwd = fwd_now(r_, false);  // what every quiet clock registers
    const uint64_t age = uint64_t(r_.age) + n;
    r_.age = age > ones(AGE_W) ? ones(AGE_W) : uint32_t(age);
  }
  // quiet() but for the sample strobe: such a clock that samples (the
  // PID's tick, every sample) publishes the velocity and the age as well,
  // and skip_sampled() is that clock, for much less than step().
  bool quiet_but_sample(const QuadIn& in) const {
    return !strobed(in) && pins_of(in) == r_.meta && settled();
  }
  void skip_sampled() {
    r_.vel_o = r_.vel_acc;
    r_.vel_acc = 0;  // no count in a quiet clock
    r_.age_o = r_.age;
    skip(1);
  }

  // Fast-forward through an edge: with these inputs held and no strobe, the
  // clocks until quiet() (0: it is now), provided that nothing a reader
  // looks at between samples changes on the way: the error flag and count
  // and the index latch (the position, velocity and age move, as they would
  // on a quiet clock's caller's next sample). kUnsettled otherwise, or when
  // the filter would take longer than kMaxSettle.
  static constexpr uint32_t kUnsettled = ~0u;
  static constexpr uint32_t kMaxSettle = (1u << FILT_W) + 8;
  uint32_t settle_clocks(const QuadIn& in) const {
    if (quiet(in)) return 0;
    if (strobed(in) || in.sample) return kUnsettled;
    if (clean_edge(in)) {
      // A move or a rising index is registered at the filter's pass and
      // gone a clock later; anything else is over with the pass.
      const uint32_t pins = pins_of(in);
      const uint32_t pass = pins ^ r_.meta;
      return (pass & 3) != 0 || (pass & pins & 4) != 0 ? kEdgeClocks : kEdgeClocks - 1;
    }
    QuadDecoder d = *this;
    for (uint32_t c = 1; c <= kMaxSettle; ++c) {
      d.step(in);
      const Regs& e = d.r_;
      if (e.err_o != r_.err_o || e.err_cnt_o != r_.err_cnt_o || e.idx_pos_o != r_.idx_pos_o ||
          e.idx_armed_o != r_.idx_armed_o || e.idx_seen_o != r_.idx_seen_o)
        return kUnsettled;
      if (d.quiet(in)) return c;
    }
    return kUnsettled;
  }
  // n clocks with these inputs after settle_clocks(in) said it settles:
  // stepped until quiet, skipped from there.
  void skip_settling(const QuadIn& in, uint32_t n) {
    // Most stretches find the decoder settled on the pins it is given
    // (quiet(), for which clean_edge() is false): skipped at once.
    if (n > 0 && quiet(in)) {
      skip(n);
      return;
    }
    if (n >= kEdgeClocks && clean_edge(in)) {
      settle_edge(in);
      skip(n - kEdgeClocks);
      return;
    }
    step_then_skip(in, n);
  }

  // A clean edge from pins `from` to in's, the decoder settled on `from` by
  // then (as clean_edge() asks of the pins it last saw): what a caller
  // checks of an edge it wants skip_settling() to take later in a stretch.
  static constexpr uint32_t kEdgeClocks = 4;
  bool clean_edge_from(uint32_t from, const QuadIn& in) const {
    return !strobed(in) && !in.sample && clean_pass(from, in);
  }
  // A strobe other than the sample's, or the reset: what no fast-forward
  // goes through.
  static bool strobed(const QuadIn& in) {
    return in.rst | in.latch | (POS_LOAD & in.pos_load) | in.idx_arm | in.idx_disarm | in.err_clr;
  }
  static uint32_t pins_of(const QuadIn& in) {
    return uint32_t(in.a) | uint32_t(in.b) << 1 | uint32_t(in.z) << 2;
  }

  // Single outputs, for users that need a few every clock.
  int32_t pos() const { return int32_t(r_.pos_o); }
  int32_t idx_pos() const { return int32_t(r_.idx_pos_o); }
  bool idx_armed() const { return r_.idx_armed_o; }
  bool idx_seen() const { return r_.idx_seen_o; }
  bool err() const { return r_.err_o; }
  uint32_t err_cnt() const { return r_.err_cnt_o; }

  QuadOut out() const {
    QuadOut o;
    o.pos = int32_t(r_.pos_o);
    o.idx_pos = int32_t(r_.idx_pos_o);
    o.idx_armed = r_.idx_armed_o;
    o.idx_seen = r_.idx_seen_o;
    o.err = r_.err_o;
    o.err_cnt = r_.err_cnt_o;
    o.vel = r_.vel_o;
    o.age = r_.age_o;
    o.a = r_.filt & 1;
    o.b = (r_.filt >> 1) & 1;
    o.z = (r_.filt >> 2) & 1;
    return o;
  }

 private:
  // The rest of skip_settling(), rarely taken, out of line: where GCC
  // inlined it, every call of skip_settling() saved the registers its steps
  // use, which the co-simulation's instruction count showed.
  [[gnu::noinline]] void step_then_skip(const QuadIn& in, uint32_t n) {
    uint32_t i = 0;
    for (; i < n && !quiet(in); ++i) step(in);
    if (i < n) skip(n - i);
  }

  // The RTL's registers, same names, in the RTL's order.
  // Direction of this clock's A or B move (A leads B: forward).
  struct Regs;
  static bool fwd_now(const Regs& r, bool a_mv) { return fwd_of(r.sync, r.filt, a_mv); }
  static bool fwd_of(uint32_t sync, uint32_t filt, bool a_mv) {
    return a_mv ? ((sync ^ (filt >> 1)) & 1) != 0 : (((sync >> 1) ^ filt) & 1) == 0;
  }

  // A clean edge: the decoder settled on the pins it last saw (as quiet()
  // would have it, strobes aside), new pins that a filter of at most one
  // clock passes at once, and neither a quadrature error nor an armed index
  // on the way. The settling then always takes the same clocks: two
  // through the synchronizers, the filter's pass, the count (a move's);
  // settle_edge() is the first kEdgeClocks, as step() does them
  // (QuadTwinFastForward holds it to step()).
  bool clean_edge(const QuadIn& in) const { return clean_pass(r_.meta, in) && settled(); }
  // in's pins after `from`: one of A and B moving, or the index, through a
  // filter of at most one clock, and no armed index hit.
  bool clean_pass(uint32_t from, const QuadIn& in) const {
    const uint32_t pins = pins_of(in);
    const uint32_t pass = pins ^ from;
    return (in.filt_len & ones(FILT_W)) <= 1 && pass != 0 && (pass & 3) != 3 &&
           !(r_.idx_armed_o && (pass & pins & 4));
  }
  // Everything through the synchronizers and filters on the pins last
  // seen (meta), nothing registered: quiet() with those pins held, strobes
  // aside.
  // (One OR of differences rather than a chain of tests: a look at the
  // core asks it of every decoder, and it is nearly always true.)
  bool settled() const {
    const uint32_t moving = (r_.meta ^ r_.sync) | (r_.sync ^ r_.filt) | r_.cnt[0] | r_.cnt[1] | r_.cnt[2] |
                            (r_.oth ^ other_of(r_.sync)) | uint32_t(r_.step) | uint32_t(r_.qerr) |
                            uint32_t(r_.z_rise);
    return moving == 0 && (!IDX_RAM || r_.idx_pos_o == r_.idx_mem[r_.idx_w]);
  }
  // A and B swapped: what each channel's "other" register holds.
  static uint32_t other_of(uint32_t ab) { return ((ab & 1) << 1) | ((ab >> 1) & 1); }
  void settle_edge(const QuadIn& in) {
    const uint32_t pins = pins_of(in);
    const bool a_mv = (pins ^ r_.meta) & 1, b_mv = ((pins ^ r_.meta) >> 1) & 1;
    // Clock 3 registers the move's direction from the new synchronizer and
    // the old filter; clock 4 counts it.
    const bool step = a_mv != b_mv, up = fwd_of(pins, r_.filt, a_mv) != in.dir_inv;
    r_.meta = r_.sync = r_.filt = pins;
    r_.oth = other_of(pins);
    r_.fwd = fwd_of(pins, pins, false);
    if (step) {
      r_.pos_o += up ? 1u : ~0u;
      const int64_t vel_sum = int64_t(r_.vel_acc) + (up ? 1 : -1);
      if (sat(vel_sum, VEL_W) == vel_sum) r_.vel_acc = int32_t(vel_sum);
      r_.age = 0;
    } else {
      const uint64_t age = uint64_t(r_.age) + kEdgeClocks;
      r_.age = age > ones(AGE_W) ? ones(AGE_W) : uint32_t(age);
    }
  }

  struct Regs {
    bool operator==(const Regs&) const = default;
    bool step = false, fwd = false, qerr = false, z_rise = false;  // the registered decision
    uint32_t meta = 0, sync = 0;                                   // 3 bits each
    uint32_t cnt[3] = {};                                          // FILT_W bits each
    uint32_t filt = 0;                                             // 3 bits
    uint32_t oth = 0;                                              // 2 bits
    uint32_t pos_o = 0;
    uint32_t idx_pos_o = 0;
    uint32_t idx_mem[2] = {};  // IDX_RAM only
    bool idx_w = false;
    bool idx_armed_o = false;
    bool idx_seen_o = false;
    bool err_o = false;
    uint32_t err_cnt_o = 0;      // ERR_W bits
    int32_t vel_acc = 0;         // VEL_W bits, signed
    int32_t vel_o = 0;           // VEL_W bits, signed
    uint32_t age = ones(AGE_W);  // AGE_W bits
    uint32_t age_o = ones(AGE_W);
  };
  Regs r_;
};

}  // namespace mc
