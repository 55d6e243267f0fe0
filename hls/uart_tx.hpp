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

  // Clocks (up to limit) that change nothing but the bit timer and the
  // bits going out: idle with nothing to send, or a byte on the line up to
  // the clock that ends it (ready_o() rises there). skip(n) does them;
  // levels() tells the line over them.
  uint32_t quiet(bool valid_i, uint32_t limit) const {
    if (!busy) return valid_i ? 0 : limit;
    const uint32_t rest = cnt + left * uint32_t(DIV);
    return rest < limit ? rest : limit;
  }
  void skip(uint32_t n) {
    if (!busy) return;
    if (n <= cnt) {
      cnt -= n;
      return;
    }
    // The bit on the line ends after cnt + 1 clocks, each next one DIV later.
    const uint32_t shifts = (n - cnt + FULL) / DIV, into = n - cnt - 1 - (shifts - 1) * DIV;
    cnt = FULL - into;
    left = uint8_t(left - shifts);
    tx_o = sh >> (shifts - 1) & 1;
    sh = uint16_t((sh >> shifts | 0x1FFu << (9 - shifts)) & 0x1FF);
  }
  // The line after each of the next n quiet clocks, as runs: f(level,
  // clocks) in order, the clocks adding up to n.
  template <typename F>
  void levels(uint32_t n, F&& f) const {
    if (!busy || n <= cnt) {
      f(tx_o, n);
      return;
    }
    if (cnt > 0) f(tx_o, cnt);
    for (uint32_t done = cnt, b = 0; done < n; ++b) {
      const uint32_t m = n - done < uint32_t(DIV) ? n - done : uint32_t(DIV);
      f(bool(sh >> b & 1), m);
      done += m;
    }
  }
};

}  // namespace mc
