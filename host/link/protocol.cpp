#include "host/link/protocol.hpp"

#include <string>

#include "host/base/errors.hpp"

namespace mc::host::proto {

namespace P = board::proto;

uint16_t crc16(const uint8_t* p, size_t n, uint16_t crc) {
  for (size_t i = 0; i < n; ++i) {
    crc = uint16_t(crc ^ (uint16_t(p[i]) << 8));
    for (int b = 0; b < 8; ++b) crc = uint16_t((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
  }
  return crc;
}

Bytes encode(const Frame& f) {
  if (f.payload.size() > size_t(P::MAX_LEN))
    throw InputError("frame payload", std::to_string(f.payload.size()) + " bytes",
                     "at most " + std::to_string(P::MAX_LEN));
  Bytes b;
  b.reserve(f.payload.size() + size_t(P::HDR_BYTES + P::CRC_BYTES));
  for (uint8_t h : {P::SYNC, uint8_t(f.payload.size()), f.seq, f.cmd}) b.push_back(h);
  for (uint8_t p : f.payload) b.push_back(p);
  const uint16_t c = crc16(b.data() + 1, b.size() - 1);
  b.push_back(uint8_t(c));
  b.push_back(uint8_t(c >> 8));
  return b;
}

bool Decoder::push(uint8_t b, Frame& out) {
  switch (state_) {
    case State::Hunt:
      if (b == P::SYNC) {
        state_ = State::Len;
        crc_ = 0xFFFF;
      } else {
        ++stats_.junk_bytes;
      }
      return false;
    case State::Len:
      if (b > P::MAX_LEN) {
        ++stats_.framing;
        state_ = State::Hunt;
        return false;
      }
      len_ = b;
      cur_ = Frame{};
      state_ = State::Seq;
      break;
    case State::Seq:
      cur_.seq = b;
      state_ = State::Cmd;
      break;
    case State::Cmd:
      cur_.cmd = b;
      state_ = len_ ? State::Payload : State::Crc0;
      break;
    case State::Payload:
      cur_.payload.push_back(b);
      if (cur_.payload.size() == len_) state_ = State::Crc0;
      break;
    case State::Crc0:
      crc_lo_ = b;
      state_ = State::Crc1;
      return false;
    case State::Crc1:
      state_ = State::Hunt;
      if (uint16_t(crc_lo_ | b << 8) != crc_) {
        ++stats_.crc;
        return false;
      }
      ++stats_.frames;
      out = std::move(cur_);
      cur_ = Frame{};  // moved from: start the next frame from a known state
      return true;
  }
  crc_ = crc16(&b, 1, crc_);
  return false;
}

void Decoder::push(const Bytes& bytes, std::vector<Frame>& out) {
  Frame f;
  for (uint8_t b : bytes)
    if (push(b, f)) out.push_back(std::move(f));
}

void Decoder::timeout() {
  if (state_ != State::Hunt) ++stats_.framing;
  state_ = State::Hunt;
}

namespace {
void put16(Bytes& b, uint32_t v) {
  b.push_back(uint8_t(v));
  b.push_back(uint8_t(v >> 8));
}
void put32(Bytes& b, uint32_t v) {
  put16(b, v);
  put16(b, v >> 16);
}
uint32_t get32(const Bytes& b, size_t i) {
  return uint32_t(b[i]) | uint32_t(b[i + 1]) << 8 | uint32_t(b[i + 2]) << 16 | uint32_t(b[i + 3]) << 24;
}
}  // namespace

Frame ping(uint8_t seq) {
  return Frame{seq, P::CMD_PING, {}};
}

Frame read(uint8_t seq, uint16_t addr) {
  Frame f{seq, P::CMD_READ, {}};
  put16(f.payload, addr);
  return f;
}

Frame write(uint8_t seq, uint16_t addr, uint32_t value) {
  Frame f{seq, P::CMD_WRITE, {}};
  put16(f.payload, addr);
  put32(f.payload, value);
  return f;
}

Frame segments(uint8_t seq, const std::vector<seg::Words>& segs) {
  const size_t most = size_t(P::MAX_LEN / P::SEG_BYTES);
  if (segs.empty() || segs.size() > most)
    throw InputError("segments in one frame", std::to_string(segs.size()), "1 to " + std::to_string(most));
  Frame f{seq, P::CMD_SEG, {}};
  for (const auto& s : segs)
    for (uint32_t w : s) put32(f.payload, w);
  return f;
}

bool is_reply(const Frame& f) {
  return (f.cmd & P::REPLY) && f.cmd != P::CMD_TLM;
}

Reply parse_reply(const Frame& f) {
  if (!is_reply(f) || f.payload.size() != size_t(P::REPLY_LEN))
    throw InputError(
        "reply frame",
        "cmd " + std::to_string(f.cmd) + ", " + std::to_string(f.payload.size()) + " payload bytes",
        "a reply command (bit 7 set) with " + std::to_string(P::REPLY_LEN) + " payload bytes");
  return Reply{f.seq, uint8_t(f.cmd & ~P::REPLY), f.payload[0], get32(f.payload, 1)};
}

bool answers(const Reply& r, const Frame& req) {
  return r.seq == req.seq && r.cmd == req.cmd;
}

bool is_telemetry(const Frame& f) {
  return f.cmd == P::CMD_TLM;
}

Telemetry parse_telemetry(const Frame& f, unsigned axes_mask) {
  size_t n = 0;
  for (unsigned m = axes_mask & 7; m; m &= m - 1) ++n;
  const size_t want = 4 * (1 + board::TLM_AXIS_WORDS.size() * n);
  if (!is_telemetry(f) || f.payload.size() != want)
    throw InputError("telemetry frame", std::to_string(f.payload.size()) + " payload bytes",
                     std::to_string(want) + " for axes mask " + std::to_string(axes_mask));
  Telemetry t;
  t.seq = f.seq;
  const uint32_t hdr = get32(f.payload, 0);
  t.sample = uint16_t(hdr);
  t.fault = uint16_t(hdr >> 16);
  size_t i = 4;
  for (int a = 0; a < 3; ++a) {
    if (!((axes_mask >> a) & 1)) continue;
    AxisSample s;
    s.axis = a;
    s.pos = int32_t(get32(f.payload, i));
    s.cmd = int32_t(get32(f.payload, i + 4));
    s.err = int32_t(get32(f.payload, i + 8));
    const uint32_t out = get32(f.payload, i + 12);
    s.u = int16_t(uint16_t(out >> board::bits::O_U_LSB));
    s.sat = (out >> board::bits::O_SAT) & 1;
    s.pid_en = (out >> board::bits::O_PID_EN) & 1;
    s.drv_en = (out >> board::bits::O_DRV_EN) & 1;
    t.axes.push_back(s);
    i += 16;
  }
  return t;
}

}  // namespace mc::host::proto
