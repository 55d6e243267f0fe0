// Telemetry captures for motionctl step, tune and hostloop: choosing the
// decimation the link can carry, streaming one axis' samples with the PID
// sample counter unwrapped, reporting gaps (never filling them in), and
// keeping the board's watchdog fed while the capture runs.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "host/link/board_link.hpp"

namespace mc::host {

// Bytes on the line: a telemetry frame with `axes` axes, and a reply.
constexpr int kReplyBytes = 6 + 5;
constexpr int telemetry_frame_bytes(int axes) {
  return 6 + 4 * (1 + 4 * axes);
}

// Line time of `frames` frames of `bytes` bytes in all from the board's
// transmitter (rtl/uart_tx.v behind rtl/link_tx.v): 10 bits a byte at the
// UART's whole clocks per bit, 2 clocks to hand each byte over, and 32
// clocks a frame for what comes between frames (the three-axis board takes
// 24: the walker's reads of the sample and the hand-over; a test holds the
// figure to the RTL).
double board_tx_seconds(int bytes, int frames, double clk_hz, double baud);

// The smallest decimation N such that a frame of `axes` axes plus `replies`
// replies queued in front of it fit in N sample periods, so no sample is
// skipped (docs/protocol.md, Telemetry).
uint32_t telemetry_decimation(double ts_s, double clk_hz, double baud, int replies, int axes = 1);
// The same for the board on `l`, with its clock and baud rate (CLK_HZ, BAUD).
uint32_t telemetry_decimation(BoardLink& l, double ts_s, int replies, int axes = 1);

// SIGINT and SIGTERM while a command has the board in a temporary state:
// catch_interrupts() installs handlers that only set a flag, and
// TelemetryStream::next() then throws Interrupted, so that the command puts
// the board back (gains, Ts, the DRV override, telemetry off) before it exits.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
void catch_interrupts();
// The flag those handlers set, for loops that stop on it themselves.
const std::atomic<bool>& interrupt_requested();

// One sample of one axis, as the telemetry frame carries it.
struct TlmSample {
  int64_t n = 0;  // PID sample count, unwrapped (the first frame's count mod 2^16 onward)
  int32_t pos = 0, cmd = 0, err = 0;
  int16_t u = 0;
  uint16_t fault = 0;
};

// The link's telemetry frames of one TLM setting (axes mask, decimation) as
// samples: frames of another setting are dropped, the 16-bit sample count is
// unwrapped from the first frame's on, and jumps past the decimation are
// counted, never filled in.
class TelemetryUnwrap {
 public:
  TelemetryUnwrap(unsigned axes_mask, uint32_t decim) : mask_(axes_mask), decim_(decim) {}
  // False for a frame of another setting; else t and its unwrapped count n.
  bool take(const proto::Frame& f, proto::Telemetry& t, int64_t& n);
  bool started() const { return have_; }
  int64_t last() const { return last_; }
  // Frames whose count jumped by more than decim, and the samples (at the
  // decimation) skipped in those jumps.
  int64_t gaps() const { return gaps_; }
  int64_t missing() const { return missing_; }

 private:
  unsigned mask_;
  uint32_t decim_;
  bool have_ = false;
  int64_t last_ = 0, gaps_ = 0, missing_ = 0;
};

// Streams telemetry for one axis every `decim` samples from construction
// until destruction (TLM = 0 then). next() waits for the next frames and
// appends them; it sends a PING every `ping_every` samples of board time, and
// whenever nothing arrived for 100 ms of wall time, so the watchdog stays fed
// and a board that stopped answering is an error.
class TelemetryStream {
 public:
  TelemetryStream(BoardLink& l, int axis, uint32_t decim, int64_t ping_every);
  ~TelemetryStream();
  TelemetryStream(const TelemetryStream&) = delete;
  TelemetryStream& operator=(const TelemetryStream&) = delete;

  // Appends at least one sample; returns how many.
  size_t next(std::vector<TlmSample>& out);
  // Frames whose sample count jumped by more than decim, and the samples
  // (at the decimation) that were skipped in those jumps.
  int64_t gaps() const { return unwrap_.gaps(); }
  int64_t missing() const { return unwrap_.missing(); }
  uint32_t decim() const { return decim_; }

 private:
  BoardLink& l_;
  uint32_t decim_;
  int64_t ping_every_;
  TelemetryUnwrap unwrap_;
  int64_t last_ping_ = 0;
};

}  // namespace mc::host
