// Generated views of hls/board_regs.hpp: the Verilog include and the register
// table of docs/protocol.md. `build/gen_board_regs --vh|--md` prints them;
// test_board_regs checks that the files in the repository are up to date.
#pragma once

#include <string>

namespace mc::host {

// rtl/board_regs.vh, complete.
std::string board_regs_vh();
// The register table for docs/protocol.md (between the GENERATED markers).
std::string board_regs_md();

}  // namespace mc::host
