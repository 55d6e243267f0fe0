// host/step_metrics: against analytic first- and second-order step responses,
// over random sample periods, with measurement noise, and on responses that
// never rise or never settle.
#include "host/control/step_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "host/base/errors.hpp"

namespace mc::host {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Trace {
  std::vector<double> t, y;
};

// Samples f(t - t0) (0 before t0) every ts from t = 0 to t_end, scaled by S
// and offset by y0.
Trace sample(const std::function<double(double)>& f, double ts, double t_end, double t0 = 0, double y0 = 0,
             double s = 1) {
  Trace tr;
  for (int k = 0; k * ts <= t_end + 1e-12; ++k) {
    const double t = k * ts;
    tr.t.push_back(t);
    tr.y.push_back(y0 + s * (t < t0 ? 0.0 : f(t - t0)));
  }
  return tr;
}

double first_order(double tau, double t) {
  return 1 - std::exp(-t / tau);
}

// Unit step response of wn^2 / (s^2 + 2 zeta wn s + wn^2), 0 < zeta < 1.
double second_order(double zeta, double wn, double t) {
  const double wd = wn * std::sqrt(1 - zeta * zeta);
  return 1 - std::exp(-zeta * wn * t) / std::sqrt(1 - zeta * zeta) * std::sin(wd * t + std::acos(zeta));
}

// First time f(t) = level on [lo, hi] with f(lo) < level <= f(hi), by bisection.
double solve(const std::function<double(double)>& f, double level, double lo, double hi) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < level ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(StepMetrics, FirstOrderMatchesAnalytic) {
  const double tau = 0.01, ts = 1e-5, t0 = 0.002, y0 = 100, s = 400, t_end = 0.2;
  const Trace tr = sample([&](double t) { return first_order(tau, t); }, ts, t_end, t0, y0, s);
  const StepMetrics m = step_metrics(tr.t, tr.y, y0, s, t0);
  std::printf("first order tau %.3g s: rise %.6g (ln 9 tau %.6g), settling %.6g (ln 50 tau %.6g)\n", tau,
              m.rise_s, std::log(9) * tau, m.settling_s, std::log(50) * tau);
  ASSERT_TRUE(m.rose);
  ASSERT_TRUE(m.settled);
  EXPECT_NEAR(m.rise_s, std::log(9) * tau, 1e-6);
  EXPECT_NEAR(m.settling_s, std::log(50) * tau, 1e-6);
  EXPECT_EQ(m.overshoot_pct, 0);
  // The tail is the last 10 % of the samples after t0: mean of S e^{-t/tau}.
  const double ta = 0.9 * (t_end - t0), tb = t_end - t0;
  const double ss = s * tau * (std::exp(-ta / tau) - std::exp(-tb / tau)) / (tb - ta);
  EXPECT_NEAR(m.ss_error, ss, 1e-3 * s * std::exp(-ta / tau) + 1e-12);
  EXPECT_NEAR(m.iae, s * tau * (1 - std::exp(-(t_end - t0) / tau)), 1e-6 * s * tau);
}

TEST(StepMetrics, SecondOrderOvershootAndPeakTime) {
  for (const double zeta : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    const double wn = 2 * kPi * 20, wd = wn * std::sqrt(1 - zeta * zeta);
    const auto f = [&](double t) { return second_order(zeta, wn, t); };
    const double t_end = 12 / (zeta * wn);
    const Trace tr = sample(f, 1e-5, t_end);
    const StepMetrics m = step_metrics(tr.t, tr.y, 0, 1, 0);
    const double os = 100 * std::exp(-zeta * kPi / std::sqrt(1 - zeta * zeta));
    std::printf("zeta %.1f: overshoot %.4f %% (analytic %.4f), peak %.5f s (pi/wd %.5f)\n", zeta,
                m.overshoot_pct, os, m.peak_s, kPi / wd);
    EXPECT_NEAR(m.overshoot_pct, os, 1e-3);
    EXPECT_NEAR(m.peak_s, kPi / wd, 1e-5);
    ASSERT_TRUE(m.rose);
    const double t_peak = kPi / wd;
    EXPECT_NEAR(m.rise_s, solve(f, 0.9, 0, t_peak) - solve(f, 0.1, 0, t_peak), 1e-6);
    // The envelope 1 + e^{-zeta wn t}/sqrt(1 - zeta^2) bounds the response,
    // and the response touches it once per half period.
    ASSERT_TRUE(m.settled);
    const double envelope = std::log(1 / (0.02 * std::sqrt(1 - zeta * zeta))) / (zeta * wn);
    EXPECT_LE(m.settling_s, envelope + 1e-9);
    EXPECT_GE(m.settling_s, envelope - kPi / wd);
    EXPECT_NEAR(m.ss_error, 0, 0.02);
  }
}

TEST(StepMetrics, SignAndOffsetDoNotMatter) {
  const auto f = [](double t) { return second_order(0.4, 100, t); };
  const Trace up = sample(f, 1e-4, 0.3, 0.01, 0, 1);
  const Trace down = sample(f, 1e-4, 0.3, 0.01, -5000, -250);
  const StepMetrics a = step_metrics(up.t, up.y, 0, 1, 0.01),
                    b = step_metrics(down.t, down.y, -5000, -250, 0.01);
  EXPECT_NEAR(a.rise_s, b.rise_s, 1e-9);
  EXPECT_NEAR(a.overshoot_pct, b.overshoot_pct, 1e-9);
  EXPECT_NEAR(a.settling_s, b.settling_s, 1e-9);
  EXPECT_NEAR(a.peak_s, b.peak_s, 1e-9);
  EXPECT_NEAR(-250 * a.ss_error, b.ss_error, 1e-9);
  EXPECT_NEAR(250 * a.iae, b.iae, 1e-6);
}

// Coarser sampling changes each metric by no more than the sample period
// (the crossings are interpolated; the peak is a sample).
TEST(StepMetrics, RandomSamplePeriodsStayWithinOneSample) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const double zeta = 0.2 + 0.7 * u01(rng), wn = 50 + 500 * u01(rng);
    const double ts = (0.002 + 0.03 * u01(rng)) / wn;  // 0.2 % to 3 % of 1/wn
    const auto f = [&](double t) { return second_order(zeta, wn, t); };
    const double t_end = 10 / (zeta * wn);
    const Trace fine = sample(f, 1e-3 / wn, t_end), coarse = sample(f, ts, t_end);
    const StepMetrics a = step_metrics(fine.t, fine.y, 0, 1, 0),
                      b = step_metrics(coarse.t, coarse.y, 0, 1, 0);
    ASSERT_TRUE(b.rose && b.settled);
    EXPECT_NEAR(b.rise_s, a.rise_s, ts) << "zeta " << zeta << " wn " << wn << " ts " << ts;
    EXPECT_NEAR(b.peak_s, a.peak_s, ts);
    EXPECT_NEAR(b.settling_s, a.settling_s, ts);
    // The sampled peak is at most the true one and within the curvature of one sample.
    EXPECT_LE(b.overshoot_pct, 100 * std::exp(-zeta * kPi / std::sqrt(1 - zeta * zeta)) + 1e-9);
    EXPECT_NEAR(b.overshoot_pct, a.overshoot_pct, 100 * wn * wn * ts * ts);
    EXPECT_NEAR(b.iae, a.iae, 1e-3 * a.iae);
  }
}

// Noise of 0.2 % of the step (a tenth of the band) moves the crossings by
// about noise / slope: a few per cent of each time, and the overshoot by the
// noise itself.
TEST(StepMetrics, NoiseMovesMetricsLittle) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> noise(-0.002, 0.002);
  for (const double zeta : {0.5, 0.7, 1.0}) {
    const double wn = 200;
    const auto f = [&](double t) {
      return zeta < 1 ? second_order(zeta, wn, t) : 1 - (1 + wn * t) * std::exp(-wn * t);
    };
    Trace tr = sample(f, 1e-5, 0.2);
    const StepMetrics clean = step_metrics(tr.t, tr.y, 0, 1, 0);
    for (int trial = 0; trial < 20; ++trial) {
      Trace noisy = tr;
      for (double& y : noisy.y) y += noise(rng);
      const StepMetrics m = step_metrics(noisy.t, noisy.y, 0, 1, 0);
      ASSERT_TRUE(m.rose && m.settled);
      EXPECT_NEAR(m.rise_s, clean.rise_s, 0.02 * clean.rise_s);
      EXPECT_NEAR(m.overshoot_pct, clean.overshoot_pct, 0.2 + 1e-9);
      EXPECT_NEAR(m.settling_s, clean.settling_s, 0.1 * clean.settling_s);
      EXPECT_NEAR(m.ss_error, clean.ss_error, 0.002);
      EXPECT_NEAR(m.iae, clean.iae, 0.02 * clean.iae);
    }
  }
}

TEST(StepMetrics, NeverRisesOrNeverSettlesIsReportedAsSuch) {
  // Stalls at half the step: no rise, no settling, a real steady-state error.
  const Trace half = sample([](double t) { return 0.5 * first_order(0.01, t); }, 1e-4, 0.2);
  const StepMetrics a = step_metrics(half.t, half.y, 0, 1, 0);
  EXPECT_FALSE(a.rose);
  EXPECT_TRUE(std::isnan(a.rise_s));
  EXPECT_FALSE(a.settled);
  EXPECT_TRUE(std::isnan(a.settling_s));
  EXPECT_NEAR(a.ss_error, 0.5, 1e-3);
  EXPECT_EQ(a.overshoot_pct, 0);

  // A sustained oscillation about the target: rises, never settles.
  const Trace osc = sample([](double t) { return 1 - std::cos(300 * t); }, 1e-4, 0.2);
  const StepMetrics b = step_metrics(osc.t, osc.y, 0, 1, 0);
  EXPECT_TRUE(b.rose);
  EXPECT_FALSE(b.settled);
  EXPECT_TRUE(std::isnan(b.settling_s));
  EXPECT_NEAR(b.overshoot_pct, 100, 0.1);

  // No motion at all.
  const Trace flat = sample([](double) { return 0.0; }, 1e-4, 0.1);
  const StepMetrics c = step_metrics(flat.t, flat.y, 0, 1, 0);
  EXPECT_FALSE(c.rose);
  EXPECT_FALSE(c.settled);
  EXPECT_NEAR(c.iae, 0.1, 1e-9);
}

TEST(StepMetrics, SamplesBeforeTheStepAreIgnored) {
  // A wild excursion before t0 must not count as overshoot or error.
  Trace tr = sample([](double t) { return first_order(0.005, t); }, 1e-4, 0.1, 0.02);
  for (size_t i = 0; tr.t[i] < 0.02; ++i) tr.y[i] = 7;
  const StepMetrics m = step_metrics(tr.t, tr.y, 0, 1, 0.02);
  EXPECT_EQ(m.overshoot_pct, 0);
  EXPECT_NEAR(m.settling_s, std::log(50) * 0.005, 1e-4);
  EXPECT_NEAR(m.iae, 0.005, 1e-5);
}

TEST(StepMetrics, BadInputThrows) {
  const std::vector<double> t{0, 1, 2}, y{0, 1, 1}, short_y{0, 1}, back_t{0, 2, 1}, nan_y{0, std::nan(""), 1};
  EXPECT_THROW(step_metrics(t, short_y, 0, 1, 0), InputError);
  EXPECT_THROW(step_metrics(t, y, 0, 0, 0), InputError);
  EXPECT_THROW(step_metrics(t, y, 0, std::nan(""), 0), InputError);
  EXPECT_THROW(step_metrics(back_t, y, 0, 1, 0), InputError);
  EXPECT_THROW(step_metrics(t, y, 0, 1, 1.5), InputError);  // one sample after t0
  EXPECT_THROW(step_metrics(t, nan_y, 0, 1, 0), InputError);
  EXPECT_THROW(step_metrics(t, y, 0, 1, 0, 0), InputError);
}

}  // namespace
}  // namespace mc::host
