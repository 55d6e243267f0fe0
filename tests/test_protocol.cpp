// The link protocol codec (host/protocol.hpp): CRC check value, frames round
// trip through the decoder, and every class of malformed input is rejected
// and counted the way the board counts it.
#include "host/link/protocol.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>

#include "host/base/errors.hpp"

namespace mc::host::proto {
namespace {

namespace P = board::proto;

TEST(Protocol, Crc16CheckValue) {
  const std::string s = "123456789";
  EXPECT_EQ(crc16(reinterpret_cast<const uint8_t*>(s.data()), s.size()), 0x29B1);
  EXPECT_EQ(crc16(nullptr, 0), 0xFFFF);
}

Frame random_frame(std::mt19937& rng) {
  Frame f;
  f.seq = uint8_t(rng());
  f.cmd = uint8_t(rng());
  f.payload.resize(rng() % (P::MAX_LEN + 1));
  for (auto& b : f.payload) b = uint8_t(rng());
  return f;
}

TEST(Protocol, RandomFramesRoundTripThroughJunk) {
  std::mt19937 rng(1);
  Decoder d;
  std::vector<Frame> sent, got;
  uint64_t junk = 0;
  for (int i = 0; i < 500; ++i) {
    Bytes gap(rng() % 4);
    for (auto& b : gap) b = uint8_t(rng() % 0xA0);  // never SYNC
    junk += gap.size();
    d.push(gap, got);
    sent.push_back(random_frame(rng));
    d.push(encode(sent.back()), got);
  }
  ASSERT_EQ(got.size(), sent.size());
  for (size_t i = 0; i < sent.size(); ++i) EXPECT_TRUE(got[i] == sent[i]) << i;
  EXPECT_EQ(d.stats().junk_bytes, junk);
  EXPECT_EQ(d.stats().crc + d.stats().framing, 0u);
}

TEST(Protocol, EveryCorruptedByteIsRejected) {
  std::mt19937 rng(2);
  for (int n = 0; n < 200; ++n) {
    const Frame f = random_frame(rng);
    Bytes b = encode(f);
    const size_t i = 2 + rng() % (b.size() - 2);  // SEQ onwards: LEN changes the framing
    b[i] ^= uint8_t(1 + rng() % 255);
    Decoder d;
    std::vector<Frame> got;
    d.push(b, got);
    d.timeout();
    EXPECT_TRUE(got.empty());
    EXPECT_EQ(d.stats().crc, 1u) << "byte " << i;
  }
}

TEST(Protocol, MalformedFramesAreCountedByClass) {
  Decoder d;
  std::vector<Frame> got;
  // LEN above MAX_LEN.
  d.push({P::SYNC, uint8_t(P::MAX_LEN + 1)}, got);
  EXPECT_EQ(d.stats().framing, 1u);
  // Truncated, then the line goes quiet.
  Bytes b = encode(write(3, board::reg::WDOG, 7));
  b.pop_back();
  d.push(b, got);
  EXPECT_TRUE(d.in_frame());
  d.timeout();
  EXPECT_EQ(d.stats().framing, 2u);
  // Garbage without SYNC.
  d.push(Bytes(10, 0x55), got);
  EXPECT_EQ(d.stats().junk_bytes, 10u);
  EXPECT_TRUE(got.empty());
  // And a good one after all of it.
  d.push(encode(ping(9)), got);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].seq, 9);
}

TEST(Protocol, RequestsRepliesAndTelemetry) {
  // The worked example of docs/protocol.md.
  const Bytes w = encode(write(0x12, board::reg::WDOG, 120000));
  const Bytes want = {0xA5, 0x06, 0x12, 0x02, 0x07, 0x01, 0xC0, 0xD4, 0x01, 0x00};
  ASSERT_EQ(Bytes(w.begin(), w.end() - 2), want);
  EXPECT_EQ(w[10], 0xDA);  // CRC-16 0xCBDA of bytes 1..9, low byte first (docs/protocol.md)
  EXPECT_EQ(w[11], 0xCB);
  const Reply r = parse_reply(Frame{0x12, uint8_t(P::CMD_WRITE | P::REPLY), {P::ST_DUP, 1, 2, 3, 4}});
  EXPECT_EQ(r.status, P::ST_DUP);
  EXPECT_EQ(r.value, 0x04030201u);
  EXPECT_TRUE(r.done());
  EXPECT_TRUE(answers(r, write(0x12, 0, 0)));
  EXPECT_FALSE(answers(r, read(0x12, 0)));
  EXPECT_THROW(parse_reply(Frame{0, P::CMD_TLM, {}}), InputError);
  EXPECT_THROW(encode(Frame{0, 0, Bytes(P::MAX_LEN + 1)}), InputError);
  EXPECT_THROW(segments(0, {}), InputError);
  EXPECT_THROW(segments(0, std::vector<seg::Words>(7)), InputError);
  EXPECT_EQ(segments(0, std::vector<seg::Words>(6)).payload.size(), size_t(P::MAX_LEN));

  Frame t{5, P::CMD_TLM, {}};
  for (uint32_t word : {0x0003002Au, 10u, 20u, uint32_t(-3), 0x00050000u | 0xFFF0u})
    for (int i = 0; i < 4; ++i) t.payload.push_back(uint8_t(word >> (8 * i)));
  const Telemetry tl = parse_telemetry(t, 2);
  EXPECT_EQ(tl.sample, 0x2A);
  EXPECT_EQ(tl.fault, 3);
  ASSERT_EQ(tl.axes.size(), 1u);
  EXPECT_EQ(tl.axes[0].axis, 1);
  EXPECT_EQ(tl.axes[0].pos, 10);
  EXPECT_EQ(tl.axes[0].cmd, 20);
  EXPECT_EQ(tl.axes[0].err, -3);
  EXPECT_EQ(tl.axes[0].u, -16);
  EXPECT_TRUE(tl.axes[0].sat);
  EXPECT_FALSE(tl.axes[0].pid_en);
  EXPECT_TRUE(tl.axes[0].drv_en);
  EXPECT_THROW(parse_telemetry(t, 3), InputError);
}

}  // namespace
}  // namespace mc::host::proto
