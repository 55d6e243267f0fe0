#include "host/link/board_link.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hls/pid_regs.hpp"

namespace mc::host {

namespace bp = board::proto;
namespace br = board::reg;
using Clock = std::chrono::steady_clock;

namespace {

std::string hex(uint32_t v, int digits) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%0*X", digits, unsigned(v));
  return b;
}

uint16_t frame_addr(const proto::Frame& f) {
  return f.payload.size() >= 2 ? uint16_t(f.payload[0] | f.payload[1] << 8) : uint16_t(0);
}

}  // namespace

const char* status_name(uint8_t s) {
  switch (s) {
    case bp::ST_OK:
      return "OK";
    case bp::ST_DUP:
      return "DUP";
    case bp::ST_BAD_REG:
      return "BAD_REG (no such register, or not writable)";
    case bp::ST_BAD_LEN:
      return "BAD_LEN (length does not fit the command)";
    case bp::ST_BAD_CMD:
      return "BAD_CMD (unknown command)";
    case bp::ST_FULL:
      return "FULL (segment queue full)";
    default:
      return "unknown status";
  }
}

std::string register_name(uint16_t addr) {
  if (addr < br::ID) return "PID " + hex(addr, 2);
  for (const board::RegDef& r : board::REGS) {
    if (!r.per_axis && r.addr == addr) return r.name;
    if (r.per_axis && addr >= br::AXIS_BASE) {
      const int a = (addr - br::AXIS_BASE) / br::AXIS_STRIDE, off = (addr - br::AXIS_BASE) % br::AXIS_STRIDE;
      if (off == r.addr) return std::string(r.name) + "[" + "xyz"[std::min(a, 2)] + "]";
    }
  }
  return "register";
}

std::string describe_request(const proto::Frame& f) {
  switch (f.cmd) {
    case bp::CMD_PING:
      return "PING";
    case bp::CMD_READ:
      return "READ " + hex(frame_addr(f), 4) + " (" + register_name(frame_addr(f)) + ")";
    case bp::CMD_WRITE:
      return "WRITE " + hex(frame_addr(f), 4) + " (" + register_name(frame_addr(f)) + ")";
    case bp::CMD_SEG:
      return "SEG (" + std::to_string(f.payload.size() / bp::SEG_BYTES) + " segments)";
    default:
      return "command " + hex(f.cmd, 2);
  }
}

BoardLink::BoardLink(ByteStream& s, LinkOptions o) : s_(s), o_(o), name_(s.name()) {}

const LinkCounters& BoardLink::counters() const {
  c_.rx = dec_.stats();
  return c_;
}

std::chrono::milliseconds BoardLink::timeout() const {
  if (!have_rtt_) return o_.first_timeout;
  const double ms = c_.srtt_ms + 4 * rttvar_ms_;
  return std::clamp(std::chrono::milliseconds(long(std::ceil(ms))), o_.min_timeout, o_.max_timeout);
}

void BoardLink::note_rtt(double ms) {
  if (!have_rtt_) {
    c_.srtt_ms = ms;
    rttvar_ms_ = ms / 2;
    have_rtt_ = true;
    return;
  }
  rttvar_ms_ = 0.75 * rttvar_ms_ + 0.25 * std::fabs(c_.srtt_ms - ms);
  c_.srtt_ms = 0.875 * c_.srtt_ms + 0.125 * ms;
}

bool BoardLink::take(const uint8_t* p, size_t n, const proto::Frame* req, proto::Reply& out) {
  bytes_in_ += n;
  bool answered = false;
  for (size_t i = 0; i < n; ++i) {
    proto::Frame f;
    if (!dec_.push(p[i], f)) continue;
    if (proto::is_telemetry(f)) {
      ++c_.telemetry;
      tlm_.push_back(std::move(f));
      if (tlm_.size() > o_.max_telemetry) {
        tlm_.pop_front();
        ++c_.telemetry_dropped;
      }
      continue;
    }
    if (!proto::is_reply(f)) continue;
    proto::Reply r;
    try {
      r = proto::parse_reply(f);
    } catch (const std::exception&) {
      continue;  // a malformed reply counts as no reply: the retry recovers
    }
    if (!answered && req && proto::answers(r, *req)) {
      out = r;
      answered = true;
    } else {
      ++c_.stale;
    }
  }
  return answered;
}

bool BoardLink::await(const proto::Frame& req, Clock::time_point deadline, proto::Reply& out) {
  uint8_t buf[256];
  for (;;) {
    const auto now = s_.now();
    if (now >= deadline) return false;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now) + std::chrono::milliseconds(1);
    const size_t n = s_.read(buf, sizeof buf, left);
    if (take(buf, n, &req, out)) return true;
  }
}

size_t BoardLink::poll(std::chrono::milliseconds wait) {
  uint8_t buf[256];
  proto::Reply unused;
  const size_t n = s_.read(buf, sizeof buf, wait);
  take(buf, n, nullptr, unused);
  return n;
}

proto::Reply BoardLink::transact(proto::Frame req) {
  req.seq = seq_.next();
  return exchange(req);
}

proto::Reply BoardLink::exchange(const proto::Frame& req) {
  const proto::Bytes bytes = proto::encode(req);
  const uint64_t good_before = dec_.stats().frames, bytes_before = bytes_in_;
  for (int attempt = 0; attempt < o_.max_tries; ++attempt) {
    if (attempt > 0) {
      ++c_.retransmits;
      dec_.timeout();  // the line was quiet for a whole timeout: a partial frame is dead
    }
    const auto sent = s_.now();
    s_.write(bytes.data(), bytes.size());
    const auto wait = std::min(o_.max_timeout, timeout() * (1 << std::min(attempt, 2)));
    proto::Reply r;
    if (await(req, sent + wait, r)) {
      if (attempt == 0) note_rtt(std::chrono::duration<double, std::milli>(s_.now() - sent).count());
      if (r.status == bp::ST_DUP) ++c_.dups;
      ++c_.requests;
      return r;
    }
  }
  const bool garbage = bytes_in_ > bytes_before && dec_.stats().frames == good_before;
  if (garbage)
    throw LinkError("device at " + name_ + " answers garbage (" + std::to_string(bytes_in_ - bytes_before) +
                    " bytes, no valid frame, to " + describe_request(req) +
                    "): not a MotionCore board, or a "
                    "wrong baud rate");
  throw LinkError("board at " + name_ + " does not answer after " + std::to_string(o_.max_tries) +
                  " tries (" + describe_request(req) + ")");
}

uint32_t BoardLink::connect() {
  transact(proto::ping(0));
  const uint32_t id = read(br::ID);
  if ((id & 0xFFFF0000u) != board::bits::ID_MAGIC)
    throw LinkError("device at " + name_ + " is not a MotionCore board (ID register " + hex(id, 8) + ")");
  if ((id & 0xFFFF) != bp::VERSION)
    throw LinkError("board at " + name_ + " speaks protocol version " + std::to_string(id & 0xFFFF) +
                    ", this motionctl version " + std::to_string(bp::VERSION));
  return id;
}

namespace {
void check(const proto::Reply& r, const proto::Frame& req) {
  if (!r.done()) throw BoardError("board refused " + describe_request(req) + ": " + status_name(r.status));
}
}  // namespace

uint32_t BoardLink::read(uint16_t addr) {
  const proto::Frame req = proto::read(0, addr);
  const proto::Reply r = transact(req);
  check(r, req);
  return r.value;
}

void BoardLink::write(uint16_t addr, uint32_t value) {
  const proto::Frame req = proto::write(0, addr, value);
  check(transact(req), req);
}

void BoardLink::write_verify(uint16_t addr, uint32_t value, uint32_t mask) {
  write(addr, value);
  const uint32_t back = read(addr);
  if ((back & mask) != (value & mask))
    throw BoardError("register " + register_name(addr) + " (" + hex(addr, 4) + ") reads back " +
                     hex(back & mask, 8) + " after writing " + hex(value & mask, 8));
}

bool BoardLink::segments(const std::vector<seg::Words>& segs) {
  // The board answers every copy of a frame as it answered the first copy
  // it evaluated (protocol version 2): FULL to any copy means that no copy
  // was queued or ever will be, DUP or OK that one copy was, once.
  const proto::Frame req = proto::segments(0, segs);
  const proto::Reply r = transact(req);
  if (r.status == bp::ST_FULL) return false;
  check(r, req);
  return true;
}

}  // namespace mc::host
