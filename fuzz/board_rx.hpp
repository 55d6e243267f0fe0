// Hostile bytes on the board's RX pin: the Verilated iCEBreaker top
// (rtl/motioncore_icebreaker.v) gets a burst of arbitrary bytes, bit by bit
// at its own baud, then a quiet line longer than its byte timeout; after each
// burst every register a frame could change is read back with good frames.
// The rule checked: only a frame with a good CRC may change the board. A
// burst in which the host's decoder (host/link/protocol, the board's own
// rules) finds no good frame must leave every register as it was, get no
// reply, and be counted exactly: bad CRCs, framing errors and junk bytes as
// the host's decoder counts them. A burst that does hold a good frame is
// legitimate; the registers are read again as the new reference.
//
//   mc::fuzz::BoardRx b;
//   std::string why = b.feed(bytes, n);  // empty: the rule held
//
// Used by fuzz/fuzz_board_rx.cpp (libFuzzer) and tests/test_board_rx.cpp
// (a bounded random run under CTest).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "Vmotioncore_icebreaker.h"
#include "fuzz/board_rx_setup.hpp"
#include "hls/board_regs.hpp"
#include "hls/pid_regs.hpp"
#include "host/link/protocol.hpp"
#include "sim/vboard/uart_model.hpp"
#include "verilated.h"

namespace mc::fuzz {

namespace bp = board::proto;
namespace br = board::reg;
namespace hp = host::proto;

// The board top's inputs at rest: reset released, UART idle, no limit, no
// probe, no e-stop, every encoder and the handwheel still. Evaluated once.
inline void inputs_at_rest(Vmotioncore_icebreaker& top) {
  top.CLK = 0;
  top.RX = 1;
  top.BTN_N = 1;
  top.ESTOP = 0;
  top.PROBE = 0;
  top.X_LIM = top.Y_LIM = top.Z_LIM = 0;
  top.X_ENC_A = top.X_ENC_B = 0;
  top.Y_ENC_A = top.Y_ENC_B = 0;
  top.Z_ENC_A = top.Z_ENC_B = 0;
  top.HW_A = top.HW_B = 0;
  top.eval();
}

// One clock with a host on the UART pins: the host's line onto RX, a clock
// edge, the board's TX line sampled.
inline void uart_clock(Vmotioncore_icebreaker& top, sim::UartSender& tx, sim::UartReceiver& rx) {
  top.RX = tx.pin();
  top.CLK = 1;
  top.eval();
  top.CLK = 0;
  top.eval();
  rx.clock(top.TX);
  tx.clock();
}

class BoardRx {
 public:
  static constexpr long kClkHz = 12'000'000, kBaud = 1'000'000;
  static constexpr int kAxes = 3;

  explicit BoardRx(uint32_t seed = 1) : ctx_(std::make_unique<VerilatedContext>()) {
    // Random power-up state: a register that relies on it shows up as a mismatch.
    ctx_->randReset(2);
    ctx_->randSeed(int(seed & 0x7fffffff));
    top_ = std::make_unique<Vmotioncore_icebreaker>(ctx_.get());
    inputs_at_rest(*top_);
    run(64);
    expect_ok(hp::ping(0), "PING");
    write_distinct_registers(kAxes, [this](uint16_t addr, uint32_t v) { write(addr, v); });
    ref_ = snapshot();
  }
  ~BoardRx() { top_->final(); }
  BoardRx(const BoardRx&) = delete;
  BoardRx& operator=(const BoardRx&) = delete;

  // One burst; returns what went wrong, or "" when the rule held.
  std::string feed(const uint8_t* p, size_t n) {
    hp::Decoder probe;  // the board's decoder, in the host: which frames are good
    std::vector<hp::Frame> good;
    probe.push(hp::Bytes(p, p + n), good);
    probe.timeout();
    const uint32_t crc0 = read(br::LINK_CRC), junk0 = read(br::LINK_JUNK);
    replies_ = 0;
    tx_.send(hp::Bytes(p, p + n));
    while (!tx_.idle()) clock();
    // Quiet past the byte timeout: a partial frame is dropped and counted.
    run(kClkHz / 1'000'000 * (bp::BYTE_TIMEOUT_US + 200));
    if (!good.empty()) {
      // A good frame may do anything a host may; start again from here.
      expect_ok(hp::ping(0), "PING after a burst with a good frame");
      ref_ = snapshot();
      ++good_bursts_;
      return {};
    }
    std::string why;
    if (replies_ != 0) why += std::to_string(replies_) + " replies to a burst without a good frame; ";
    const uint32_t crc1 = read(br::LINK_CRC), junk1 = read(br::LINK_JUNK);
    const auto delta16 = [](uint32_t now, uint32_t before, int shift) {
      return uint64_t(uint16_t((now >> shift) - (before >> shift)));
    };
    const hp::DecodeStats& s = probe.stats();
    if (delta16(crc1, crc0, 0) != s.crc % 65536)
      why += "LINK_CRC counted " + std::to_string(delta16(crc1, crc0, 0)) + " bad CRCs, the decoder " +
             std::to_string(s.crc) + "; ";
    if (delta16(crc1, crc0, 16) != s.framing % 65536)
      why += "LINK_CRC counted " + std::to_string(delta16(crc1, crc0, 16)) + " framing errors, the decoder " +
             std::to_string(s.framing) + "; ";
    if (delta16(junk1, junk0, 0) != s.junk_bytes % 65536)
      why += "LINK_JUNK counted " + std::to_string(delta16(junk1, junk0, 0)) + " junk bytes, the decoder " +
             std::to_string(s.junk_bytes) + "; ";
    const std::vector<std::pair<uint16_t, uint32_t>> now = snapshot();
    for (size_t i = 0; i < now.size(); ++i)
      if (now[i].second != ref_[i].second)
        why += "register " + hex(now[i].first) + " changed from " + hex(ref_[i].second) + " to " +
               hex(now[i].second) + "; ";
    return why;
  }

  uint64_t cycles() const { return cycles_; }
  uint64_t good_bursts() const { return good_bursts_; }
  // Registers compared after each burst.
  size_t watched() const { return ref_.size(); }

 private:
  static uint16_t axis(int a, uint16_t off) { return axis_reg(a, off); }
  static std::string hex(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%X", v);
    return b;
  }

  void clock() {
    uart_clock(*top_, tx_, rx_);
    while (rx_.has_byte()) {
      hp::Frame f;
      if (dec_.push(rx_.take(), f) && !hp::is_telemetry(f)) {
        ++replies_;
        last_ = f;
      }
    }
    ++cycles_;
  }
  void run(long n) {
    for (long i = 0; i < n; ++i) clock();
  }

  // A request on a quiet line; its reply, or an exception naming it.
  hp::Reply transact(hp::Frame req, const char* what) {
    req.seq = seq_.next();
    replies_ = 0;
    tx_.send(hp::encode(req));
    // The request, the reply and slack, at 10 bits a byte.
    const long timeout = 80L * 10 * sim::uart_clocks_per_bit(kClkHz, kBaud);
    while (!tx_.idle()) clock();
    for (long i = 0; i < timeout && replies_ == 0; ++i) clock();
    if (replies_ == 0) throw std::runtime_error(std::string("board_rx: no reply to ") + what);
    const hp::Reply r = hp::parse_reply(last_);
    if (!hp::answers(r, req)) throw std::runtime_error(std::string("board_rx: wrong reply to ") + what);
    return r;
  }
  void expect_ok(const hp::Frame& req, const char* what) {
    if (transact(req, what).status != bp::ST_OK)
      throw std::runtime_error(std::string("board_rx: refused ") + what);
  }
  uint32_t read(uint16_t addr) {
    const hp::Reply r = transact(hp::read(0, addr), "READ");
    if (r.status != bp::ST_OK) throw std::runtime_error("board_rx: READ " + hex(addr) + " refused");
    return r.value;
  }
  void write(uint16_t addr, uint32_t v) { expect_ok(hp::write(0, addr, v), "WRITE"); }

  // Everything a frame could change, and nothing that changes by itself.
  std::vector<std::pair<uint16_t, uint32_t>> snapshot() {
    std::vector<uint16_t> addrs = {br::FAULT,    br::CTRL,     br::WDOG,    br::SAFETY,
                                   br::TLM,      br::IP_STAT,  br::IP_SEGS, br::IP_SET_X,
                                   br::IP_SET_Y, br::IP_SET_Z, br::HW_POS,  br::HW_CFG};
    for (int a = 0; a < kAxes; ++a) {
      for (uint16_t off : {br::AX_POS, br::AX_ENC_CFG, br::AX_IDX, br::AX_ENC_STAT, br::AX_DRV, br::AX_FERR})
        addrs.push_back(axis(a, off));
      for (uint8_t r = 0; r < pid_reg::NREGS_RAM; ++r) addrs.push_back(pid_reg::addr(uint8_t(a), r));
      addrs.push_back(pid_reg::addr(uint8_t(a), pid_reg::CTRL));
    }
    addrs.push_back(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS));
    std::vector<std::pair<uint16_t, uint32_t>> v;
    v.reserve(addrs.size());
    for (uint16_t a : addrs) v.emplace_back(a, read(a));
    return v;
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmotioncore_icebreaker> top_;
  sim::UartSender tx_{sim::uart_clocks_per_bit(kClkHz, kBaud)};
  sim::UartReceiver rx_{sim::uart_clocks_per_bit(kClkHz, kBaud)};
  hp::Decoder dec_;
  hp::SeqGen seq_{1};
  hp::Frame last_;
  int replies_ = 0;
  uint64_t cycles_ = 0, good_bursts_ = 0;
  std::vector<std::pair<uint16_t, uint32_t>> ref_;
};

}  // namespace mc::fuzz
