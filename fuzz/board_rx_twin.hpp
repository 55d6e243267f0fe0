// Hostile bytes into the board twin's link (hls/mc_board.hpp), fast enough
// for the millions of inputs a fuzzer needs; fuzz/board_rx.hpp is the same
// rule on the Verilated board's RX pin, at about one input a second.
//
// Each input starts from the same board: reset, the sample period set,
// then every writable register given a distinct value over the link,
// drives disarmed. The bytes
// arrive as uart_rx hands them to link_rx, one every ten bit times (a
// back-to-back 8N1 line at the board's baud); when they end inside a frame
// the line stays quiet past the byte timeout. A second copy of that board runs the same clocks with a
// quiet line. The rule: a burst in which the host's decoder
// (host/link/protocol, the board's own rules) finds no good frame leaves the
// board exactly as the quiet line left its copy (the motion core, the
// safety block, the handwheel decoder, the register file's registers and
// every word of its RAM but the two link counters, link_tx and uart_tx, so
// no reply), and the link counters grow exactly as the host's decoder
// counted. The twin's own fast-forward skips the clocks in which only
// counters move, which is where the speed comes from; tests/test_board_twin.cpp
// holds the twin to the RTL at every pin.
//
//   mc::fuzz::BoardRxTwin b;
//   std::string why = b.feed(bytes, n);  // empty: the rule held
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz/board_rx_setup.hpp"
#include "hls/board_regs.hpp"
#include "hls/motioncore_icebreaker.hpp"
#include "hls/pid_regs.hpp"
#include "host/link/protocol.hpp"
#include "sim/vboard/uart_model.hpp"

namespace mc::fuzz {

class BoardRxTwin {
 public:
  using Board = MotioncoreIcebreaker<>::Board;
  static constexpr long kClkHz = 12'000'000, kBaud = 1'000'000;
  static constexpr int kAxes = 3;
  static constexpr int kBitClocks = sim::uart_clocks_per_bit(kClkHz, kBaud);
  // What the burst is checked against: the host's decoder decides which
  // bursts hold a good frame, or (to show the check can fail) every burst
  // is checked as if it held none.
  enum class Expect { FromDecoder, NoGoodFrame };

  BoardRxTwin() {
    McBoardIn in = idle_;
    in.rst = true;
    for (int i = 0; i < 16; ++i) ref_.clock(in);
    // A sample period of 1 ms, the bench's fpga-1ms (at reset it is the
    // PID's latency, a sample every few dozen clocks, and the samples'
    // clocks would be most of the work).
    write(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), uint32_t(kClkHz / 1000));
    write_distinct_registers(kAxes, [this](uint16_t addr, uint32_t v) { write(addr, v); });
    run(ref_, kClkHz / 1000);
  }

  // One burst on a fresh copy of the board; what went wrong, or "".
  std::string feed(const uint8_t* p, size_t n, Expect expect = Expect::FromDecoder) {
    namespace br = board::reg;
    host::proto::Decoder probe;  // which frames are good
    std::vector<host::proto::Frame> good;
    probe.push(host::proto::Bytes(p, p + n), good);
    probe.timeout();
    a_ = ref_;
    b_ = ref_;
    uint64_t clocks = 0;
    for (size_t i = 0; i < n; ++i) {
      a_.u_urx.data_o = p[i];  // uart_rx's strobe for a received byte
      a_.u_urx.valid_o = true;
      clocks += run(a_, 10 * kBitClocks);
    }
    // A partial frame: quiet past the byte timeout, so it is dropped and
    // counted.
    if (a_.u_lrx.st != a_.u_lrx.S_HUNT)
      clocks += run(a_, uint64_t(kClkHz) / 1'000'000 * (board::proto::BYTE_TIMEOUT_US + 200));
    run(b_, clocks);
    if (expect == Expect::FromDecoder && !good.empty()) {
      ++good_bursts_;
      return {};
    }
    std::string why;
    const auto& ra = a_.u_regs;
    const auto& rb = b_.u_regs;
    const auto delta16 = [&](uint16_t reg, int shift) {
      const uint8_t w = ra.sidx(reg);
      return uint64_t(uint16_t((ra.shadow[w] >> shift) - (rb.shadow[w] >> shift)));
    };
    const host::proto::DecodeStats& s = probe.stats();
    const auto count = [&](const char* what, uint16_t reg, int shift, uint64_t want) {
      if (delta16(reg, shift) != want % 65536)
        why += std::string(what) + ": the board counted " + std::to_string(delta16(reg, shift)) +
               ", the decoder " + std::to_string(want) + "; ";
    };
    count("bad CRCs", br::LINK_CRC, 0, s.crc);
    count("framing errors", br::LINK_CRC, 16, s.framing);
    count("junk bytes", br::LINK_JUNK, 0, s.junk_bytes);
    for (int w = 0; w < 256; ++w)
      if (w != ra.sidx(br::LINK_CRC) && w != ra.sidx(br::LINK_JUNK) && ra.shadow[w] != rb.shadow[w])
        why += "register RAM word " + hex(uint32_t(w)) + " changed from " + hex(rb.shadow[w]) + " to " +
               hex(ra.shadow[w]) + "; ";
    if (ra.r != rb.r) why += "the register file's registers changed; ";
    if (a_.u_ltx != b_.u_ltx || a_.u_utx != b_.u_utx) why += "the board sent a reply; ";
    if (a_.u_safety != b_.u_safety) why += "the safety block changed; ";
    if (a_.u_core != b_.u_core) why += "the motion core changed; ";
    if (a_.u_hw != b_.u_hw || a_.hb != b_.hb) why += "the handwheel or heartbeat changed; ";
    return why;
  }

  uint64_t good_bursts() const { return good_bursts_; }
  // Clocks stepped one by one so far (the others were skipped).
  uint64_t stepped() const { return stepped_; }

 private:
  static std::string hex(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%X", v);
    return b;
  }

  // n clocks of b with the line quiet: skipped where only counters move.
  uint64_t run(Board& b, uint64_t n) {
    for (uint64_t done = 0; done < n;) {
      const uint64_t left = n - done;
      const uint32_t k = b.quiet(idle_, left > 0xFFFFFFFFu ? 0xFFFFFFFFu : uint32_t(left));
      if (k > 0) {
        b.skip(k);
        done += k;
      } else {
        b.clock(idle_);
        ++done;
        ++stepped_;
      }
    }
    return n;
  }

  // A write over the pins, clock by clock, at the board's baud; its reply
  // must say OK.
  void write(uint16_t addr, uint32_t v) {
    sim::UartSender tx(kBitClocks);
    sim::UartReceiver rx(kBitClocks);
    host::proto::Frame req = host::proto::write(0, addr, v);
    req.seq = ++seq_;
    tx.send(host::proto::encode(req));
    host::proto::Decoder dec;
    McBoardIn in = idle_;
    for (long i = 0; i < 400L * kBitClocks; ++i) {
      in.rx = tx.pin();
      ref_.clock(in);
      rx.clock(ref_.tx_o());
      tx.clock();
      while (rx.has_byte()) {
        host::proto::Frame f;
        if (dec.push(rx.take(), f)) {
          const host::proto::Reply r = host::proto::parse_reply(f);
          if (!host::proto::answers(r, req) || r.status != board::proto::ST_OK)
            throw std::runtime_error("board_rx_twin: WRITE " + hex(addr) + " refused");
          return;
        }
      }
    }
    throw std::runtime_error("board_rx_twin: no reply to WRITE " + hex(addr));
  }

  McBoardIn idle_;  // reset released, line idle, every other pin at rest
  Board ref_;       // the board every input starts from
  Board a_, b_;     // the burst's board, and its quiet-line copy
  uint8_t seq_ = 0;
  uint64_t good_bursts_ = 0, stepped_ = 0;
};

}  // namespace mc::fuzz
