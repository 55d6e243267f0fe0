// Port access for Verilated models: Verilator gives a port of up to 32 bits
// as an integer, up to 64 as a 64-bit integer and wider ones as a word array;
// these access bit fields the same way on all.
#pragma once

#include <cstddef>
#include <cstdint>

#include "verilated.h"

namespace mc::vl {

template <typename P, typename V>
void set(P& p, V v) {
  p = P(v);
}
inline void put32(uint32_t& p, int, uint32_t v) {
  p = v;
}
inline void put32(uint64_t& p, int i, uint32_t v) {
  p = (p & ~(uint64_t(0xFFFFFFFFu) << (32 * i))) | (uint64_t(v) << (32 * i));
}
template <std::size_t N>
void put32(VlWide<N>& p, int i, uint32_t v) {
  p[i] = v;
}
template <typename P>
uint32_t get_bits(const P& p, int lsb, int w) {
  return uint32_t((uint64_t(p) >> lsb) & ((uint64_t(1) << w) - 1));
}
template <std::size_t N>
uint32_t get_bits(const VlWide<N>& p, int lsb, int w) {
  const uint64_t lo = p[lsb / 32], hi = (lsb / 32 + 1 < int(N)) ? p[lsb / 32 + 1] : 0;
  return uint32_t((((hi << 32) | lo) >> (lsb % 32)) & ((uint64_t(1) << w) - 1));
}

}  // namespace mc::vl
