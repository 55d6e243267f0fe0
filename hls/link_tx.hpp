// link_tx twin: the frame sender of the link protocol, clock by clock.
// Mirrors rtl/link_tx.v, which documents how to drive it: payload words go
// into a RAM of 16 (we, waddr, wdata); strobe start while busy_o() is low
// with the header fields, which must hold until busy_o() falls; the bytes go
// to uart_tx through byte_o/valid_o.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
#pragma once

#include <cstdint>

#include "board_regs.hpp"
#include "crc16_ccitt.hpp"

namespace mc {

struct LinkTxIn {
  bool operator==(const LinkTxIn&) const = default;
  bool rst = false;
  // payload RAM
  bool we = false;
  uint8_t waddr = 0;  // 4 bits
  uint32_t wdata = 0;
  // frame
  bool start = false;
  uint8_t seq = 0, cmd = 0;
  bool status_en = false;
  uint8_t status = 0;
  uint8_t wbase = 0, nwords = 0;  // 4 bits each
  // uart_tx
  bool ready = false;
};

struct LinkTx {
  bool operator==(const LinkTx&) const = default;
  enum : uint8_t { S_IDLE = 0, S_HDR = 1, S_STAT = 2, S_DATA = 3, S_CRC0 = 4, S_CRC1 = 5, S_END = 6 };

  uint32_t ram[16] = {};
  uint32_t q = 0;
  uint8_t ra = 0;  // 4 bits
  uint8_t st = S_IDLE;
  uint8_t hb = 0;     // 2 bits: header byte, and byte within a word
  uint8_t wleft = 0;  // 4 bits: words left after the current one
  bool hold = false;  // the byte just handed over has not left uart_tx's ready yet
  uint8_t byte_o = 0;
  bool valid_o = false;
  Crc16Ccitt u_crc;

  bool busy_o() const { return st != S_IDLE; }

  static uint8_t len(const LinkTxIn& in) { return uint8_t((in.nwords & 0xF) << 2) + uint8_t(in.status_en); }

  // The next byte, by state.
  uint8_t nb(const LinkTxIn& in) const {
    switch (st) {
      case S_HDR:
        return hb == 0 ? board::proto::SYNC : hb == 1 ? len(in) : hb == 2 ? in.seq : in.cmd;
      case S_STAT:
        return in.status;
      case S_DATA:
        return uint8_t(q >> (hb * 8));
      case S_CRC0:
        return uint8_t(u_crc.crc_o);
      default:
        return uint8_t(u_crc.crc_o >> 8);
    }
  }

  void clock(const LinkTxIn& in) {
    const uint8_t s = st;
    const bool go = s != S_IDLE && s != S_END && in.ready && !valid_o && !hold && !u_crc.busy_o();
    const uint8_t b = nb(in);
    const bool crc_en = go && (s == S_STAT || s == S_DATA || (s == S_HDR && hb != 0));
    const uint8_t l = len(in);

    // Payload RAM: q reads the word before this clock's write.
    const uint32_t qn = ram[ra];
    if (in.we) ram[in.waddr & 0xF] = in.wdata;
    q = qn;

    const bool v = valid_o;
    valid_o = false;
    if (in.rst) {
      st = S_IDLE;
    } else if (s == S_IDLE) {
      if (in.start) {
        st = S_HDR;
        hb = 0;
        ra = in.wbase & 0xF;
        wleft = uint8_t((in.nwords - 1) & 0xF);
      }
    } else if (s == S_END) {
      if (in.ready && !hold && !v) st = S_IDLE;
    } else if (go) {
      byte_o = b;
      valid_o = true;
      const uint8_t h = hb;
      hb = uint8_t((h + 1) & 3);
      switch (s) {
        case S_HDR:
          if (h == 3) {
            hb = 0;
            st = in.status_en ? S_STAT : (l == 0 ? S_CRC0 : S_DATA);
          }
          break;
        case S_STAT:
          hb = 0;
          st = l == 1 ? S_CRC0 : S_DATA;
          break;
        case S_DATA:
          if (h == 3) {
            ra = uint8_t((ra + 1) & 0xF);
            if (wleft == 0) st = S_CRC0;
            wleft = uint8_t((wleft - 1) & 0xF);
          }
          break;
        case S_CRC0:
          st = S_CRC1;
          break;
        default:
          st = S_END;
          break;
      }
    }
    hold = v;  // uart_tx's ready falls the clock after it takes a byte
    u_crc.clock(s == S_IDLE, crc_en, b);
  }

  // A clock with this input changes nothing but the CRC's shifting: idle
  // with no start, or a frame waiting for uart_tx's ready; nothing written,
  // the RAM's output settled. skip(n) does such clocks.
  bool quiet(const LinkTxIn& in) const {
    if (in.rst || in.we || valid_o || hold || q != ram[ra]) return false;
    return st == S_IDLE ? !in.start && u_crc.at_init() : !in.ready;
  }
  void skip(uint32_t n) { u_crc.skip(n); }
};

}  // namespace mc
