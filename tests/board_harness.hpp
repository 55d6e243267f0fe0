// The Verilated iCEBreaker top (rtl/motioncore_icebreaker.v) with a host on
// its UART pins: frames from host/protocol, bits from sim/uart_model. Every
// clock it moves the host's line, samples the board's, and decodes what the
// board sends; replies and telemetry frames are kept apart.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "Vmotioncore_icebreaker.h"
#include "fuzz/board_rx.hpp"  // the pins at rest and a clock with the UART: shared with the fuzzer
#include "hls/board_regs.hpp"
#include "host/link/protocol.hpp"
#include "sim/vboard/uart_model.hpp"
#include "vl_context.hpp"

namespace mc::test {

namespace bp = board::proto;
namespace br = board::reg;
namespace bb = board::bits;
namespace hp = host::proto;

constexpr long kClkHz = 12'000'000;
constexpr long kBaud = 1'000'000;
constexpr int kCpb = sim::uart_clocks_per_bit(kClkHz, kBaud);
// Clocks the host waits for a reply: a frame of 58 bytes (telemetry) may be
// in front of it, plus the reply and slack.
constexpr long kReplyTimeout = 80L * 10 * kCpb;
// The board drops a frame stalled this long.
constexpr long kByteTimeout = kClkHz / 1'000'000 * bp::BYTE_TIMEOUT_US;

class BoardTb {
 public:
  explicit BoardTb(uint32_t seed = 1)
      : ctx_(random_context(seed)), top_(std::make_unique<Vmotioncore_icebreaker>(ctx_.get())) {
    fuzz::inputs_at_rest(*top_);
    run(64);  // power-on reset and the PID's state clear
  }
  ~BoardTb() { top_->final(); }

  Vmotioncore_icebreaker& pins() { return *top_; }
  uint64_t cycles() const { return cycles_; }

  // One clock: host line, board edge, board line.
  void clock() {
    fuzz::uart_clock(*top_, tx_, rx_);
    while (rx_.has_byte()) {
      hp::Frame f;
      if (dec_.push(rx_.take(), f)) (hp::is_telemetry(f) ? tlm_ : replies_).push_back(std::move(f));
    }
    ++cycles_;
  }
  void run(long n) {
    for (long i = 0; i < n; ++i) clock();
  }

  // Sends raw bytes and waits until they have left the host's line.
  void send_raw(const hp::Bytes& b) {
    tx_.send(b);
    while (!tx_.idle()) clock();
  }
  // Sends a frame (then the trailing bytes, which arrive while the board
  // works on it); returns the reply to it, or nothing after the timeout.
  std::optional<hp::Reply> transact(const hp::Frame& req, long timeout = kReplyTimeout,
                                    const hp::Bytes& trailing = {}) {
    replies_.clear();
    hp::Bytes b = hp::encode(req);
    b.insert(b.end(), trailing.begin(), trailing.end());
    send_raw(b);
    for (long i = 0; i < timeout; ++i) {
      clock();
      if (!replies_.empty()) {
        hp::Reply r = hp::parse_reply(replies_.front());
        replies_.clear();
        EXPECT_TRUE(hp::answers(r, req)) << "reply to seq " << int(r.seq) << " cmd " << int(r.cmd);
        return r;
      }
    }
    return std::nullopt;
  }
  // Register access that must succeed.
  uint32_t read(uint16_t addr) {
    auto r = transact(hp::read(seq_.next(), addr));
    EXPECT_TRUE(r && r->status == bp::ST_OK)
        << "read 0x" << std::hex << addr << " status " << (r ? int(r->status) : -1);
    return r ? r->value : 0;
  }
  void write(uint16_t addr, uint32_t v) {
    auto r = transact(hp::write(seq_.next(), addr, v));
    EXPECT_TRUE(r && r->status == bp::ST_OK)
        << "write 0x" << std::hex << addr << " status " << (r ? int(r->status) : -1);
  }
  uint8_t next_seq() { return seq_.next(); }

  std::vector<hp::Frame>& telemetry() { return tlm_; }
  const hp::DecodeStats& host_rx_stats() const { return dec_.stats(); }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmotioncore_icebreaker> top_;
  sim::UartSender tx_{kCpb};
  sim::UartReceiver rx_{kCpb};
  hp::Decoder dec_;
  hp::SeqGen seq_{1};
  std::vector<hp::Frame> replies_, tlm_;
  uint64_t cycles_ = 0;
};

}  // namespace mc::test
