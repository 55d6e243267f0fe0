// Segments over the link, counted where they land: the board's queue is
// tapped (VirtualBoard::tap_segments) and held against what the host sent.
// - A host that reads some replies after its timeout (a loaded machine)
//   must not queue a frame twice when the queue is full: a doubling such as
//   `motionctl --sim --engine rtl run examples/surface.nc` showed (11,030
//   segments run for 10,832 sent).
// - The soak of issue 18, short: a G-code job over a line with 1e-3 bit
//   flips and 1e-3 drops each way loses, doubles and reorders nothing.
// Both run in board time on the in-process virtual board: deterministic.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/link/serial_port.hpp"
#include "host/motion/interp_plan.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/link_soak.hpp"
#include "sim/vboard/virtual_board.hpp"

#ifndef MC_SOURCE_DIR
#error "MC_SOURCE_DIR: the repository root, for examples/"
#endif

namespace mc::test {
namespace {

namespace br = board::reg;
namespace bb = board::bits;
using std::chrono::milliseconds;

// Dwells told apart by their rate word (the i-th a 2^-40 part faster), so
// the tally knows each one.
std::vector<seg::Words> dwells(size_t n, double seconds) {
  std::vector<seg::Words> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    seg::Segment d = host::plan_dwell({0, 0, 0}, seconds).seg;
    d.inc += i;
    out.push_back(seg::pack(d));
  }
  return out;
}

// A host on a loaded machine: now and then it reads the board's bytes late
// (a stall of 20..150 ms of board time, at random, seeded), so some replies
// come after the host's timeout, when it has sent the frame again. Bytes keep
// their order.
class LateReader final : public host::ByteStream {
 public:
  LateReader(host::ByteStream& inner, double stall_p, uint32_t seed) : in_(inner), p_(stall_p), rng_(seed) {}
  void write(const uint8_t* p, size_t n) override { in_.write(p, n); }
  size_t read(uint8_t* p, size_t n, milliseconds timeout) override {
    const auto end = now() + timeout;
    for (;;) {
      size_t k = 0;
      while (k < n && !q_.empty() && q_.front().first <= now()) {
        p[k++] = q_.front().second;
        q_.pop_front();
      }
      if (k > 0) return k;
      auto until = end;
      if (!q_.empty()) until = std::min(until, q_.front().first);
      if (now() >= until) {
        if (now() >= end) return 0;
        continue;
      }
      uint8_t buf[256];
      const auto wait = std::chrono::duration_cast<milliseconds>(until - now()) + milliseconds(1);
      const size_t got = in_.read(buf, sizeof buf, wait);
      if (got == 0) continue;
      auto due = now();
      if (std::uniform_real_distribution<double>(0, 1)(rng_) < p_)
        due += milliseconds(std::uniform_int_distribution<int>(20, 150)(rng_));
      if (!q_.empty()) due = std::max(due, q_.back().first);
      for (size_t i = 0; i < got; ++i) q_.emplace_back(due, buf[i]);
    }
  }
  std::string name() const override { return in_.name(); }
  std::chrono::steady_clock::time_point now() const override { return in_.now(); }

 private:
  host::ByteStream& in_;
  double p_;
  std::mt19937 rng_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, uint8_t>> q_;
};

// Streams `segs` six to a frame as job_stream does (FULL: poll, then the
// same segments again in a new request) and waits until the board ran them.
// Returns what the board's queue took.
sim::SegmentTally stream_and_tally(sim::VirtualBoard& board, host::ByteStream& s, const host::LinkOptions& lo,
                                   const std::vector<seg::Words>& segs, uint64_t& full_replies,
                                   milliseconds full_wait = milliseconds(1)) {
  std::vector<uint32_t> tap;
  board.tap_segments(&tap);
  host::BoardLink link(s, lo);
  link.connect();
  link.write(br::WDOG, (1u << 24) - 1);
  const uint32_t segs0 = link.read(br::IP_SEGS);
  link.write(br::CTRL, 1u << bb::C_ARM);  // dwells run only while armed
  full_replies = 0;
  for (size_t i = 0; i < segs.size(); i += 6) {
    const std::vector<seg::Words> batch(segs.begin() + long(i),
                                        segs.begin() + long(std::min(segs.size(), i + 6)));
    int tries = 0;
    while (!link.segments(batch)) {
      ++full_replies;
      EXPECT_LT(++tries, 10000) << "the queue never drained";
      if (tries >= 10000) break;
      link.poll(full_wait);
    }
  }
  // Bounded in tries, each 10 ms of board time and more.
  for (int i = 0; i < 100000 && ((link.read(br::IP_SEGS) - segs0) & 0xFFFF) < segs.size(); ++i)
    link.poll(milliseconds(10));
  board.tap_segments(nullptr);
  EXPECT_EQ(link.read(br::FAULT), 0u);
  return sim::tally_segments(segs, tap);
}

TEST(LinkTally, ClassifiesLostDoubledReorderedForeign) {
  const std::vector<seg::Words> s = dwells(20, 1e-3);
  const auto words = [&](std::initializer_list<int> idx) {
    std::vector<uint32_t> w;
    for (int i : idx) {
      const seg::Words x = i >= 0 ? s[size_t(i)] : seg::pack(host::plan_dwell({0, 0, 0}, 0.5).seg);
      w.insert(w.end(), x.begin(), x.end());
    }
    return w;
  };
  sim::SegmentTally t =
      sim::tally_segments(s, words({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19}));
  EXPECT_TRUE(t.clean());
  EXPECT_EQ(t.matched, 20u);
  // 3..5 twice, 8 and 9 never, 12 and 13 swapped, a segment never sent.
  t = sim::tally_segments(
      s, words({0, 1, 2, 3, 4, 5, 3, 4, 5, 6, 7, 10, 11, 13, 12, -1, 14, 15, 16, 17, 18, 19}));
  EXPECT_EQ(t.applied, 22u);
  EXPECT_EQ(t.doubled, 3u);
  EXPECT_EQ(t.lost, 2u);
  EXPECT_EQ(t.reordered, 1u);
  EXPECT_EQ(t.foreign, 1u);
  EXPECT_EQ(t.matched, 17u);
  // A word short: counted apart, never a whole segment.
  std::vector<uint32_t> w = words({0, 1});
  w.pop_back();
  t = sim::tally_segments(s, w);
  EXPECT_EQ(t.partial, 9u);
  EXPECT_FALSE(t.clean());
}

// A host that stalls now and then (LateReader) reads some replies after its
// timeout, when it has sent the frame again. With the queue full, one copy
// of a frame is refused FULL while a later copy finds room; unless the board
// answers every copy as it answered the first, the late FULL of an earlier
// copy tells the host "not queued" and it sends the segments again. Before
// protocol version 2 this run queued 18 segments twice (3 frames).
TEST(LinkDuplicates, StallingHostAndAFullQueueQueueNothingTwice) {
  sim::VirtualBoard board(machine::default_machine());
  sim::BoardStream s(board);
  LateReader late(s, 0.05, 1);
  host::LinkOptions lo;
  lo.max_tries = 50;
  uint64_t full = 0;
  const std::vector<seg::Words> segs = dwells(600, 20e-3);
  const sim::SegmentTally t = stream_and_tally(board, late, lo, segs, full);
  EXPECT_GT(full, 10u) << "the queue was never full: the test does not test";
  EXPECT_TRUE(t.clean()) << "lost " << t.lost << ", doubled " << t.doubled << ", reordered " << t.reordered
                         << ", foreign " << t.foreign;
  EXPECT_EQ(t.matched, segs.size());
}

// The same with bytes flipped and dropped both ways (2e-3 each) and the
// soak's link options: replies lost rather than late.
TEST(LinkDuplicates, InjectedErrorsAndAFullQueueQueueNothingTwice) {
  sim::VirtualBoard board(machine::default_machine());
  sim::BoardStream s(board);
  host::FaultInjector line(s, 2e-3, 2e-3, 7);
  uint64_t full = 0;
  const std::vector<seg::Words> segs = dwells(90, 200e-3);
  const sim::SegmentTally t =
      stream_and_tally(board, line, sim::soak_link_options(), segs, full, milliseconds(10));
  EXPECT_GT(full, 10u);
  EXPECT_GT(line.flipped() + line.dropped(), 20u);
  EXPECT_TRUE(t.clean()) << "lost " << t.lost << ", doubled " << t.doubled << ", reordered " << t.reordered
                         << ", foreign " << t.foreign;
  EXPECT_EQ(t.matched, segs.size());
}

// issue 18's soak, short: 30 s of board time of examples/profile.nc on the
// twin, 1e-3 flips and 1e-3 drops each way (`motionctl sim soak` runs the hour).
TEST(LinkSoak, ShortSoakLosesDoublesReordersNothing) {
  sim::SoakOptions o;
  o.job = std::string(MC_SOURCE_DIR) + "/examples/profile.nc";
  o.board_s = 30;
  const sim::SoakResult r = sim::run_link_soak(machine::default_machine(), o);
  EXPECT_GE(r.board_s, 30);
  EXPECT_GE(r.passes, 1);
  EXPECT_GT(r.segs.sent, 0u);
  EXPECT_EQ(r.segs.applied, r.segs.sent);
  EXPECT_EQ(r.segs.lost, 0u);
  EXPECT_EQ(r.segs.doubled, 0u);
  EXPECT_EQ(r.segs.reordered, 0u);
  EXPECT_EQ(r.segs.foreign, 0u);
  EXPECT_EQ(r.fault, 0u);
  // The faults happened and the link worked through them.
  EXPECT_GT(r.to_board.flipped + r.to_board.dropped, 10u);
  EXPECT_GT(r.to_host.flipped + r.to_host.dropped, 10u);
  EXPECT_GT(r.link.retransmits, 0u);
  EXPECT_GT(r.board_crc + r.board_framing + r.board_junk, 0u);
}

}  // namespace
}  // namespace mc::test
