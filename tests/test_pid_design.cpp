// The host's PID design: the Tustin discretization against an independent
// derivation, its frequency response against C(s) on the warped axis, the
// coefficient quantization, and the designed words run through the twin.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <random>
#include <vector>

#include "hls/mc_fixed.hpp"
#include "hls/pid_core.hpp"
#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/control/pid_design.hpp"

using namespace mc::host;
using cplx = std::complex<double>;

namespace {

// Independent of the implementation: write C(s) as one ratio
//   ((Kp Tf + Kd) s^2 + (Kp + Ki Tf) s + Ki) / (Tf s^2 + s)
// and apply the generic bilinear map s = k (1 - q)/(1 + q), q = z^-1, k = 2/Ts,
// multiplying through by (1 + q)^2.
TransferFunction bilinear_reference(const PidGains& g) {
  const double n2 = g.kp * g.tf + g.kd, n1 = g.kp + g.ki * g.tf, n0 = g.ki;
  const double d2 = g.tf, d1 = 1, d0 = 0;
  const double k = 2 / g.ts;
  // (1-q)^2 = [1,-2,1], (1-q)(1+q) = [1,0,-1], (1+q)^2 = [1,2,1]
  const auto map = [k](double c2, double c1, double c0) {
    return std::array<double, 3>{c2 * k * k + c1 * k + c0, -2 * c2 * k * k + 2 * c0,
                                 c2 * k * k - c1 * k + c0};
  };
  auto b = map(n2, n1, n0);
  auto a = map(d2, d1, d0);
  const double a0 = a[0];
  for (auto& v : b) v /= a0;
  for (auto& v : a) v /= a0;
  return {b, a};
}

double max_abs(const std::array<double, 3>& v) {
  return std::max({std::fabs(v[0]), std::fabs(v[1]), std::fabs(v[2])});
}

PidGains random_gains(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const auto logu = [&](double lo, double hi) { return lo * std::pow(hi / lo, u(rng)); };
  PidGains g{};
  g.ts = logu(1e-6, 1e-2);
  g.kp = logu(1e-3, 1e2);
  g.ki = u(rng) < 0.2 ? 0.0 : logu(1e-2, 1e4);
  g.kd = u(rng) < 0.2 ? 0.0 : logu(1e-6, 1e-1);
  g.tf = u(rng) < 0.3 ? 0.0 : logu(0.1, 100) * g.ts;
  return g;
}

const double kTs[] = {10e-3, 1e-3, 100e-6, 10e-6};

// Gain sets covering P only, I only, PD, PID with and without the filter, and a
// filter much slower than Ts (alpha close to 1).
std::vector<PidGains> gain_sets(double ts) {
  return {
      {2, 30, 0.05, 0, ts},    {2, 30, 0.05, 5e-4, ts},    {0.5, 0, 0, 0, ts},       {0, 5, 0, 0, ts},
      {1, 0, 0.002, 2e-5, ts}, {10, 1000, 0.01, 1e-4, ts}, {0.2, 3, 1e-4, 2e-3, ts},
  };
}

// Log grid of omega from omega_nyq * 1e-5 to 0.95 omega_nyq.
std::vector<double> omega_grid(double ts, int n = 80) {
  const double wn = M_PI / ts, lo = 1e-5 * wn, hi = 0.95 * wn;
  std::vector<double> w;
  w.reserve(n);
  for (int i = 0; i < n; ++i) w.push_back(lo * std::pow(hi / lo, double(i) / (n - 1)));
  return w;
}

// The analog controller on the Tustin-warped axis: s = j (2/Ts) tan(omega Ts/2).
cplx warped_c(const PidGains& g, double omega) {
  return eval_s(g, 2 / g.ts * std::tan(omega * g.ts / 2));
}

// Evaluating the direct form (b, a) near z = 1 subtracts nearly equal sums:
// however exact the design, the computed B(z) and A(z) are off by a few eps
// times sum|b_i| and sum|a_i| (the condition number of polynomial evaluation;
// 8 eps covers the rounding of the coefficients and of Horner's scheme). At
// Ts = 10 us and omega*Ts ~ 1e-5 that is ~1e-8 relative: the very loss that
// makes the core use the parallel form. The slack is relative to |C|.
double direct_form_rel_slack(const TransferFunction& h, double omega, double ts, cplx c) {
  const double eps = std::numeric_limits<double>::epsilon();
  const double th = omega * ts, alpha = h.a[2];
  const cplx one_minus_q{2 * std::sin(th / 2) * std::sin(th / 2), std::sin(th)};
  // |A| = |1 - q| |1 - alpha q|, each factor formed without cancellation.
  const double abs_a = std::abs(one_minus_q) * std::abs((1 - alpha) + alpha * one_minus_q);
  const double abs_b = std::abs(c) * abs_a;
  const auto sum_abs = [](const std::array<double, 3>& v) {
    return std::fabs(v[0]) + std::fabs(v[1]) + std::fabs(v[2]);
  };
  return 8 * eps * (sum_abs(h.b) / abs_b + sum_abs(h.a) / abs_a);
}

}  // namespace

// ---------------------------------------------------------------------------
// Discretization

TEST(PidDesign, MatchesHandExpandedFormulas) {
  std::mt19937_64 rng(12345);
  for (int n = 0; n < 2000; ++n) {
    const PidGains g = random_gains(rng);
    const double alpha = (2 * g.tf - g.ts) / (2 * g.tf + g.ts);
    const double beta = 2 * g.kd / (2 * g.tf + g.ts);
    const double kit = g.ki * g.ts / 2;
    const TransferFunction h = tustin(g);
    EXPECT_EQ(h.a[0], 1.0);
    EXPECT_DOUBLE_EQ(h.a[1], -(1 + alpha));
    EXPECT_DOUBLE_EQ(h.a[2], alpha);
    const double scale = max_abs(h.b);
    EXPECT_NEAR(h.b[0], g.kp + kit + beta, 1e-14 * scale);
    EXPECT_NEAR(h.b[1], -g.kp * (1 + alpha) + kit * (1 - alpha) - 2 * beta, 1e-14 * scale);
    EXPECT_NEAR(h.b[2], g.kp * alpha - kit * alpha + beta, 1e-14 * scale);
  }
}

TEST(PidDesign, MatchesGenericBilinearTransform) {
  std::mt19937_64 rng(777);
  for (int n = 0; n < 2000; ++n) {
    const PidGains g = random_gains(rng);
    const TransferFunction h = tustin(g), r = bilinear_reference(g);
    // The reference forms terms of size k^2 = (2/Ts)^2 that cancel; compare to
    // the size of the coefficients, not each one.
    const double sb = max_abs(r.b), sa = max_abs(r.a);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(h.b[i], r.b[i], 1e-11 * sb) << "b" << i << " ts=" << g.ts << " tf=" << g.tf;
      EXPECT_NEAR(h.a[i], r.a[i], 1e-11 * sa) << "a" << i << " ts=" << g.ts << " tf=" << g.tf;
    }
  }
}

TEST(PidDesign, SeedFormWhenTfIsZero) {
  for (const double ts : kTs) {
    const PidGains g{2, 30, 0.05, 0, ts};
    const double ka = 2 + 30 * ts / 2 + 2 * 0.05 / ts;
    const double kb = 30 * ts - 4 * 0.05 / ts;
    const double kc = -2 + 30 * ts / 2 + 2 * 0.05 / ts;
    const auto seed = seed_form(g);
    ASSERT_TRUE(seed.has_value());
    EXPECT_DOUBLE_EQ(seed->ka, ka);
    EXPECT_DOUBLE_EQ(seed->kb, kb);
    EXPECT_DOUBLE_EQ(seed->kc, kc);
    const TransferFunction h = tustin(g);
    EXPECT_DOUBLE_EQ(h.b[0], ka);
    EXPECT_DOUBLE_EQ(h.b[1], kb);
    EXPECT_DOUBLE_EQ(h.b[2], kc);
    EXPECT_EQ(h.a, (std::array<double, 3>{1, 0, -1}));
  }
  EXPECT_FALSE(seed_form(PidGains{2, 30, 0.05, 1e-4, 1e-3}).has_value());
}

TEST(PidDesign, IntegratorPoleAtZEqualsOne) {
  std::mt19937_64 rng(99);
  for (int n = 0; n < 500; ++n) {
    PidGains g = random_gains(rng);
    const TransferFunction h = tustin(g);
    // A(1) = 0: the pole at z = 1 is always there...
    EXPECT_NEAR(h.a[0] + h.a[1] + h.a[2], 0.0, 1e-15);
    // ...and B(1) = 2 kiT (1 - alpha), so it is an integrator exactly when Ki > 0.
    const double alpha = h.a[2], kit = g.ki * g.ts / 2;
    const double b1 = h.b[0] + h.b[1] + h.b[2];
    EXPECT_NEAR(b1, 2 * kit * (1 - alpha), 1e-12 * max_abs(h.b));
    if (g.ki > 0) {
      EXPECT_GT(b1, 0.0);
    }
  }
  const TransferFunction pd = tustin(PidGains{1, 0, 0.01, 1e-4, 1e-3});
  EXPECT_NEAR(pd.b[0] + pd.b[1] + pd.b[2], 0.0, 1e-15 * max_abs(pd.b));
}

TEST(PidDesign, TimeDomainParallelFormEqualsDirectForm) {
  const PidGains g{2, 30, 0.05, 5e-4, 1e-4};
  const Realization r = realization(g);
  const TransferFunction h = tustin(g);
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> e_dist(-100, 100);
  double i = 0, d = 0, e1 = 0, e2 = 0, u1 = 0, u2 = 0;
  for (int k = 0; k < 5000; ++k) {
    const double e = e_dist(rng);
    i += r.ki * (e + e1);
    d = r.kd_a * d + r.kd_b * (e - e1);
    const double up = r.kp * e + i + d;
    const double ud = h.b[0] * e + h.b[1] * e1 + h.b[2] * e2 - h.a[1] * u1 - h.a[2] * u2;
    ASSERT_NEAR(up, ud, 1e-9 * (1 + std::fabs(up))) << "k=" << k;
    e2 = e1;
    e1 = e;
    u2 = u1;
    u1 = ud;
  }
}

// ---------------------------------------------------------------------------
// Frequency response: Tustin maps s = j (2/Ts) tan(omega Ts/2) onto z = e^{j omega Ts}.

TEST(PidDesign, FrequencyResponseIsWarpedAnalog) {
  for (const double ts : kTs) {
    for (const PidGains& g : gain_sets(ts)) {
      const TransferFunction h = tustin(g);
      const Realization r = realization(g);
      for (const double w : omega_grid(ts)) {
        const cplx c = warped_c(g, w);
        const double tol = 1e-9 * std::abs(c);
        EXPECT_LE(std::abs(eval_z(r, w, ts) - c), tol) << "parallel ts=" << ts << " w=" << w;
        const double tol_direct = std::max(1e-9, direct_form_rel_slack(h, w, ts, c)) * std::abs(c);
        EXPECT_LE(std::abs(eval_z(h, w, ts) - c), tol_direct)
            << "direct ts=" << ts << " w=" << w << " kp=" << g.kp << " ki=" << g.ki << " kd=" << g.kd
            << " tf=" << g.tf;
      }
    }
  }
}

// With the quantized coefficients. Each realized coefficient is within 2^-23
// of its design value, relatively (a 24-bit mantissa with the largest shift
// keeps |m| >= 2^22, and rounding errs by at most 1/2). Per branch that gives
//   |dP| <= 2^-23 |P|,  |dI| <= 2^-23 |I|,
//   |dD| <= |D| (2^-23 + 2^-23 |alpha| / |1 - alpha z^-1|)   (dD/dalpha = D z^-1/(1 - alpha z^-1)),
// so |dC| is bounded by their sum; 1% on top for second-order terms and the
// 1e-9 of the exact comparison above.
TEST(PidDesign, QuantizedFrequencyResponseWithinMantissaBound) {
  const double eps = std::ldexp(1.0, -23);
  for (const double ts : kTs) {
    for (const PidGains& g : gain_sets(ts)) {
      const PidDesign d = design(g);
      const Realization& r = d.ideal;
      for (const double w : omega_grid(ts)) {
        const cplx q = std::polar(1.0, -w * ts);
        const cplx p_br = r.kp, i_br = r.ki * (1.0 + q) / (1.0 - q);
        const cplx one_aq = 1.0 - r.kd_a * q;
        const cplx d_br = r.kd_b * (1.0 - q) / one_aq;
        const double bound = eps * (std::abs(p_br) + std::abs(i_br) +
                                    std::abs(d_br) * (1 + std::fabs(r.kd_a) / std::abs(one_aq)));
        const cplx c = warped_c(g, w);
        const double tol = 1.01 * bound + 1e-9 * std::abs(c);
        EXPECT_LE(std::abs(eval_z(d.realized, w, ts) - c), tol) << "ts=" << ts << " w=" << w;
        const double tol_direct = tol + direct_form_rel_slack(d.fixed_tf, w, ts, c) * std::abs(c);
        EXPECT_LE(std::abs(eval_z(d.fixed_tf, w, ts) - c), tol_direct) << "ts=" << ts << " w=" << w;
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Quantization

TEST(Quantize, RoundTripAndPrecision) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  const double eps = std::ldexp(1.0, -23);
  for (int n = 0; n < 20000; ++n) {
    const int fx = n % 2 ? mc::D_OPER_FRAC : 0;
    const double mag = std::pow(10.0, -12 + 18 * u(rng));  // 1e-12 .. 1e6
    const double v = u(rng) < 0.5 ? -mag : mag;
    const mc::Coef c = quantize(v, fx);
    ASSERT_GE(c.m, -(1 << 23));
    ASSERT_LE(c.m, (1 << 23) - 1);
    ASSERT_GE(c.s, 0);
    ASSERT_LE(c.s, 63);
    const double r = realize(c, fx);
    ASSERT_EQ(r, std::ldexp(double(c.m), fx - c.s));
    if (c.s < 63) {
      EXPECT_LE(rel_error(v, r), eps) << v;
      // The largest shift: one more would not fit.
      const double m_next = std::round(std::ldexp(v, c.s + 1 - fx));
      EXPECT_TRUE(m_next > (1 << 23) - 1 || m_next < -(1 << 23)) << v;
    }
    // The word carries the same numbers.
    const mc::Coef back = mc::coef_unpack(mc::coef_pack(c));
    ASSERT_EQ(back.m, c.m);
    ASSERT_EQ(back.s, c.s);
  }
}

TEST(Quantize, ExactValues) {
  const mc::Coef two = quantize(2.0, 0);
  EXPECT_EQ(two.m, 1 << 22);
  EXPECT_EQ(two.s, 21);
  EXPECT_EQ(mc::coef_pack(two), 0x15400000u);
  // alpha = -1 (Tf = 0) is exact: the most negative mantissa.
  const mc::Coef m1 = quantize(-1.0, mc::D_OPER_FRAC);
  EXPECT_EQ(m1.m, -(1 << 23));
  EXPECT_EQ(m1.s, 38);
  EXPECT_EQ(realize(m1, mc::D_OPER_FRAC), -1.0);
  const mc::Coef p1 = quantize(1.0, mc::D_OPER_FRAC);
  EXPECT_EQ(p1.m, 1 << 22);
  EXPECT_EQ(p1.s, 37);
}

TEST(Quantize, Boundaries) {
  const double mmax = (1 << 23) - 1;
  // Largest value at s = 0.
  EXPECT_EQ(coef_max(0), mmax);
  EXPECT_EQ(coef_max(mc::D_OPER_FRAC), std::ldexp(mmax, mc::D_OPER_FRAC));
  mc::Coef c = quantize(mmax, 0);
  EXPECT_EQ(c.m, (1 << 23) - 1);
  EXPECT_EQ(c.s, 0);
  c = quantize(-(mmax + 1), 0);
  EXPECT_EQ(c.m, -(1 << 23));
  EXPECT_EQ(c.s, 0);
  EXPECT_EQ(mc::coef_pack(c), 0x00800000u);
  // Rounds to mmax at s = 0, still fits; just above rounds to 2^23 and does not.
  EXPECT_EQ(quantize(mmax + 0.49, 0).m, (1 << 23) - 1);
  EXPECT_THROW(quantize(mmax + 0.5, 0), InputError);
  EXPECT_THROW(quantize(-(mmax + 1) - 0.5, 0), InputError);
  EXPECT_THROW(quantize(1e9, 0), InputError);
  EXPECT_THROW(quantize(std::ldexp(mmax + 1, mc::D_OPER_FRAC), mc::D_OPER_FRAC), InputError);
  // Smallest values: s = 63.
  c = quantize(std::ldexp(1.0, -63), 0);
  EXPECT_EQ(c.m, 1);
  EXPECT_EQ(c.s, 63);
  c = quantize(std::ldexp(-3.0, -63 + mc::D_OPER_FRAC), mc::D_OPER_FRAC);
  EXPECT_EQ(c.m, -3);
  EXPECT_EQ(c.s, 63);
  EXPECT_EQ(mc::coef_pack(c), (63u << 24) | 0xFFFFFDu);
  // The largest mantissa at s = 63 is exact.
  c = quantize(std::ldexp(mmax, -63), 0);
  EXPECT_EQ(c.m, (1 << 23) - 1);
  EXPECT_EQ(c.s, 63);
  // Below half the finest step: lost, word 0.
  c = quantize(std::ldexp(0.49, -63), 0);
  EXPECT_EQ(c.m, 0);
  EXPECT_EQ(c.s, 0);
  c = quantize(-1e-30, 0);
  EXPECT_EQ(c.m, 0);
  EXPECT_EQ(rel_error(-1e-30, realize(c, 0)), 1.0);
  // Zero.
  c = quantize(0.0, 0);
  EXPECT_EQ(c.m, 0);
  EXPECT_EQ(c.s, 0);
  EXPECT_EQ(rel_error(0.0, 0.0), 0.0);
}

TEST(Quantize, RejectsNonFiniteAndNamesTheCoefficient) {
  EXPECT_THROW(quantize(std::nan(""), 0), InputError);
  EXPECT_THROW(quantize(INFINITY, 0), InputError);
  try {
    quantize(2e7, 0, "kd_b");
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(e.quantity(), "kd_b");
    EXPECT_NE(std::string(e.what()).find("kd_b = 20000000: too large"), std::string::npos) << e.what();
    EXPECT_NE(e.expected().find("8388607"), std::string::npos);
  }
}

// ---------------------------------------------------------------------------
// Validation and the assembled design

TEST(PidDesign, ValidationMessages) {
  const auto message = [](PidGains g) -> std::string {
    try {
      validate(g);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message({2, 30, 0.05, 0, 1e-4}), "");
  EXPECT_EQ(message({0, 0, 0, 0, 1e-4}), "");
  EXPECT_EQ(message({2, 30, 0.05, 0, -1e-4}), "ts = -0.0001: expected a finite sample period > 0 s");
  EXPECT_NE(message({2, 30, 0.05, 0, 0}).find("ts = 0:"), std::string::npos);
  EXPECT_NE(message({2, 30, 0.05, 0, NAN}).find("ts = nan: not finite"), std::string::npos);
  EXPECT_NE(message({2, 30, 0.05, 0, INFINITY}).find("ts = inf: not finite"), std::string::npos);
  EXPECT_NE(message({2, 30, 0.05, -1, 1e-4}).find("tf = -1: expected"), std::string::npos);
  EXPECT_NE(message({-2, 30, 0.05, 0, 1e-4}).find("kp = -2: negative gains are rejected; expected kp >= 0"),
            std::string::npos);
  EXPECT_NE(message({2, -30, 0.05, 0, 1e-4}).find("ki = -30: negative"), std::string::npos);
  EXPECT_NE(message({2, 30, -0.05, 0, 1e-4}).find("kd = -0.05: negative"), std::string::npos);
  EXPECT_NE(message({NAN, 30, 0.05, 0, 1e-4}).find("kp = nan: not finite"), std::string::npos);
  PidGains g{2, 30, 0.05, 0, 1e-4};
  g.ff1 = INFINITY;
  EXPECT_NE(message(g).find("ff1 = inf"), std::string::npos);
  try {
    validate({-2, 0, 0, 0, 1e-3});
  } catch (const InputError& e) {
    EXPECT_EQ(e.quantity(), "kp");
    EXPECT_EQ(e.value(), "-2");
    EXPECT_EQ(e.problem(), "negative gains are rejected");
  }
}

TEST(PidDesign, DesignAssemblesTheWords) {
  PidGains g{2, 30, 0.05, 5e-4, 1e-4};
  g.ff1 = 0.01;
  g.ff2 = 1e-30;  // below resolution: lost
  const PidDesign d = design(g);
  const char* names[] = {"kp", "ki", "kd_a", "kd_b", "kf1", "kf2"};
  const uint8_t regs[] = {mc::pid_reg::KP,   mc::pid_reg::KI,  mc::pid_reg::KD_A,
                          mc::pid_reg::KD_B, mc::pid_reg::KF1, mc::pid_reg::KF2};
  const double designs[] = {2, 0.0015, 9.0 / 11, 1000.0 / 11, 100, 1e-22};
  for (int i = 0; i < 6; ++i) {
    const FixedCoef& f = d.fixed[i];
    EXPECT_EQ(f.name, names[i]);
    EXPECT_EQ(f.reg, regs[i]);
    EXPECT_EQ(f.fx, i == 2 ? mc::D_OPER_FRAC : 0);
    EXPECT_NEAR(f.design, designs[i], 1e-14 * designs[i]) << f.name;
    const mc::Coef c = mc::coef_unpack(f.word);
    EXPECT_EQ(c.m, f.coef.m);
    EXPECT_EQ(c.s, f.coef.s);
    EXPECT_EQ(f.value, realize(c, f.fx));
    EXPECT_EQ(f.lost, i == 5) << f.name;
    if (i < 5) {
      EXPECT_LE(f.rel_error, std::ldexp(1.0, -23)) << f.name;
    }
  }
  EXPECT_EQ(d.max_rel_error, 1.0);  // the lost kf2
  EXPECT_EQ(d.realized.kp, d.fixed[0].value);
  EXPECT_EQ(d.realized.kd_a, d.fixed[2].value);
  const TransferFunction h = transfer_function(d.realized);
  EXPECT_EQ(h.b, d.fixed_tf.b);
  EXPECT_EQ(h.a, d.fixed_tf.a);
  EXPECT_FALSE(d.seed.has_value());

  // A derivative too strong for the word names the coefficient and its formula.
  try {
    design(PidGains{1, 0, 100, 0, 1e-6});
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(e.quantity(), "kd_b = 2Kd/(2Tf+Ts)");
  }
  EXPECT_THROW(design(PidGains{1, 0, 0, 0, -1}), InputError);
}

// The designed words, loaded into the bit-accurate twin, realize the designed
// controller: the twin's output stays within one output unit of the double
// recursion with the realized coefficients. This pins the meaning of the word
// format (fx of each operand) on the design side.
TEST(PidDesign, WordsDriveTheTwinAsDesigned) {
  const PidGains sets[] = {
      {2, 30, 0.05, 5e-4, 1e-4}, {5, 2000, 0.001, 2e-5, 1e-5}, {0.8, 10, 0.02, 2e-3, 1e-3}};
  for (const PidGains& g : sets) {
    const PidDesign d = design(g);
    const mc::PidParams p = core_params(d);
    mc::PidState st;
    const Realization& r = d.realized;
    std::mt19937_64 rng(11);
    std::uniform_int_distribution<int> e_dist(-20, 20);
    double i = 0, dd = 0, e1 = 0;
    for (int k = 0; k < 3000; ++k) {
      const int e = e_dist(rng);
      const mc::PidOut o = mc::pid_axis_update(p, st, true, e, 0);
      i += r.ki * (e + e1);
      dd = r.kd_a * dd + r.kd_b * (e - e1);
      e1 = e;
      const double u = r.kp * e + i + dd;
      ASSERT_LT(std::fabs(u), 30000.0);
      ASSERT_LE(std::fabs(o.u - u), 1.0) << "k=" << k << " ts=" << g.ts;
    }
  }
}
