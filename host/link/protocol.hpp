// The link protocol codec (docs/protocol.md): CRC-16, frame encoding, a
// streaming decoder with the board's own rules, request builders and reply and
// telemetry parsers. No I/O here: a transport (serial port, pseudo-terminal,
// the testbench's bit-level UART) moves the bytes.
//
// Retransmission contract: a request gets a fresh sequence number (SeqGen);
// after a timeout the host sends the very same frame again. The board applies
// a frame at most once (it remembers the last applied SEQ) and answers a
// repeat with ST_DUP, which means "already done". A segment frame refused
// ST_FULL is remembered too: its repeats get ST_FULL, so no copy of it is
// ever queued. A PING starts a session: it is never a duplicate and makes
// the board forget the last SEQ.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hls/board_regs.hpp"
#include "hls/interp_seg.hpp"

namespace mc::host::proto {

using Bytes = std::vector<uint8_t>;

// CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, MSB first, no final xor.
// crc16("123456789") == 0x29B1.
uint16_t crc16(const uint8_t* p, size_t n, uint16_t crc = 0xFFFF);
inline uint16_t crc16(const Bytes& b) {
  return crc16(b.data(), b.size());
}

struct Frame {
  uint8_t seq = 0;
  uint8_t cmd = 0;
  Bytes payload;
  bool operator==(const Frame& o) const { return seq == o.seq && cmd == o.cmd && payload == o.payload; }
};

// SYNC, LEN, SEQ, CMD, payload, CRC (low byte first). Throws InputError when
// the payload exceeds MAX_LEN.
Bytes encode(const Frame& f);

// What the decoder threw away, by cause (the board keeps the same counts).
struct DecodeStats {
  uint64_t frames = 0;      // good frames
  uint64_t crc = 0;         // CRC mismatch
  uint64_t framing = 0;     // LEN above MAX_LEN, or a frame cut short (timeout())
  uint64_t junk_bytes = 0;  // bytes skipped while looking for SYNC
};

// Byte-stream decoder. After a bad frame it looks for SYNC from the next byte,
// exactly as the board does, so both sides count the same drops.
class Decoder {
 public:
  // Feeds one byte; returns true and fills `out` when it completes a good frame.
  bool push(uint8_t b, Frame& out);
  // Feeds a run of bytes; appends the good frames.
  void push(const Bytes& bytes, std::vector<Frame>& out);
  // The line went quiet for the byte timeout: a partial frame is dropped.
  void timeout();
  bool in_frame() const { return state_ != State::Hunt; }
  const DecodeStats& stats() const { return stats_; }

 private:
  enum class State { Hunt, Len, Seq, Cmd, Payload, Crc0, Crc1 };
  State state_ = State::Hunt;
  Frame cur_;
  size_t len_ = 0;
  uint16_t crc_ = 0;
  uint8_t crc_lo_ = 0;
  DecodeStats stats_;
};

// Sequence numbers for new requests (8 bits, wrapping).
class SeqGen {
 public:
  explicit SeqGen(uint8_t first = 0) : next_(first) {}
  uint8_t next() { return next_++; }

 private:
  uint8_t next_;
};

// Requests.
Frame ping(uint8_t seq);
Frame read(uint8_t seq, uint16_t addr);
Frame write(uint8_t seq, uint16_t addr, uint32_t value);
// 1..6 whole segments (InputError otherwise).
Frame segments(uint8_t seq, const std::vector<seg::Words>& segs);

// A reply to a request.
struct Reply {
  uint8_t seq = 0;
  uint8_t cmd = 0;  // the request's command
  uint8_t status = 0;
  uint32_t value = 0;
  // The request took effect (now or, for ST_DUP, the first time).
  bool done() const { return status == board::proto::ST_OK || status == board::proto::ST_DUP; }
};
bool is_reply(const Frame& f);
// Throws InputError if `f` is not a well-formed reply.
Reply parse_reply(const Frame& f);
// Whether `r` answers request `req` (same SEQ and command).
bool answers(const Reply& r, const Frame& req);

// One axis of a telemetry frame.
struct AxisSample {
  int axis = 0;
  int32_t pos = 0;  // feedback at the sample, counts
  int32_t cmd = 0;  // command at the sample, counts
  int32_t err = 0;  // PID error
  int16_t u = 0;    // PID output
  bool sat = false, pid_en = false, drv_en = false;
};
struct Telemetry {
  uint8_t seq = 0;      // telemetry frame counter
  uint16_t sample = 0;  // PID sample count (mod 2^16): gaps show skipped frames
  uint16_t fault = 0;   // FAULT register
  std::vector<AxisSample> axes;
};
bool is_telemetry(const Frame& f);
// axes_mask: TLM.axes as configured (the frame does not repeat it). Throws
// InputError if the length does not match.
Telemetry parse_telemetry(const Frame& f, unsigned axes_mask);

}  // namespace mc::host::proto
