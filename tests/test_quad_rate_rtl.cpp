// quad_decoder: the highest edge rate counted without loss, per filter
// length, measured on the RTL (co-simulated with the twin) with edges at
// random phase to the clock and a metastable window around each clock edge.
// Prints the table that docs/encoder.md quotes:
//   build/tests/test_quad_rate_rtl --gtest_filter='*Table*'
// MC_QUAD_RATE_EDGES sets the edges per trial (default 2000).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "Vquad_decoder.h"
#include "quad_cosim.hpp"

namespace mc::test {
namespace {

using QuadCosim = QuadCosimT<Vquad_decoder, QuadDefault>;

// iCEBreaker oscillator (DESIGN.md), only to print the rates in edges/s.
constexpr double kBoardClockHz = 12e6;
// The spacing grid of the search, clocks per edge.
constexpr double kStep = 1.0 / 64;
// Edges per burst at one phase.
constexpr int kBurst = 50;

class RateBench {
 public:
  explicit RateBench(uint32_t seed) : b_(seed), rng_(seed) {}
  RateTrial run(uint32_t len, double T, double e, int n) {
    b_.in.filt_len = len;
    return rate_trial(b_, T, e, n, kBurst, rng_);
  }
  double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  int mismatches() const { return b_.sim.mismatches(); }

 private:
  QuadBench<QuadCosim> b_;
  std::mt19937_64 rng_;
};

struct Row {
  uint32_t len;
  double e;
  double limit;   // clocks per edge: the closest spacing that counted exactly
  double theory;  // spacing_limit() without the metastable window
};

TEST(QuadRate, MaxCountRateTable) {
  const int edges = int(env_count("MC_QUAD_RATE_EDGES", 2000));
  RateBench rb(uint32_t(env_count("MC_SEED", 20261122)));
  std::vector<Row> rows;
  for (double e : {0.0, 1.0 / 3}) {
    for (uint32_t len : {0u, 1u, 2u, 3u, 4u, 8u, 16u}) {
      const double theory = spacing_limit(int(len), e, 0);
      // Down the grid from safely above the limit to the first spacing that
      // loses a count or flags an error; the one before it is the limit.
      double T = std::ceil((theory + 0.5) / kStep) * kStep;
      RateTrial r = rb.run(len, T, e, edges);
      ASSERT_TRUE(r.exact && !r.err) << "filt_len " << len << " fails even at spacing " << T;
      for (;;) {
        r = rb.run(len, T - kStep, e, edges);
        // Loss beyond the limit is always reported, never silent.
        ASSERT_TRUE(r.exact || r.err) << "silent loss: filt_len " << len << " spacing " << T - kStep;
        if (!r.exact || r.err) break;
        T -= kStep;
      }
      // The limit agrees with the analysis: no slower than the ideal bound
      // plus the metastable window and one grid step, never faster than it.
      EXPECT_GE(T, theory - 1e-9) << "filt_len " << len << " e " << e;
      EXPECT_LE(T, spacing_limit(int(len), e, kAperture) + kStep) << "filt_len " << len << " e " << e;
      // Anywhere below the limit rate: exact. Past it: the error is flagged.
      for (int i = 0; i < 8; ++i) {
        const double slow = T * rb.uni(1, 3);
        r = rb.run(len, slow, e, edges / 4);
        EXPECT_TRUE(r.exact && !r.err) << "filt_len " << len << " spacing " << slow;
        const double fast = T * rb.uni(0.6, 0.9);
        r = rb.run(len, fast, e, edges / 4);
        EXPECT_TRUE(r.err) << "filt_len " << len << " spacing " << fast << " e " << e;
      }
      rows.push_back({len, e, T, theory});
    }
  }
  EXPECT_EQ(rb.mismatches(), 0);

  std::printf(
      "\nquad_decoder: highest edge rate counted without loss (RTL, %d edges per trial,\n"
      "in bursts of %d at random phase to the clock, metastable window +-%.2f clock,\n"
      "spacing grid %.4f clock)\n\n",
      edges, kBurst, kAperture, kStep);
  std::printf("| filt_len | phase error | clocks/edge | edges/clock | Medges/s at %.0f MHz | analysis |\n",
              kBoardClockHz / 1e6);
  std::printf("|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows)
    std::printf("| %u | %.0f deg | %.3f | %.3f | %.2f | %.3f |\n", r.len, r.e * 90, r.limit, 1 / r.limit,
                kBoardClockHz / r.limit / 1e6, 1 / r.theory);
}

}  // namespace
}  // namespace mc::test
