// pid_core twin: NAXES Tustin PID position loops sharing one multiply datapath.
//
// How to drive it (the same as rtl/pid_core.v): write coefficients and limits
// through write(addr, data) (addresses in hls/pid_regs.hpp), set CTRL.enable per
// axis, then call sample(cmd, fb) once per sample period. After the call,
// u(axis) holds the new drive output, err(axis) the processed error and
// sat(axis) whether the output limit was active. The RTL takes G_LATENCY cycles
// from its sample tick to the same values; the numbers are identical bit for bit.
//
// Realization (docs/numerics.md derives it): parallel form
//   P(k) = kp * e(k)
//   I(k) = I(k-1) + ki * (e(k) + e(k-1))            ki = Ki*Ts/2
//   D(k) = alpha * D(k-1) + beta * (e(k) - e(k-1))   alpha = (2Tf-Ts)/(2Tf+Ts),
//                                                    beta = 2Kd/(2Tf+Ts)
//   F(k) = kf1 * (c(k)-c(k-1)) + kf2 * (c(k)-2c(k-1)+c(k-2))
//   u(k) = sat(P + I + D + F)
// which has exactly the transfer function of the Tustin-discretized
// C(s) = Kp + Ki/s + Kd s/(Tf s + 1), but never subtracts nearly equal
// coefficients, so the integral action survives at short Ts.
//
// Anti-windup is conditional integration against the headroom: while the
// output is beyond its limit, the integrator may not grow past what the limit
// leaves (limit - P - D - F) unless it already was there. With |I| bounded by
// the output limit, the output leaves saturation on the first sample whose
// error has the opposite sign.
#pragma once

#include <cstdint>

#include "mc_fixed.hpp"
#include "pid_regs.hpp"

namespace mc {

// Sweep latency in clock cycles, tick to last output: the RTL's schedule
// (see rtl/pid_core.v). Each axis has a slot of pid_axis_cycles; the back end
// of the last axis and the tick add pid_fill_cycles. Shortest legal Ts = this
// value.
constexpr int pid_axis_cycles = 18;
constexpr int pid_fill_cycles = 16;
constexpr int pid_latency(int naxes) {
  return naxes * pid_axis_cycles + pid_fill_cycles;
}

// Per-axis parameters as stored (the coefficient RAM of the RTL).
struct PidParams {
  bool operator==(const PidParams&) const = default;
  uint32_t word[pid_reg::NREGS_RAM] = {};
};

// Per-axis state carried between samples.
struct PidState {
  bool operator==(const PidState&) const = default;
  int64_t i = 0;   // integrator, Q17.32
  int64_t d = 0;   // derivative filter state, Q17.32
  int32_t e1 = 0;  // e(k-1)
  int32_t c1 = 0;  // c(k-1)
  int32_t c2 = 0;  // c(k-2)
};

struct PidOut {
  bool operator==(const PidOut&) const = default;
  int32_t u = 0;    // drive output, OUT_W bits
  int32_t err = 0;  // processed error (after deadband and clamp)
  bool sat = false;
};

// Deadband then clamp, on the saturated difference command - feedback.
inline int32_t pid_error(int32_t cmd, int32_t fb, uint32_t dband_w, uint32_t elim_w) {
  const int32_t e_raw = sat32(int64_t(cmd) - fb);
  const int64_t db = dband_w & 0x7FFFFFFFu;
  const int64_t el = elim_w & 0x7FFFFFFFu;
  int64_t e = e_raw > db ? e_raw - db : (e_raw < -db ? e_raw + db : 0);
  if (el != 0) e = e > el ? el : (e < -el ? -el : e);
  return int32_t(e);
}

// Effective output limit in output units: 0 or out of range means full scale.
inline int64_t pid_olim(uint32_t w) {
  const int64_t v = w & 0xFFFF;
  return (v == 0 || v > OUT_MAX) ? OUT_MAX : v;
}

// An axis's parameters as the sample applies them: the coefficients' shifts
// and the limits worked out from the words once, when they are written
// (PidCore), rather than at every sample.
struct PidPrepared {
  bool operator==(const PidPrepared&) const = default;
  CoefShift kp, ki, kd_a, kd_b, kf1, kf2;
  uint32_t dband, elim;  // the words, as pid_error reads them
  int64_t ulim, ibound;  // the output and integrator bounds, accumulator units
};
inline PidPrepared pid_prepare(const PidParams& p) {
  using namespace pid_reg;
  PidPrepared q{};
  q.kp = coef_shift(coef_unpack(p.word[KP]));
  q.ki = coef_shift(coef_unpack(p.word[KI]));
  q.kd_a = coef_shift(coef_unpack(p.word[KD_A]));
  q.kd_b = coef_shift(coef_unpack(p.word[KD_B]));
  q.kf1 = coef_shift(coef_unpack(p.word[KF1]));
  q.kf2 = coef_shift(coef_unpack(p.word[KF2]));
  q.dband = p.word[DBAND];
  q.elim = p.word[ELIM];
  q.ulim = pid_olim(p.word[OLIM]) << ACC_FRAC;
  const int64_t il_w = p.word[ILIM] & 0xFFFF;
  q.ibound = (il_w != 0 && (il_w << ACC_FRAC) < q.ulim) ? (il_w << ACC_FRAC) : q.ulim;
  return q;
}

// One sample of one axis. This is the arithmetic of the RTL schedule, step for
// step; the order of the saturating additions matters and is the same.
inline PidOut pid_axis_update(const PidPrepared& p, PidState& st, bool enable, int32_t cmd, int32_t fb) {
  PidOut o;
  const int32_t e = pid_error(cmd, fb, p.dband, p.elim);
  const int32_t sum_e = sat32(int64_t(e) + st.e1);
  const int32_t dif_e = sat32(int64_t(e) - st.e1);
  const int32_t vel = sat32(int64_t(cmd) - st.c1);
  const int32_t acc = sat32(int64_t(cmd) - 2 * int64_t(st.c1) + st.c2);
  o.err = e;
  if (!enable) {
    // Disabled: output 0 and the dynamic state cleared; the error and command
    // history keep tracking so that enabling is bumpless.
    st.i = 0;
    st.d = 0;
    st.e1 = e;
    st.c2 = st.c1;
    st.c1 = cmd;
    return o;
  }
  const int64_t pterm = mul_align(p.kp, e);
  const int64_t di = mul_align(p.ki, sum_e);
  const int64_t da = mul_align(p.kd_a, acc_to_doper(st.d));
  const int64_t db = mul_align(p.kd_b, dif_e);
  const int64_t f1 = mul_align(p.kf1, vel);
  const int64_t f2 = mul_align(p.kf2, acc);

  const int64_t ulim = p.ulim, ibound = p.ibound;

  int64_t i_c = sat_acc(st.i + di);
  i_c = i_c > ibound ? ibound : (i_c < -ibound ? -ibound : i_c);
  const int64_t dn = sat_acc(da + db);
  const int64_t ff = sat_acc(f1 + f2);
  const int64_t rest = sat_acc(sat_acc(pterm + dn) + ff);
  const int64_t v = sat_acc(rest + i_c);

  int64_t i_n = i_c;
  if (v > ulim) {
    const int64_t head = sat_acc(ulim - rest);
    const int64_t cap = head > st.i ? head : st.i;
    i_n = i_c < cap ? i_c : cap;
  } else if (v < -ulim) {
    const int64_t head = sat_acc(-ulim - rest);
    const int64_t cap = head < st.i ? head : st.i;
    i_n = i_c > cap ? i_c : cap;
  }
  const int32_t u = acc_to_out(sat_acc(rest + i_n));
  const int32_t ul = int32_t(ulim >> ACC_FRAC);
  o.u = u > ul ? ul : (u < -ul ? -ul : u);
  o.sat = v > ulim || v < -ulim;

  st.i = i_n;
  st.d = dn;
  st.e1 = e;
  st.c2 = st.c1;
  st.c1 = cmd;
  return o;
}
inline PidOut pid_axis_update(const PidParams& p, PidState& st, bool enable, int32_t cmd, int32_t fb) {
  return pid_axis_update(pid_prepare(p), st, enable, cmd, fb);
}

// SERVO = false: rtl/pid_core.v built without its loops (a stepper board):
// an enable write is ignored, so every axis runs as a disabled one.
template <int NAXES, bool SERVO = true>
class PidCore {
  static_assert(NAXES >= 1 && NAXES <= 15, "pid_core: NAXES must be 1..15");

 public:
  bool operator==(const PidCore&) const = default;
  static constexpr int latency = pid_latency(NAXES);

  PidCore() {
    for (PidPrepared& q : prep_) q = pid_prepare(PidParams{});
  }

  // Synchronous reset: enables and state cleared, Ts back to its minimum.
  // The coefficient RAM keeps its contents, as block RAM does.
  void reset() {
    for (int a = 0; a < NAXES; ++a) {
      st_[a] = PidState{};
      out_[a] = PidOut{};
      en_[a] = false;
    }
    ts_ = latency;
  }

  void write(uint8_t addr, uint32_t data) {
    const int ax = addr >> 4, r = addr & 0xF;
    if (ax == pid_reg::GLOBAL_AXIS) {
      if (r == pid_reg::G_TS) ts_ = data < uint32_t(latency) ? uint32_t(latency) : data;
      return;
    }
    if (ax >= NAXES) return;
    if (r < pid_reg::NREGS_RAM) {
      par_[ax].word[r] = data;
      prep_[ax] = pid_prepare(par_[ax]);
    } else if (r == pid_reg::CTRL)
      en_[ax] = SERVO && (data & 1);
  }

  uint32_t read(uint8_t addr) const {
    const int ax = addr >> 4, r = addr & 0xF;
    if (ax == pid_reg::GLOBAL_AXIS) {
      if (r == pid_reg::G_TS) return ts_;
      if (r == pid_reg::G_LATENCY) return latency;
      if (r == pid_reg::G_NAXES) return NAXES;
      return 0;
    }
    if (ax >= NAXES) return 0;
    if (r < pid_reg::NREGS_RAM) return par_[ax].word[r];
    if (r == pid_reg::CTRL) return en_[ax] ? 1u : 0u;
    return 0;
  }

  void sample(const int32_t* cmd, const int32_t* fb) {
    for (int a = 0; a < NAXES; ++a) out_[a] = pid_axis_update(prep_[a], st_[a], en_[a], cmd[a], fb[a]);
  }

  int32_t u(int a) const { return out_[a].u; }
  int32_t err(int a) const { return out_[a].err; }
  bool sat(int a) const { return out_[a].sat; }
  const PidState& state(int a) const { return st_[a]; }
  uint32_t ts_cycles() const { return ts_; }

 private:
  PidParams par_[NAXES];
  PidPrepared prep_[NAXES];  // par_ as sample() applies it
  PidState st_[NAXES];
  PidOut out_[NAXES];
  bool en_[NAXES] = {};
  uint32_t ts_ = latency;
};

// pid_core clock by clock: the RTL's control timing (the state clearing after
// reset, the sample timer, the sweep, the configuration handshake) around the
// sample-level arithmetic of PidCore. Outputs are those of the current clock,
// before its edge; clock() is the edge. The arithmetic of a sample is done at
// its tick; the RTL publishes it over the sweep and done() marks the clock in
// which all of it is out, which is when a user of u()/err()/sat() reads it.
// ceil(log2(v)), as Verilog's $clog2.
constexpr int clog2(int v) {
  return v <= 1 ? 0 : 1 + clog2((v + 1) / 2);
}

template <int NAXES, bool SERVO = true>
class PidCoreClocked {
 public:
  bool operator==(const PidCoreClocked&) const = default;
  static constexpr int latency = PidCore<NAXES, SERVO>::latency;
  // State RAM depth: clog2(NAXES + 1) slot bits + 3 word bits (rtl/pid_core.v).
  static constexpr int clear_cycles = 8 << clog2(NAXES + 1);

  struct In {
    bool operator==(const In&) const = default;
    bool rst = false;
    bool we = false;
    uint8_t waddr = 0;
    uint32_t wdata = 0;
    bool re = false;
    uint8_t raddr = 0;
    const int32_t* cmd = nullptr;  // NAXES values, read at a tick only
    const int32_t* fb = nullptr;
  };

  bool tick() const { return tick_; }
  bool done() const { return done_; }
  bool busy() const { return run_ || clr_; }
  bool wready() const { return !busy(); }
  bool rready(bool we) const { return !busy() && !we; }
  bool rvalid() const { return rvalid_; }
  uint32_t rdata() const { return rdata_; }
  bool enabled(int a) const { return core_.read(uint8_t(a << 4 | pid_reg::CTRL)) & 1; }
  // Clocks since the tick in the current clock during a sweep (1 in the
  // clock after the tick, latency in done's), else 0.
  int sweep_clock() const { return run_ ? latency - left_ : done_ ? latency : 0; }
  const PidCore<NAXES, SERVO>& core() const { return core_; }

  // Fast-forward: with no port activity, no tick due in the next n clocks
  // and, inside a sweep, its last clock (done) not among them, a clock only
  // counts the timers down (the sample's arithmetic was done at the tick).
  // edge: the last of the n clocks may be the one whose edge raises the
  // tick or done, which skip() then raises as clock() would.
  // through_done: done may be among the n clocks (skip() goes through it;
  // done_in() tells its clock), so only the tick bounds them.
  bool quiet(const In& in, uint32_t n, bool edge = false, bool through_done = false) const {
    return !in.rst && !in.we && !in.re && !clr_ && !tick_ && (through_done || !done_) && !rvalid_ &&
           n < quiet_limit(through_done) + 1 + (edge ? 1 : 0);
  }
  // No port activity and not clearing: what quiet() asks but the timers.
  bool quiet_but_timers(const In& in) const { return !in.rst && !in.we && !in.re && !clr_; }
  void skip(uint32_t n) {
    if (run_ && uint32_t(left_) <= n) {
      // The sweep ends: done in the last of the n edges, or its clock
      // among them and gone.
      done_ = uint32_t(left_) == n;
      run_ = false;
      left_ = 0;
    } else {
      if (run_) left_ -= int(n);
      done_ = done_ && n == 0;
    }
    if (tcnt_ == n) {
      tick_ = true;
      tcnt_ = core_.ts_cycles();
    } else {
      tcnt_ -= n;
    }
  }
  // The most clocks the timers allow quiet() (0 if the next is the tick or
  // done).
  uint32_t quiet_limit(bool through_done = false) const {
    const uint32_t t = tcnt_ - 1;
    return !through_done && run_ && uint32_t(left_ - 1) < t ? uint32_t(left_ - 1) : t;
  }
  // Of the clocks from this one, the number of done's (0: this one), or
  // kNoDone when no sweep is under way.
  static constexpr uint32_t kNoDone = ~0u;
  uint32_t done_in() const { return done_ ? 0 : run_ ? uint32_t(left_) : kNoDone; }
  // The sample timer: the tick comes in the clock in which it is 1.
  uint32_t timer() const { return tcnt_; }

  void clock(const In& in) {
    if (in.rst) {
      core_.reset();
      clr_ = true;
      cc_ = 0;
      tcnt_ = 1;
      tick_ = run_ = done_ = rvalid_ = false;
      left_ = 0;
      return;
    }
    // Configuration lands before a sample taken in the same clock; a new Ts
    // waits for the next reload.
    const uint32_t ts = core_.ts_cycles();
    const bool idle = !busy();
    if (in.we && idle) core_.write(in.waddr, in.wdata);
    rvalid_ = in.re && idle && !in.we;
    if (rvalid_) rdata_ = core_.read(in.raddr);
    if (tick_) core_.sample(in.cmd, in.fb);
    // Sweep: run for latency - 1 clocks after the tick, done in the next.
    done_ = run_ && left_ == 1;
    if (run_) {
      run_ = --left_ != 0;
    } else if (tick_) {
      run_ = true;
      left_ = latency - 1;
    }
    // Timer, held while clearing; the first tick follows the clearing.
    if (clr_) {
      clr_ = ++cc_ != clear_cycles;
      tick_ = false;
      tcnt_ = 1;
    } else {
      tick_ = tcnt_ == 1;
      tcnt_ = tcnt_ == 1 ? ts : tcnt_ - 1;
    }
  }

 private:
  PidCore<NAXES, SERVO> core_;
  bool clr_ = true, tick_ = false, run_ = false, done_ = false, rvalid_ = false;
  int cc_ = 0, left_ = 0;
  uint32_t tcnt_ = 1, rdata_ = 0;
};

}  // namespace mc
