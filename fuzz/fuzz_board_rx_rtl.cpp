// libFuzzer target: arbitrary bytes on the Verilated board's RX pin
// (fuzz/board_rx.hpp): only a frame with a good CRC may change the board.
// About one input a second, so fuzz/run.sh uses it to replay on the RTL the
// inputs fuzz_board_rx (the same rule on the board twin) found.
// One board serves every input (building one costs more than an input); each
// input is one burst, followed by a quiet line and a full register check.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz/board_rx.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static mc::fuzz::BoardRx board;
  // Longer bursts add clocks, not new decoder states.
  const std::string why = board.feed(data, size < 1024 ? size : 1024);
  if (!why.empty()) {
    std::fprintf(stderr, "board_rx: %s\n", why.c_str());
    std::abort();
  }
  return 0;
}
