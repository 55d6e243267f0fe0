// libFuzzer target: arbitrary bytes into the board twin's link
// (fuzz/board_rx_twin.hpp): only a frame with a good CRC may change the
// board. Every input starts from the same board, so an input found here
// replays alone, here and on the RTL (fuzz_board_rx_rtl).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fuzz/board_rx_twin.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static mc::fuzz::BoardRxTwin board;
  const std::string why = board.feed(data, size);
  if (!why.empty()) {
    std::fprintf(stderr, "board_rx: %s\n", why.c_str());
    std::abort();
  }
  return 0;
}
