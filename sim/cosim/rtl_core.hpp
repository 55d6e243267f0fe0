// The Verilated rtl/motion_core.v (NAXES = 2) as a CoreModel. Kept behind a
// factory so that Verilator's headers stay out of the rest of the sim.
#pragma once

#include <memory>
#include <string>

#include "sim/cosim/core_model.hpp"

namespace mc::sim {

// fst_path non-empty: every signal of the core is dumped there (GTKWave).
std::unique_ptr<CoreModel> make_rtl_core(const std::string& fst_path = "");

}  // namespace mc::sim
