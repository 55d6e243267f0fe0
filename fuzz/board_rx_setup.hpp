// What both board harnesses (fuzz/board_rx.hpp on the Verilated board,
// fuzz/board_rx_twin.hpp on the twin) write before the first burst:
// distinct values in every writable register, so that a stray write of zero
// or of another register's value shows. The drives stay disarmed and the
// PIDs off: nothing moves.
#pragma once

#include <cstdint>

#include "hls/board_regs.hpp"
#include "hls/pid_regs.hpp"

namespace mc::fuzz {

// Register off of axis a.
inline uint16_t axis_reg(int a, uint16_t off) {
  return uint16_t(board::reg::AXIS_BASE + a * board::reg::AXIS_STRIDE + off);
}

// write(addr, value) for each register, in order.
template <class Write>
void write_distinct_registers(int naxes, Write&& write) {
  namespace br = board::reg;
  write(br::WDOG, (1u << board::WDOG_W) - 1);
  write(br::SAFETY, 0x07);
  write(br::HW_CFG, 0x105);
  for (int a = 0; a < naxes; ++a) {
    write(uint16_t(br::IP_SET_X + a), 0x12345u * uint32_t(a + 1));
    write(axis_reg(a, br::AX_ENC_CFG), 0x103u + uint32_t(a));
    write(axis_reg(a, br::AX_FERR), 1000u + uint32_t(a));
    for (uint8_t r = 0; r < pid_reg::NREGS_RAM; ++r)
      write(pid_reg::addr(uint8_t(a), r), 0x1001u * (uint32_t(r) + 1) + uint32_t(a));
  }
}

}  // namespace mc::fuzz
