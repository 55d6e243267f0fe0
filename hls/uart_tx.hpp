// uart_tx twin: the 8N1 transmitter, clock by clock. Mirrors rtl/uart_tx.v:
// present a byte with valid_i while ready_o(); tx_o idles high and comes
// straight from a register.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
#pragma once

#include <cstdint>

namespace mc {

template <int CLK_HZ = 12'000'000, int BAUD = 1'000'000>
struct UartTx {
  bool operator==(const UartTx&) const = default;
  static constexpr int DIV = (CLK_HZ + BAUD / 2) / BAUD;  // clocks per bit, as uart_rx
  static_assert(DIV >= 4, "uart_tx: CLK_HZ/BAUD must be at least 4");
  static constexpr uint32_t FULL = DIV - 1;

  uint32_t cnt = 0;
  uint8_t left = 0;  // bits still to send after the one on the line
  uint16_t sh = 0;   // 9 bits: data then the stop bit
  bool busy = false;
  bool tx_o = true;

  bool ready_o() const { return !busy; }

  void clock(bool rst, uint8_t data_i, bool valid_i) {
    if (rst) {
      busy = false;
      tx_o = true;
    } else if (!busy) {
      if (valid_i) {
        busy = true;
        tx_o = false;
        sh = uint16_t(0x100 | data_i);
        cnt = FULL;
        left = 9;
      }
    } else if (cnt != 0) {
      --cnt;
    } else if (left == 0) {
      busy = false;
    } else {
      cnt = FULL;
      --left;
      tx_o = sh & 1;
      sh = uint16_t(0x100 | sh >> 1);
    }
  }

  // Clocks (up to limit) that change nothing but the bit timer: idle with
  // nothing to send, or inside a bit. skip(n) does them.
  uint32_t quiet(bool valid_i, uint32_t limit) const {
    if (!busy) return valid_i ? 0 : limit;
    return cnt < limit ? cnt : limit;
  }
  void skip(uint32_t n) {
    if (busy) cnt -= n;
  }
};

}  // namespace mc
