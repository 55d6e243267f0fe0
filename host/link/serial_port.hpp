// Byte transports for the board link: the interface BoardLink speaks over,
// the serial port (a real board's FTDI UART, or the virtual board's
// pseudo-terminal), and a fault injector that corrupts and drops bytes for
// the link's tests.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>

namespace mc::host {

// A transport failed (absent or busy port, I/O error). The message names the
// port and says what happened.
class LinkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ByteStream {
 public:
  virtual ~ByteStream() = default;
  // Writes all n bytes (throws LinkError on failure).
  virtual void write(const uint8_t* p, size_t n) = 0;
  // Reads what is available, waiting up to `timeout` for the first byte;
  // returns the number of bytes read, 0 when the timeout passed.
  virtual size_t read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) = 0;
  // For messages: "/dev/ttyUSB1".
  virtual std::string name() const = 0;
  // The clock read()'s timeout runs on, which BoardLink's retransmission
  // deadlines use too: the wall clock for a port; a simulated board's own
  // clock, so that a session over it is the same however fast it runs.
  virtual std::chrono::steady_clock::time_point now() const { return std::chrono::steady_clock::now(); }
};

// A serial port in raw mode, 8N1 at `baud` (the board's 1 Mbaud by default;
// a pseudo-terminal ignores the rate), locked against a second user. Input
// waiting from before the open is discarded.
class SerialPort final : public ByteStream {
 public:
  // Throws LinkError: "no such port /dev/ttyUSB1", "port /dev/ttyUSB1 busy
  // (another program has it open)", "cannot open port ...: <reason>".
  explicit SerialPort(const std::string& path, long baud = 1'000'000);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  void write(const uint8_t* p, size_t n) override;
  size_t read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) override;
  std::string name() const override { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

// Wraps a stream and, for each byte in either direction, flips a random bit
// of it with probability flip_rate and drops it with probability drop_rate.
// Each direction draws from its own generator (seeded from `seed`), so the
// faults of one direction depend only on the bytes that went that way: over
// a deterministic stream (the in-process virtual board) a run repeats exactly.
class FaultInjector final : public ByteStream {
 public:
  FaultInjector(ByteStream& inner, double flip_rate, double drop_rate, uint32_t seed = 1);
  void write(const uint8_t* p, size_t n) override;
  size_t read(uint8_t* p, size_t n, std::chrono::milliseconds timeout) override;
  std::string name() const override { return inner_.name(); }
  std::chrono::steady_clock::time_point now() const override { return inner_.now(); }

  // What happened to the bytes of one direction.
  struct Counts {
    uint64_t bytes = 0;  // offered to the injector
    uint64_t flipped = 0, dropped = 0;
  };
  const Counts& to_device() const { return out_.n; }   // written (host to board)
  const Counts& from_device() const { return in_.n; }  // read (board to host)
  uint64_t flipped() const { return out_.n.flipped + in_.n.flipped; }
  uint64_t dropped() const { return out_.n.dropped + in_.n.dropped; }

 private:
  struct Way {
    explicit Way(uint32_t seed) : rng(seed) {}
    std::mt19937 rng;
    Counts n;
  };
  // Applies the faults in place; returns the bytes kept.
  size_t corrupt(Way& w, uint8_t* p, size_t n);
  ByteStream& inner_;
  double flip_, drop_;
  Way out_, in_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
};

}  // namespace mc::host
