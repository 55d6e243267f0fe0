// mc_safety twin: the fault latches, the arm state and the link watchdog,
// clock by clock. Mirrors rtl/mc_safety.v, which documents the behaviour:
// every fault source sets its FAULT bit and disarms at once; arming needs
// FAULT clear; the watchdog trips when armed and no frame came for wdog
// clocks.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
// Per-axis signals are bit masks, bit a for axis a.
#pragma once

#include <cstdint>

#include "board_regs.hpp"

namespace mc {

struct McSafetyIn {
  bool operator==(const McSafetyIn&) const = default;
  bool rst = false;
  // host commands
  bool arm_set = false, arm_clr = false;
  uint16_t clr = 0;
  uint8_t cfg = 0;    // the SAFETY register
  uint32_t wdog = 0;  // clock cycles, 24 bits
  bool kick = false;  // a valid frame arrived
  // fault sources
  bool estop = false, stop = false;
  uint8_t lim = 0, ferr = 0, enc_err = 0;
};

template <int NAXES = 3>
struct McSafety {
  bool operator==(const McSafety&) const = default;
  static_assert(NAXES >= 1 && NAXES <= 3, "mc_safety: NAXES must be 1..3");
  static constexpr uint8_t AXES = (1u << NAXES) - 1;

  uint32_t wd = 0;  // 24 bits
  uint8_t enc_err_d = 0;
  uint16_t fault_o = 0;
  bool armed_o = false;

  static bool estop_act(uint8_t cfg, bool estop, bool stop) {
    namespace bb = board::bits;
    return stop || ((cfg >> bb::S_ESTOP_EN & 1) && (estop != bool(cfg >> bb::S_ESTOP_INV & 1)));
  }
  static uint8_t lim_act(uint8_t cfg, uint8_t lim) {
    namespace bb = board::bits;
    return uint8_t(cfg >> bb::S_LIM_EN_LSB & (lim ^ cfg >> bb::S_LIM_INV_LSB) & AXES);
  }
  bool estop_act_o(const McSafetyIn& in) const { return estop_act(in.cfg, in.estop, in.stop); }
  uint8_t lim_act_o(const McSafetyIn& in) const { return lim_act(in.cfg, in.lim); }
  uint8_t allow_o() const { return armed_o ? AXES : 0; }
  bool wd_trip(const McSafetyIn& in) const { return armed_o && wd >= (in.wdog & 0xFFFFFF); }

  // The fault events of this clock.
  uint16_t ev(const McSafetyIn& in) const {
    namespace bb = board::bits;
    return uint16_t(uint32_t(wd_trip(in)) << bb::F_WDOG | uint32_t(estop_act_o(in)) << bb::F_ESTOP |
                    uint32_t(lim_act_o(in)) << bb::F_LIMIT_LSB | uint32_t(in.ferr & AXES) << bb::F_FERR_LSB |
                    uint32_t(in.enc_err & ~enc_err_d & AXES) << bb::F_ENC_LSB);
  }

  void clock(const McSafetyIn& in) {
    const bool trip = wd_trip(in);
    const uint16_t e = ev(in);
    if (in.rst || in.kick || !armed_o)
      wd = 0;
    else if (!trip)
      wd = (wd + 1) & 0xFFFFFF;
    enc_err_d = in.rst ? 0 : uint8_t(in.enc_err & AXES);
    fault_o = in.rst ? 0 : uint16_t((fault_o & ~in.clr) | e);
    if (in.rst || e != 0 || in.arm_clr)
      armed_o = false;
    else if (in.arm_set && fault_o == 0)
      armed_o = true;
  }

  // Clocks (up to limit) with these inputs that change nothing but the
  // watchdog's count: no event, no command; armed, the watchdog counts to
  // its trip. skip(n) does them.
  uint32_t quiet(const McSafetyIn& in, uint32_t limit) const {
    if (in.rst || in.arm_set || in.arm_clr || in.clr != 0 || in.kick || ev(in) != 0) return 0;
    if ((in.enc_err & AXES) != enc_err_d) return 0;
    if (!armed_o) return wd == 0 ? limit : 0;
    const uint32_t left = (in.wdog & 0xFFFFFF) - wd;  // wd < wdog: no trip in this clock
    return left < limit ? left : limit;
  }
  void skip(uint32_t n) {
    if (armed_o) wd += n;
  }
};

}  // namespace mc
