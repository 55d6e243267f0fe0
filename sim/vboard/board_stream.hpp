// The virtual board as a host byte stream in board time, in process: a read
// runs the board (whole plant steps) until it sends or the timeout passes on
// the board's own clock. A host session over it (BoardLink) is then the same
// on any engine, however fast or slow it runs, and needs no pseudo-terminal:
// the engine comparison and the speed measurement use it.
//
//   VirtualBoard b(machine);  BoardStream s(b);  host::BoardLink link(s);
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "host/link/serial_port.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::sim {

class BoardStream final : public mc::host::ByteStream {
 public:
  // log: keep every TX byte with its clock, and the axes' positions after
  // every run of the board (up to a byte or the timeout; for comparisons).
  explicit BoardStream(VirtualBoard& b, bool log = false) : b_(b), log_(log) {}
  void write(const uint8_t* p, size_t n) override { b_.send(p, n); }
  size_t read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) override;
  std::string name() const override { return "virtual board (in process)"; }
  // Board time: the link's retransmission deadlines count board clocks.
  std::chrono::steady_clock::time_point now() const override {
    return std::chrono::steady_clock::time_point(
        std::chrono::nanoseconds(int64_t(double(b_.cycles()) * 1e9 / b_.clock_hz())));
  }

  std::vector<std::pair<uint64_t, uint8_t>> tx;  // (clock, byte), with log
  std::vector<double> pos;                       // kBoardAxes per run, with log

 private:
  VirtualBoard& b_;
  bool log_;
  std::vector<uint8_t> pending_;
};

// The speed of the virtual board under a host session, measured in process.
struct VBoardSpeed {
  std::string workload;  // "hold" or "move"
  BoardEngine engine = BoardEngine::Twin;
  int axes = 0;
  double board_s = 0, wall_s = 0, cpu_s = 0;  // cpu_s: this thread's CPU time
  uint64_t clocks = 0, stepped = 0;
  double speed() const { return wall_s > 0 ? board_s / wall_s : 0; }
};
// Gains on every configured axis (the machine's PID at Ts = 100 us), armed,
// every PID enabled; then for board_s of board time either hold position
// ("hold") or move X and Y back and forth at 25 mm/s ("move"), the host
// reading STATUS every 10 ms of board time (the watchdog fed). Z stands
// 5 mm above the workpiece's face, if the machine has one.
VBoardSpeed measure_vboard_speed(const MachineConfig& m, BoardEngine e, const std::string& workload,
                                 double board_s);

}  // namespace mc::sim
