// Fixed-point formats of the MotionCore datapath, and the saturating primitives
// that every twin uses. This is the one place the formats live; rtl/mc_fixed.vh
// mirrors the widths as Verilog parameters and tests/test_regs_agree.cpp checks
// that the two agree.
//
// Synthesizable subset: fixed-width integers, no heap, no recursion, static loop
// bounds. Wide intermediates use `mc::i128`, the stand-in for an HLS tool's
// ap_int<89>; no value wider than 89 bits is ever formed.
#pragma once

#include <cstdint>

namespace mc {

__extension__ typedef __int128 i128;

// --- Formats (see docs/numerics.md for why each width suffices) ------------
// Positions and errors: signed 32-bit encoder counts.
constexpr int POS_W = 32;
// Controller output: signed 16-bit drive units (full scale +-32767 = DAC/PWM range).
constexpr int OUT_W = 16;
constexpr int32_t OUT_MAX = (1 << (OUT_W - 1)) - 1;
// Accumulator: Q17.32, i.e. output units with 32 fraction bits, 50 bits signed.
// Integrator, derivative state and every aligned product use this format.
constexpr int ACC_W = 50;
constexpr int ACC_FRAC = 32;
// Coefficient word: value = mantissa * 2^(FX - shift), mantissa signed 24-bit,
// shift 0..63, where FX is the fraction bits of the operand it multiplies.
constexpr int COEF_M_W = 24;
constexpr int COEF_S_W = 6;
constexpr int COEF_S_MAX = (1 << COEF_S_W) - 1;
// Multiplier operand: signed 32-bit. The derivative state enters it as Q17.15.
constexpr int MUL_X_W = 32;
constexpr int D_OPER_FRAC = 15;
constexpr int PROD_W = COEF_M_W + MUL_X_W;  // 56: exact product

constexpr int64_t smax(int w) {
  return (int64_t(1) << (w - 1)) - 1;
}
constexpr int64_t smin(int w) {
  return -(int64_t(1) << (w - 1));
}

// Saturate a wide value to a signed w-bit range (w <= 63). The 64-bit
// forms serve sums of accumulator-wide values, which never leave 52 bits.
constexpr int64_t sat(i128 v, int w) {
  return v > smax(w) ? smax(w) : (v < smin(w) ? smin(w) : int64_t(v));
}
constexpr int64_t sat(int64_t v, int w) {
  return v > smax(w) ? smax(w) : (v < smin(w) ? smin(w) : v);
}
constexpr int32_t sat32(i128 v) {
  return int32_t(sat(v, 32));
}
constexpr int32_t sat32(int64_t v) {
  return int32_t(sat(v, 32));
}
constexpr int64_t sat_acc(i128 v) {
  return sat(v, ACC_W);
}
constexpr int64_t sat_acc(int64_t v) {
  return sat(v, ACC_W);
}

// Sign-extend the low w bits of x.
constexpr int64_t sext(uint64_t x, int w) {
  const uint64_t m = uint64_t(1) << (w - 1);
  x &= (w == 64) ? ~uint64_t(0) : ((uint64_t(1) << w) - 1);
  return int64_t((x ^ m) - m);
}

// Coefficient word layout: [29:24] shift, [23:0] mantissa; [31:30] read as 0.
struct Coef {
  bool operator==(const Coef&) const = default;
  int32_t m;  // signed COEF_M_W bits
  int s;      // 0..COEF_S_MAX
};
constexpr Coef coef_unpack(uint32_t w) {
  return Coef{int32_t(sext(w, COEF_M_W)), int((w >> COEF_M_W) & COEF_S_MAX)};
}
constexpr uint32_t coef_pack(Coef c) {
  return (uint32_t(c.s & COEF_S_MAX) << COEF_M_W) | (uint32_t(c.m) & ((uint32_t(1) << COEF_M_W) - 1));
}

// The shared multiply-and-align step: m * x aligned into the accumulator
// format, i.e. round((m * x * 2^32) / 2^s), rounding half up, saturated.
// The RTL forms exactly {p, 32'b0} + 2^(s-1), shifts right by s, saturates.
// In 64 bits: with s >= 32 the shift takes the 32 zero bits and s - 32 of
// the product, the rounding bit landing inside it; below, the rounding bit
// falls among the zeros and the result is the product shifted left, which
// saturates exactly where it leaves ACC_W bits.
// The shifts and bounds depend on the coefficient alone: CoefShift works
// them out once, for a caller that applies one coefficient many times (the
// PID twin's sample, PidPrepared).
struct CoefShift {
  bool operator==(const CoefShift&) const = default;
  int32_t m;
  bool right;     // s >= ACC_FRAC: (p + round) >> q
  int q;          // s - ACC_FRAC
  int64_t round;  // 2^(q-1), 0 for q = 0
  int k;          // s < ACC_FRAC: p * 2^k, k = ACC_FRAC - s (1..32)
  int64_t lim;    // |p 2^k| within ACC_W bits below it
};
constexpr CoefShift coef_shift(Coef c) {
  CoefShift h{c.m, c.s >= ACC_FRAC, 0, 0, 0, 0};
  if (h.right) {
    h.q = c.s - ACC_FRAC;
    h.round = h.q == 0 ? 0 : int64_t(1) << (h.q - 1);
  } else {
    h.k = ACC_FRAC - c.s;
    h.lim = int64_t(1) << (ACC_W - 1 - h.k);
  }
  return h;
}
constexpr int64_t mul_align(const CoefShift& c, int32_t x) {
  const int64_t p = int64_t(c.m) * x;                 // PROD_W bits, exact
  if (c.right) return sat_acc((p + c.round) >> c.q);  // arithmetic: floor
  return p >= c.lim ? smax(ACC_W) : (p < -c.lim ? smin(ACC_W) : p * (int64_t(1) << c.k));
}
constexpr int64_t mul_align(Coef c, int32_t x) {
  return mul_align(coef_shift(c), x);
}

// The same product in the two parts the RTL delivers (rtl/mul_align.v):
// y = yh + yc. yh is the product aligned with one extra fraction bit, floored,
// halved and saturated; yc is the rounding increment still to be added, 0
// when yh is saturated. pid_core's adder takes yc as its carry-in, so the
// increment needs no adder of its own. mul_align(c, x) == yh + yc always.
struct MulAlignParts {
  bool operator==(const MulAlignParts&) const = default;
  int64_t yh;  // ACC_W bits signed
  int yc;      // 0 or 1
};
constexpr MulAlignParts mul_align_parts(Coef c, int32_t x) {
  const i128 p = i128(c.m) * x;
  const int up = ACC_FRAC + 1 - c.s;  // z = floor(p * 2^up): at most 89 bits
  const i128 z = up >= 0 ? p * (i128(1) << up) : (p >> -up);
  const i128 h = z >> 1;
  const int z0 = int(z & 1);
  if (h > smax(ACC_W) || h < smin(ACC_W)) return MulAlignParts{sat_acc(h), 0};
  // h + 1 would be one past the maximum: the maximum itself, no increment.
  if (h == smax(ACC_W) && z0 != 0) return MulAlignParts{smax(ACC_W), 0};
  return MulAlignParts{int64_t(h), z0};
}

// Accumulator (Q.32) to output units, round half up, saturated to OUT_W.
constexpr int32_t acc_to_out(int64_t v) {
  return int32_t(sat((v + (int64_t(1) << (ACC_FRAC - 1))) >> ACC_FRAC, OUT_W));
}

// Accumulator to the Q17.15 multiplier operand, round half up, saturated.
constexpr int32_t acc_to_doper(int64_t v) {
  constexpr int sh = ACC_FRAC - D_OPER_FRAC;
  return sat32((v + (int64_t(1) << (sh - 1))) >> sh);
}

// A free-running PWM counter of period P compared with a duty d <= P held
// through n clocks: of the counter values p0, p0 + 1, ... (mod P) the n
// clocks see, how many lie below d. The twins' fast-forwards count a PWM
// pin's high clocks over a skipped stretch with it (not RTL).
constexpr uint64_t pwm_high_count(uint32_t p0, uint32_t d, uint32_t P, uint64_t n) {
  const uint32_t rem = uint32_t(n % P);
  // Whole periods, then rem values from p0, wrapping at most once.
  uint64_t high = n / P * d;
  if (p0 < d) high += (p0 + rem < d ? p0 + rem : d) - p0;
  if (p0 + rem > P) high += (p0 + rem - P < d ? p0 + rem - P : d);
  return high;
}

}  // namespace mc
