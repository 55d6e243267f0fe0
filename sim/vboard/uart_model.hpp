// Bit-level UART (8N1) models for a clocked simulation: one drives a line, the
// other samples one, both advanced one clock at a time by the caller. They
// know nothing of the simulator, so they bridge anything that moves bytes
// (a testbench, a pseudo-terminal) to the pins of a Verilated board.
//
//   UartSender tx(clocks_per_bit);  UartReceiver rx(clocks_per_bit);
//   tx.send(bytes);
//   each clock: top->RX = tx.pin(); eval; rx.clock(top->TX); tx.clock();
//               if (rx.has_byte()) use(rx.take());
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <stdexcept>
#include <vector>

namespace mc::sim {

// Clocks per bit, rounded as the RTL rounds it (uart_rx.v).
constexpr int uart_clocks_per_bit(long clk_hz, long baud) {
  return int((clk_hz + baud / 2) / baud);
}

class UartSender {
 public:
  explicit UartSender(int clocks_per_bit) : cpb_(clocks_per_bit) {
    if (cpb_ < 2) throw std::invalid_argument("UartSender: clocks_per_bit must be at least 2");
  }
  void send(const std::vector<uint8_t>& bytes) { q_.insert(q_.end(), bytes.begin(), bytes.end()); }
  void send(uint8_t b) { q_.push_back(b); }
  // The line level in this clock (idle high).
  bool pin() const { return level_; }
  // Nothing queued and the line idle.
  bool idle() const { return q_.empty() && bit_ < 0; }
  // Bytes not yet fully sent, the one on the line included.
  size_t queued() const { return q_.size() + (bit_ >= 0 ? 1 : 0); }
  // How many of the next clock() calls surely leave pin() as it is.
  uint32_t steady() const {
    if (bit_ < 0) return q_.empty() ? UINT32_MAX : 0;
    return cnt_ == 0 ? 0 : uint32_t(cpb_ - cnt_);
  }
  // pin() after t more clock() calls: the rest of the byte on the line,
  // then the queued bytes back to back, then idle (high).
  bool pin_after(uint64_t t) const {
    if (t == 0) return level_;
    if (bit_ < 0 && q_.empty()) return true;
    // Bits from the start of the byte on the line (an idle line: from the
    // end of one), the t-th call's bit among them.
    const uint64_t b =
        (bit_ < 0 ? 10 : uint64_t(bit_)) + (uint64_t(bit_ < 0 ? 0 : cnt_) + t - 1) / uint64_t(cpb_);
    if (b <= 9) return bit_level(cur_, int(b));
    const uint64_t k = (b - 10) / 10;
    return k < q_.size() ? bit_level(q_[size_t(k)], int((b - 10) % 10)) : true;
  }
  // n clock() calls; inside a bit only the counter moves.
  void clock_n(uint32_t n) {
    while (n > 0) {
      if (bit_ < 0 && q_.empty()) return;
      if (bit_ >= 0 && cnt_ > 0 && cnt_ + 1 < cpb_) {
        const uint32_t m = std::min(n, uint32_t(cpb_ - 1 - cnt_));
        cnt_ += int(m);
        n -= m;
        continue;
      }
      clock();
      --n;
    }
  }
  // Advance one clock.
  void clock() {
    if (bit_ < 0) {
      if (q_.empty()) return;
      cur_ = q_.front();
      q_.pop_front();
      bit_ = 0;
      cnt_ = 0;
    }
    level_ = bit_level(cur_, bit_);
    if (++cnt_ == cpb_) {
      cnt_ = 0;
      if (++bit_ == 10) bit_ = -1;
    }
  }

 private:
  // Bit 0 start, 1..8 data LSB first, 9 stop.
  static bool bit_level(uint8_t byte, int bit) {
    return bit == 0 ? false : bit == 9 ? true : ((byte >> (bit - 1)) & 1);
  }

  int cpb_;
  std::deque<uint8_t> q_;
  uint8_t cur_ = 0;
  int bit_ = -1, cnt_ = 0;
  bool level_ = true;
};

// A receiver's sampling of the line, without the bytes it took: cheap to
// copy, so that a copy can look ahead for the next byte.
class UartBits {
 public:
  explicit UartBits(int clocks_per_bit) : cpb_(clocks_per_bit) {
    if (cpb_ < 2) throw std::invalid_argument("UartReceiver: clocks_per_bit must be at least 2");
  }
  // Sample the line in this clock; at a stop bit's sample, on_stop(byte,
  // stop bit high).
  template <typename F>
  void clock(bool level, F&& on_stop) {
    if (bit_ < 0) {
      if (!level) {
        bit_ = 0;
        cnt_ = cpb_ / 2;  // to the middle of the start bit
      }
      return;
    }
    if (--cnt_ > 0) return;
    cnt_ = cpb_;
    if (bit_ == 0) {
      if (level)
        bit_ = -1;  // a glitch, not a start bit
      else
        ++bit_;
    } else if (bit_ <= 8) {
      sh_ = uint8_t((sh_ >> 1) | (level ? 0x80 : 0));
      ++bit_;
    } else {
      on_stop(sh_, level);
      bit_ = -1;
    }
  }
  // n clock(level) calls with the line held; between samples only the
  // counter moves.
  template <typename F>
  void clock_n(bool level, uint32_t n, F&& on_stop) {
    while (n > 0) {
      if (bit_ < 0 && level) return;
      if (bit_ >= 0 && cnt_ > 1) {
        const uint32_t m = std::min(n, uint32_t(cnt_ - 1));
        cnt_ -= int(m);
        n -= m;
        continue;
      }
      clock(level, on_stop);
      --n;
    }
  }
  bool busy() const { return bit_ >= 0; }
  // Inside a byte: the clock() calls up to the one that takes it (its stop
  // bit's sample, which also finds a framing error).
  uint64_t clocks_to_byte() const {
    return busy() ? uint64_t(cnt_) + uint64_t(9 - bit_) * uint64_t(cpb_) : 0;
  }

 private:
  int cpb_;
  int bit_ = -1, cnt_ = 0;
  uint8_t sh_ = 0;
};

class UartReceiver {
 public:
  explicit UartReceiver(int clocks_per_bit) : bits_(clocks_per_bit) {}
  // Sample the line in this clock.
  void clock(bool level) {
    bits_.clock(level, [this](uint8_t byte, bool stop) { take(byte, stop); });
  }
  // n clock(level) calls with the line held.
  void clock_n(bool level, uint32_t n) {
    bits_.clock_n(level, n, [this](uint8_t byte, bool stop) { take(byte, stop); });
  }
  bool has_byte() const { return !out_.empty(); }
  uint8_t take() {
    const uint8_t b = out_.front();
    out_.pop_front();
    return b;
  }
  bool busy() const { return bits_.busy(); }
  uint64_t clocks_to_byte() const { return bits_.clocks_to_byte(); }
  uint64_t framing_errors() const { return framing_errors_; }
  // The sampling alone, to look ahead on a copy.
  const UartBits& bits() const { return bits_; }

 private:
  void take(uint8_t byte, bool stop) {
    if (stop)
      out_.push_back(byte);
    else
      ++framing_errors_;
  }
  UartBits bits_;
  std::deque<uint8_t> out_;
  uint64_t framing_errors_ = 0;
};

}  // namespace mc::sim
