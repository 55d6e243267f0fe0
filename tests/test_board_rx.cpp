// Hostile bytes on the board's RX line (fuzz/board_rx.hpp), a bounded run
// under CTest: random bytes, good frames with bytes flipped, cut short or
// run together. No burst without a good frame may change a register, draw a
// reply, or be counted other than as the host's decoder counts it. The
// libFuzzer targets run the same check on their own inputs: fuzz_board_rx
// on the board twin (fuzz/board_rx_twin.hpp), fuzz_board_rx_rtl here.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "fuzz/board_rx.hpp"
#include "fuzz/board_rx_twin.hpp"

namespace mc::test {
namespace {

namespace hp = host::proto;
namespace br = board::reg;

// A good request of any kind, to any address, with any value.
hp::Bytes some_frame(std::mt19937& rng) {
  const uint16_t addrs[] = {br::CTRL,     br::WDOG,         br::TLM,          br::IP_CTRL,
                            br::IP_SET_X, uint16_t(0x0203), uint16_t(0x0F00), uint16_t(rng())};
  const uint16_t addr = addrs[rng() % 8];
  switch (rng() % 4) {
    case 0:
      return hp::encode(hp::write(uint8_t(rng()), addr, uint32_t(rng())));
    case 1:
      return hp::encode(hp::read(uint8_t(rng()), addr));
    case 2: {
      std::vector<seg::Words> segs(1 + rng() % 6);
      for (auto& w : segs)
        for (auto& x : w) x = uint32_t(rng());
      return hp::encode(hp::segments(uint8_t(rng()), segs));
    }
    default:
      return hp::encode(hp::ping(uint8_t(rng())));
  }
}

// Random bytes, or good frames flipped, cut short or with a byte dropped.
hp::Bytes piece(std::mt19937& rng) {
  hp::Bytes f;
  const int kind = int(rng() % 4);
  if (kind == 0) {
    f.resize(1 + rng() % 300);
    for (auto& x : f) x = uint8_t(rng());
    return f;
  }
  f = some_frame(rng);
  if (kind == 1) {
    for (int flips = 1 + int(rng() % 3); flips > 0; --flips) f[rng() % f.size()] ^= uint8_t(1 + rng() % 255);
  } else if (kind == 2) {
    f.resize(1 + rng() % (f.size() - 1));
  } else {
    f.erase(f.begin() + long(rng() % f.size()));
  }
  return f;
}

// A burst: up to 12 pieces back to back, so that one piece's leftovers meet
// the next piece's start. The quiet line after it ends any partial frame.
hp::Bytes burst(std::mt19937& rng) {
  hp::Bytes b;
  for (int n = 1 + int(rng() % 12); n > 0; --n) {
    const hp::Bytes p = piece(rng);
    b.insert(b.end(), p.begin(), p.end());
  }
  return b;
}

// Feeds bursts (seed 11) to a harness until at least `limit` bytes have gone
// in; each must leave the board as the quiet line does (feed() says why not).
struct Fed {
  int bursts = 0;
  size_t bytes = 0;
};
template <class Board>
void feed_bursts(Board& board, size_t limit, Fed& fed) {
  std::mt19937 rng(11);
  for (; fed.bytes < limit; ++fed.bursts) {
    const hp::Bytes b = burst(rng);
    fed.bytes += b.size();
    ASSERT_EQ(board.feed(b.data(), b.size()), "") << "burst " << fed.bursts << " (" << b.size() << " bytes)";
  }
}

TEST(BoardRx, NoBadFrameChangesTheBoard) {
  fuzz::BoardRx board(7);
  Fed fed;
  // A bounded run: 20 k bytes or more, some seconds of simulation.
  ASSERT_NO_FATAL_FAILURE(feed_bursts(board, 20000, fed));
  const int bursts = fed.bursts;
  const size_t bytes = fed.bytes;
  std::printf(
      "%d bursts, %zu bytes, %llu board clocks, %llu bursts held a good frame, %zu registers watched\n",
      bursts, bytes, (unsigned long long)board.cycles(), (unsigned long long)board.good_bursts(),
      board.watched());
  EXPECT_LT(board.good_bursts(), uint64_t(bursts) / 10) << "the bursts were meant to be bad";
}

// The twin harness the fuzzer runs: the same bursts, many more of them.
TEST(BoardRxTwin, NoBadFrameChangesTheBoard) {
  fuzz::BoardRxTwin board;
  Fed fed;
  ASSERT_NO_FATAL_FAILURE(feed_bursts(board, 2000000, fed));
  const int bursts = fed.bursts;
  const size_t bytes = fed.bytes;
  std::printf("%d bursts, %zu bytes, %llu clocks stepped, %llu bursts held a good frame\n", bursts, bytes,
              (unsigned long long)board.stepped(), (unsigned long long)board.good_bursts());
  EXPECT_LT(board.good_bursts(), uint64_t(bursts) / 10) << "the bursts were meant to be bad";
  EXPECT_GT(board.good_bursts(), 0u) << "some cut or flipped frames stay good (a flip in a payload byte "
                                        "then in the CRC is rare, a dropped duplicate byte is not)";
}

// The check sees what a good frame does when it is told the burst held
// none: a write changes a register and draws a reply; a segment changes the
// queue; a bare reply-less change is reported too.
TEST(BoardRxTwin, TheCheckSeesAChangedBoard) {
  fuzz::BoardRxTwin board;
  const auto fails_as_bad = [&](const hp::Frame& f) {
    const hp::Bytes b = hp::encode(f);
    EXPECT_EQ(board.feed(b.data(), b.size()), "") << "a good frame is allowed";
    return board.feed(b.data(), b.size(), fuzz::BoardRxTwin::Expect::NoGoodFrame);
  };
  const std::string w = fails_as_bad(hp::write(9, br::WDOG, 5));
  EXPECT_NE(w.find("register RAM word"), std::string::npos) << w;
  EXPECT_NE(w.find("reply"), std::string::npos) << w;
  const std::string r = fails_as_bad(hp::read(9, br::WDOG));
  EXPECT_EQ(r.find("register RAM word"), std::string::npos) << r;
  EXPECT_NE(r.find("reply"), std::string::npos) << r;
  std::vector<seg::Words> segs(2);
  for (auto& s : segs)
    for (auto& x : s) x = 0x1234u;
  const std::string q = fails_as_bad(hp::segments(9, segs));
  EXPECT_NE(q.find("motion core"), std::string::npos) << q;
  // A frame with its CRC flipped is bad for both: nothing to report.
  hp::Bytes bad = hp::encode(hp::write(9, br::WDOG, 5));
  bad.back() ^= 1;
  EXPECT_EQ(board.feed(bad.data(), bad.size(), fuzz::BoardRxTwin::Expect::NoGoodFrame), "");
}

}  // namespace
}  // namespace mc::test
