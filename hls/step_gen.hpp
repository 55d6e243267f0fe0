// step_gen twin: step and direction for a stepper driver, one step per
// count of the position command, clock by clock. Mirrors rtl/step_gen.v,
// which documents the behaviour: a +-1 change of the command's two low bits
// owes a step; owed steps wait in a small signed backlog; a turn sets dir
// up for max(setup, 1) clocks before the pulse; a pulse is high max(pw, 1)
// clocks and low at least one clock more.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
#pragma once

#include <cstdint>

namespace mc {

struct StepGenIn {
  bool operator==(const StepGenIn&) const = default;
  bool rst = false;
  uint8_t cmd = 0;  // the position command's two low bits
  bool sync = false, en = false;
  uint32_t pw = 0, setup = 0;  // PW_W bits each
  bool clr = false;
};

template <int PW_W = 8, int BL_W = 4>
struct StepGen {
  bool operator==(const StepGen&) const = default;
  static_assert(PW_W >= 2 && PW_W <= 16, "step_gen: PW_W must be 2..16");
  static_assert(BL_W >= 2 && BL_W <= 8, "step_gen: BL_W must be 2..8");
  static constexpr uint32_t PW_MASK = (1u << PW_W) - 1;
  static constexpr uint32_t BL_MASK = (1u << BL_W) - 1;
  static constexpr uint32_t BL_MAX = BL_MASK >> 1;
  enum : uint8_t { ST_IDLE = 0, ST_SETUP = 1, ST_HIGH = 2, ST_LOW = 3 };

  uint8_t last = 0;  // 2 bits
  uint8_t st = ST_IDLE;
  uint32_t tmr = 0;  // PW_W bits
  bool step_o = false, dir_o = true, err_o = false;
  uint32_t backlog_o = 0;  // BL_W bits, two's complement

  // The backlog as a signed number of owed steps (positive: forward).
  int backlog() const { return backlog_o >> (BL_W - 1) & 1 ? int(backlog_o) - (1 << BL_W) : int(backlog_o); }

  void clock(const StepGenIn& in) {
    const uint8_t d = uint8_t((in.cmd - last) & 3);
    const bool moving = in.en && !in.sync;
    const bool inc = moving && d == 1, dec = moving && d == 3, jump = moving && d == 2;
    const bool owed = backlog_o != 0;
    const bool fwd = !(backlog_o >> (BL_W - 1) & 1);
    const bool tmr_end = tmr <= 1;
    const bool ready = owed && fwd == dir_o;
    const bool turn = in.en && owed && fwd != dir_o && (st == ST_IDLE || st == ST_SETUP);
    const bool rise = in.en && ready && (st == ST_IDLE || (st == ST_SETUP && tmr_end));
    const uint32_t taken = rise ? (backlog_o + (dir_o ? BL_MASK : 1u)) & BL_MASK : backlog_o;
    const bool over = (inc && taken == BL_MAX) || (dec && taken == ((0u - BL_MAX) & BL_MASK));

    last = in.rst ? 0 : uint8_t(in.cmd & 3);
    if (in.rst || !in.en)
      backlog_o = 0;
    else if (over)
      backlog_o = taken;
    else
      backlog_o = (taken + uint32_t(inc) - uint32_t(dec)) & BL_MASK;

    // An event in the same clock as clr wins, as in the RTL.
    err_o = !in.rst && (over || jump || (err_o && !in.clr));

    if (in.rst) {
      st = ST_IDLE;
      tmr = 0;
      step_o = false;
      dir_o = true;
    } else if (rise) {
      st = ST_HIGH;
      tmr = in.pw & PW_MASK;
      step_o = true;
    } else if (turn) {
      st = ST_SETUP;
      tmr = in.setup & PW_MASK;
      dir_o = fwd;
    } else {
      switch (st) {
        case ST_IDLE:
          break;
        case ST_SETUP:
          if (!tmr_end) --tmr;
          break;
        case ST_HIGH:
          if (!in.en) {
            st = ST_IDLE;
            step_o = false;
          } else if (tmr_end) {
            st = ST_LOW;
            tmr = in.pw & PW_MASK;
            step_o = false;
          } else {
            --tmr;
          }
          break;
        default:  // ST_LOW
          if (!in.en || tmr_end)
            st = ST_IDLE;
          else
            --tmr;
      }
    }
  }
};

}  // namespace mc
