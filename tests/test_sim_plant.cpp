// The DC-motor axis plant (sim/dc_motor.hpp): the exact ZOH discretization
// against the hand-derived analytic step response, stiction without chatter,
// the encoder pins through the quad_decoder twin, the drive stages, and the
// default gains closing a stable loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>
#include <vector>

#include "hls/quad_decoder.hpp"
#include "host/control/pid_design.hpp"
#include "host/machine/machine_config.hpp"
#include "sim/plant/dc_motor.hpp"

namespace mc::sim {
namespace {

using machine::axis;
using machine::default_machine;
using machine::PidConfig;
using cplx = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

AxisConfig default_x() {
  return axis(default_machine(), "x");
}

// A motor whose electromechanical poles are complex (large L, small J), with
// viscous friction and a load force, so that every input path is exercised.
AxisConfig complex_pole_axis() {
  AxisConfig a = default_x();
  a.motor = MotorParams{1.0, 10e-3, 0.05, 0.05, 1e-5, 1e-5, 2e-3, 3e-3};
  a.load_kg = 2;
  a.load_force_n = 2;  // 1.6 mN*m at the shaft: less than stiction, so the load alone cannot move it
  return a;
}

// The linear model's response to a voltage step V at t = 0 from rest, derived
// by hand. With x = [i, w]: x' = A x + g, A = [[-R/L, -Ke/L], [Kt/J, -B/J]],
// g = [V/L, -tau/J] (tau: the load torque). Steady state (x' = 0):
//   w_ss = (V - R tau/Kt) / (Ke + R B/Kt),  i_ss = (B w_ss + tau) / Kt,
// and x(t) = x_ss - e^{At} x_ss with Sylvester's formula for distinct
// eigenvalues l1, l2 (real or a complex pair):
//   e^{At} = ((A - l2 I) e^{l1 t} - (A - l1 I) e^{l2 t}) / (l1 - l2).
// theta is the integral of w: w_ss t - sum_k c_k (e^{lk t} - 1) / lk.
struct Analytic {
  double r, l, kt, ke, j, b, tau, v;
  double i_ss, w_ss;
  cplx l1, l2;
  cplx ci1, ci2, cw1, cw2;  // i(t) = i_ss - ci1 e^{l1 t} - ci2 e^{l2 t}, likewise w

  Analytic(const MotorParams& m, double j_total, double tau_load, double volts)
      : r(m.r_ohm),
        l(m.l_h),
        kt(m.kt_nm_per_a),
        ke(m.ke_v_s_per_rad),
        j(j_total),
        b(m.b_nm_s_per_rad),
        tau(tau_load),
        v(volts) {
    w_ss = (v - r * tau / kt) / (ke + r * b / kt);
    i_ss = (b * w_ss + tau) / kt;
    const double a11 = -r / l, a12 = -ke / l, a21 = kt / j, a22 = -b / j;
    const double tr = a11 + a22, det = a11 * a22 - a12 * a21;
    const cplx disc = std::sqrt(cplx(tr * tr - 4 * det));
    l1 = (tr + disc) / 2.0;
    l2 = (tr - disc) / 2.0;
    // (A - l I) x_ss, first and second rows.
    const auto row = [&](cplx lam, int k) {
      return k == 0 ? (a11 - lam) * i_ss + a12 * w_ss : a21 * i_ss + (a22 - lam) * w_ss;
    };
    ci1 = row(l2, 0) / (l1 - l2);
    ci2 = -row(l1, 0) / (l1 - l2);
    cw1 = row(l2, 1) / (l1 - l2);
    cw2 = -row(l1, 1) / (l1 - l2);
  }
  double current(double t) const { return i_ss - (ci1 * std::exp(l1 * t) + ci2 * std::exp(l2 * t)).real(); }
  double speed(double t) const { return w_ss - (cw1 * std::exp(l1 * t) + cw2 * std::exp(l2 * t)).real(); }
  double position(double t) const {
    return w_ss * t - (cw1 * (std::exp(l1 * t) - 1.0) / l1 + cw2 * (std::exp(l2 * t) - 1.0) / l2).real();
  }
};

double rel_err(double got, double want) {
  return std::fabs(got - want) / std::fabs(want);
}

void expect_zoh_exact(const AxisConfig& cfg, double dt, bool want_complex) {
  AxisPlant p(cfg, dt);
  p.set_friction(false);
  const double volts = 12;
  const Analytic an(cfg.motor, p.inertia_kg_m2(), p.load_torque_nm(), volts);
  ASSERT_EQ(std::fabs(an.l1.imag()) > 0, want_complex) << an.l1;
  // Checkpoints from 1 ms to 87 ms, geometric, each a whole number of steps.
  std::vector<int64_t> marks;
  for (int n = 0; n <= 20; ++n) {
    const double t = std::round(1e-3 * std::pow(1.25, n) / 1e-4) * 1e-4;  // 1 ms .. 87 ms
    marks.push_back(std::llround(t / dt));
  }
  int64_t k = 0;
  double worst = 0;
  for (const int64_t m : marks) {
    for (; k < m; ++k) p.step(volts);
    const double t = double(k) * dt;
    ASSERT_NEAR(p.time_s(), t, 1e-12);
    // Without viscous friction or load the current decays to exactly 0, and
    // its relative error would measure nothing but that: floor the scale at
    // 1e-3 of the stall current.
    const double i_scale = std::max(std::fabs(an.current(t)), 1e-3 * volts / cfg.motor.r_ohm);
    const double ei = std::fabs(p.current_a() - an.current(t)) / i_scale;
    const double ew = rel_err(p.speed_rad_s(), an.speed(t));
    const double et = rel_err(p.position_rad(), an.position(t));
    EXPECT_LE(ei, 1e-6) << "i at t=" << t << " dt=" << dt;
    EXPECT_LE(ew, 1e-6) << "w at t=" << t << " dt=" << dt;
    EXPECT_LE(et, 1e-6) << "theta at t=" << t << " dt=" << dt;
    worst = std::max({worst, ei, ew, et});
  }
  std::printf("dt = %g s: worst relative error vs analytic %.3g over %zu checkpoints\n", dt, worst,
              marks.size());
}

TEST(SimPlant, ZohEqualsAnalyticDefaultMotorRealPoles) {
  for (const double dt : {1e-6, 1e-5, 1e-4}) expect_zoh_exact(default_x(), dt, false);
}

TEST(SimPlant, ZohEqualsAnalyticComplexPoles) {
  for (const double dt : {1e-6, 1e-5, 1e-4}) expect_zoh_exact(complex_pole_axis(), dt, true);
}

TEST(SimPlant, TablePositionAndEncoderQuantization) {
  const AxisConfig cfg = default_x();
  AxisPlant p(cfg, 1e-6);
  for (const double theta : {0.0, 1e-9, -1e-9, 2 * kPi, -2 * kPi * 3.25, 1234.5678}) {
    p.reset(theta);
    EXPECT_EQ(p.position_rad(), theta);
    EXPECT_DOUBLE_EQ(p.position_m(), theta / (2 * kPi) / cfg.gear_ratio * cfg.lead_m_per_rev);
    EXPECT_EQ(p.encoder_count(), int64_t(std::floor(theta / (2 * kPi) * cfg.encoder_cpr))) << theta;
  }
  p.reset(-1e-9);
  EXPECT_EQ(p.encoder_count(), -1);  // floor, not truncation toward 0
  // Random angles, whole counts and their neighbours among them, on both
  // sides of zero: the count is floor()'s.
  std::mt19937_64 rng(5);
  for (int i = 0; i < 200000; ++i) {
    double theta = std::uniform_real_distribution<double>(-1e4, 1e4)(rng);
    if (i % 2 == 0) theta = std::round(theta / (2 * kPi) * cfg.encoder_cpr) * (2 * kPi) / cfg.encoder_cpr;
    if (i % 4 == 0) theta = std::nextafter(theta, i % 8 == 0 ? 1e9 : -1e9);
    p.reset(theta);
    ASSERT_EQ(p.encoder_count(), int64_t(std::floor(theta * (cfg.encoder_cpr / (2 * kPi))))) << theta;
  }
  EXPECT_DOUBLE_EQ(counts_per_m(cfg), 2000 / 0.005);
}

// --- Friction ----------------------------------------------------------------

// The steady speed with Coulomb friction tc and load torque tau (moving +):
// V = R i + Ke w, Kt i = B w + tc + tau  =>  w = (V - R (tc + tau)/Kt) / (Ke + R B/Kt).
double friction_speed(const MotorParams& m, double tau, double v) {
  return (v - m.r_ohm * (m.coulomb_nm + tau) / m.kt_nm_per_a) /
         (m.ke_v_s_per_rad + m.r_ohm * m.b_nm_s_per_rad / m.kt_nm_per_a);
}

void run(AxisPlant& p, double v, double seconds, int* sign_flips = nullptr) {
  const int64_t n = std::llround(seconds / p.dt_s());
  double last = p.speed_rad_s();
  for (int64_t k = 0; k < n; ++k) {
    p.step(v);
    const double w = p.speed_rad_s();
    if (sign_flips && ((w > 0 && last < 0) || (w < 0 && last > 0))) ++*sign_flips;
    if (w != 0) last = w;
  }
}

TEST(SimPlant, BelowBreakawayStaysExactlyAtRest) {
  for (const AxisConfig& cfg : {default_x(), complex_pole_axis()}) {
    AxisPlant p(cfg, 1e-6);
    ASSERT_TRUE(p.stuck());
    const double tau = p.load_torque_nm();
    // The current settles at V/R: breakaway when Kt V/R - tau > stiction.
    const double v_break = (cfg.motor.stiction_nm + tau) * cfg.motor.r_ohm / cfg.motor.kt_nm_per_a;
    const int64_t n = 300000;
    for (int64_t k = 0; k < n; ++k) {
      p.step(0.999 * v_break);
      ASSERT_EQ(p.speed_rad_s(), 0.0) << k;
      ASSERT_EQ(p.position_rad(), 0.0) << k;
    }
    EXPECT_TRUE(p.stuck());
    EXPECT_NEAR(p.current_a(), 0.999 * v_break / cfg.motor.r_ohm, 1e-9);

    AxisPlant q(cfg, 1e-6);
    run(q, 1.001 * v_break, 0.3);
    EXPECT_FALSE(q.stuck());
    EXPECT_GT(q.speed_rad_s(), 0.0);
    EXPECT_GT(q.position_rad(), 0.0);
  }
}

TEST(SimPlant, SteadySpeedWithFrictionMatchesAnalytic) {
  for (const AxisConfig& cfg : {default_x(), complex_pole_axis()}) {
    for (const double v : {2.0, 12.0, 24.0}) {
      AxisPlant p(cfg, 1e-6);
      run(p, v, 0.6);
      const double want = friction_speed(cfg.motor, p.load_torque_nm(), v);
      EXPECT_LE(rel_err(p.speed_rad_s(), want), 1e-6) << v << " V: " << p.speed_rad_s() << " vs " << want;
      // The current then supplies exactly the friction and load torque.
      EXPECT_LE(rel_err(p.current_a(),
                        (cfg.motor.b_nm_s_per_rad * want + cfg.motor.coulomb_nm + p.load_torque_nm()) /
                            cfg.motor.kt_nm_per_a),
                1e-6);
    }
  }
}

// Friction may stop the shaft, never push it through zero speed: every
// reversal passes through exact rest (w == 0), and the shaft leaves rest only
// when the driving torque exceeds stiction. The default motor is overdamped
// and stops without reversing; the complex-pole motor's inductance keeps
// braking current flowing when it stops, which can legitimately start it
// backwards a few times before it settles.
TEST(SimPlant, ComesToRestWithoutChatter) {
  for (const bool underdamped : {false, true}) {
    const AxisConfig cfg = underdamped ? complex_pole_axis() : default_x();
    AxisPlant p(cfg, 1e-6);
    run(p, 12, 0.2);
    ASSERT_GT(p.speed_rad_s(), 10.0);
    int reversals = 0, direct_reversals = 0, stops = 0;
    double last = p.speed_rad_s();
    for (int k = 0; k < 500000; ++k) {
      const double before = p.speed_rad_s();
      const bool was_stuck = p.stuck();
      const double drive = p.driving_torque_nm();
      p.step(0);
      const double w = p.speed_rad_s();
      direct_reversals += (before > 0 && w < 0) || (before < 0 && w > 0);
      stops += !was_stuck && p.stuck();
      if (was_stuck && w != 0) {
        EXPECT_GT(std::fabs(drive), cfg.motor.stiction_nm) << k;
      }
      if ((w > 0 && last < 0) || (w < 0 && last > 0)) ++reversals;
      if (w != 0) last = w;
    }
    EXPECT_EQ(direct_reversals, 0);
    if (underdamped) {
      EXPECT_LE(reversals, 10);
    } else {
      EXPECT_EQ(reversals, 0);
      EXPECT_EQ(stops, 1);
    }
    std::printf("%s motor: %d stops, %d reversals before rest\n", underdamped ? "complex-pole" : "default",
                stops, reversals);
    ASSERT_TRUE(p.stuck());
    ASSERT_EQ(p.speed_rad_s(), 0.0);
    const double rest = p.position_rad();
    for (int k = 0; k < 200000; ++k) {
      p.step(0);
      ASSERT_EQ(p.speed_rad_s(), 0.0) << k;
      ASSERT_EQ(p.position_rad(), rest) << k;
    }
  }
}

TEST(SimPlant, ReversalCrossesZeroOnce) {
  AxisPlant p(default_x(), 1e-6);
  run(p, 12, 0.1);
  int flips = 0, stuck_steps = 0;
  double last = p.speed_rad_s();
  for (int k = 0; k < 200000; ++k) {
    p.step(-12);
    const double w = p.speed_rad_s();
    stuck_steps += p.stuck();
    if ((w > 0 && last < 0) || (w < 0 && last > 0)) ++flips;
    if (w != 0) last = w;
  }
  EXPECT_EQ(flips, 1);
  EXPECT_LT(p.speed_rad_s(), 0.0);
  // -12 V is far beyond breakaway: the shaft rests for a step or two only.
  EXPECT_LE(stuck_steps, 2);
}

TEST(SimPlant, FrictionOffIsTheLinearModel) {
  AxisPlant p(default_x(), 1e-6);
  p.set_friction(false);
  EXPECT_FALSE(p.stuck());
  p.step(0.01);  // far below breakaway: moves anyway
  EXPECT_GT(p.current_a(), 0.0);
  for (int k = 0; k < 1000; ++k) p.step(0.01);
  EXPECT_GT(p.speed_rad_s(), 0.0);
  p.reset();
  EXPECT_EQ(p.time_s(), 0.0);
  EXPECT_EQ(p.speed_rad_s(), 0.0);
}

// hold() against step(): random voltages held for random stretches, with
// stiction, reversals and rests. One plant takes every stretch with hold()
// (again after each stop at a count change), the other steps one at a time;
// each stop must be the first step whose count differs, and the two must end
// every stretch in the same state, bit for bit. A third plant is an
// independent reference: x <- Ad x + Bd u iterated, with the friction rules
// of docs/plant.md written out here, which the runs may differ from only by
// rounding (the runs take Ad^k from tables).
// bigs: hold_counting() must stop on steps that move the count by more
// than one (a fine encoder) at least this often.
void check_hold(const AxisConfig& cfg, bool friction, uint64_t seed, int stretches, uint64_t bigs = 0) {
  AxisPlant held(cfg, 1e-6), stepped(cfg, 1e-6);
  held.set_friction(friction);
  stepped.set_friction(friction);
  AxisPlant spare(cfg, 1e-6);
  spare.set_friction(!friction);  // take_motion() brings the friction too
  const Eigen::Matrix3d ad = stepped.ad();
  const Eigen::Matrix<double, 3, 2> bd = stepped.bd();
  const MotorParams& m = cfg.motor;
  Eigen::Vector3d ref = Eigen::Vector3d::Zero();
  bool ref_stuck = friction;
  const double rtc = cfg.encoder_cpr / (2 * kPi), tau_load = held.load_torque_nm();
  const auto ref_step = [&](double v) {
    double dir = ref(1) > 0 ? 1 : -1;
    if (friction && ref_stuck) {
      const double drive = m.kt_nm_per_a * ref(0) - tau_load;
      if (std::fabs(drive) <= m.stiction_nm) {
        ref(0) =
            std::exp(-m.r_ohm / m.l_h * 1e-6) * ref(0) - std::expm1(-m.r_ohm / m.l_h * 1e-6) / m.r_ohm * v;
        return;
      }
      ref_stuck = false;
      dir = drive > 0 ? 1 : -1;
    }
    ref = ad * ref + bd * Eigen::Vector2d(v, tau_load + (friction ? dir * m.coulomb_nm : 0));
    if (friction && ref(1) * dir <= 0) {
      ref(1) = 0;
      ref_stuck = true;
    }
  };
  std::mt19937_64 rng(seed);
  uint64_t stops = 0, count_mismatch = 0, total = 0, moved = 0, passed = 0, big_stops = 0;
  double hold_s = 0;
  double worst = 0;
  for (int s = 0; s < stretches; ++s) {
    // Mostly small voltages (stiction, slow creep), some large, some rests.
    const int kind = int(rng() % 4);
    const double v = kind == 0   ? 0.0
                     : kind == 1 ? std::uniform_real_distribution<double>(-0.4, 0.4)(rng)
                                 : std::uniform_real_distribution<double>(-48, 48)(rng) / (kind == 2 ? 8 : 1);
    const uint64_t n = 1 + rng() % (rng() % 4 == 0 ? 20000 : 600);
    uint64_t done = 0;
    while (done < n) {
      const int64_t before = held.encoder_count();
      const auto t0 = std::chrono::steady_clock::now();
      // Half the holds sample the position along the way, as the
      // co-simulation's trace does.
      // Room for every sample the stretch could take, and no more.
      const uint64_t first = 1 + rng() % 16, every = 1 + rng() % 12;
      const bool sampled = rng() % 2 == 0;
      std::vector<double> samples(sampled && n - done >= first ? (n - done - first) / every + 1 : 0);
      AxisPlant::Samples out{first, every, samples.data(), samples.size()};
      // A third of the holds go through the count changes, noting each.
      const bool counting = rng() % 3 == 0;
      const uint64_t step0 = rng() % 1000;
      std::vector<AxisPlant::CountChange> changes;
      AxisPlant::Held h{0, false};
      if (counting) h = held.hold_counting(v, n - done, out, changes, step0);
      const uint64_t took = counting  ? h.steps
                            : sampled ? held.hold(v, n - done, out)
                                      : held.hold(v, n - done);
      samples.resize(samples.size() - out.room);
      ASSERT_EQ(out.out, samples.data() + samples.size());
      if (sampled && n - done >= first) {
        // first is left on the next sample, counted from the call's end.
        const uint64_t next = took < first ? first : first + ((took - first) / every + 1) * every;
        ASSERT_EQ(out.first, next - took) << "stretch " << s;
      }
      hold_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      total += took;
      ASSERT_GE(took, 1u);
      ASSERT_LE(took, n - done);
      size_t sample = 0, change = 0;
      int64_t last = before;
      bool last_big = false;  // the last step taken moved the count by more than one
      for (uint64_t k = 0; k < took; ++k) {
        if (!counting) {
          ASSERT_EQ(stepped.encoder_count(), before) << "stretch " << s << ": hold() passed a count change";
        }
        stepped.step(v);
        if (counting && stepped.encoder_count() != last) {
          // Every change noted, with its step, and none passed that moved
          // the count by more than one.
          ASSERT_LT(change, changes.size()) << "stretch " << s << ", step " << k + 1 << ": a change missing";
          ASSERT_EQ(changes[change].step, step0 + k + 1) << "stretch " << s;
          ASSERT_EQ(changes[change].count, stepped.encoder_count()) << "stretch " << s;
          ++change;
          const int64_t d = stepped.encoder_count() - last;
          last = stepped.encoder_count();
          ASSERT_TRUE(d == 1 || d == -1 || k + 1 == took) << "stretch " << s << ": went on after " << d;
          last_big = d != 1 && d != -1;
          if (k + 1 < took) ++passed;
        }
        if (sampled && k + 1 >= first && (k + 1 - first) % every == 0) {
          ASSERT_LT(sample, samples.size()) << "stretch " << s << ": a sample missing";
          ASSERT_EQ(samples[sample++], stepped.position_m()) << "stretch " << s << ", step " << k + 1;
        }
        ref_step(v);
        // Another count is rounding only where the two angles straddle a
        // count boundary.
        const double c = ref(2) * rtc, gap = std::fabs(c - std::round(c));
        if (int64_t(std::floor(c)) != stepped.encoder_count() &&
            gap > std::fabs(ref(2) - stepped.position_rad()) * rtc)
          ++count_mismatch;
      }
      ASSERT_EQ(sample, samples.size()) << "stretch " << s << ": samples past the steps taken";
      ASSERT_EQ(change, changes.size()) << "stretch " << s << ": a change noted that did not happen";
      ASSERT_EQ(h.big, last_big) << "stretch " << s;
      big_stops += last_big;
      if (counting && took < n - done) {
        ASSERT_TRUE(h.big) << "stretch " << s << ": hold_counting() stopped short without a big change";
        ++stops;
      } else if (took < n - done) {
        ASSERT_NE(held.encoder_count(), before)
            << "stretch " << s << ": hold() stopped without a count change";
        ++stops;
      }
      done += took;
      // Now and then the holds go on in another plant of the axis that
      // took the motion so far (as the co-simulation's plants held ahead
      // do): nothing of the run may stay behind.
      if (rng() % 8 == 0) {
        spare.take_motion(held);
        std::swap(held, spare);
        ++moved;
      }
      ASSERT_EQ(held.position_rad(), stepped.position_rad()) << "stretch " << s;
      ASSERT_EQ(held.speed_rad_s(), stepped.speed_rad_s()) << "stretch " << s;
      ASSERT_EQ(held.current_a(), stepped.current_a()) << "stretch " << s;
      ASSERT_EQ(held.stuck(), stepped.stuck()) << "stretch " << s;
    }
    worst = std::max({worst, std::fabs(ref(2) - stepped.position_rad()) / std::max(1.0, std::fabs(ref(2))),
                      std::fabs(ref(1) - stepped.speed_rad_s()) / std::max(1.0, std::fabs(ref(1)))});
  }
  std::printf(
      "%s, friction %d: %d stretches, %llu steps, %llu stops at a count change, %llu changes passed, "
      "%llu stops after a step of several counts, worst relative "
      "difference from the iterated ZOH %.2g, %llu steps with another count beyond rounding; "
      "hold() %.2f ns per step\n",
      cfg.motor.l_h > 1e-3 ? "complex poles" : "default axis", friction, stretches, (unsigned long long)total,
      (unsigned long long)stops, (unsigned long long)passed, (unsigned long long)big_stops, worst,
      (unsigned long long)count_mismatch, hold_s * 1e9 / double(total));
  EXPECT_GT(stops, 100u);
  EXPECT_GT(moved, 100u);
  EXPECT_GT(passed, 100u);  // hold_counting() went on through changes
  EXPECT_GE(big_stops, bigs);
  EXPECT_LT(worst, 1e-9);
  EXPECT_EQ(count_mismatch, 0u);
}

TEST(SimPlant, HoldTakesTheStepsStepWouldTake) {
  check_hold(default_x(), true, 1, 3000);
  check_hold(default_x(), false, 2, 3000);
  AxisConfig z = default_x();
  z.load_force_n = 60;  // a Z axis: gravity through the screw
  check_hold(z, true, 3, 3000);
  check_hold(complex_pole_axis(), true, 4, 1000);
  AxisConfig fine = default_x();
  fine.encoder_cpr = 1 << 24;  // many counts a step once the shaft moves
  check_hold(fine, true, 5, 1000, 100);
}

// Plants of the same discretization share their tables of powers, built
// once: an axis built while others live moves exactly as one built alone,
// whether its matrices are another's or not.
TEST(SimPlant, PlantsAliveTogetherMoveAsPlantsAlone) {
  const auto trajectory = [](AxisPlant& p) {
    std::vector<double> x;
    for (int k = 0; k < 6000; ++k) {
      p.step(k < 3000 ? 9.0 : -4.5);
      if (k % 7 == 0) x.insert(x.end(), {p.current_a(), p.speed_rad_s(), p.position_rad()});
    }
    return x;
  };
  AxisConfig z = default_x();
  z.load_force_n = 60;
  const std::vector<AxisConfig> cfgs = {default_x(), complex_pole_axis(), z, default_x()};
  std::vector<std::vector<double>> alone;
  for (const AxisConfig& c : cfgs) {
    AxisPlant p(c, 1e-6);
    alone.push_back(trajectory(p));
  }
  std::vector<AxisPlant> together;
  together.reserve(cfgs.size() + 1);
  for (const AxisConfig& c : cfgs) together.emplace_back(c, 1e-6);
  together.emplace_back(default_x(), 2e-6);  // another step: other tables
  for (size_t i = 0; i < cfgs.size(); ++i) EXPECT_EQ(trajectory(together[i]), alone[i]) << "axis " << i;
  // The different ones do move differently (the check can fail).
  EXPECT_NE(alone[0], alone[1]);
  EXPECT_NE(alone[0], alone[2]);
  AxisPlant slow(default_x(), 2e-6);
  EXPECT_EQ(trajectory(together.back()), trajectory(slow));
}

// The per-step cost, printed for docs/plant.md; not asserted (speed is never
// asserted in unit tests). What is asserted is the long run's physics: under
// a symmetric +-12 V square wave the axis settles into a periodic motion
// (the same state one period later) that is odd-symmetric (half a period
// later every state variable has the opposite sign), because the model and
// its friction are odd in the speed. 2 million steps: 50 periods of 40 ms.
TEST(SimPlant, StepCostAndSquareWaveSteadyState) {
  AxisPlant p(default_x(), 1e-6);
  const int n = 2000000, half = 20000;
  struct State {
    double i, w, theta;
  };
  const auto state = [&p] { return State{p.current_a(), p.speed_rad_s(), p.position_rad()}; };
  State period_start{}, mid{};
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < n; ++k) {
    if (k == n - 2 * half) period_start = state();
    if (k == n - half) mid = state();
    p.step((k / half) % 2 ? 12.0 : -12.0);
  }
  const auto t1 = std::chrono::steady_clock::now();
  const double ns = std::chrono::duration<double, std::nano>(t1 - t0).count() / n;
  std::printf("AxisPlant::step with friction: %.1f ns per step (%d steps)\n", ns, n);
  const State end = state();
  std::printf("last period: i %.6g -> %.6g -> %.6g A, w %.6g -> %.6g -> %.6g rad/s, stroke %.6g rad\n",
              period_start.i, mid.i, end.i, period_start.w, mid.w, end.w, mid.theta - period_start.theta);
  // The half period is 2.8 mechanical time constants: the motion reverses
  // at nearly full speed; each half period ends a net stroke away.
  ASSERT_GT(std::fabs(end.w), 100.0);
  const double stroke = mid.theta - period_start.theta;
  ASSERT_LT(stroke, -1.0);  // the first half of each period is at -12 V
  // Periodic: one period later, the same current and speed, no net travel.
  EXPECT_NEAR(end.i, period_start.i, 1e-9 * std::fabs(end.i));
  EXPECT_NEAR(end.w, period_start.w, 1e-9 * std::fabs(end.w));
  EXPECT_NEAR(end.theta - period_start.theta, 0.0, 1e-9 * std::fabs(stroke));
  // Odd: half a period later, the opposite current and speed, the stroke back.
  EXPECT_NEAR(mid.i, -end.i, 1e-9 * std::fabs(end.i));
  EXPECT_NEAR(mid.w, -end.w, 1e-9 * std::fabs(end.w));
  EXPECT_NEAR(end.theta - mid.theta, -stroke, 1e-9 * std::fabs(stroke));
}

// --- Encoder pins --------------------------------------------------------------

TEST(SimEncoder, GrayCodeAndIndex) {
  const QuadPins seq[4] = {
      {false, false, false}, {true, false, false}, {true, true, false}, {false, true, false}};
  for (int64_t c = -12; c <= 12; ++c) {
    const QuadPins p = quadrature_pins(c, 8);
    const QuadPins& w = seq[((c % 4) + 4) % 4];
    EXPECT_EQ(p.a, w.a) << c;
    EXPECT_EQ(p.b, w.b) << c;
    EXPECT_EQ(p.z, c % 8 == 0) << c;
    EXPECT_EQ(quadrature_pins(c, 6).z, c % 6 == 0) << c;  // a count per turn that is not a power of two
    EXPECT_FALSE(quadrature_pins(c, 0).z) << c;           // no index
    // Neighbouring counts differ in exactly one of A, B.
    const QuadPins n = quadrature_pins(c + 1, 8);
    EXPECT_EQ(int(p.a != n.a) + int(p.b != n.b), 1) << c;
  }
}

// Feeds pins through the decoder twin; `clocks` per count change.
class DecoderBench {
 public:
  explicit DecoderBench(uint32_t filt_len) { in_.filt_len = filt_len; }
  void apply(const QuadPins& p, int clocks) {
    in_.a = p.a;
    in_.b = p.b;
    in_.z = p.z;
    for (int k = 0; k < clocks; ++k) out_ = dec_.step(in_);
  }
  const QuadOut& out() const { return out_; }

 private:
  QuadDecoder<> dec_;
  QuadIn in_;
  QuadOut out_;
};

TEST(SimEncoder, RandomWalkRoundTripsThroughDecoderTwin) {
  std::mt19937_64 rng(4);
  for (const uint32_t filt : {0u, 3u}) {
    DecoderBench bench(filt);
    int64_t count = 0;
    // Synchronizer (2) + filter (filt) + output register: settle before reading.
    const int hold = int(filt) + 4;
    for (int k = 0; k < 20000; ++k) {
      count += (rng() & 1) ? 1 : -1;
      bench.apply(quadrature_pins(count, 2000), hold);
      ASSERT_EQ(bench.out().pos, count) << "step " << k << " filt " << filt;
      ASSERT_FALSE(bench.out().err) << k;
    }
  }
}

TEST(SimEncoder, PlantDirectionMatchesDecoder) {
  for (const double v : {24.0, -24.0}) {
    AxisPlant p(default_x(), 1e-6);
    DecoderBench bench(2);
    const int clocks_per_step = 12;  // 12 MHz core clock, 1 us plant step
    for (int k = 0; k < 20000; ++k) {
      p.step(v);
      bench.apply(quadrature_pins(p.encoder_count(), 2000), clocks_per_step);
    }
    bench.apply(quadrature_pins(p.encoder_count(), 2000), 8);
    EXPECT_EQ(bench.out().pos, p.encoder_count());
    EXPECT_FALSE(bench.out().err);
    EXPECT_GT(std::abs(p.encoder_count()), 100);
    EXPECT_EQ(p.encoder_count() > 0, v > 0);
  }
}

// --- Drive stages --------------------------------------------------------------

TEST(SimDrive, PwmQuantizationAndSign) {
  DriveConfig d = default_x().drive;
  ASSERT_EQ(d.kind, DriveConfig::Kind::Pwm);
  ASSERT_EQ(d.pwm_bits, 9);
  EXPECT_DOUBLE_EQ(d.pwm_hz, 12e6 / 512);
  const double lsb = d.supply_v / 512;
  EXPECT_EQ(drive_volts(d, 0), 0.0);
  EXPECT_EQ(drive_volts(d, 63), 0.0);  // below one PWM count: 63 >> 6 = 0
  EXPECT_DOUBLE_EQ(drive_volts(d, 64), lsb);
  EXPECT_DOUBLE_EQ(drive_volts(d, -64), -lsb);
  EXPECT_DOUBLE_EQ(drive_volts(d, 32767), 511 * lsb);  // a 9-bit counter is never high for all 512
  EXPECT_DOUBLE_EQ(drive_volts(d, 1 << 20), 511 * lsb);
  EXPECT_DOUBLE_EQ(drive_volts(d, -(1 << 20)), -511 * lsb);
  std::mt19937 rng(7);
  for (int k = 0; k < 10000; ++k) {
    const int32_t u = int32_t(rng() % 65535) - 32767;
    const double v = drive_volts(d, u);
    EXPECT_EQ(pwm_duty(d, u), std::abs(u) / 64);
    const int duty = std::abs(u) / 64;
    EXPECT_DOUBLE_EQ(v, (u < 0 ? -1 : 1) * duty * lsb);
    EXPECT_LE(std::fabs(v - u * d.supply_v / 32768), lsb);
  }
}

TEST(SimDrive, DacQuantizationAndSaturation) {
  DriveConfig d = default_x().drive;
  d.kind = DriveConfig::Kind::Dac;
  ASSERT_EQ(d.dac_bits, 12);
  const double step = 20.0 / 4096;
  EXPECT_EQ(drive_volts(d, 0), 0.0);
  EXPECT_EQ(drive_volts(d, 15), 0.0);  // 15 >> 4 = 0
  EXPECT_DOUBLE_EQ(drive_volts(d, 16), step * d.amp_gain);
  EXPECT_DOUBLE_EQ(drive_volts(d, -1), -step * d.amp_gain);  // floor: the top bits of a negative word
  EXPECT_DOUBLE_EQ(drive_volts(d, 32767), 2047 * step * d.amp_gain);
  EXPECT_DOUBLE_EQ(drive_volts(d, -32767), -2048 * step * d.amp_gain);
  std::mt19937 rng(8);
  for (int k = 0; k < 10000; ++k) {
    const int32_t u = int32_t(rng() % 65535) - 32767;
    const double dac = drive_volts(d, u) / d.amp_gain;
    const double code = dac / step;
    EXPECT_NEAR(code, std::round(code), 1e-9);
    EXPECT_EQ(int(std::lround(code)), int(std::floor(u / 16.0))) << u;
  }
  // A larger amplifier gain saturates at the supply.
  d.amp_gain = 10;
  EXPECT_EQ(drive_volts(d, 32767), d.supply_v);
  EXPECT_EQ(drive_volts(d, -32767), -d.supply_v);
  EXPECT_DOUBLE_EQ(drive_volts(d, 16 * 100), 100 * step * 10);
}

TEST(SimDrive, HostDacRoundsAndClamps) {
  const double step = 20.0 / 4096;
  EXPECT_EQ(dac_volts(12, 10, 0), 0.0);
  EXPECT_DOUBLE_EQ(dac_volts(12, 10, 0.49 * step), 0.0);
  EXPECT_DOUBLE_EQ(dac_volts(12, 10, 0.51 * step), step);
  EXPECT_DOUBLE_EQ(dac_volts(12, 10, -0.51 * step), -step);
  EXPECT_DOUBLE_EQ(dac_volts(12, 10, 3.0), std::round(3.0 / step) * step);
  EXPECT_DOUBLE_EQ(dac_volts(12, 10, 50), 10 - step);
  EXPECT_DOUBLE_EQ(dac_volts(12, 10, -50), -10);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> vd(-9.99, 9.99);
  for (int k = 0; k < 10000; ++k) {
    const double v = vd(rng);
    EXPECT_LE(std::fabs(dac_volts(12, 10, v) - v), step / 2 + 1e-12);
  }
}

// --- Closed loop with the default gains ----------------------------------------

// The Tustin PID in double precision, realized as the core realizes it
// (hls/pid_core.hpp: parallel form, conditional-integration anti-windup).
class RefPid {
 public:
  explicit RefPid(const PidConfig& c)
      : r_(mc::host::realization({c.kp, c.ki, c.kd, c.tf_s, c.ts_s, c.ff1, c.ff2})), lim_(c.out_limit) {}
  double step(double e) {
    const double ic = i_ + r_.ki * (e + e1_);
    d_ = r_.kd_a * d_ + r_.kd_b * (e - e1_);
    const double rest = r_.kp * e + d_, v = rest + ic;
    double in = ic;
    if (v > lim_) in = std::min(ic, std::max(lim_ - rest, i_));
    if (v < -lim_) in = std::max(ic, std::min(-lim_ - rest, i_));
    i_ = in;
    e1_ = e;
    return std::clamp(rest + i_, -lim_, lim_);
  }

 private:
  mc::host::Realization r_;
  double lim_, i_ = 0, d_ = 0, e1_ = 0;
};

struct StepResult {
  double overshoot, settle_s, final_err_counts;
};

StepResult closed_loop_step(const AxisConfig& cfg, double step_m) {
  AxisPlant p(cfg, 1e-6);
  RefPid pid(cfg.pid);
  const int64_t target = std::llround(step_m * counts_per_m(cfg));
  const int per_sample = int(std::lround(cfg.pid.ts_s / p.dt_s()));
  const double duration = 0.3;
  double peak = 0, settle = 0;
  const double band = 0.02 * double(target);
  for (int k = 0; k * cfg.pid.ts_s < duration; ++k) {
    const double e = double(target - p.encoder_count());
    const double u = pid.step(e);
    const double v = drive_volts(cfg.drive, int32_t(std::lround(u)));
    for (int s = 0; s < per_sample; ++s) p.step(v);
    const double pos = double(p.encoder_count());
    peak = std::max(peak, pos);
    if (std::fabs(pos - double(target)) > band) settle = p.time_s();
  }
  return {(peak - double(target)) / double(target), settle, double(target - p.encoder_count())};
}

// The default gains are the documented rule applied to the default axis
// (docs/plant.md), rounded to 4 digits in the file.
TEST(SimClosedLoop, DefaultGainsFollowTheDesignRule) {
  const AxisConfig cfg = default_x();
  const MotorParams& m = cfg.motor;
  const AxisPlant p(cfg, 1e-6);
  const double tau =
      m.r_ohm * p.inertia_kg_m2() / (m.kt_nm_per_a * m.ke_v_s_per_rad + m.r_ohm * m.b_nm_s_per_rad);
  // Steady speed per volt, times the drive and encoder gains: counts/s per drive unit.
  const double k = m.kt_nm_per_a / (m.kt_nm_per_a * m.ke_v_s_per_rad + m.r_ohm * m.b_nm_s_per_rad) *
                   cfg.drive.supply_v / 32767 * cfg.encoder_cpr / (2 * kPi);
  const double wc = 2 * kPi * 50, wi = wc / 3, kc = wc / k;
  std::printf(
      "rule: K = %.4g counts/s per drive unit, tau = %.4g ms, Kc = %.4g -> Kp %.4g Ki %.4g Kd %.4g Tf %.4g "
      "us\n",
      k, 1e3 * tau, kc, kc * (1 + wi * tau), kc * wi, kc * tau, 1e6 / (10 * wc));
  EXPECT_NEAR(cfg.pid.kp, kc * (1 + wi * tau), 5e-4 * cfg.pid.kp);
  EXPECT_NEAR(cfg.pid.ki, kc * wi, 5e-4 * cfg.pid.ki);
  EXPECT_NEAR(cfg.pid.kd, kc * tau, 5e-4 * cfg.pid.kd);
  EXPECT_NEAR(cfg.pid.tf_s, 1 / (10 * wc), 5e-4 * cfg.pid.tf_s);
  EXPECT_EQ(cfg.pid.ts_s, 1e-4);

  // The ideal loop of the rule: L(s) = wc (s + wi) / s^2 after the D zero
  // cancels the mechanical pole, so T(s) = wc (s + wi) / (s^2 + wc s + wc wi).
  // Its step response, by partial fractions over the (complex) poles.
  const cplx disc = std::sqrt(cplx(wc * wc - 4 * wc * wi));
  const cplx p1 = (-wc + disc) / 2.0, p2 = (-wc - disc) / 2.0;
  const cplx r1 = wc * (p1 + wi) / (p1 * (p1 - p2)), r2 = wc * (p2 + wi) / (p2 * (p2 - p1));
  const auto ideal = [&](double t) { return 1 + (r1 * std::exp(p1 * t) + r2 * std::exp(p2 * t)).real(); };

  // The loop as configured: the default gains (Tustin, at Ts, with the D
  // filter Tf) on the linear plant (its electrical pole and all), driven
  // through the linearized drive (supply_v / 32767 V per drive unit) and
  // measured without quantization. A unit step keeps the drive far from
  // saturation, so the loop is linear and comparable with T(s).
  AxisPlant lin(cfg, 1e-6);
  lin.set_friction(false);
  RefPid pid(cfg.pid);
  const double counts_per_rad = cfg.encoder_cpr / (2 * kPi);
  const int per_sample = int(std::lround(cfg.pid.ts_s / lin.dt_s()));
  double peak = 0, settle = 0, worst = 0, peak_ideal = 0, settle_ideal = 0;
  for (int n = 0; n * cfg.pid.ts_s < 0.2; ++n) {
    const double u = pid.step(1.0 - lin.position_rad() * counts_per_rad);
    ASSERT_LT(std::fabs(u), 0.5 * cfg.pid.out_limit) << "saturated: not the linear loop";
    for (int s = 0; s < per_sample; ++s) lin.step(u * cfg.drive.supply_v / 32767);
    const double t = lin.time_s(), y = lin.position_rad() * counts_per_rad, yi = ideal(t);
    peak = std::max(peak, y);
    peak_ideal = std::max(peak_ideal, yi);
    if (std::fabs(y - 1) > 0.02) settle = t;
    if (std::fabs(yi - 1) > 0.02) settle_ideal = t;
    // After the rise: the first milliseconds differ by the lags T(s) leaves out.
    if (t > 0.01) worst = std::max(worst, std::fabs(y - yi));
  }
  std::printf(
      "ideal loop of the rule: overshoot %.1f %%, 2 %% settling %.1f ms; default gains on the linear plant: "
      "%.1f %%, %.1f ms; largest difference after 10 ms %.4f of the step\n",
      100 * (peak_ideal - 1), 1e3 * settle_ideal, 100 * (peak - 1), 1e3 * settle, worst);
  // docs/plant.md quotes the ideal figures; the configured loop must be that loop,
  // up to what sampling at Ts, the D filter and the electrical pole add.
  EXPECT_NEAR(peak - 1, peak_ideal - 1, 0.02);
  EXPECT_NEAR(settle, settle_ideal, 0.1 * settle_ideal);
  EXPECT_LT(worst, 0.03);
}

TEST(SimClosedLoop, DefaultGainsSettleA1mmStep) {
  for (const char* name : {"x", "y"}) {
    const AxisConfig cfg = axis(default_machine(), name);
    const StepResult r = closed_loop_step(cfg, 1e-3);
    std::printf("axis %s, 1 mm step: overshoot %.1f %%, 2 %% settling %.1f ms, final error %.0f counts\n",
                name, 100 * r.overshoot, 1e3 * r.settle_s, r.final_err_counts);
    // docs/plant.md: the ideal loop of the design rule (wc = 2 pi 50 Hz,
    // wi = wc/3) overshoots 16.3 % and enters the 2 % band at 28.5 ms; the
    // derivative kick of a 1 mm step saturates the drive for about 1 ms and
    // stiction ends the approach, which the measured 20.5 % / 42.8 ms show.
    // The bounds leave room for that and fail on a loop that rings or creeps.
    EXPECT_LT(r.overshoot, 0.25);
    EXPECT_LT(r.settle_s, 0.05);
    EXPECT_LE(std::fabs(r.final_err_counts), 2);
  }
}

}  // namespace
}  // namespace mc::sim
