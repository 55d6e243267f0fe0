// mul_align RTL against mc::mul_align_parts (the twin) and against an
// independent exact-rational reference: random operands over every shift,
// streamed one per cycle, plus the extremes of both operands and products that
// round exactly onto the saturation limits.
#include <gtest/gtest.h>

#include <deque>
#include <memory>
#include <random>

#include "Vmul_align.h"
#include "hls/mc_fixed.hpp"
#include "verilated.h"
#include "vl_context.hpp"

namespace mc {
namespace {

// Independent reference: round-half-up of m*x*2^(32-s) by exact integer
// arithmetic on the quotient and remainder, then saturation.
int64_t reference(int32_t m, int32_t x, int s) {
  const i128 num = i128(m) * x * (i128(1) << 32);
  const i128 den = i128(1) << s;
  i128 q = num / den, r = num % den;
  if (r < 0) {  // floor division
    q -= 1;
    r += den;
  }
  if (2 * r >= den) q += 1;
  return sat(q, ACC_W);
}

// The RTL streams: one operand pair per clock edge, each result three edges
// after its operands (the edge that samples them included). The harness keeps
// the operands in flight and checks every result against the twin's parts,
// the twin's whole product and the independent reference.
class MulAlignSim {
 public:
  static constexpr int kLatency = 3;
  MulAlignSim() : ctx_(test::random_context(1)) { dut_ = std::make_unique<Vmul_align>(ctx_.get()); }
  // Present one operand pair, clock once, check the result that came out.
  void push(int32_t m, int32_t x, int s) {
    flight_.push_back(Op{m, x, s, edges_ + 1});
    clock(m, x, s);
  }
  // Clock the last operands out (with zero operands that are not checked).
  void drain() {
    while (!flight_.empty()) clock(0, 0, 0);
  }
  int checked() const { return checked_; }

 private:
  struct Op {
    int32_t m, x;
    int s;
    int64_t edge;  // the clock edge that sampled the operands
  };
  void clock(int32_t m, int32_t x, int s) {
    dut_->m = uint32_t(m) & 0xFFFFFF;
    dut_->x = uint32_t(x);
    dut_->s = uint8_t(s);
    dut_->clk = 0;
    dut_->eval();
    dut_->clk = 1;
    dut_->eval();
    ++edges_;
    // Operands sampled at edge n come out after edge n + kLatency - 1.
    if (flight_.empty() || edges_ < flight_.front().edge + kLatency - 1) return;
    const Op o = flight_.front();
    flight_.pop_front();
    check(o);
  }
  void check(const Op& o) {
    const MulAlignParts want = mul_align_parts(Coef{o.m, o.s}, o.x);
    const int64_t twin = mul_align(Coef{o.m, o.s}, o.x);
    ASSERT_EQ(want.yh + want.yc, twin) << "m=" << o.m << " x=" << o.x << " s=" << o.s;
    ASSERT_EQ(twin, reference(o.m, o.x, o.s)) << "m=" << o.m << " x=" << o.x << " s=" << o.s;
    // Decode the RTL's sign-folded body: y = {ys, yw ^ ys} + yc.
    const uint64_t body = (uint64_t(1) << (ACC_W - 1)) - 1;
    const uint64_t yw = dut_->ys ? (~dut_->yw & body) : (dut_->yw & body);
    const int64_t yh = sext(yw | (uint64_t(dut_->ys) << (ACC_W - 1)), ACC_W);
    ASSERT_EQ(yh, want.yh) << "m=" << o.m << " x=" << o.x << " s=" << o.s;
    ASSERT_EQ(int(dut_->yc), want.yc) << "m=" << o.m << " x=" << o.x << " s=" << o.s;
    ++checked_;
  }
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmul_align> dut_;
  std::deque<Op> flight_;
  int64_t edges_ = 0;
  int checked_ = 0;
};

TEST(MulAlign, RandomAllShiftsMatchTwinAndReference) {
  MulAlignSim sim;
  std::mt19937_64 rng(42);
  for (int i = 0; i < 200000; ++i) {
    const int s = int(rng() % 64);
    const int32_t m = int32_t(sext(rng(), COEF_M_W));
    int32_t x = int32_t(rng());
    x >>= int(rng() % 32);  // spread magnitudes
    sim.push(m, x, s);
  }
  sim.drain();
  EXPECT_EQ(sim.checked(), 200000);
}

TEST(MulAlign, Extremes) {
  MulAlignSim sim;
  const int32_t ms[] = {-(1 << 23), -1, 0, 1, (1 << 23) - 1};
  const int32_t xs[] = {INT32_MIN, -1, 0, 1, INT32_MAX};
  for (int32_t m : ms)
    for (int32_t x : xs)
      for (int s = 0; s < 64; ++s) sim.push(m, x, s);
  sim.drain();
}

// Products whose rounding lands exactly on the saturation limits. With
// z = floor(m * x * 2^(33 - s)) (one extra fraction bit): z = 2^50 - 1 rounds
// to 2^49, one past the maximum, so the increment must be dropped;
// z = -2^50 - 1 rounds to exactly the minimum; z = -2^50 - 2 is one below it.
// Random operands practically never land there; these operands were found by
// factoring, and the test checks that each one is on its edge.
TEST(MulAlign, RoundingAtTheLimits) {
  struct Edge {
    int32_t m, x;
    int s;
    i128 z;
  };
  const i128 two50 = i128(1) << 50;
  const Edge edges[] = {
      {614141, 1833292203, 33, two50 - 1},    {1082401, 2080374846, 34, two50 - 1},
      {2164802, 2080374846, 35, two50 - 1},   {4329604, 2080374846, 36, two50 - 1},
      {818201, -1376067625, 33, -two50 - 1},  {1342505, -1677312050, 34, -two50 - 1},
      {2685010, -1677312050, 35, -two50 - 1}, {5370020, -1677312050, 36, -two50 - 1},
      {3836089, -587004059, 34, -two50 - 2},  {3836089, -1174008118, 35, -two50 - 2},
      {7601985, -1184848333, 36, -two50 - 2},
  };
  MulAlignSim sim;
  for (const Edge& e : edges) {
    const i128 p = i128(e.m) * e.x;
    ASSERT_EQ(p >> (e.s - 33), e.z) << "not on its edge: m=" << e.m << " x=" << e.x;
    const MulAlignParts pa = mul_align_parts(Coef{e.m, e.s}, e.x);
    if (e.z == two50 - 1) {
      EXPECT_EQ(pa.yh, smax(ACC_W));
      EXPECT_EQ(pa.yc, 0);
    }
    if (e.z == -two50 - 1) {
      EXPECT_EQ(pa.yh + pa.yc, smin(ACC_W));
    }
    sim.push(e.m, e.x, e.s);
  }
  sim.drain();
}

TEST(MulAlign, RoundsHalfUpAndSaturates) {
  // 1 * 1 * 2^32 / 2^33 = 0.5 -> 1 ; -0.5 -> 0 (half up).
  EXPECT_EQ(mul_align(Coef{1, 33}, 1), 1);
  EXPECT_EQ(mul_align(Coef{-1, 33}, 1), 0);
  EXPECT_EQ(mul_align(Coef{-3, 33}, 1), -1);  // -1.5 -> -1
  EXPECT_EQ(mul_align(Coef{(1 << 23) - 1, 0}, INT32_MAX), smax(ACC_W));
  EXPECT_EQ(mul_align(Coef{-(1 << 23), 0}, INT32_MAX), smin(ACC_W));
}

}  // namespace
}  // namespace mc
