// The Verilated rtl/motion_core.v (NAXES = 2) as a CoreModel. Kept behind a
// factory so that Verilator's headers stay out of the rest of the sim.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "sim/cosim/core_model.hpp"

namespace mc::sim {

// fst_path non-empty: every signal of the core is dumped there (GTKWave).
std::unique_ptr<CoreModel> make_rtl_core(const std::string& fst_path = "");
// Clocks per CPU second of the Verilated core alone: reset, then `clocks`
// edges in a bare C++ loop with every input held (no harness, no kernel).
double bare_rtl_clocks_per_s(uint64_t clocks);

}  // namespace mc::sim
