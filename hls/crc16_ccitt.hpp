// crc16_ccitt twin: CRC-16/CCITT-FALSE one bit per clock. Mirrors
// rtl/crc16_ccitt.v: strobe init_i to start, give a byte with en_i while
// busy_o() is low, read crc_o once busy_o() falls, 8 clocks later.
//
// Synthesizable subset: fixed-width integers, no heap, static loop bounds.
// The members are the RTL's registers, same names; clock() is one edge.
#pragma once

#include <cstdint>

namespace mc {

struct Crc16Ccitt {
  bool operator==(const Crc16Ccitt&) const = default;
  uint16_t crc_o = 0xFFFF;
  uint8_t sh = 0;
  uint8_t n = 0;  // bits left to shift in

  bool busy_o() const { return n != 0; }

  void clock(bool init_i, bool en_i, uint8_t data_i) {
    if (init_i) {
      crc_o = 0xFFFF;
      n = 0;
    } else if (en_i && n == 0) {
      sh = data_i;
      n = 8;
    } else if (n != 0) {
      shift();
    }
  }

  // k clocks with init_i and en_i low: the bits left shift in, then nothing.
  void skip(uint32_t k) {
    for (uint32_t i = 0; i < 8; ++i)
      if (i < k && n != 0) shift();
  }

  // The state a clock with init_i leaves: true when it is already there.
  bool at_init() const { return crc_o == 0xFFFF && n == 0; }

 private:
  void shift() {
    const bool fb = ((crc_o >> 15) ^ (sh >> 7)) & 1;
    crc_o = uint16_t(crc_o << 1 ^ (fb ? 0x1021 : 0));
    sh = uint8_t(sh << 1);
    --n;
  }
};

}  // namespace mc
