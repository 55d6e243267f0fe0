// mul_align RTL against mc::mul_align (the twin) and against an independent
// exact-rational reference: random operands over every shift, plus the
// extremes of both operands.
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "Vmul_align.h"
#include "mc_fixed.hpp"
#include "verilated.h"

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

class MulAlignSim {
 public:
  MulAlignSim() : ctx_(std::make_unique<VerilatedContext>()) {
    ctx_->randReset(2);
    dut_ = std::make_unique<Vmul_align>(ctx_.get());
  }
  // Pipelined: push one operand pair per cycle, results come two cycles later.
  int64_t run(int32_t m, int32_t x, int s) {
    dut_->m = uint32_t(m) & 0xFFFFFF;
    dut_->x = uint32_t(x);
    dut_->s = uint8_t(s);
    for (int i = 0; i < 2; ++i) {
      dut_->clk = 0;
      dut_->eval();
      dut_->clk = 1;
      dut_->eval();
    }
    return sext(dut_->y, ACC_W);
  }

 private:
  std::unique_ptr<VerilatedContext> ctx_;
  std::unique_ptr<Vmul_align> dut_;
};

TEST(MulAlign, RandomAllShiftsMatchTwinAndReference) {
  MulAlignSim sim;
  std::mt19937_64 rng(42);
  for (int i = 0; i < 200000; ++i) {
    const int s = int(rng() % 64);
    const int32_t m = int32_t(sext(rng(), COEF_M_W));
    int32_t x = int32_t(rng());
    x >>= int(rng() % 32);  // spread magnitudes
    const int64_t twin = mul_align(Coef{m, s}, x);
    ASSERT_EQ(twin, reference(m, x, s)) << "m=" << m << " x=" << x << " s=" << s;
    ASSERT_EQ(sim.run(m, x, s), twin) << "m=" << m << " x=" << x << " s=" << s;
  }
}

TEST(MulAlign, Extremes) {
  MulAlignSim sim;
  const int32_t ms[] = {-(1 << 23), -1, 0, 1, (1 << 23) - 1};
  const int32_t xs[] = {INT32_MIN, -1, 0, 1, INT32_MAX};
  for (int32_t m : ms)
    for (int32_t x : xs)
      for (int s = 0; s < 64; ++s) {
        const int64_t twin = mul_align(Coef{m, s}, x);
        ASSERT_EQ(twin, reference(m, x, s));
        ASSERT_EQ(sim.run(m, x, s), twin) << "m=" << m << " x=" << x << " s=" << s;
      }
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
