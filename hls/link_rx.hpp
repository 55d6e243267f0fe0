// link_rx twin: the frame parser of the link protocol, clock by clock.
// Mirrors rtl/link_rx.v, which documents how to drive it: feed it uart_rx's
// bytes; a good frame pulses frame_o with seq_o, cmd_o, len_o and its payload
// readable from the RAM (pay_raddr in, pay_rdata_o a clock later); a bad
// frame pulses one of crc_err_o, framing_o, junk_o.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
#pragma once

#include <cstdint>

#include "board_regs.hpp"
#include "crc16_ccitt.hpp"

namespace mc {

struct LinkRxIn {
  bool operator==(const LinkRxIn&) const = default;
  bool rst = false;
  uint8_t byte = 0;
  bool valid = false;
  bool ferr = false;
  uint8_t pay_raddr = 0;
};

template <int CLK_HZ = 12'000'000>
struct LinkRx {
  bool operator==(const LinkRx&) const = default;
  static_assert(CLK_HZ >= 1'000'000, "link_rx: CLK_HZ below 1 MHz");
  static constexpr uint32_t TIMEOUT = uint32_t(CLK_HZ / 1'000'000 * board::proto::BYTE_TIMEOUT_US);  // clocks
  enum : uint8_t { S_HUNT = 0, S_LEN = 1, S_SEQ = 2, S_CMD = 3, S_PAY = 4, S_CRC0 = 5, S_CRC1 = 6 };

  bool frame_o = false;
  uint8_t seq_o = 0, cmd_o = 0, len_o = 0;
  uint8_t pay_rdata_o = 0;
  bool crc_err_o = false, framing_o = false, junk_o = false;
  uint8_t st = S_HUNT;
  uint8_t idx = 0;  // payload bytes received
  uint8_t crc_lo = 0;
  uint32_t idle = 0;  // clocks since the last byte, within a frame
  Crc16Ccitt u_crc;
  uint8_t pay[256] = {};

  bool stalled() const { return st != S_HUNT && idle == TIMEOUT; }

  void clock(const LinkRxIn& in) {
    const uint8_t s = st;
    const bool stall = stalled();
    const uint16_t crc = u_crc.crc_o;
    const bool crc_busy = u_crc.busy_o();
    const bool crc_en = in.valid && (s == S_LEN || s == S_SEQ || s == S_CMD || s == S_PAY);

    // Payload RAM: the read sees the word before this clock's write.
    pay_rdata_o = pay[in.pay_raddr];
    if (in.valid && s == S_PAY) pay[idx] = in.byte;

    frame_o = false;
    crc_err_o = false;
    framing_o = false;
    junk_o = false;
    if (in.valid || s == S_HUNT)
      idle = 0;
    else if (!stall)
      ++idle;
    if (in.rst) {
      st = S_HUNT;
    } else if (stall || (in.ferr && s != S_HUNT)) {
      st = S_HUNT;
      framing_o = true;
    } else if (in.ferr) {
      junk_o = true;
    } else if (in.valid) {
      switch (s) {
        case S_HUNT:
          if (in.byte == board::proto::SYNC)
            st = S_LEN;
          else
            junk_o = true;
          break;
        case S_LEN:
          len_o = in.byte;
          idx = 0;
          if (in.byte > board::proto::MAX_LEN) {
            st = S_HUNT;
            framing_o = true;
          } else {
            st = S_SEQ;
          }
          break;
        case S_SEQ:
          seq_o = in.byte;
          st = S_CMD;
          break;
        case S_CMD:
          cmd_o = in.byte;
          st = len_o == 0 ? S_CRC0 : S_PAY;
          break;
        case S_PAY:
          if (uint8_t(idx + 1) == len_o) st = S_CRC0;
          idx = uint8_t(idx + 1);
          break;
        case S_CRC0:
          crc_lo = in.byte;
          st = S_CRC1;
          break;
        default:  // S_CRC1, and the unused codes
          st = S_HUNT;
          if (uint16_t(in.byte << 8 | crc_lo) == crc && !crc_busy)
            frame_o = true;
          else
            crc_err_o = true;
          break;
      }
    }
    u_crc.clock(s == S_HUNT, crc_en, in.byte);
  }

  // Clocks (up to limit) that change nothing but the stall timer and the
  // CRC's shifting, with no byte arriving: hunting with every strobe low, or
  // inside a frame waiting for its next byte before the timeout. skip(n)
  // does them.
  uint32_t quiet(const LinkRxIn& in, uint32_t limit) const {
    if (in.rst || in.valid || in.ferr || frame_o || crc_err_o || framing_o || junk_o) return 0;
    if (pay_rdata_o != pay[in.pay_raddr]) return 0;
    if (st == S_HUNT) return idle == 0 && u_crc.at_init() ? limit : 0;
    const uint32_t left = TIMEOUT - idle;  // the clock with idle == TIMEOUT drops the frame
    return left < limit ? left : limit;
  }
  void skip(uint32_t n) {
    if (st != S_HUNT) idle += n;
    u_crc.skip(n);
  }
};

}  // namespace mc
