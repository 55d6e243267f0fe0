// The fixed-point controller against double precision.
//
// For several gain sets and Ts in {10 ms, 1 ms, 100 us, 10 us}, the twin
// (bit-exact with the RTL) is driven with the same integer error sequence as
// a double-precision Tustin controller (the difference equation of C(z),
// designed independently of the parallel realization). The output sequences
// must agree within 1e-3 of full scale, RMS; the measured figures are printed
// as the table that docs/numerics.md quotes.
//
// The paper's direct form, with its coefficients quantized to the same 24-bit
// mantissas, is run on the same input to show why it is not used: at short Ts
// its KA + KB + KC (= 2 Ki Ts, the integral action) drowns in the rounding of
// coefficients of size 2 Kd / Ts.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "hls/pid_core.hpp"
#include "host/control/pid_design.hpp"

namespace mc {
namespace {

using host::PidGains;

struct Case {
  const char* name;
  PidGains g;
  bool dither = true;
};

constexpr double kFullScale = OUT_MAX;
const double kTs[] = {10e-3, 1e-3, 100e-6, 10e-6};

// Gain sets in core units (drive units per count): a stiff filtered PID, the
// issue's example with a derivative filter, a weak integral and a pure
// Tustin derivative (Tf = 0).
std::vector<Case> cases(double ts) {
  return {{"stiff", PidGains{20, 400, 0.2, 1e-3, ts}},
          {"example", PidGains{2, 30, 0.05, 5e-4, ts}},
          {"weak-i", PidGains{5, 2, 0, 0, ts}},
          // Without dither: see PureTustinDerivativeIntegratesNoiseAtNyquist.
          {"tf0", PidGains{4, 50, 1e-4, 0, ts}, false}};
}

// Encoder-like error: two sinusoids plus dither, integer counts.
std::vector<int32_t> error_signal(double ts, double duration, uint64_t seed, bool with_dither = true) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> dither(with_dither ? -2 : 0, with_dither ? 2 : 0);
  const size_t n = size_t(std::llround(duration / ts));
  std::vector<int32_t> e(n);
  for (size_t k = 0; k < n; ++k) {
    const double t = double(k) * ts;
    e[k] = int32_t(std::lround(200 * std::sin(2 * M_PI * 5 * t) + 40 * std::sin(2 * M_PI * 37 * t + 1))) +
           dither(rng);
  }
  return e;
}

// Direct form II transposed of (b, a) in double.
std::vector<double> run_double(const host::TransferFunction& h, const std::vector<int32_t>& e) {
  std::vector<double> u(e.size());
  double z1 = 0, z2 = 0;
  for (size_t k = 0; k < e.size(); ++k) {
    const double x = e[k];
    const double y = h.b[0] * x + z1;
    z1 = h.b[1] * x - h.a[1] * y + z2;
    z2 = h.b[2] * x - h.a[2] * y;
    u[k] = y;
  }
  return u;
}

std::vector<int32_t> run_fixed(const host::PidDesign& d, const std::vector<int32_t>& e) {
  const PidParams p = host::core_params(d);
  PidState st;
  std::vector<int32_t> u(e.size());
  for (size_t k = 0; k < e.size(); ++k) u[k] = pid_axis_update(p, st, true, e[k], 0).u;
  return u;
}

struct Deviation {
  double rms_fs;   // RMS difference / full scale
  double max_lsb;  // largest difference, drive units
  double peak;     // largest |u| of the reference, drive units
};

template <typename U>
Deviation compare(const std::vector<U>& fixed, const std::vector<double>& ref) {
  double s2 = 0, mx = 0, peak = 0;
  for (size_t k = 0; k < ref.size(); ++k) {
    const double d = double(fixed[k]) - ref[k];
    s2 += d * d;
    mx = std::max(mx, std::abs(d));
    peak = std::max(peak, std::abs(ref[k]));
  }
  return {std::sqrt(s2 / double(ref.size())) / kFullScale, mx, peak};
}

TEST(PidNumerics, FixedPointTracksDoubleAtEveryTs) {
  std::printf("\n| gains | Ts | samples | RMS dev / full scale | max dev (drive units) | peak output |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (double ts : kTs) {
    for (const auto& c : cases(ts)) {
      const auto e = error_signal(ts, 2.0, 1, c.dither);
      const auto d = host::design(c.g);
      const auto ref = run_double(d.tf, e);
      const auto dev = compare(run_fixed(d, e), ref);
      std::printf("| %s | %g s | %zu | %.2e | %.3f | %.0f |\n", c.name, ts, e.size(), dev.rms_fs, dev.max_lsb,
                  dev.peak);
      ASSERT_LT(dev.peak, kFullScale) << "test input saturates; the comparison would be meaningless";
      EXPECT_LT(dev.rms_fs, 1e-3) << c.name << " at Ts=" << ts;
      // Far tighter in practice: the output rounding (0.5 unit) dominates.
      EXPECT_LT(dev.max_lsb, 1.0) << c.name << " at Ts=" << ts;
    }
  }
}

// With Tf = 0 the Tustin derivative has its pole at z = -1: the alternating
// sum of the error's differences never decays, so encoder dither accumulates
// as a random walk at the Nyquist frequency, in double precision as much as in
// fixed point. A derivative filter (Tf > 0) bounds it. This is why the
// product's default Tf is positive.
TEST(PidNumerics, PureTustinDerivativeIntegratesNoiseAtNyquist) {
  const double ts = 10e-6;
  const auto e = error_signal(ts, 2.0, 1, true);
  auto peak_of = [&](double tf) {
    const auto d = host::design(PidGains{0, 0, 0.002, tf, ts});
    double peak = 0;
    for (double u : run_double(d.tf, e)) peak = std::max(peak, std::abs(u));
    return peak;
  };
  const double p0 = peak_of(0), p1 = peak_of(1e-4);
  std::printf("\nKd = 0.002, Ts = 10 us, dithered error: peak |u| %.0f with Tf = 0, %.0f with Tf = 100 us\n",
              p0, p1);
  EXPECT_GT(p0, 10 * p1);
  EXPECT_GT(p0, kFullScale);  // it would saturate a real drive
}

// Only the integral acts: Kp = Kd = 0, a constant error of one count, for
// 10 s of samples. Any loss of integral action shows as a slope error.
TEST(PidNumerics, LongIntegralOnlyRun) {
  std::printf("\n| Ts | samples | ki = Ki*Ts/2 | final output fixed | final output double | rel. error |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (double ts : kTs) {
    const PidGains g{0, 3000, 0, 0, ts};  // reaches 30000 after 10 s at e = 1
    const auto d = host::design(g);
    const size_t n = size_t(std::llround(10.0 / ts));
    const std::vector<int32_t> e(n, 1);
    const auto ref = run_double(d.tf, e);
    const auto fx = run_fixed(d, e);
    const auto dev = compare(fx, ref);
    const double rel = std::abs(double(fx.back()) - ref.back()) / ref.back();
    std::printf("| %g s | %zu | %.3e | %d | %.3f | %.1e |\n", ts, n, d.realized.ki, fx.back(), ref.back(),
                rel);
    EXPECT_LT(dev.rms_fs, 1e-3);
    EXPECT_LT(dev.max_lsb, 1.0);
    EXPECT_LT(rel, 1e-4);
  }
}

// The paper's recurrence u(k) = KA e(k) + KB e(k-1) + KC e(k-2) + u(k-2), its
// coefficients quantized to the same 24-bit mantissa the core uses, computed
// exactly otherwise. Shown failing where the parallel form passes.
TEST(PidNumerics, DirectFormLosesIntegralAtShortTs) {
  const double ts = 10e-6;
  const PidGains g{0, 3000, 0.2, 0, ts};  // Kd present: KA, KC ~ 2 Kd / Ts = 4e4
  const auto seed = host::seed_form(g);
  ASSERT_TRUE(seed.has_value());
  const double ka = host::realize(host::quantize(seed->ka, 0), 0);
  const double kb = host::realize(host::quantize(seed->kb, 0), 0);
  const double kc = host::realize(host::quantize(seed->kc, 0), 0);
  const double ideal_i = 2 * g.ki * ts;  // KA + KB + KC
  const double got_i = ka + kb + kc;
  std::printf("\ndirect form at Ts = 10 us: KA+KB+KC = %.6e, should be %.6e (error %.1f%%)\n", got_i, ideal_i,
              100 * std::abs(got_i - ideal_i) / ideal_i);
  EXPECT_GT(std::abs(got_i - ideal_i) / ideal_i, 1e-2) << "direct form unexpectedly keeps its integral";

  // The parallel form's integrator coefficient at the same Ts is exact to 2^-23.
  const auto d = host::design(g);
  EXPECT_LT(std::abs(d.realized.ki - g.ki * ts / 2) / (g.ki * ts / 2), 1.2e-7);
}

}  // namespace
}  // namespace mc
