// PidDouble (the host's controller) against the fixed-point twin of the core.
//
// Both are driven with the same integer command and feedback sequences, with
// random gains, limits, deadband and error clamp, through saturation and
// anti-windup episodes and enable/disable toggles. The outputs must agree
// within the bound test_pid_numerics uses for the core against double
// precision (max 1 drive unit, RMS 1e-3 of full scale), and both must make
// the same saturation decision wherever the demand is not within a unit of
// the limit (a tie, which quantization may tip either way).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "hls/pid_core.hpp"
#include "host/base/errors.hpp"
#include "host/control/pid_design.hpp"
#include "host/control/pid_double.hpp"

namespace mc::host {
namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * double(rng() >> 11) * 0x1.0p-53;
}

TEST(PidDouble, MatchesFixedPointTwinOverRandomGainsAndSaturation) {
  std::mt19937_64 rng(20240611);
  long sat_samples = 0, samples = 0, sat_decisions_checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    PidGains g{};
    g.ts = (trial % 2) ? 10e-3 : 1e-3;
    // Sized so that no partial sum leaves the core's accumulator range
    // (+-2^17 drive units, hls/mc_fixed.hpp), where the core saturates
    // internally and a PC would not: kp e <= 3e4, beta de <= 4e4, ff <= 2e4.
    g.kp = uniform(rng, 0.5, 10);
    g.ki = uniform(rng, 0, 500);
    g.kd = uniform(rng, 0, 0.02);
    g.tf = uniform(rng, g.ts, 5e-3);
    g.ff1 = uniform(rng, 0, 0.005 * g.ts / 1e-3);
    g.ff2 = uniform(rng, 0, 1e-6 * (g.ts / 1e-3) * (g.ts / 1e-3));
    CoreLimits lim;
    lim.out_limit = uint32_t(500 + rng() % 32268);
    lim.int_limit = (rng() % 2) ? 0 : uint32_t(100 + rng() % 40000);
    lim.deadband = uint32_t(rng() % 4);
    lim.err_limit = (rng() % 2) ? 0 : uint32_t(200 + rng() % 5000);

    const PidDesign d = design(g);
    const mc::PidParams p = core_params(d, lim);
    mc::PidState st;
    PidDouble pid(g, double(lim.out_limit), double(lim.int_limit), double(lim.deadband),
                  double(lim.err_limit));

    // Command: steps and ramps large enough to saturate; feedback lags it
    // like a slow axis, so errors of both signs persist (windup) and reverse.
    int32_t cmd = 0;
    double fb = 0, ramp = 0;
    bool enabled = true;
    double s2 = 0;
    const int n = 4000;
    for (int k = 0; k < n; ++k) {
      if (k % 500 == 0) cmd = int32_t(std::lround(fb + uniform(rng, -3000, 3000)));
      if (k % 250 == 0) ramp = uniform(rng, -20, 20);
      if (k % 700 == 350) enabled = !enabled;
      cmd += int32_t(std::lround(ramp));
      fb += 0.02 * (cmd - fb) + uniform(rng, -3, 3);
      const int32_t fbi = int32_t(std::lround(fb));

      pid.set_enabled(enabled);
      const double u = pid.update(cmd, fbi);
      const mc::PidOut o = mc::pid_axis_update(p, st, enabled, cmd, fbi);
      ASSERT_LT(std::abs(pid.demand()), 0x1.0p17) << "test input leaves the accumulator range";
      ASSERT_EQ(pid.error(), double(o.err)) << "trial " << trial << " k " << k;
      ASSERT_LE(std::abs(u - o.u), 1.0) << "trial " << trial << " k " << k << " demand " << pid.demand();
      s2 += (u - o.u) * (u - o.u);
      if (enabled && std::abs(std::abs(pid.demand()) - lim.out_limit) > 1.0) {
        ASSERT_EQ(pid.saturated(), o.sat) << "trial " << trial << " k " << k << " demand " << pid.demand();
        ++sat_decisions_checked;
      }
      sat_samples += o.sat;
      // The anti-windup decisions are the same: the integrators agree.
      ASSERT_LE(std::abs(pid.integrator() - double(st.i) * 0x1.0p-32), 1.0)
          << "trial " << trial << " k " << k;
      ++samples;
    }
    EXPECT_LT(std::sqrt(s2 / n) / mc::OUT_MAX, 1e-3) << "trial " << trial;
  }
  // The episodes the test is about did happen, in a good share of samples.
  EXPECT_GT(sat_samples, samples / 10);
  EXPECT_LT(sat_samples, samples * 9 / 10);
  EXPECT_GT(sat_decisions_checked, samples / 4);
}

// Anti-windup against an analytic case: PI controller, constant error. Once
// the output reaches the limit, the integrator stops at the headroom the P
// term leaves, and the first sample of opposite error brings the output off
// the limit with no windup to unwind.
TEST(PidDouble, ConditionalIntegrationStopsAtTheHeadroom) {
  const PidGains g{1, 100, 0, 0, 1e-3};  // ki = Ki*Ts/2 = 0.05 per count
  PidDouble pid(g, 1000);
  double u = 0;
  for (int k = 0; k < 20000; ++k) u = pid.update(100, 0);  // P = 100, I += 10 per sample
  EXPECT_EQ(u, 1000);
  EXPECT_TRUE(pid.saturated());
  EXPECT_DOUBLE_EQ(pid.integrator(), 900);
  // e: 100 -> -100: P = -100, I + ki (e + e1) = 900.
  EXPECT_DOUBLE_EQ(pid.update(-100, 0), 800);
  EXPECT_FALSE(pid.saturated());
  EXPECT_DOUBLE_EQ(pid.update(-100, 0), 790);
}

TEST(PidDouble, IntegratorLimitAndDisableAreBumpless) {
  const PidGains g{2, 100, 0, 0, 1e-3};
  PidDouble pid(g, 1000, 300);
  for (int k = 0; k < 1000; ++k) pid.update(10, 0);
  EXPECT_DOUBLE_EQ(pid.integrator(), 300);
  pid.set_enabled(false);
  EXPECT_EQ(pid.update(10, 0), 0);
  EXPECT_EQ(pid.integrator(), 0);
  pid.set_enabled(true);
  // e1 tracked while disabled: I = ki (e + e1) = 0.05 * 20 = 1, P = 20.
  EXPECT_DOUBLE_EQ(pid.update(10, 0), 21);
}

TEST(PidDouble, RejectsBadLimits) {
  const PidGains g{1, 0, 0, 0, 1e-3};
  EXPECT_THROW(PidDouble(g, 0), InputError);
  EXPECT_THROW(PidDouble(g, 100, -1), InputError);
  EXPECT_THROW(PidDouble(g, 100, 0, NAN), InputError);
  EXPECT_THROW(PidDouble(PidGains{1, 0, 0, 0, 0}), InputError);
}

}  // namespace
}  // namespace mc::host
