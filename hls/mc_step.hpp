// mc_step twin: the board's stepper axes, clock by clock: STEP_CFG from the
// register bus, a step generator per axis on the command's low bits, the
// quadrature copy of the steps sent and the pin multiplexers. Mirrors
// rtl/mc_step.v, which documents the behaviour; the members are the RTL's
// registers, same names, and clock() is one edge. The multiplexed outputs
// are wires of this clock's inputs and registers: out(in) gives them.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
#pragma once

#include <cstdint>

#include "board_regs.hpp"
#include "step_gen.hpp"

namespace mc {

// Inputs of one clock: the RTL's ports without clk and the _i suffix; per
// axis a bit each, bit a for axis a (cmd: two bits per axis).
struct McStepIn {
  bool operator==(const McStepIn&) const = default;
  bool rst = false;
  bool bus_we = false;
  uint8_t bus_addr = 0;  // 5 bits
  uint32_t bus_wdata = 0;
  uint8_t cmd = 0;  // two low bits of each axis's command
  uint8_t sync = 0;
  bool allow = false;
  uint8_t clr = 0;
  uint8_t pwm = 0, dir = 0, enc_a = 0, enc_b = 0;
};

// The combinational outputs, bit a for axis a.
struct McStepOut {
  uint8_t pwm = 0, dir = 0, enc_a = 0, enc_b = 0;
  bool operator==(const McStepOut&) const = default;
};

// STEPPERS: the axes built with a step generator, bit a for axis a (the
// RTL's parameter); the others keep the H-bridge's pins and ignore STEP_CFG.
template <int NAXES = 3, int STEPPERS = 7>
class McStep {
  static_assert(NAXES >= 1 && NAXES <= 3, "mc_step: NAXES must be 1..3");

 public:
  using Gen = StepGen<6, 4>;
  static constexpr uint8_t AXES = (1u << NAXES) - 1;
  static constexpr uint8_t BUILT = uint8_t(STEPPERS & AXES);

  // The RTL's registers.
  uint8_t stepper = 0, closed = 0, step_inv = 0, dir_rev = 0;  // bit per axis
  uint8_t pw = 0, setup = 0;                                   // 6 bits
  Gen u_gen[NAXES];
  uint8_t q[NAXES] = {};  // 2 bits: the steps sent, as a quadrature phase
  bool step_q[NAXES] = {}, err_q[NAXES] = {}, fe[NAXES] = {};

  bool operator==(const McStep&) const = default;

  uint8_t stepper_o() const { return stepper; }
  uint8_t err_o() const {
    return bits([this](int a) { return u_gen[a].err_o; });
  }
  uint8_t ferr_o() const {
    return bits([this](int a) { return fe[a]; });
  }
  // The pins' multiplexers, axis by axis: a stepper axis drives STEP/DIR,
  // an open-loop one feeds its decoder the steps sent.
  bool pwm_o(int a, bool pwm) const {
    return stepper >> a & 1 ? u_gen[a].step_o != bool(step_inv >> a & 1) : pwm;
  }
  bool dir_o(int a, bool dir) const {
    return stepper >> a & 1 ? u_gen[a].dir_o != bool(dir_rev >> a & 1) : dir;
  }
  uint8_t enc_a_o(uint8_t enc_a) const {
    return mux(enc_a, [this](int a) { return bool((q[a] >> 1 ^ q[a]) & 1); });
  }
  uint8_t enc_b_o(uint8_t enc_b) const {
    return mux(enc_b, [this](int a) { return bool(q[a] >> 1 & 1); });
  }
  McStepOut out(const McStepIn& in) const {
    McStepOut o;
    o.enc_a = enc_a_o(in.enc_a);
    o.enc_b = enc_b_o(in.enc_b);
    for (int a = 0; a < NAXES; ++a) {
      o.pwm = uint8_t(o.pwm | uint32_t(pwm_o(a, in.pwm >> a & 1)) << a);
      o.dir = uint8_t(o.dir | uint32_t(dir_o(a, in.dir >> a & 1)) << a);
    }
    return o;
  }

  // With these inputs held, a clock changes nothing: no STEP_CFG write, and
  // every built generator idle with nothing owed, its command unchanged and
  // its pins' edges already seen.
  bool quiet(const McStepIn& in) const {
    if (in.rst || (in.bus_we && in.bus_addr == (board::reg::STEP_CFG & 0x1F))) return false;
    for (int a = 0; a < NAXES; ++a) {
      if (!(BUILT >> a & 1)) continue;
      const Gen& g = u_gen[a];
      if (g.st != Gen::ST_IDLE || g.backlog_o != 0 || g.last != (in.cmd >> (2 * a) & 3) ||
          (g.err_o && in.clr >> a & 1))
        return false;
      if (g.step_o != step_q[a] || g.err_o != err_q[a] || fe[a]) return false;
    }
    return true;
  }

  // Every built generator disabled (no stepper axis armed): a command
  // that moves changes nothing but what each remembers of it (follow()).
  bool following(const McStepIn& in) const { return !in.allow || (stepper & BUILT) == 0; }
  // After clocks in which following() held: the command as the last of
  // them showed it.
  void follow(uint8_t cmd) {
    for (int a = 0; a < NAXES; ++a)
      if (BUILT >> a & 1) u_gen[a].last = uint8_t(cmd >> (2 * a) & 3);
  }

  void clock(const McStepIn& in) {
    namespace bb = board::bits;
    // The generators' inputs take this clock's STEP_CFG (registers).
    for (int a = 0; a < NAXES; ++a) {
      if (!(BUILT >> a & 1)) continue;  // not built: the generator stays as reset left it
      const bool step = u_gen[a].step_o, sdir = u_gen[a].dir_o, err = u_gen[a].err_o;
      StepGenIn g;
      g.rst = in.rst;
      g.cmd = uint8_t(in.cmd >> (2 * a) & 3);
      g.sync = in.sync >> a & 1;
      g.en = in.allow && (stepper >> a & 1);
      g.pw = pw;
      g.setup = setup;
      g.clr = in.clr >> a & 1;
      u_gen[a].clock(g);
      if (in.rst) {
        q[a] = 0;
        step_q[a] = err_q[a] = fe[a] = false;
      } else {
        fe[a] = err && !err_q[a];
        if (step && !step_q[a]) q[a] = uint8_t((sdir ? q[a] + 1 : q[a] - 1) & 3);
        step_q[a] = step;
        err_q[a] = err;
      }
    }
    if (in.rst) {
      stepper = closed = step_inv = dir_rev = 0;
      pw = setup = 0;
    } else if (in.bus_we && in.bus_addr == (board::reg::STEP_CFG & 0x1F)) {
      const uint32_t d = in.bus_wdata;
      stepper = uint8_t(d >> bb::SC_STEPPER_LSB & BUILT);
      closed = uint8_t(d >> bb::SC_CLOSED_LSB & AXES);
      pw = uint8_t(d >> bb::SC_PW_LSB & 0x3F);
      setup = uint8_t(d >> bb::SC_SETUP_LSB & 0x3F);
      step_inv = uint8_t(d >> bb::SC_STEP_INV_LSB & AXES);
      dir_rev = uint8_t(d >> bb::SC_DIR_INV_LSB & AXES);
    }
  }

 private:
  // Open-loop stepper axes take f(a), the others the pins.
  template <class F>
  uint8_t mux(uint8_t pins, F&& f) const {
    uint8_t v = 0;
    for (int a = 0; a < NAXES; ++a) {
      const bool loop = (stepper >> a & 1) && !(closed >> a & 1);
      v = uint8_t(v | uint32_t(loop ? f(a) : bool(pins >> a & 1)) << a);
    }
    return v;
  }
  template <class F>
  static uint8_t bits(F&& f) {
    uint8_t v = 0;
    for (int a = 0; a < NAXES; ++a) v = uint8_t(v | uint32_t(f(a)) << a);
    return v;
  }
};

}  // namespace mc
