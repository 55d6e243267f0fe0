// Prints a generated view of hls/board_regs.hpp: --vh (rtl/board_regs.vh) or
// --md (the register table of docs/protocol.md). `make regs` writes both.
#include <cstdio>
#include <cstring>

#include "host/link/board_regs_gen.hpp"

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--vh") == 0) {
    std::fputs(mc::host::board_regs_vh().c_str(), stdout);
    return 0;
  }
  if (argc == 2 && std::strcmp(argv[1], "--md") == 0) {
    std::fputs(mc::host::board_regs_md().c_str(), stdout);
    return 0;
  }
  std::fputs("usage: gen_board_regs --vh | --md\n", stderr);
  return 2;
}
