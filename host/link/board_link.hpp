// The host side of the board link (docs/protocol.md): stop-and-wait
// request/reply over any ByteStream, with retransmission.
//
// Each request gets a new SEQ; when its reply does not come within the
// timeout the very same frame goes out again. The board applies a frame at
// most once and answers a repeat with DUP, so a DUP to our pending request
// means "done": nothing is lost and nothing applied twice. A segment frame
// refused FULL stays refused: its copies get FULL too, so whichever copy a
// late reply answers, it tells the truth. The timeout
// follows the measured round trip (srtt + 4 rttvar, doubled per retry up to 4x).
// After max_tries the link gives up with "board at PORT does not answer
// after N tries"; when what came back was bytes without a single valid
// frame, "... answers garbage". Telemetry frames arriving meanwhile are
// queued apart from replies.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "host/link/protocol.hpp"
#include "host/link/serial_port.hpp"

namespace mc::host {

// The board refused a request (BAD_REG, BAD_LEN, BAD_CMD).
class BoardError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LinkOptions {
  int max_tries = 6;
  std::chrono::milliseconds first_timeout{200};  // before any round trip was measured
  std::chrono::milliseconds min_timeout{30};
  std::chrono::milliseconds max_timeout{2000};
  size_t max_telemetry = 200000;  // frames kept; older ones are dropped
};

struct LinkCounters {
  uint64_t requests = 0;     // requests completed
  uint64_t retransmits = 0;  // frames sent again after a timeout
  uint64_t dups = 0;         // DUP replies (a retransmitted request already applied)
  uint64_t stale = 0;        // replies that answered no pending request
  uint64_t telemetry = 0;    // telemetry frames received
  uint64_t telemetry_dropped = 0;
  double srtt_ms = 0;  // smoothed round trip
  proto::DecodeStats rx;
};

class BoardLink {
 public:
  explicit BoardLink(ByteStream& s, LinkOptions o = {});

  // PING (starts a session: the board forgets the last SEQ) and checks the
  // ID register. Throws LinkError when the device is not a MotionCore board.
  uint32_t connect();

  // Sends the request (any SEQ in `req` is replaced) and returns the reply;
  // throws LinkError when it never comes. A refused request is returned,
  // not thrown: see the helpers below for that.
  proto::Reply transact(proto::Frame req);

  // Register access; a refusal throws BoardError naming the register.
  uint32_t read(uint16_t addr);
  void write(uint16_t addr, uint32_t value);
  // Writes, reads back, and throws BoardError when (read & mask) differs.
  void write_verify(uint16_t addr, uint32_t value, uint32_t mask = 0xFFFFFFFFu);
  // Queues 1..6 segments; returns false when the queue lacked room (FULL:
  // nothing queued, not even by a retransmitted copy; try again later),
  // true when queued (once).
  bool segments(const std::vector<seg::Words>& segs);

  // Reads what arrives within `wait` without sending anything, queuing
  // telemetry (a reply that arrives now answers nothing and counts as
  // stale). Returns the number of bytes read.
  size_t poll(std::chrono::milliseconds wait);

  // Telemetry frames received so far (in order), for captures.
  std::deque<proto::Frame>& telemetry() { return tlm_; }
  const LinkCounters& counters() const;
  // The stream's clock: board time over the in-process virtual board.
  std::chrono::steady_clock::time_point now() const { return s_.now(); }
  const std::string& port_name() const { return name_; }

 private:
  std::chrono::milliseconds timeout() const;
  // Sends `req` as it is (its SEQ too) until a reply answers it.
  proto::Reply exchange(const proto::Frame& req);
  void note_rtt(double ms);
  // Reads until a reply answering `req` arrives or the deadline passes.
  bool await(const proto::Frame& req, std::chrono::steady_clock::time_point deadline, proto::Reply& out);
  // Decodes bytes: telemetry into tlm_; returns true and fills `out` when a
  // reply answers `req` (nullptr: none is pending).
  bool take(const uint8_t* p, size_t n, const proto::Frame* req, proto::Reply& out);

  ByteStream& s_;
  LinkOptions o_;
  std::string name_;
  proto::SeqGen seq_{1};
  proto::Decoder dec_;
  std::deque<proto::Frame> tlm_;
  mutable LinkCounters c_;
  bool have_rtt_ = false;
  double rttvar_ms_ = 0;
  uint64_t bytes_in_ = 0;
};

// "READ 0x0104 (STATUS)": names for messages.
std::string describe_request(const proto::Frame& f);
std::string register_name(uint16_t addr);
const char* status_name(uint8_t status);

}  // namespace mc::host
