// Register addresses of pid_core's configuration port. Mirrored by
// rtl/pid_regs.vh; tests/test_regs_agree.cpp parses that file and fails if the
// two disagree, so change both together.
//
// Address = {axis[3:0], reg[3:0]}. Axis 15 selects the global registers.
#pragma once

#include <cstdint>

namespace mc::pid_reg {

// Per-axis registers. Coefficient words: [29:24] shift, [23:0] mantissa
// (see hls/mc_fixed.hpp). Limits are unsigned; 0 means "no limit".
constexpr uint8_t KP = 0x0;        // proportional, operand e (counts)
constexpr uint8_t KI = 0x1;        // Ki*Ts/2, operand e(k)+e(k-1)
constexpr uint8_t KD_A = 0x2;      // derivative pole alpha, operand D(k-1) in Q17.15
constexpr uint8_t KD_B = 0x3;      // derivative gain beta, operand e(k)-e(k-1)
constexpr uint8_t KF1 = 0x4;       // FF1/Ts, operand c(k)-c(k-1)
constexpr uint8_t KF2 = 0x5;       // FF2/Ts^2, operand c(k)-2c(k-1)+c(k-2)
constexpr uint8_t ILIM = 0x6;      // integrator limit, output units [15:0]
constexpr uint8_t OLIM = 0x7;      // output limit, output units [15:0] (0 or >32767: 32767)
constexpr uint8_t DBAND = 0x8;     // deadband, counts [30:0]
constexpr uint8_t ELIM = 0x9;      // error clamp, counts [30:0]
constexpr uint8_t CTRL = 0xF;      // bit 0: enable
constexpr uint8_t NREGS_RAM = 10;  // registers 0..9 live in the coefficient RAM

// Global registers (axis field = GLOBAL_AXIS).
constexpr uint8_t GLOBAL_AXIS = 0xF;
constexpr uint8_t G_TS = 0x0;       // sample period in clock cycles (clamped to >= latency)
constexpr uint8_t G_LATENCY = 0x1;  // read-only: cycles one sweep of all axes takes
constexpr uint8_t G_NAXES = 0x2;    // read-only: number of axes

constexpr uint8_t addr(uint8_t axis, uint8_t reg) {
  return uint8_t((axis << 4) | (reg & 0xF));
}

}  // namespace mc::pid_reg
