// C/RTL co-simulation of the interpolator: one testbench drives the Verilated
// rtl/interp_core.v and its twin hls/interp_core.hpp with the same inputs
// every clock and compares every output every clock. On top, the path
// properties (tests/interp_bench.hpp) are asserted on the RTL's own output
// over thousands of random segments.
//
// MC_INTERP_RTL_SEGMENTS sets the length of the random runs (default 2000),
// MC_SEED the seed.
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <sstream>

#include "Vinterp_core.h"
#include "hls/interp_core.hpp"
#include "interp_bench.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc::test {
namespace {

constexpr int kAw = 9;
using Twin = InterpCore<kAw>;

uint64_t env_or(const char* name, uint64_t dflt) {
  const char* v = std::getenv(name);
  return v ? std::strtoull(v, nullptr, 0) : dflt;
}

class InterpCosim {
 public:
  explicit InterpCosim(uint32_t seed) : ctx_(random_context(seed)) {
    dut_ = std::make_unique<Vinterp_core>(ctx_.get(), "interp_core");
    twin_.reset();
    drive(InterpIn{});
    dut_->rst = 1;
    for (int i = 0; i < 3; ++i) edge();
    dut_->rst = 0;
    compare();
  }
  ~InterpCosim() { dut_->final(); }
  InterpCosim(const InterpCosim&) = delete;
  InterpCosim& operator=(const InterpCosim&) = delete;

  void clock(const InterpIn& in) {
    drive(in);
    edge();
    twin_.clock(in);
    ++cycles_;
    compare();
  }

  Vec3 pos() const {
    Vec3 p{};
    for (int a = 0; a < 3; ++a) p[size_t(a)] = int32_t(get_bits(dut_->pos_o, 32 * a, 32));
    return p;
  }
  int seg_cnt() const { return dut_->seg_cnt_o; }
  int count() const { return dut_->count_o; }
  bool busy() const { return dut_->busy_o; }
  bool ovf() const { return dut_->ovf_o; }
  bool underrun() const { return dut_->underrun_o; }
  bool mismatch() const { return mismatch_; }
  uint64_t cycles() const { return cycles_; }

 private:
  void drive(const InterpIn& in) {
    dut_->wr_i = in.wr;
    dut_->wdata_i = in.wdata;
    dut_->abort_i = in.abort;
    dut_->hold_i = in.hold;
    dut_->clr_i = in.clr;
    dut_->set_i = in.set;
    for (int a = 0; a < 3; ++a) put32(dut_->set_pos_i, a, uint32_t(in.set_pos[a]));
    dut_->jog_i = in.jog;
    dut_->jog_neg_i = in.jog_neg;
  }
  void edge() {
    dut_->clk = 0;
    dut_->eval();
    dut_->clk = 1;
    dut_->eval();
  }
  void compare() {
    if (mismatch_) return;
    std::ostringstream diff;
    for (int a = 0; a < 3; ++a)
      if (pos()[size_t(a)] != twin_.pos(a))
        diff << " pos[" << a << "] rtl " << pos()[size_t(a)] << " twin " << twin_.pos(a);
    if (busy() != twin_.busy()) diff << " busy rtl " << busy() << " twin " << twin_.busy();
    if (underrun() != twin_.underrun())
      diff << " underrun rtl " << underrun() << " twin " << twin_.underrun();
    if (ovf() != twin_.ovf()) diff << " ovf rtl " << ovf() << " twin " << twin_.ovf();
    if (seg_cnt() != twin_.seg_cnt()) diff << " seg_cnt rtl " << seg_cnt() << " twin " << twin_.seg_cnt();
    if (count() != twin_.count()) diff << " count rtl " << count() << " twin " << twin_.count();
    if (!diff.str().empty()) {
      mismatch_ = true;
      ADD_FAILURE() << "RTL and twin differ at cycle " << cycles_ << ":" << diff.str();
    }
  }

  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vinterp_core> dut_;
  Twin twin_;
  uint64_t cycles_ = 0;
  bool mismatch_ = false;
};

// A host model: queues words, runs the clock, lets a checker watch the RTL.
struct Rig {
  InterpCosim sim;
  PathChecker* chk = nullptr;
  std::mt19937_64 rng;
  double hold_rate = 0;  // probability of a held cycle

  explicit Rig(uint32_t seed) : sim(seed), rng(seed) {}

  // Every clock: the twin agrees, and no axis moves more than one count
  // unless the position was loaded.
  void clock(InterpIn in = {}) {
    if (hold_rate > 0 && std::uniform_real_distribution<double>(0, 1)(rng) < hold_rate) in.hold = true;
    const Vec3 before = sim.pos();
    sim.clock(in);
    const Vec3 p = sim.pos();
    for (int a = 0; a < 3 && !in.set; ++a)
      if (std::llabs(p[size_t(a)] - before[size_t(a)]) > 1)
        ADD_FAILURE() << "axis " << a << " moved " << p[size_t(a)] - before[size_t(a)]
                      << " counts in a clock";
    if (chk) chk->observe(p, sim.seg_cnt());
  }
  bool push(const PlannedSegment& p) { return push_words(seg::pack(p.seg)); }
  bool push_words(const seg::Words& w) {
    const bool room = sim.count() <= Twin::DEPTH - seg::SEG_WORDS;
    for (const uint32_t word : w) {
      InterpIn in;
      in.wr = true;
      in.wdata = word;
      clock(in);
    }
    return room;
  }
  void set(const Vec3& p) {
    InterpIn in;
    in.set = 7;
    for (int a = 0; a < 3; ++a) in.set_pos[a] = int32_t(p[size_t(a)]);
    clock(in);
  }
  void drain() {
    while (!sim.mismatch() && (sim.busy() || sim.count() >= seg::SEG_WORDS)) clock();
  }
};

TEST(InterpRtl, RandomSegmentsBitExactWithPathProperties) {
  const uint32_t seed = uint32_t(env_or("MC_SEED", 1));
  const int nseg = int(env_or("MC_INTERP_RTL_SEGMENTS", 2000));
  SegGen g(seed);
  g.max_line = 200;
  g.max_radius = 150;
  Rig rig(seed);
  rig.hold_rate = 0.02;
  const Vec3 start{123, -456, 789};
  rig.set(start);
  PathChecker chk(start);
  rig.chk = &chk;
  Vec3 at = start;
  for (int i = 0; i < nseg && !rig.sim.mismatch(); ++i) {
    const auto p = g.any(at);
    at = p.end;
    ASSERT_TRUE(rig.push(p));
    chk.expect(p);
    // Vary the queue depth: deep, shallow, and empty (underruns).
    const int keep = int(g.irange(0, 3)) == 0 ? 0 : int(g.irange(1, 20));
    while (!rig.sim.mismatch() && rig.sim.count() >= keep * seg::SEG_WORDS && (keep > 0 || rig.sim.busy()))
      rig.clock();
  }
  rig.drain();
  ASSERT_FALSE(rig.sim.mismatch());
  EXPECT_FALSE(chk.failed());
  EXPECT_EQ(chk.checked(), nseg);
  EXPECT_EQ(rig.sim.pos(), at);
  std::printf("interp RTL: %d segments, %lld steps, %llu cycles bit-exact with the twin\n", chk.checked(),
              static_cast<long long>(chk.steps()), static_cast<unsigned long long>(rig.sim.cycles()));
}

TEST(InterpRtl, FastFeedKeepsUpAcrossJunctions) {
  // Iterations due every clock or two: the pending counter saturates during
  // loads, which must slow the path down, never bend it.
  SegGen g(7);
  g.min_rate = 0.7;
  g.max_rate = 0.99;
  g.dwells = false;
  Rig rig(7);
  PathChecker chk({0, 0, 0});
  rig.chk = &chk;
  Vec3 at{0, 0, 0};
  for (int i = 0; i < 300 && !rig.sim.mismatch(); ++i) {
    const auto p = g.any(at);
    at = p.end;
    ASSERT_TRUE(rig.push(p));
    chk.expect(p);
    while (!rig.sim.mismatch() && rig.sim.count() >= 8 * seg::SEG_WORDS) rig.clock();
  }
  rig.drain();
  ASSERT_FALSE(rig.sim.mismatch());
  EXPECT_EQ(chk.checked(), 300);
  EXPECT_EQ(rig.sim.pos(), at);
}

TEST(InterpRtl, MalformedWordsAndRandomControlStayBitExact) {
  // Raw random words (any type, any field) mixed with good segments, and
  // random abort, hold, clear and set: nothing here is a valid program, but
  // RTL and twin must agree on every cycle, and no axis may ever move more
  // than one count per clock (Rig::clock checks).
  const uint32_t seed = uint32_t(env_or("MC_SEED", 1)) + 100;
  std::mt19937_64 rng(seed);
  auto r = [&](uint64_t n) { return rng() % n; };
  Rig rig(seed);
  SegGen g(seed);
  for (int round = 0; round < 400 && !rig.sim.mismatch(); ++round) {
    seg::Words w{};
    if (r(2) == 0) {
      w = seg::pack(g.any(rig.sim.pos()).seg);
    } else {
      for (uint32_t& x : w) x = uint32_t(rng());
      w[seg::W_N] &= 0x3F;                              // keep runs short
      w[seg::W_INC_HI] |= 0x8000;                       // and fast
      w[seg::W_E] = uint32_t(int32_t(r(2001)) - 1000);  // D0 near a circle, mostly
    }
    rig.push_words(w);
    for (int k = int(r(400)); k > 0 && !rig.sim.mismatch(); --k) {
      InterpIn in;
      const uint64_t e = r(1000);
      in.abort = e < 3;
      in.hold = e >= 3 && e < 50;
      in.clr = e >= 50 && e < 60;
      in.set = e >= 60 && e < 65 ? uint8_t(rng() % 8) : 0;
      for (int a = 0; a < 3; ++a) in.set_pos[a] = int32_t(rng());
      in.jog = e >= 65 && e < 120 ? uint8_t(rng() % 8) : 0;
      in.jog_neg = r(2) == 0;
      if (r(5) == 0) {
        in.wr = true;  // a stray word: misaligns the writer until an abort
        in.wdata = uint32_t(rng());
      }
      rig.clock(in);
    }
  }
  ASSERT_FALSE(rig.sim.mismatch());
}

// The handwheel jog: one count per strobe while idle, either way, per axis;
// a load in the same clock wins; saturates, never wraps; ignored while a
// segment runs (the path is the one without the strobes).
TEST(InterpRtl, JogMovesTheIdleCommandOneCount) {
  Rig rig(31);
  rig.set({10, -5, 0});
  auto jog = [&](uint8_t axes, bool neg) {
    InterpIn in;
    in.jog = axes;
    in.jog_neg = neg;
    rig.clock(in);
  };
  jog(1, false);
  EXPECT_EQ(rig.sim.pos(), (Vec3{11, -5, 0}));
  jog(6, true);
  EXPECT_EQ(rig.sim.pos(), (Vec3{11, -6, -1}));
  InterpIn both;  // load X, jog X and Y: X takes the load
  both.set = 1;
  both.set_pos[0] = 100;
  both.jog = 3;
  rig.clock(both);
  EXPECT_EQ(rig.sim.pos(), (Vec3{100, -5, -1}));
  rig.set({INT32_MAX, INT32_MIN, 0});
  jog(1, false);
  jog(2, true);
  EXPECT_EQ(rig.sim.pos(), (Vec3{INT32_MAX, INT32_MIN, 0}));

  // While a segment runs the strobes change nothing.
  Rig plain(32);
  SegGen g(33);
  const PlannedSegment seg = g.line({0, 0, 0});
  for (Rig* x : {&rig, &plain}) {
    x->set({0, 0, 0});
    x->push(seg);
  }
  std::mt19937_64 rng(34);
  int strobes = 0;
  while (plain.sim.busy() || plain.sim.count() >= seg::SEG_WORDS) {
    InterpIn in;
    in.jog = rig.sim.busy() ? uint8_t(rng() % 8) : 0;
    in.jog_neg = rng() % 2;
    strobes += in.jog != 0;
    rig.clock(in);
    plain.clock();
    ASSERT_EQ(rig.sim.pos(), plain.sim.pos());
  }
  EXPECT_GT(strobes, 100);  // the run was long enough to try
  EXPECT_FALSE(rig.sim.mismatch());
}

TEST(InterpRtl, FifoOverflowDropsWholeSegmentsInOrder) {
  Rig rig(3);
  PathChecker chk({0, 0, 0});
  Vec3 at{0, 0, 0};
  int admitted = 0;
  for (int i = 0; i < 60; ++i) {
    Vec3 to = at;
    to[0] += 2 + i % 4;
    to[2] -= i % 3;
    const auto p = host::plan_line(at, to, 5e5);
    rig.hold_rate = 1;  // hold: nothing drains while we overfill
    if (rig.push(p)) {
      ++admitted;
      chk.expect(p);
      at = to;
    }
  }
  EXPECT_EQ(admitted, Twin::DEPTH / seg::SEG_WORDS + 1);  // the queue, plus one loaded
  EXPECT_TRUE(rig.sim.ovf());
  rig.hold_rate = 0;
  rig.chk = &chk;
  rig.drain();
  ASSERT_FALSE(rig.sim.mismatch());
  EXPECT_EQ(chk.checked(), admitted);
  EXPECT_EQ(rig.sim.pos(), at);
  EXPECT_TRUE(rig.sim.underrun());  // the last line was not marked last
  InterpIn clr;
  clr.clr = true;
  rig.clock(clr);
  EXPECT_FALSE(rig.sim.ovf());
  EXPECT_FALSE(rig.sim.underrun());
}

TEST(InterpRtl, UnderrunHoldsAndResumes) {
  Rig rig(4);
  PathChecker chk({0, 0, 0});
  rig.chk = &chk;
  const auto a = host::plan_arc({0, 0, 0}, {0, 0, 0}, {-40, 30}, true, 5e5);  // full circle, R = 50
  ASSERT_TRUE(rig.push(a));
  chk.expect(a);
  rig.drain();
  EXPECT_TRUE(rig.sim.underrun());
  for (int i = 0; i < 5000; ++i) rig.clock();
  EXPECT_EQ(rig.sim.pos(), (Vec3{0, 0, 0}));
  auto b = host::plan_line({0, 0, 0}, {-17, 9, 4}, 5e5);
  b.seg.last = true;
  ASSERT_TRUE(rig.push(b));
  chk.expect(b);
  rig.drain();
  ASSERT_FALSE(rig.sim.mismatch());
  EXPECT_EQ(rig.sim.pos(), (Vec3{-17, 9, 4}));
  EXPECT_EQ(chk.checked(), 2);
}

}  // namespace
}  // namespace mc::test
