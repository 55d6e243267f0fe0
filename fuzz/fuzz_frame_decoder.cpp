// libFuzzer target: the host's frame decoder (host/link/protocol) on
// arbitrary bytes from the line. Beyond "no crash, no undefined behaviour":
// - every byte is accounted for: good frames, bad CRCs, framing errors and
//   junk bytes, and no byte is counted twice;
// - feeding byte by byte and in one run gives the same frames and counts;
// - a good frame encodes back to bytes that decode to the same frame;
// - the reply and telemetry parsers accept a frame or refuse it with
//   InputError, never anything else.
// The first input byte picks where the line goes quiet (Decoder::timeout).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "host/base/errors.hpp"
#include "host/link/protocol.hpp"

namespace hp = mc::host::proto;

namespace {

constexpr size_t kOverhead = mc::board::proto::HDR_BYTES + mc::board::proto::CRC_BYTES;

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const size_t quiet_every = data[0] == 0 ? size : data[0];
  const hp::Bytes bytes(data + 1, data + size);

  hp::Decoder one, run;
  std::vector<hp::Frame> frames_one, frames_run;
  hp::Bytes chunk;
  for (size_t i = 0; i < bytes.size(); ++i) {
    hp::Frame f;
    if (one.push(bytes[i], f)) frames_one.push_back(f);
    chunk.push_back(bytes[i]);
    if ((i + 1) % quiet_every == 0) {
      run.push(chunk, frames_run);
      chunk.clear();
      one.timeout();
      run.timeout();
    }
  }
  run.push(chunk, frames_run);
  one.timeout();
  run.timeout();

  check(frames_one == frames_run);
  const hp::DecodeStats& s = one.stats();
  const hp::DecodeStats& r = run.stats();
  check(s.frames == r.frames && s.crc == r.crc && s.framing == r.framing && s.junk_bytes == r.junk_bytes);
  check(s.frames == frames_one.size());
  check(!one.in_frame());
  // Every byte is consumed once: a junk byte, a good frame (header, payload,
  // CRC), a bad-CRC frame (at least a header and a CRC) or a frame that ended
  // in a framing error (at least its SYNC).
  size_t good_bytes = 0;
  for (const hp::Frame& f : frames_one) good_bytes += kOverhead + f.payload.size();
  const size_t accounted = s.junk_bytes + good_bytes + kOverhead * s.crc + s.framing;
  check(accounted <= bytes.size());
  if (s.crc == 0 && s.framing == 0) check(accounted == bytes.size());

  for (const hp::Frame& f : frames_one) {
    check(f.payload.size() <= size_t(mc::board::proto::MAX_LEN));
    hp::Decoder again;
    std::vector<hp::Frame> back;
    again.push(hp::encode(f), back);
    check(back.size() == 1 && back[0] == f);
    try {
      if (hp::is_reply(f)) (void)hp::parse_reply(f);
    } catch (const mc::host::InputError&) {  // a refusal, with its reason: fine
    }
    for (unsigned mask = 0; mask < 8 && hp::is_telemetry(f); ++mask) {
      try {
        (void)hp::parse_telemetry(f, mask);
      } catch (const mc::host::InputError&) {
      }
    }
  }
  return 0;
}
