// uart_rx twin: the 8N1 receiver, clock by clock. Mirrors rtl/uart_rx.v,
// which documents how to drive it: rx must already be synchronized; each
// byte pulses valid_o (or ferr_o, for a low stop bit) for one clock.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
#pragma once

#include <cstdint>

namespace mc {

template <int CLK_HZ = 12'000'000, int BAUD = 1'000'000>
struct UartRx {
  bool operator==(const UartRx&) const = default;
  static constexpr int DIV = (CLK_HZ + BAUD / 2) / BAUD;  // clocks per bit
  static_assert(DIV >= 4, "uart_rx: CLK_HZ/BAUD must be at least 4");
  static_assert((int64_t(DIV) * BAUD - CLK_HZ) * 50 <= CLK_HZ &&
                    (CLK_HZ - int64_t(DIV) * BAUD) * 50 <= CLK_HZ,
                "uart_rx: BAUD is more than 2 % off any whole divisor of CLK_HZ");
  static constexpr uint32_t FULL = DIV - 1, HALF = DIV / 2 - 1;

  uint8_t data_o = 0;
  bool valid_o = false, ferr_o = false;
  bool busy = false;
  uint32_t cnt = 0;  // clocks to the middle of the next bit, minus one
  uint8_t bitn = 0;  // 0 start, 1..8 data, 9 stop
  uint8_t sh = 0;

  void clock(bool rst, bool rx_i) {
    valid_o = false;
    ferr_o = false;
    if (rst) {
      busy = false;
    } else if (!busy) {
      if (!rx_i) {
        busy = true;
        cnt = HALF;
        bitn = 0;
      }
    } else if (cnt != 0) {
      --cnt;
    } else {
      const uint8_t b = bitn;
      cnt = FULL;
      bitn = uint8_t((b + 1) & 0xF);
      if (b == 0) {
        if (rx_i) busy = false;  // the start bit did not last: a glitch
      } else if (b == 9) {
        busy = false;
        data_o = sh;
        valid_o = rx_i;
        ferr_o = !rx_i;
      } else {
        sh = uint8_t(uint32_t(rx_i) << 7 | sh >> 1);
      }
    }
  }

  // Clocks (up to limit) that change nothing but the bit timer: idle with
  // the line high, or between two samples of a byte (the line is not
  // looked at there). skip(n) does them.
  uint32_t quiet(bool rx_i, uint32_t limit) const {
    if (valid_o || ferr_o) return 0;
    if (!busy) return rx_i ? limit : 0;
    return cnt < limit ? cnt : limit;
  }
  void skip(uint32_t n) {
    if (busy) cnt -= n;
  }

  // Inside a byte, with the line's future known: rx(t) is rx_i in the t-th
  // clock from now. The clocks (up to limit) before the stop bit's sample
  // (valid_o rises there), in which only the timer, the bit count and the
  // shift register move; a start bit that did not last ends them at its
  // sample. skip_line(n, rx) does them (not RTL).
  template <typename Rx>
  uint32_t quiet_line(Rx&& rx, uint32_t limit) const {
    if (!busy || valid_o || ferr_o) return 0;
    const uint32_t stop = cnt + uint32_t(9 - bitn) * uint32_t(DIV);
    if (bitn == 0 && cnt < limit && rx(cnt)) return cnt;
    return stop < limit ? stop : limit;
  }
  template <typename Rx>
  void skip_line(uint32_t n, Rx&& rx) {
    uint32_t t = cnt;  // the clock of the next sample
    if (n <= t) {
      cnt -= n;
      return;
    }
    for (; t < n; t += uint32_t(DIV)) {
      if (bitn != 0) sh = uint8_t(uint32_t(rx(t)) << 7 | sh >> 1);
      bitn = uint8_t(bitn + 1);
    }
    cnt = FULL - (n - 1 - (t - uint32_t(DIV)));
  }
};

}  // namespace mc
