// mc_io twin: the board's machine I/O, clock by clock: probe and home-switch
// filters and latch strobes, spindle PWM and coolant, the handwheel jog.
// Mirrors rtl/mc_io.v, which documents the behaviour; the members are the
// RTL's registers, same names, and clock() is one edge.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
#pragma once

#include <cstdint>

#include "board_regs.hpp"
#include "mc_fixed.hpp"

namespace mc {

// Inputs of one clock: the RTL's ports without clk and the _i suffix.
struct McIoIn {
  bool operator==(const McIoIn&) const = default;
  bool rst = false;
  bool bus_we = false;
  uint8_t bus_addr = 0;  // 5 bits
  uint32_t bus_wdata = 0;
  bool armed = false;
  uint8_t lim_inv = 0;  // bit per axis
  uint8_t lim = 0;      // bit per axis, synchronized
  bool probe = false;   // synchronized
  uint8_t idx_armed = 0;
  bool ip_idle = false;
  uint8_t hw_pos = 0;  // the handwheel count's low bits
};

template <int NAXES = 3>
class McIo {
  static_assert(NAXES >= 1 && NAXES <= 3, "mc_io: NAXES must be 1..3");

 public:
  static constexpr int NS = NAXES + 1;  // filtered inputs: home switches, then the probe
  static constexpr uint8_t AXES = (1u << NAXES) - 1;

  bool operator==(const McIo&) const = default;

  // The RTL's registers.
  struct R {
    bool operator==(const R&) const = default;
    // from the bus
    bool sp_on = false, sp_rev = false, flood = false, mist = false, mist_on_dir = false;
    uint16_t duty = 0;  // 10 bits
    uint8_t lsrc = 0;   // 6 bits
    bool probe_inv = false, lstop = false;
    bool m_on = false, m_det1 = false;
    uint8_t m_axis = 0, m_step = 0;
    uint8_t m_rate = 0;
    uint16_t m_inc = 0;  // 12 bits
    // switch filters
    uint8_t sw = 0;          // NS bits
    uint8_t sw_cnt[4] = {};  // 2 bits each
    // latches, spindle, jog
    uint8_t latch_o = 0;
    bool stop_o = false;
    uint16_t pcnt = 0;  // 10 bits
    bool sp_pwm_o = false, sp_en_o = false, sp_dir_o = false, flood_o = false, mist_o = false;
    uint8_t ref_pos = 0;
    uint16_t pend = 0;  // signed
    uint8_t tmr = 0;    // 16-clock units
    uint8_t jog_o = 0;
    bool jog_neg_o = false;
  };
  R r;

  uint32_t stat_o() const {
    namespace bb = board::bits;
    return uint32_t(r.sw >> NAXES & 1) << bb::IOS_PROBE | uint32_t(r.sw & AXES) << bb::IOS_HOME_LSB |
           uint32_t(r.pend) << bb::IOS_MPG_PEND_LSB;
  }

  void clock(const McIoIn& in) {
    namespace br = board::reg;
    namespace bb = board::bits;
    // Nonblocking: every right-hand side reads o, this clock's registers.
    const R o = r;
    R& n = r;

    // Switch filters and latch strobes.
    const uint8_t swin = sw_in(o, in);
    R reset_regs;  // the registers' reset values (probe_inv for the reset's levels)
    const uint8_t swrst = sw_in(reset_regs, in);
    uint8_t rise = 0;
    for (int i = 0; i < NS; ++i) {
      const bool v = swin >> i & 1, s = o.sw >> i & 1;
      const bool pass = o.sw_cnt[i] == 3;  // the new level's fourth clock
      if (v && !s && pass) rise = uint8_t(rise | 1u << i);
      if (in.rst) {
        n.sw = uint8_t((n.sw & ~(1u << i)) | (swrst & (1u << i)));
        n.sw_cnt[i] = 0;
      } else if (v == s) {
        n.sw_cnt[i] = 0;
      } else {
        if (pass) n.sw = uint8_t(n.sw ^ (1u << i));
        n.sw_cnt[i] = uint8_t((o.sw_cnt[i] + 1) & 3);
      }
    }
    uint8_t lat = 0;
    for (int i = 0; i < NAXES; ++i) {
      const uint32_t src = o.lsrc >> (2 * i) & 3;
      if ((src == bb::L_SRC_HOME && (rise >> i & 1)) || (src == bb::L_SRC_PROBE && (rise >> NAXES & 1)))
        lat = uint8_t(lat | 1u << i);
    }
    n.latch_o = in.rst ? 0 : lat;
    n.stop_o = !in.rst && o.lstop && (lat & in.idx_armed) != 0;

    // Spindle and coolant.
    if (in.rst) {
      n.pcnt = 0;
      n.sp_pwm_o = n.sp_en_o = n.sp_dir_o = n.flood_o = n.mist_o = false;
    } else {
      n.pcnt = (o.pcnt + 1) & 0x3FF;
      n.sp_pwm_o = in.armed && o.sp_on && (o.duty == 0x3FF || o.pcnt < o.duty);
      n.sp_en_o = in.armed && o.sp_on;
      n.sp_dir_o = in.armed && (o.mist_on_dir ? o.mist : o.sp_on && o.sp_rev);
      n.flood_o = in.armed && o.flood;
      n.mist_o = in.armed && o.mist;
    }

    // Handwheel jog.
    const uint8_t det = detent_len(o);
    const Detent dt = detent(o, in.hw_pos);
    const bool det_up = dt == Detent::Up, det_dn = dt == Detent::Down;
    const uint16_t inc = o.m_step < 3 ? uint16_t(bb::MPG_STEPS[o.m_step]) : o.m_inc;
    const bool neg = o.pend >> 15 & 1;
    const bool room = neg == (o.pend >> 14 & 1) || det_dn != neg;
    const bool pend_nz = o.pend != 0;
    const bool go = o.m_on && in.armed && in.ip_idle && pend_nz && o.tmr == 0 && !(det_up || det_dn);
    const uint16_t step = (det_up || det_dn) ? uint16_t(det_dn ? 0u - inc : inc) : uint16_t(neg ? 1 : 0xFFFF);
    const uint16_t p_next = uint16_t(o.pend + step);
    n.jog_o = 0;
    n.jog_neg_o = !in.rst && neg;
    if (in.rst || !o.m_on) {
      n.ref_pos = in.hw_pos;
      n.pend = 0;
      n.tmr = 0;
    } else {
      if (det_up || det_dn) n.ref_pos = uint8_t(det_dn ? o.ref_pos - det : o.ref_pos + det);
      if (((det_up || det_dn) && room) || go) n.pend = p_next;
      if (go)
        n.tmr = o.m_rate < bb::MPG_MIN_RATE ? uint8_t(bb::MPG_MIN_RATE) : o.m_rate;
      else if (o.tmr != 0 && (o.pcnt & 15) == 15)
        n.tmr = uint8_t(o.tmr - 1);
      if (go) n.jog_o = uint8_t(1u << o.m_axis & 7);
    }

    // Registers from the bus.
    if (in.rst) {
      n.sp_on = n.sp_rev = n.flood = n.mist = n.mist_on_dir = false;
      n.duty = 0;
      n.lsrc = 0;
      n.probe_inv = n.lstop = false;
      n.m_on = n.m_det1 = false;
      n.m_axis = n.m_step = 0;
      n.m_rate = 0;
      n.m_inc = 0;
    } else if (in.bus_we) {
      const uint32_t d = in.bus_wdata;
      switch (in.bus_addr) {
        case br::IO_CTRL & 0x1F:
          n.sp_on = d >> bb::IO_SPINDLE & 1;
          n.sp_rev = d >> bb::IO_SPINDLE_REV & 1;
          n.flood = d >> bb::IO_FLOOD & 1;
          n.mist = d >> bb::IO_MIST & 1;
          n.mist_on_dir = d >> bb::IO_MIST_ON_DIR & 1;
          n.duty = uint16_t(d >> bb::IO_DUTY_LSB & 0x3FF);
          break;
        case br::LATCH & 0x1F:
          n.lsrc = uint8_t(d >> bb::L_SRC_LSB & 0x3F);
          n.probe_inv = d >> bb::L_PROBE_INV & 1;
          n.lstop = d >> bb::L_STOP & 1;
          break;
        case br::MPG & 0x1F:
          n.m_on = d >> bb::M_ON & 1;
          n.m_axis = uint8_t(d >> bb::M_AXIS_LSB & 3);
          n.m_step = uint8_t(d >> bb::M_STEP_LSB & 3);
          n.m_det1 = d >> bb::M_DETENT1 & 1;
          n.m_rate = uint8_t(d >> bb::M_RATE_LSB);
          break;
        case br::MPG_INC & 0x1F:
          n.m_inc = uint16_t(d & ((1u << bb::MPG_INC_BITS) - 1));
          break;
        default:
          break;
      }
    }
  }

  // ---- fast-forward ----------------------------------------------------------
  // With these inputs held, a clock changes nothing but the spindle's PWM
  // counter (and its pin): no bus write, the switches settled, no strobe,
  // the jog timer run out, no detent, nothing pending that may move (or
  // MPG off with the handwheel where it was), every other output at the
  // value it is being given.
  bool quiet(const McIoIn& in) const {
    if (in.rst || in.bus_we) return false;
    if (sw_in(r, in) != r.sw) return false;
    for (int i = 0; i < NS; ++i)
      if (r.sw_cnt[i] != 0) return false;
    if (r.latch_o != 0 || r.stop_o || r.jog_o != 0 || r.tmr != 0 || r.jog_neg_o != bool(r.pend >> 15 & 1))
      return false;
    if (!r.m_on) {
      if (in.hw_pos != r.ref_pos || r.pend != 0) return false;
    } else {
      if (detent(r, in.hw_pos) != Detent::None) return false;
      if (r.pend != 0 && in.armed && in.ip_idle) return false;
    }
    const bool on = in.armed && r.sp_on;
    const bool steady_pwm = !on || r.duty == 0 || r.duty == 0x3FF;
    return r.sp_en_o == on && r.sp_dir_o == (in.armed && (r.mist_on_dir ? r.mist : r.sp_on && r.sp_rev)) &&
           r.flood_o == (in.armed && r.flood) && r.mist_o == (in.armed && r.mist) &&
           (!steady_pwm || r.sp_pwm_o == (on && r.duty == 0x3FF));
  }
  // Of the next n quiet clocks, those after whose edge SP_PWM is high: the
  // pin after an edge is "counter < duty" of the clock before (always high
  // at duty 1023) while the spindle is on, and a quiet stretch holds the
  // enable and the duty (a host that measures the duty over a skipped
  // stretch needs it; not RTL).
  uint64_t sp_high_in(uint32_t n) const {
    constexpr uint32_t kPeriod = 1024;  // the 10-bit counter
    if (!r.sp_en_o || r.duty == 0) return 0;
    if (r.duty == kPeriod - 1) return n;
    return pwm_high_count(r.pcnt, r.duty, kPeriod, n);
  }
  // n quiet clocks with `armed` held: the PWM counter runs, its pin shows
  // the last of them.
  void skip(uint32_t n, bool armed) {
    if (n == 0) return;
    const uint32_t last = (r.pcnt + n - 1) & 0x3FF;
    r.sp_pwm_o = armed && r.sp_on && (r.duty == 0x3FF || last < r.duty);
    r.pcnt = uint16_t((r.pcnt + n) & 0x3FF);
  }

 private:
  // A whole detent of the handwheel since ref_pos, either way (hw_pos's low
  // bits, a signed 8-bit difference): four counts, or one with MPG.detent1.
  enum class Detent { None, Up, Down };
  static uint8_t detent_len(const R& o) { return o.m_det1 ? 1 : 4; }
  static Detent detent(const R& o, uint8_t hw_pos) {
    const uint8_t hd = uint8_t(hw_pos - o.ref_pos), det = detent_len(o);
    if (!(hd & 0x80) && hd >= det) return Detent::Up;
    if ((hd & 0x80) && uint8_t(0 - hd) >= det) return Detent::Down;
    return Detent::None;
  }

  // The switches as the filters see them: home switches, then the probe.
  static uint8_t sw_in(const R& o, const McIoIn& in) {
    return uint8_t(((in.lim ^ in.lim_inv) & AXES) | uint32_t(in.probe != o.probe_inv) << NAXES);
  }
};

}  // namespace mc
