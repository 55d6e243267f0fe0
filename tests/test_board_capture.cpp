// Telemetry captures (host/board_capture.hpp) against a scripted board: the
// decimation the link can carry, the sample counter unwrapped across its
// 16-bit wrap, and a skipped frame reported as a gap, never filled in.
#include "host/link/board_capture.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <vector>

#include "host/base/errors.hpp"
#include "host/link/protocol.hpp"

namespace mc::host {
namespace {

namespace bp = board::proto;

void put32(proto::Bytes& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(uint8_t(v >> (8 * i)));
}

// Answers every request OK; once TLM is written non-zero, sends one
// telemetry frame of axis 0 per sample count in `samples` with each read.
class ScriptedBoard final : public ByteStream {
 public:
  explicit ScriptedBoard(std::vector<uint16_t> samples) : samples_(std::move(samples)) {}
  void write(const uint8_t* p, size_t n) override {
    for (size_t i = 0; i < n; ++i) {
      proto::Frame f;
      if (!dec_.push(p[i], f)) continue;
      if (f.cmd == bp::CMD_WRITE && f.payload.size() == 6 &&
          uint16_t(f.payload[0] | f.payload[1] << 8) == board::reg::TLM)
        streaming_ = f.payload[2] != 0;
      proto::Frame r{f.seq, uint8_t(f.cmd | bp::REPLY), {bp::ST_OK, 0, 0, 0, 0}};
      const proto::Bytes b = proto::encode(r);
      out_.insert(out_.end(), b.begin(), b.end());
    }
  }
  size_t read(uint8_t* p, size_t n, std::chrono::milliseconds) override {
    if (streaming_ && next_ < samples_.size()) {
      const uint16_t s = samples_[next_++];
      proto::Frame t{uint8_t(next_), bp::CMD_TLM, {}};
      put32(t.payload, s);                               // TLM_HDR: sample count, no fault
      put32(t.payload, uint32_t(10 * s));                // POS
      put32(t.payload, uint32_t(10 * s + 1));            // CMD
      put32(t.payload, 1);                               // ERR
      put32(t.payload, uint32_t(int16_t(-7)) & 0xFFFF);  // OUT
      const proto::Bytes b = proto::encode(t);
      out_.insert(out_.end(), b.begin(), b.end());
    }
    size_t k = 0;
    while (k < n && !out_.empty()) {
      p[k++] = out_.front();
      out_.pop_front();
    }
    return k;
  }
  std::string name() const override { return "scripted"; }

 private:
  std::vector<uint16_t> samples_;
  size_t next_ = 0;
  bool streaming_ = false;
  proto::Decoder dec_;
  std::deque<uint8_t> out_;
};

TEST(BoardCapture, DecimationFitsTheFrameAndTheReplies) {
  // At 12 MHz and 1 Mbaud a byte takes 122 clocks (120 on the line, 2
  // handing it over), a frame 32 more: 26 bytes = 3204 clocks = 267 us; each
  // reply (11 bytes) 1374 clocks more. (BoardRtl.TelemetryFitsTheLineTimeTheHostBudgets
  // holds the figure to the board.)
  constexpr double clk = 12e6;
  EXPECT_EQ(telemetry_frame_bytes(1), 26);
  EXPECT_DOUBLE_EQ(board_tx_seconds(26, 1, clk, 1e6), 3204 / clk);
  EXPECT_DOUBLE_EQ(board_tx_seconds(26 + 2 * kReplyBytes, 3, clk, 1e6), 5952 / clk);
  EXPECT_EQ(telemetry_decimation(100e-6, clk, 1e6, 0), 3u);
  EXPECT_EQ(telemetry_decimation(100e-6, clk, 1e6, 1), 4u);      // 381.5 us
  EXPECT_EQ(telemetry_decimation(100e-6, clk, 1e6, 2), 5u);      // 496 us
  EXPECT_EQ(telemetry_decimation(3204 / clk, clk, 1e6, 0), 1u);  // exactly one frame per sample
  EXPECT_EQ(telemetry_decimation(3203 / clk, clk, 1e6, 0), 2u);
  EXPECT_EQ(telemetry_decimation(1e-3, clk, 1e6, 2), 1u);
  // 115200 baud: 104 clocks a bit (uart_tx rounds 104.17), 1042 a byte.
  EXPECT_EQ(telemetry_decimation(100e-6, clk, 115200, 0), 23u);
  EXPECT_EQ(telemetry_decimation(100e-6, clk, 1e6, 0, 3), 6u);  // 58 bytes: 7108 clocks
  EXPECT_THROW(telemetry_decimation(0, clk, 1e6, 0), InputError);
  EXPECT_THROW(telemetry_decimation(100e-6, clk, 0, 0), InputError);
}

TEST(BoardCapture, UnwrapsTheCounterAndReportsGaps) {
  // Decimation 5: 65530 -> 65535 -> 4 wraps cleanly; 4 -> 14 skips one frame.
  ScriptedBoard board({65525, 65530, 65535, 4, 14, 19});
  BoardLink link(board);
  std::vector<TlmSample> v;
  {
    TelemetryStream s(link, 0, 5, 1000);
    while (v.size() < 6) s.next(v);
    EXPECT_EQ(s.gaps(), 1);
    EXPECT_EQ(s.missing(), 1);
  }
  const std::vector<int64_t> n = {65525, 65530, 65535, 65540, 65550, 65555};
  ASSERT_EQ(v.size(), n.size());
  for (size_t i = 0; i < n.size(); ++i) {
    EXPECT_EQ(v[i].n, n[i]) << i;
    EXPECT_EQ(v[i].pos, int32_t(10 * uint16_t(n[i])));
    EXPECT_EQ(v[i].cmd, int32_t(10 * uint16_t(n[i]) + 1));
    EXPECT_EQ(v[i].err, 1);
    EXPECT_EQ(v[i].u, -7);
  }
}

}  // namespace
}  // namespace mc::host
