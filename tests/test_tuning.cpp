// host/tuning: relay analysis against the plant's frequency response,
// identification of the simulated default axis, pole placement, and the
// designed gains closing the loop on the true nonlinear plant.
#include "host/control/tuning.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>

#include "hls/pid_core.hpp"
#include "host/base/errors.hpp"
#include "host/machine/machine_config.hpp"
#include "sim/plant/dc_motor.hpp"

namespace mc::host {
namespace {

using cplx = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

machine::AxisConfig default_x() {
  return machine::axis(machine::default_machine(), "x");
}

// The axis from drive units to counts, sampled with a ZOH at ts: the exact
// discrete frequency response of what a relay or PID at ts sees (the plant's
// own ZOH matrices at step ts). Drive units through the averaged PWM: a
// multiple of 2^(15 - pwm_bits) maps to exactly u / 32768 * supply_v.
cplx plant_z(const machine::AxisConfig& cfg, double ts, double w) {
  sim::AxisPlant p(cfg, ts);
  const cplx z = std::polar(1.0, w * ts);
  const Eigen::Matrix3cd m = z * Eigen::Matrix3cd::Identity() - p.ad().cast<cplx>();
  const Eigen::Vector3cd x = m.partialPivLu().solve(p.bd().col(0).cast<cplx>());
  return x(2) * (cfg.drive.supply_v / 32768 * double(cfg.encoder_cpr) / (2 * kPi));
}

// The frequency in (0, pi/ts) where the sampled plant's phase is phase_deg.
double phase_crossing(const machine::AxisConfig& cfg, double ts, double phase_deg) {
  const double target = phase_deg * kPi / 180;
  // The phase falls monotonically from -90 deg; unwrap through -180.
  const auto phase = [&](double w) {
    const double a = std::arg(plant_z(cfg, ts, w));
    return a > 0 ? a - 2 * kPi : a;
  };
  double lo = 1, hi = kPi / ts * 0.999;
  for (int i = 0; i < 100; ++i) {
    const double mid = std::sqrt(lo * hi);
    (phase(mid) > target ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

// Relay control of the simulated axis at ts about a setpoint half a count
// off the encoder's grid (so the error is never exactly 0).
std::vector<double> relay_capture(const machine::AxisConfig& cfg, bool friction, double d, double eps,
                                  double ts, double duration) {
  sim::AxisPlant p(cfg, 1e-6);
  p.set_friction(friction);
  Relay relay(d, eps);
  const int per_sample = int(std::lround(ts / p.dt_s()));
  std::vector<double> y;
  for (int k = 0; k * ts < duration; ++k) {
    const double pos = double(p.encoder_count());
    y.push_back(pos);
    const double v = sim::drive_volts(cfg.drive, int32_t(relay.update(0.5 - pos)));
    for (int s = 0; s < per_sample; ++s) p.step(v);
  }
  return y;
}

// The relay's limit cycle lies where the describing function says, to about
// a degree; this plant's phase is so flat near -180 deg (-90 from the
// integrator, the rest from two lags far apart) that a degree is 5 % of
// frequency. So Ku and Tu are biased low and high by 10 % and 5 % against the
// plant's exact -180 deg point, whatever the sample period, while the point
// the relay does find (its period, pi a / (4 d)) lies on the plant's
// frequency response to 1 %. docs/tuning.md discusses it.
TEST(TuningRelay, UltimateGainAndPeriodMatchThePlant) {
  const machine::AxisConfig cfg = default_x();
  const double d = 8192;
  for (const double ts : {1e-5, 1e-4}) {
    const double wu = phase_crossing(cfg, ts, -180);
    const double ku = 1 / std::abs(plant_z(cfg, ts, wu)), tu = 2 * kPi / wu;
    for (const bool friction : {false, true}) {
      const RelayResult r = relay_analyse(relay_capture(cfg, friction, d, 0, ts, 0.3), ts, d, 0);
      const cplx g = plant_z(cfg, ts, 2 * kPi / r.tu);
      std::printf(
          "relay d %.0f, ts %g us, friction %-3s: Ku %.1f (plant %.1f, %+.1f %%), Tu %.3f ms (plant %.3f, "
          "%+.1f %%), "
          "a %.1f counts, %d periods; plant at Tu: %.1f deg, 1/|G| %.1f\n",
          d, 1e6 * ts, friction ? "on" : "off", r.ku, ku, 100 * (r.ku / ku - 1), 1e3 * r.tu, 1e3 * tu,
          100 * (r.tu / tu - 1), r.amplitude, r.periods, std::arg(g) * 180 / kPi, 1 / std::abs(g));
      EXPECT_NEAR(r.ku, ku, 0.12 * ku);
      EXPECT_NEAR(r.tu, tu, 0.07 * tu);
      EXPECT_GE(r.periods, 10);
      if (!friction) {
        EXPECT_NEAR(r.ku, 1 / std::abs(g), 0.01 * r.ku);
        EXPECT_NEAR(std::fabs(std::arg(g)) * 180 / kPi, 180, 2);
      }
    }
  }
}

// With hysteresis the relay finds the point where the plant's phase is
// -180 + asin(eps/a) and its gain pi a / (4 d): compare at the measured Tu.
TEST(TuningRelay, HysteresisMovesThePointAsTheDescribingFunctionSays) {
  const machine::AxisConfig cfg = default_x();
  const double ts = cfg.pid.ts_s, d = 8192;
  for (const double eps : {2.0, 8.0}) {
    const RelayResult r = relay_analyse(relay_capture(cfg, false, d, eps, ts, 0.4), ts, d, eps);
    const cplx g = plant_z(cfg, ts, 2 * kPi / r.tu);
    const double phase = std::arg(g) * 180 / kPi - (std::arg(g) > 0 ? 360 : 0);
    std::printf("eps %.0f: a %.1f, Tu %.3f ms, phase %.1f deg (plant at Tu %.1f), |G| %.4g (plant %.4g)\n",
                eps, r.amplitude, 1e3 * r.tu, r.phase_deg, phase, kPi * r.amplitude / (4 * d), std::abs(g));
    EXPECT_NEAR(r.phase_deg, phase, 3);
    EXPECT_NEAR(kPi * r.amplitude / (4 * d), std::abs(g), 0.05 * std::abs(g));
  }
}

// Measurement noise of +-2 counts (a noisy encoder line, vibration) on top
// of the quantization: the crossing detector needs a quarter amplitude
// below the centre before it counts a period, and the amplitude is a
// least-squares fit, so both barely move.
TEST(TuningRelay, NoiseBarelyMovesTheEstimate) {
  const machine::AxisConfig cfg = default_x();
  const double ts = cfg.pid.ts_s, d = TuneDefaults::relay_amplitude;
  const std::vector<double> y = relay_capture(cfg, true, d, 0, ts, TuneDefaults::relay_duration_s);
  const RelayResult clean = relay_analyse(y, ts, d, 0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(-2, 2);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> yn = y;
    for (double& v : yn) v += noise(rng);
    const RelayResult r = relay_analyse(yn, ts, d, 0);
    EXPECT_NEAR(r.tu, clean.tu, 0.02 * clean.tu);
    EXPECT_NEAR(r.ku, clean.ku, 0.03 * clean.ku);
  }
}

TEST(TuningRelay, RejectsCapturesWithoutALimitCycle) {
  std::vector<double> flat(1000, 3.0), slow(1000);
  for (size_t i = 0; i < slow.size(); ++i) slow[i] = 100 * std::sin(2 * kPi * double(i) / 400);
  EXPECT_THROW(relay_analyse(flat, 1e-4, 1000, 0), InputError);
  EXPECT_THROW(relay_analyse(slow, 1e-4, 1000, 0), InputError);  // 2.5 periods
  EXPECT_THROW(relay_analyse(slow, 0, 1000, 0), InputError);
  EXPECT_THROW(Relay(0, 1), InputError);
  EXPECT_THROW(Relay(1, -1), InputError);
}

TEST(TuningRelay, RulesGiveTheTabulatedGains) {
  const RelayResult r{100, 0.01, 10, -180, 0, 5};
  const PidGains zn = design_relay(r, 1e-4, RelayRule::ZieglerNichols);
  EXPECT_DOUBLE_EQ(zn.kp, 60);
  EXPECT_DOUBLE_EQ(zn.ki, 60 / 0.005);
  EXPECT_DOUBLE_EQ(zn.kd, 60 * 0.01 / 8);
  EXPECT_DOUBLE_EQ(zn.tf, 0.01 / 80);
  const PidGains tl = design_relay(r, 1e-4, RelayRule::TyreusLuyben);
  EXPECT_DOUBLE_EQ(tl.kp, 100 / 2.2);
  EXPECT_DOUBLE_EQ(tl.ki, 100 / 2.2 / 0.022);
  const PidGains no = design_relay(r, 1e-3, RelayRule::NoOvershoot);
  EXPECT_DOUBLE_EQ(no.kp, 20);
  EXPECT_DOUBLE_EQ(no.kd, 20 * 0.01 / 3);
  EXPECT_DOUBLE_EQ(no.tf, 1e-3);  // Td/10 = 0.33 ms, held at Ts
}

TEST(TuningExcitation, PrbsIsAMaximalLengthSequence) {
  const std::vector<double> u = prbs(100, 1e-4, 2 * 1023e-4, 1e-4, false);
  ASSERT_EQ(u.size(), 2046u);
  double sum = 0;
  for (size_t i = 0; i < 1023; ++i) {
    EXPECT_EQ(u[i], u[i + 1023]);
    EXPECT_EQ(std::fabs(u[i]), 100);
    sum += u[i];
  }
  EXPECT_EQ(std::fabs(sum), 100);  // 512 of one level, 511 of the other
  for (size_t per : {3u, 11u, 31u, 33u, 93u, 341u}) {
    bool periodic = true;
    for (size_t i = 0; i + per < 1023 && periodic; ++i) periodic = u[i] == u[i + per];
    EXPECT_FALSE(periodic) << per;
  }
  // Balanced: each held bit is followed by its negation.
  const std::vector<double> b = prbs(50, 5e-4, 0.1, 1e-4);
  ASSERT_EQ(b.size(), 1000u);
  for (size_t i = 0; i + 10 <= b.size(); i += 10) {
    EXPECT_EQ(b[i], b[i + 4]);
    EXPECT_EQ(b[i] + b[i + 5], 0);
  }
  EXPECT_THROW(prbs(0, 1e-3, 1, 1e-4), InputError);
}

TEST(TuningExcitation, MultisineHasPowerOnlyAtItsTones) {
  const double ts = 1e-4, dur = 0.5, amp = 1000;
  const std::vector<double> u = multisine(amp, 10, 500, 8, dur, ts);
  ASSERT_EQ(u.size(), 5000u);
  double peak = 0;
  for (double x : u) peak = std::max(peak, std::fabs(x));
  EXPECT_NEAR(peak, amp, 1e-9);
  // DFT bins are 2 Hz apart; the tones sit on bins (whole cycles per capture).
  int tones = 0;
  double total = 0, in_tones = 0;
  for (int bin = 0; bin < 2500; ++bin) {
    cplx s = 0;
    for (size_t i = 0; i < u.size(); ++i) s += u[i] * std::polar(1.0, -2 * kPi * bin * double(i) / 5000);
    const double pw = std::norm(s);
    total += pw;
    if (pw > 1e-6 * 5000.0 * 5000 * amp * amp) {
      ++tones;
      in_tones += pw;
      EXPECT_GE(bin * 2.0, 10 - 1e-9);
      EXPECT_LE(bin * 2.0, 500 + 1e-9);
    }
  }
  EXPECT_EQ(tones, 8);
  EXPECT_NEAR(in_tones / total, 1, 1e-9);
  EXPECT_THROW(multisine(amp, 10, 6000, 8, dur, ts), InputError);  // above Nyquist
}

// The identified model's continuous parameters from the config: docs/plant.md,
// K with the PWM's u / 32768 * supply mapping.
struct TrueModel {
  double k, tau;
};
TrueModel true_model(const machine::AxisConfig& cfg) {
  const machine::MotorParams& m = cfg.motor;
  const sim::AxisPlant p(cfg);
  const double den = m.kt_nm_per_a * m.ke_v_s_per_rad + m.r_ohm * m.b_nm_s_per_rad;
  return {m.kt_nm_per_a / den * cfg.drive.supply_v / 32768 * double(cfg.encoder_cpr) / (2 * kPi),
          m.r_ohm * p.inertia_kg_m2() / den};
}

// Open-loop excitation of the simulated axis: u(k) held over sample k, y(k)
// the position at sample k, in counts (quantized: the encoder count; else the
// exact angle in counts).
struct Capture {
  std::vector<double> u, y;
};
Capture excite(const machine::AxisConfig& cfg, const std::vector<double>& u, bool friction, bool quantized) {
  sim::AxisPlant p(cfg, 1e-6);
  p.set_friction(friction);
  const int per_sample = int(std::lround(cfg.pid.ts_s / p.dt_s()));
  Capture c;
  for (double uk : u) {
    c.u.push_back(uk);
    c.y.push_back(quantized ? double(p.encoder_count())
                            : p.position_rad() / (2 * kPi) * double(cfg.encoder_cpr));
    const double v = sim::drive_volts(cfg.drive, int32_t(std::lround(uk)));
    for (int s = 0; s < per_sample; ++s) p.step(v);
  }
  return c;
}

TEST(TuningIdentify, ExactOnTheDiscreteModel) {
  // Data generated by the model class itself: recovered to rounding.
  const double k = 7.7, tau = 0.0072, ts = 1e-4, p = std::exp(-ts / tau);
  const std::vector<double> u = prbs(4096, 5e-3, 0.5, ts);
  std::vector<double> y(u.size(), 0.0);
  double x = 0, v = 0;
  for (size_t i = 0; i < u.size(); ++i) {
    y[i] = x;
    const double w = k * u[i];
    x += w * ts + (v - w) * tau * (1 - p);
    v = w + (v - w) * p;
  }
  for (const bool coulomb : {false, true}) {
    const AxisModel m = identify(u, y, ts, coulomb, false);
    EXPECT_NEAR(m.k, k, 1e-6 * k);
    EXPECT_NEAR(m.tau, tau, 1e-6 * tau);
    EXPECT_NEAR(m.coulomb, 0, 1e-6);
    EXPECT_LT(m.fit_rms, 1e-6);
  }
}

TEST(TuningIdentify, RejectsCapturesThatDoNotFit) {
  const machine::AxisConfig cfg = default_x();
  const std::vector<double> u = prbs(4096, 10e-3, 0.5, cfg.pid.ts_s);
  Capture c = excite(cfg, u, true, true);
  EXPECT_THROW(identify(c.u, std::vector<double>(c.y.begin(), c.y.end() - 1), cfg.pid.ts_s), InputError);
  EXPECT_THROW(identify({1, 2, 3}, {0, 0, 0}, cfg.pid.ts_s), InputError);
  EXPECT_THROW(identify(c.u, c.y, 0), InputError);
  // No drive, no motion: nothing to identify.
  EXPECT_THROW(identify(std::vector<double>(c.u.size(), 0.0), std::vector<double>(c.y.size(), 0.0), 1e-4),
               InputError);
  // Encoder wired backwards: the drive moves the axis the other way.
  for (double& y : c.y) y = -y;
  EXPECT_THROW(identify(c.u, c.y, cfg.pid.ts_s), InputError);
  c.y[7] = std::nan("");
  EXPECT_THROW(identify(c.u, c.y, cfg.pid.ts_s), InputError);
}

TEST(TuningIdentify, RecoversTheDefaultAxis) {
  const machine::AxisConfig cfg = default_x();
  const TrueModel tm = true_model(cfg);
  // The excitation docs/tuning.md recommends: balanced PRBS, 4096 drive
  // units (6 V), 10 ms bits (longer than tau), 1 s.
  const std::vector<double> u = prbs(TuneDefaults::prbs_amplitude, TuneDefaults::prbs_bit_s,
                                     TuneDefaults::prbs_duration_s, cfg.pid.ts_s);
  for (const bool friction : {false, true}) {
    for (const bool quantized : {false, true}) {
      const Capture c = excite(cfg, u, friction, quantized);
      const AxisModel m = identify(c.u, c.y, cfg.pid.ts_s, friction);
      double excursion = 0;
      for (double y : c.y) excursion = std::max(excursion, std::fabs(y));
      std::printf(
          "friction %-3s encoder %-9s: K %.4f (true %.4f, %+.2f %%), tau %.4f ms (true %.4f, %+.2f %%), "
          "Coulomb %.1f du, fit rms %.3f counts, fast %.3f ms, travel %.2f mm\n",
          friction ? "on" : "off", quantized ? "quantized" : "exact", m.k, tm.k, 100 * (m.k / tm.k - 1),
          1e3 * m.tau, 1e3 * tm.tau, 100 * (m.tau / tm.tau - 1), m.coulomb, m.fit_rms, 1e3 * m.tau_fast,
          1e3 * excursion / machine::counts_per_m(cfg));
      EXPECT_NEAR(m.k, tm.k, 0.02 * tm.k);
      EXPECT_NEAR(m.tau, tm.tau, 0.03 * tm.tau);
      EXPECT_LT(m.fit_rms, 0.5);
      if (friction) {
        EXPECT_NEAR(m.coulomb, 52.9, 10);  // Tc R / Kt in drive units
      }
    }
  }
}

// The closed-loop characteristic polynomial of K/(s (tau s + 1)) with the
// PID, divided by tau Tf: [1, c3, c2, c1, c0].
std::array<double, 5> closed_loop_poly(const AxisModel& m, const PidGains& g) {
  const double tt = m.tau * g.tf;
  return {1, (m.tau + g.tf) / tt, (1 + m.k * (g.kp * g.tf + g.kd)) / tt, m.k * (g.kp + g.ki * g.tf) / tt,
          m.k * g.ki / tt};
}

TEST(TuningDesign, PolePlacementPutsThePolesWhereAsked) {
  const AxisModel m{7.7, 7.2e-3, 0, 1e-4, 0, 0, 0};
  for (const double wc : {150.0, 300.0, 600.0, 1200.0}) {
    for (const double zeta : {0.7, 1.0}) {
      for (const double n : {1.5, 2.0, 4.0}) {
        const PidGains g = design_model(m, wc, zeta, n);
        const std::array<double, 5> c = closed_loop_poly(m, g);
        // The polynomial and, at the double pole, its derivative vanish.
        const auto poly = [&](cplx s) { return (((c[0] * s + c[1]) * s + c[2]) * s + c[3]) * s + c[4]; };
        const auto dpoly = [&](cplx s) { return ((4.0 * c[0] * s + 3 * c[1]) * s + 2 * c[2]) * s + c[3]; };
        const double scale = std::pow(n * wc, 4);
        const cplx dominant = wc * cplx(-zeta, std::sqrt(std::max(0.0, 1 - zeta * zeta)));
        EXPECT_LT(std::abs(poly(dominant)), 1e-9 * scale) << wc << " " << zeta << " " << n;
        EXPECT_LT(std::abs(poly(cplx(-n * wc))), 1e-9 * scale);
        EXPECT_LT(std::abs(dpoly(cplx(-n * wc))), 1e-9 * scale / (n * wc));
        EXPECT_GT(g.kp, 0);
        EXPECT_GT(g.ki, 0);
        EXPECT_GE(g.kd, 0);
        EXPECT_EQ(g.ts, m.ts);
      }
    }
  }
  EXPECT_THROW(design_model(m, 10, 1, 2), InputError);     // slower than 1/tau
  EXPECT_THROW(design_model(m, 20000, 1, 2), InputError);  // Tf below Ts/2
}

// The true plant (friction, stiction, electrical pole, averaged PWM, encoder)
// in closed loop with the quantized controller the core runs (the hls twin):
// a step of `step` counts from rest at t = 0.
StepMetrics truth_step(const machine::AxisConfig& cfg, const PidGains& g, double step, double duration) {
  sim::AxisPlant p(cfg, 1e-6);
  const mc::PidParams par = core_params(design(g), CoreLimits{32767, 0, 0, 0});
  mc::PidState st;
  const int per_sample = int(std::lround(g.ts / p.dt_s()));
  const auto target = int32_t(std::lround(step));
  std::vector<double> t, y;
  for (int k = 0; k * g.ts <= duration; ++k) {
    const auto fb = int32_t(p.encoder_count());
    t.push_back(k * g.ts);
    y.push_back(fb);
    const double v = sim::drive_volts(cfg.drive, pid_axis_update(par, st, true, target, fb).u);
    for (int s = 0; s < per_sample; ++s) p.step(v);
  }
  return step_metrics(t, y, 0, target, 0);
}

PidGains config_gains(const machine::AxisConfig& cfg) {
  PidGains g{};
  g.kp = cfg.pid.kp;
  g.ki = cfg.pid.ki;
  g.kd = cfg.pid.kd;
  g.tf = cfg.pid.tf_s;
  g.ts = cfg.pid.ts_s;
  return g;
}

// The whole model method on the default machine: excite the true plant,
// identify, design with the default bandwidth and damping, and close the
// loop on the true plant with the quantized controller. The 1 mm step
// (400 counts) is the one docs/plant.md measures the default gains with.
TEST(TuningDesign, ModelMethodBeatsTheDefaultGains) {
  const machine::AxisConfig cfg = default_x();
  const Capture c = excite(cfg,
                           prbs(TuneDefaults::prbs_amplitude, TuneDefaults::prbs_bit_s,
                                TuneDefaults::prbs_duration_s, cfg.pid.ts_s),
                           true, true);
  const AxisModel m = identify(c.u, c.y, cfg.pid.ts_s);
  const double wc = default_bandwidth(m);
  const PidGains g = design_model(m, wc), g0 = config_gains(cfg);
  std::printf("model: K %.4f counts/s/du, tau %.4f ms, tau_fast %.3f ms, Coulomb %.1f du; wc %.1f rad/s\n",
              m.k, 1e3 * m.tau, 1e3 * m.tau_fast, m.coulomb, wc);
  std::printf("designed: Kp %.2f Ki %.0f Kd %.4f Tf %.1f us\n", g.kp, g.ki, g.kd, 1e6 * g.tf);
  const double step = 400, dur = 0.3;
  const StepMetrics t0 = truth_step(cfg, g0, step, dur), p0 = predict_step(m, g0, step, dur).metrics;
  const StepMetrics t1 = truth_step(cfg, g, step, dur), p1 = predict_step(m, g, step, dur).metrics;
  const auto show = [](const char* what, const StepMetrics& s) {
    std::printf(
        "%-22s overshoot %5.1f %%, settling %5.1f ms, rise %5.2f ms, ss error %+.1f counts, IAE %.3f\n", what,
        s.overshoot_pct, 1e3 * s.settling_s, 1e3 * s.rise_s, s.ss_error, s.iae);
  };
  show("default, true plant", t0);
  show("default, predicted", p0);
  show("designed, true plant", t1);
  show("designed, predicted", p1);
  ASSERT_TRUE(t0.settled && t1.settled && p1.settled);
  EXPECT_LE(t1.overshoot_pct, 10);
  EXPECT_LT(t1.settling_s, t0.settling_s);
  EXPECT_LE(std::fabs(t1.ss_error), 1);
  // Damping 1 or below at the same bandwidth: the PID's zeros add overshoot
  // the poles do not show, which is why the default damping is 2.
  for (const double zeta : {0.7, 1.0}) {
    const PidGains gz = design_model(m, wc, zeta);
    const StepMetrics tz = truth_step(cfg, gz, step, dur);
    std::printf("zeta %.1f at the same wc: overshoot %.1f %% (true plant), %.1f %% (predicted)\n", zeta,
                tz.overshoot_pct, predict_step(m, gz, step, dur).metrics.overshoot_pct);
    EXPECT_GT(tz.overshoot_pct, 10);
  }
  // The prediction is what the board will show, within the model's error.
  EXPECT_NEAR(p1.overshoot_pct, t1.overshoot_pct, 3);
  EXPECT_NEAR(p1.settling_s, t1.settling_s, 0.15 * t1.settling_s);
  EXPECT_NEAR(p0.overshoot_pct, t0.overshoot_pct, 3);
  EXPECT_NEAR(p0.settling_s, t0.settling_s, 0.15 * t0.settling_s);
}

// The relay method end to end on the true plant: the rules give stable loops;
// the printed metrics are what docs/tuning.md compares.
TEST(TuningDesign, RelayRulesCloseAStableLoop) {
  const machine::AxisConfig cfg = default_x();
  const double ts = cfg.pid.ts_s, d = 8192;
  const RelayResult r = relay_analyse(relay_capture(cfg, true, d, 0, ts, 0.3), ts, d, 0);
  const struct {
    const char* name;
    RelayRule rule;
  } rules[] = {{"Ziegler-Nichols", RelayRule::ZieglerNichols},
               {"Tyreus-Luyben", RelayRule::TyreusLuyben},
               {"no overshoot", RelayRule::NoOvershoot}};
  for (const auto& rr : rules) {
    const PidGains g = design_relay(r, ts, rr.rule);
    const StepMetrics t = truth_step(cfg, g, 400, 0.5);
    std::printf("%-16s Kp %6.1f Ki %7.0f Kd %.4f Tf %5.1f us: overshoot %5.1f %%, settling %5.1f ms\n",
                rr.name, g.kp, g.ki, g.kd, 1e6 * g.tf, t.overshoot_pct, 1e3 * t.settling_s);
    EXPECT_TRUE(t.rose) << rr.name;
    EXPECT_TRUE(t.settled) << rr.name;
  }
}

TEST(TuningDesign, PredictionHonoursTheOutputLimit) {
  const AxisModel m{7.7, 7.2e-3, 0, 1e-4, 0, 0, 0};
  const PidGains g = design_model(m, 300);
  const Prediction full = predict_step(m, g, 2000, 0.2), lim = predict_step(m, g, 2000, 0.2, 5000);
  ASSERT_EQ(full.y.size(), 2001u);
  double umax = 0, ulim = 0;
  for (size_t i = 0; i < full.u.size(); ++i) {
    umax = std::max(umax, std::fabs(full.u[i]));
    ulim = std::max(ulim, std::fabs(lim.u[i]));
  }
  EXPECT_LE(umax, 32767);
  EXPECT_EQ(ulim, 5000);
  // A fifth of the drive cannot accelerate the axis as fast.
  ASSERT_TRUE(full.metrics.rose && lim.metrics.rose);
  EXPECT_GT(lim.metrics.rise_s, full.metrics.rise_s);
  EXPECT_THROW(predict_step(m, g, 0, 0.1), InputError);
  EXPECT_THROW(predict_step(m, g, 100, -1), InputError);
  EXPECT_THROW(predict_step(m, g, 100, 0.1, 40000), InputError);
}

}  // namespace
}  // namespace mc::host
