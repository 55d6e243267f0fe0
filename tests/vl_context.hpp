// Contexts and port access for Verilated models in the testbenches.
#pragma once

#include <cstdint>
#include <memory>

#include "sim/cosim/vl_ports.hpp"  // sim/vl_ports.hpp: put32, get_bits
#include "verilated.h"

namespace mc::test {

using mc::vl::get_bits;
using mc::vl::put32;

// A context whose models power up in random state (randReset(2)), seeded so
// that a failure reproduces: a missing reset shows as a twin mismatch.
inline std::unique_ptr<VerilatedContext> random_context(uint32_t seed) {
  auto ctx = std::make_unique<VerilatedContext>();
  ctx->randReset(2);
  ctx->randSeed(int(seed & 0x7fffffff));
  return ctx;
}

}  // namespace mc::test
