#include "host/control/tuning.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>

#include "hls/pid_core.hpp"
#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"

namespace mc::host {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require_positive(const char* name, double v, const char* expected) {
  if (!std::isfinite(v) || !(v > 0)) throw InputError(name, format_number(v), expected);
}

void require_finite(const char* name, const std::vector<double>& x) {
  for (size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw InputError(std::string(name) + "[" + std::to_string(i) + "]", format_number(x[i]),
                       "a finite sample");
}

double sgn(double x) {
  return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0);
}

}  // namespace

// --- Relay feedback -----------------------------------------------------------

Relay::Relay(double d, double eps) : d_(d), eps_(eps), out_(d) {
  require_positive("relay amplitude", d, "a finite amplitude > 0 drive units");
  if (!std::isfinite(eps) || eps < 0)
    throw InputError("relay hysteresis", format_number(eps), "a finite hysteresis >= 0 counts");
}

double Relay::update(double error) {
  if (error > eps_) out_ = d_;
  if (error < -eps_) out_ = -d_;
  return out_;
}

RelayResult relay_analyse(const std::vector<double>& y, double ts, double d, double eps) {
  require_positive("ts", ts, "a finite sample period > 0 s");
  require_positive("relay amplitude", d, "a finite amplitude > 0 drive units");
  if (!std::isfinite(eps) || eps < 0)
    throw InputError("relay hysteresis", format_number(eps), "a finite hysteresis >= 0 counts");
  require_finite("relay capture", y);
  if (y.size() < 32)
    throw InputError("relay capture", std::to_string(y.size()) + " samples", "at least 32 samples");

  // Centre and half range from the second half, which is past the transient.
  const auto half = y.begin() + std::ptrdiff_t(y.size() / 2);
  const auto [lo, hi] = std::minmax_element(half, y.end());
  const double centre = 0.5 * (*lo + *hi), arm = 0.25 * 0.5 * (*hi - *lo);

  // Rising crossings of the centre, interpolated. A crossing counts only
  // after the signal has been a quarter amplitude below the centre, so
  // noise and encoder steps at the centre cannot add short periods.
  std::vector<double> up;
  bool armed = false;
  for (size_t i = 1; i < y.size(); ++i) {
    if (y[i - 1] < centre - arm) armed = true;
    if (armed && y[i - 1] < centre && y[i] >= centre) {
      up.push_back(ts * (double(i - 1) + (centre - y[i - 1]) / (y[i] - y[i - 1])));
      armed = false;
    }
  }
  const int all_periods = int(up.size()) - 1;
  const int skip = std::max(1, all_periods / 3);
  const int periods = all_periods - skip;
  if (periods < 3)
    throw InputError("relay capture", std::to_string(std::max(all_periods, 0)) + " oscillation periods",
                     "at least 4 (the first third is skipped as transient, 3 must remain)",
                     "capture longer or check that the relay makes the axis oscillate");

  RelayResult r{};
  r.periods = periods;
  const double t_a = up[size_t(skip)], t_b = up.back();
  r.tu = (t_b - t_a) / periods;
  double pmin = r.tu, pmax = r.tu;
  for (size_t i = size_t(skip) + 1; i < up.size(); ++i) {
    pmin = std::min(pmin, up[i] - up[i - 1]);
    pmax = std::max(pmax, up[i] - up[i - 1]);
  }
  r.period_spread = (pmax - pmin) / r.tu;
  if (r.tu < 4 * ts)
    throw InputError("relay period", format_number(r.tu) + " s",
                     "at least 4 samples (" + format_number(4 * ts) + " s)",
                     "the oscillation is too fast for the sample period");

  // The describing function of the relay sees only the first harmonic of
  // its input: fit offset + cos + sin at 2 pi / Tu over the settled periods.
  const double w = 2 * kPi / r.tu;
  const auto k_a = size_t(std::ceil(t_a / ts)), k_b = size_t(std::floor(t_b / ts));
  Eigen::MatrixXd a(Eigen::Index(k_b - k_a + 1), 3);
  Eigen::VectorXd b(a.rows());
  for (size_t k = k_a; k <= k_b; ++k) {
    const auto row = Eigen::Index(k - k_a);
    const double t = double(k) * ts;
    a.row(row) << 1.0, std::cos(w * t), std::sin(w * t);
    b(row) = y[k];
  }
  const Eigen::Vector3d c = a.colPivHouseholderQr().solve(b);
  r.amplitude = std::hypot(c(1), c(2));
  if (!(r.amplitude > eps))
    throw InputError("relay amplitude", format_number(r.amplitude) + " counts",
                     "an oscillation larger than the hysteresis " + format_number(eps) + " counts",
                     "raise the relay amplitude");
  // -1/N(a) = -(pi / 4d) (sqrt(a^2 - eps^2) + j eps): the loop point found
  // lies eps' worth below the real axis. Its real part gives Ku.
  r.ku = 4 * d / (kPi * std::sqrt(r.amplitude * r.amplitude - eps * eps));
  r.phase_deg = -180 + std::asin(eps / r.amplitude) * 180 / kPi;
  return r;
}

PidGains design_relay(const RelayResult& r, double ts, RelayRule rule, double n_filter) {
  require_positive("ku", r.ku, "a finite ultimate gain > 0");
  require_positive("tu", r.tu, "a finite ultimate period > 0 s");
  require_positive("ts", ts, "a finite sample period > 0 s");
  require_positive("derivative filter ratio", n_filter, "a finite ratio Td/Tf > 0");
  double kp = 0, ti = 0, td = 0;
  switch (rule) {
    case RelayRule::ZieglerNichols:
      kp = 0.6 * r.ku, ti = r.tu / 2, td = r.tu / 8;
      break;
    case RelayRule::TyreusLuyben:
      kp = r.ku / 2.2, ti = 2.2 * r.tu, td = r.tu / 6.3;
      break;
    case RelayRule::NoOvershoot:
      kp = 0.2 * r.ku, ti = r.tu / 2, td = r.tu / 3;
      break;
  }
  PidGains g{};
  g.kp = kp;
  g.ki = kp / ti;
  g.kd = kp * td;
  g.tf = std::max(td / n_filter, ts);
  g.ts = ts;
  return g;
}

// --- Excitation ---------------------------------------------------------------

std::vector<double> prbs(double amplitude, double bit_s, double duration_s, double ts, bool balanced) {
  require_positive("excitation amplitude", amplitude, "a finite amplitude > 0 drive units");
  require_positive("ts", ts, "a finite sample period > 0 s");
  require_positive("PRBS bit time", bit_s, "a finite bit time > 0 s");
  require_positive("excitation duration", duration_s, "a finite duration > 0 s");
  const auto per_bit = std::max<long>(1, std::lround(bit_s / ts));
  const auto n = size_t(std::llround(duration_s / ts));
  std::vector<double> u;
  u.reserve(n);
  // x^10 + x^7 + 1, a primitive polynomial: the state runs through all 1023
  // nonzero values.
  uint32_t lfsr = 1;
  double level = 0;
  for (size_t bit = 0; u.size() < n; ++bit) {
    if (!balanced || bit % 2 == 0) {
      level = (lfsr & 1) ? amplitude : -amplitude;
      const uint32_t fb = (lfsr ^ (lfsr >> 3)) & 1;
      lfsr = (lfsr >> 1) | (fb << 9);
    } else {
      level = -level;
    }
    for (long s = 0; s < per_bit && u.size() < n; ++s) u.push_back(level);
  }
  return u;
}

std::vector<double> multisine(double amplitude, double f_lo_hz, double f_hi_hz, int tones, double duration_s,
                              double ts) {
  require_positive("excitation amplitude", amplitude, "a finite amplitude > 0 drive units");
  require_positive("ts", ts, "a finite sample period > 0 s");
  require_positive("excitation duration", duration_s, "a finite duration > 0 s");
  require_positive("lowest frequency", f_lo_hz, "a finite frequency > 0 Hz");
  if (!std::isfinite(f_hi_hz) || !(f_hi_hz >= f_lo_hz) || !(f_hi_hz < 0.5 / ts))
    throw InputError("highest frequency", format_number(f_hi_hz) + " Hz",
                     "from the lowest frequency up to below Nyquist, " + format_number(0.5 / ts) + " Hz");
  if (tones < 1 || tones > 1000) throw InputError("tones", std::to_string(tones), "1 to 1000 tones");
  const auto n = size_t(std::llround(duration_s / ts));
  std::vector<double> u(n, 0.0);
  for (int k = 0; k < tones; ++k) {
    const double f0 = tones == 1 ? f_lo_hz : f_lo_hz * std::pow(f_hi_hz / f_lo_hz, double(k) / (tones - 1));
    const double f = std::max(1.0, std::round(f0 * duration_s)) / duration_s;
    // Schroeder's phases keep the crest factor low: more power per peak.
    const double phase = -kPi * k * (k - 1) / tones;
    for (size_t i = 0; i < n; ++i) u[i] += std::cos(2 * kPi * f * double(i) * ts + phase);
  }
  double peak = 0;
  for (double x : u) peak = std::max(peak, std::fabs(x));
  for (double& x : u) x *= amplitude / peak;
  return u;
}

// --- Identification -----------------------------------------------------------

namespace {

// The velocity equation v(k) = sum_{i=1..na} a_i v(k-i) + sum_{i=1..na+1}
// b_i u(k-i) [+ c dir(k-1)], with v(k) = y(k) - y(k-1) (the ZOH of a plant
// with na velocity lags and an integrator has na + 1 input terms) and dir the measured
// direction of motion (see directions()): a fixed regressor, so that the
// friction term keeps the fits linear and smooth in the parameters.
struct VelocityArx {
  size_t na;
  bool coulomb;
  Eigen::VectorXd theta;  // a_1..a_na, b_1..b_(na+1), [c]

  static Eigen::Index size(size_t na, bool coulomb) { return Eigen::Index(2 * na + 1 + (coulomb ? 1 : 0)); }
  Eigen::Index cols() const { return size(na, coulomb); }
  size_t first() const { return na + 1; }  // the first row: u(k - na - 1) exists
  double a(size_t i) const { return theta(Eigen::Index(i - 1)); }
  double b(size_t i) const { return theta(Eigen::Index(na + i - 1)); }
  double c() const { return coulomb ? theta(cols() - 1) : 0.0; }

  const std::vector<double>* dir = nullptr;

  // Regressor rows k = na+1 .. n-1 from the velocities vel.
  Eigen::MatrixXd regressors(const std::vector<double>& u, const std::vector<double>& vel) const {
    Eigen::MatrixXd m(Eigen::Index(u.size() - first()), cols());
    for (size_t k = first(); k < u.size(); ++k) {
      const auto r = Eigen::Index(k - first());
      for (size_t i = 1; i <= na; ++i) m(r, Eigen::Index(i - 1)) = vel[k - i];
      for (size_t i = 1; i <= na + 1; ++i) m(r, Eigen::Index(na + i - 1)) = u[k - i];
      if (coulomb) m(r, cols() - 1) = (*dir)[k - 1];
    }
    return m;
  }

  // The model's own noise-free velocities, driven by u from v's first samples.
  std::vector<double> simulate(const std::vector<double>& u, const std::vector<double>& v) const {
    std::vector<double> vs(v.begin(), v.begin() + std::ptrdiff_t(na + 1));
    vs.resize(u.size());
    for (size_t k = first(); k < u.size(); ++k) {
      double acc = coulomb ? c() * (*dir)[k - 1] : 0.0;
      for (size_t i = 1; i <= na; ++i) acc += a(i) * vs[k - i];
      for (size_t i = 1; i <= na + 1; ++i) acc += b(i) * u[k - i];
      vs[k] = acc;
    }
    return vs;
  }

  bool stable() const {
    // The roots of z^2 - a1 z - a2 (z - a1 for one pole) inside the unit circle.
    const double a1 = a(1), a2 = na == 2 ? a(2) : 0.0;
    return std::fabs(a2) < 1 && std::fabs(a1) < 1 - a2;
  }
};

std::vector<double> differences(const std::vector<double>& y) {
  std::vector<double> v(y.size(), 0.0);
  for (size_t k = 1; k < y.size(); ++k) v[k] = y[k] - y[k - 1];
  return v;
}

// The sign of the motion over the last 4 samples: steadier than one
// sample's difference of a quantized position.
std::vector<double> directions(const std::vector<double>& y) {
  std::vector<double> d(y.size(), 0.0);
  for (size_t k = 1; k < y.size(); ++k) d[k] = sgn(y[k] - y[k >= 4 ? k - 4 : 0]);
  return d;
}

Eigen::VectorXd targets(const std::vector<double>& v, size_t na) {
  Eigen::VectorXd t(Eigen::Index(v.size() - na - 1));
  for (size_t k = na + 1; k < v.size(); ++k) t(Eigen::Index(k - na - 1)) = v[k];
  return t;
}

// Ordinary least squares; throws InputError when the drive does not excite
// every parameter.
VelocityArx least_squares(const std::vector<double>& u, const std::vector<double>& v, size_t na, bool coulomb,
                          const std::vector<double>& dir) {
  VelocityArx m{na, coulomb, {}, &dir};
  const Eigen::MatrixXd phi = m.regressors(u, v);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(phi);
  if (qr.rank() < m.cols())
    throw InputError("excitation capture",
                     "rank " + std::to_string(qr.rank()) + " of " + std::to_string(m.cols()),
                     "a drive signal that excites the axis (not constant, the axis moving)");
  m.theta = qr.solve(targets(v, na));
  return m;
}

}  // namespace

AxisModel identify(const std::vector<double>& u, const std::vector<double>& y, double ts, bool coulomb,
                   bool fast_pole) {
  require_positive("ts", ts, "a finite sample period > 0 s");
  if (u.size() != y.size())
    throw InputError(
        "excitation capture",
        std::to_string(u.size()) + " drive and " + std::to_string(y.size()) + " position samples",
        "as many drive as position samples");
  if (u.size() < 40)
    throw InputError("excitation capture", std::to_string(u.size()) + " samples", "at least 40 samples");
  require_finite("drive", u);
  require_finite("position", y);
  const std::vector<double> v = differences(y);

  // Stage 1, a one-pole model on decimated data. At the full rate the axis
  // moves a few counts per sample, and the encoder's +-1 count in v(k-1)
  // biases least squares badly (tau comes out several times too short).
  // Decimated until the typical move per sample is 30 counts (or at most to
  // 100 rows), the quantization is a small error in a large signal. The drive
  // is averaged over each decimated sample: exact for a PRBS whose bits are
  // whole multiples of the factor.
  double ms = 0;
  for (double x : v) ms += x * x;
  const double rms_move = std::sqrt(ms / double(v.size() - 1));
  const size_t max_factor = std::max<size_t>(1, u.size() / 100);
  const size_t factor = std::min(max_factor, size_t(std::ceil(30 / std::max(rms_move, 1e-9))));
  const std::vector<double> dir = directions(y);
  // A factor that happens to alias with the excitation (a balanced PRBS whose
  // bit is the factor: the averaged drive just alternates) leaves the
  // regression singular; halve it until the fit is a stable axis.
  VelocityArx coarse{1, coulomb, {}, nullptr};
  std::vector<double> dird;
  double td = ts, pd = 0;
  for (size_t f = factor;; f = f / 2) {
    std::vector<double> ud, yd;
    for (size_t j = 0; (j + 1) * f <= u.size(); ++j) {
      double sum = 0;
      for (size_t i = 0; i < f; ++i) sum += u[j * f + i];
      ud.push_back(sum / double(f));
      yd.push_back(y[j * f]);
    }
    dird = directions(yd);
    try {
      coarse = least_squares(ud, differences(yd), 1, coulomb, dird);
    } catch (const InputError&) {
      if (f <= 1) throw;
      continue;
    }
    td = ts * double(f);
    pd = coarse.a(1);
    const bool ok = pd > 0 && pd < 1 && coarse.b(1) + coarse.b(2) > 0;
    if (ok) break;
    if (f <= 1)
      throw InputError(
          "identified velocity pole", "p = " + format_number(pd) + " at " + format_number(td) + " s",
          "0 < p < 1 and a positive gain (a stable DC-motor axis, drive and encoder in the same sense)",
          "the capture does not fit K/(s (tau s + 1))");
  }
  const double tau1 = -td / std::log(pd), k1 = (coarse.b(1) + coarse.b(2)) / (td * (1 - pd));

  // Stage 2, one pole at the full rate by instrumental variables: the
  // regressors recomputed from the current model's noise-free simulation are
  // correlated with the true velocity but not with the quantization noise.
  VelocityArx one{1, coulomb, Eigen::VectorXd(VelocityArx::size(1, coulomb)), &dir};
  {
    // The stage-1 model's K, tau and friction at ts (the exact ZOH).
    const double p = std::exp(-ts / tau1);
    one.theta(0) = p;
    one.theta(1) = k1 * (ts - tau1 * (1 - p));
    one.theta(2) = k1 * (tau1 * (1 - p) - ts * p);
    if (coulomb) one.theta(3) = coarse.c() / (coarse.b(1) + coarse.b(2)) * k1 * ts * (1 - p);
    const Eigen::MatrixXd phi = one.regressors(u, v);
    const Eigen::VectorXd tgt = targets(v, 1);
    for (int iter = 0; iter < 5; ++iter) {
      const Eigen::MatrixXd z = one.regressors(u, one.simulate(u, v));
      Eigen::FullPivLU<Eigen::MatrixXd> lu(z.transpose() * phi);
      if (!lu.isInvertible()) break;
      VelocityArx next{1, coulomb, lu.solve(z.transpose() * tgt), &dir};
      if (!next.stable()) break;
      one = next;
    }
  }

  // Stage 3, output error: the parameters whose simulated position fits the
  // measured one best (Levenberg-Marquardt, each step a linear least-squares
  // solve). For white measurement noise such as the encoder's quantization
  // this is the maximum-likelihood fit, and it sees the second (electrical)
  // pole that a one-pole equation-error fit turns into a biased tau.
  const size_t na = fast_pole ? 2 : 1;
  VelocityArx m{na, coulomb, Eigen::VectorXd::Zero(VelocityArx::size(na, coulomb)), &dir};
  m.theta(0) = one.a(1);
  m.theta(Eigen::Index(na)) = one.b(1);
  m.theta(Eigen::Index(na + 1)) = one.b(2);
  if (coulomb) m.theta(m.cols() - 1) = one.c();
  const auto residual = [&](const VelocityArx& mm) -> Eigen::VectorXd {
    const std::vector<double> vs = mm.simulate(u, v);
    Eigen::VectorXd r(Eigen::Index(y.size()));
    double pos = y[0];
    r(0) = 0;
    for (size_t k = 1; k < y.size(); ++k) {
      pos += vs[k];
      r(Eigen::Index(k)) = y[k] - pos;
    }
    return r;
  };
  Eigen::VectorXd r = residual(m);
  double cost = r.squaredNorm(), lambda = 1e-3;
  Eigen::MatrixXd jac(r.size(), m.cols());
  for (int iter = 0; iter < 60 && lambda < 1e10; ++iter) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      VelocityArx mj = m;
      const double h = 1e-6 * std::max(std::fabs(m.theta(j)), 1e-6);
      mj.theta(j) += h;
      jac.col(j) = (residual(mj) - r) / h;  // d r / d theta
    }
    const Eigen::MatrixXd jtj = jac.transpose() * jac;
    const Eigen::VectorXd jtr = jac.transpose() * r;
    bool improved = false;
    while (lambda < 1e10) {
      Eigen::MatrixXd lhs = jtj;
      lhs.diagonal() *= 1 + lambda;
      VelocityArx next{na, coulomb, m.theta - lhs.ldlt().solve(jtr), &dir};
      if (next.stable()) {
        const Eigen::VectorXd rn = residual(next);
        if (rn.squaredNorm() < cost) {
          const double gain = cost - rn.squaredNorm();
          m = next;
          r = rn;
          cost = r.squaredNorm();
          lambda = std::max(lambda / 10, 1e-9);
          improved = gain > 1e-12 * cost;
          break;
        }
      }
      lambda *= 10;
    }
    if (!improved) break;
  }

  // Velocity poles: the roots of z^2 - a1 z - a2 (z - a1 for one pole).
  const double a1 = m.a(1), a2 = na == 2 ? m.a(2) : 0.0;
  double bsum = 0;
  for (size_t i = 1; i <= na + 1; ++i) bsum += m.b(i);
  const double disc = a1 * a1 + 4 * a2;
  const double p_slow = disc >= 0 ? 0.5 * (a1 + std::sqrt(disc)) : std::nan("");
  const double p_fast = disc >= 0 ? 0.5 * (a1 - std::sqrt(disc)) : std::nan("");
  if (!(p_slow > 0 && p_slow < 1) || !(bsum > 0))
    throw InputError(
        "identified velocity pole", "p = " + format_number(p_slow) + ", gain sum " + format_number(bsum),
        "0 < p < 1 and a positive gain (a stable DC-motor axis, drive and encoder in the same sense)",
        "the capture does not fit K/(s (tau s + 1))");
  AxisModel am{};
  am.ts = ts;
  // The fast pole (the electrical L/R, a drive's lag) only when it is a real
  // positive one; a pole at or below 0 in z has no continuous counterpart
  // and stands for less than a sample of lag.
  am.tau_fast = p_fast > 0 ? -ts / std::log(p_fast) : 0.0;
  // K/(s (tau s + 1)) with tau the sum of the time constants: the same
  // low-frequency behaviour (s and s^2 terms) as the two-pole plant, and
  // exactly R J / (Kt Ke) for a DC motor (docs/plant.md).
  am.tau = -ts / std::log(p_slow) + am.tau_fast;
  am.k = bsum / (ts * (1 - a1 - a2));
  // c = -(sum b) f: the friction as a drive offset opposing the motion.
  am.coulomb = coulomb ? std::max(0.0, -m.c() / bsum) : 0.0;
  am.fit_rms = std::sqrt(cost / double(y.size()));
  am.samples = int(y.size());
  return am;
}

// --- Design and prediction ----------------------------------------------------

PidGains design_model(const AxisModel& m, double wc, double zeta, double n) {
  require_positive("model gain K", m.k, "a finite gain > 0 counts/s per drive unit");
  require_positive("model tau", m.tau, "a finite time constant > 0 s");
  require_positive("model ts", m.ts, "a finite sample period > 0 s");
  require_positive("bandwidth wc", wc, "a finite closed-loop bandwidth > 0 rad/s");
  require_positive("damping zeta", zeta, "a finite damping > 0");
  require_positive("real pole ratio n", n, "a finite ratio > 0");
  // The characteristic polynomial, divided by tau Tf,
  //   s^4 + (1/tau + 1/Tf) s^3 + (1 + K (Kp Tf + Kd))/(tau Tf) s^2
  //       + K (Kp + Ki Tf)/(tau Tf) s + K Ki/(tau Tf),
  // matched term by term to (s^2 + 2 zeta wc s + wc^2)(s + n wc)^2
  //   = s^4 + c3 s^3 + c2 s^2 + c1 s + c0:
  // c3 fixes Tf, then c0 gives Ki, c1 Kp, c2 Kd.
  const double w2 = wc * wc;
  const double c3 = 2 * (zeta + n) * wc;
  const double c2 = w2 * (1 + 4 * zeta * n + n * n);
  const double c1 = 2 * n * wc * w2 * (1 + zeta * n);
  const double c0 = n * n * w2 * w2;
  const double inv_tf = c3 - 1 / m.tau;
  if (!(inv_tf > 0))
    throw InputError("bandwidth wc", format_number(wc) + " rad/s",
                     "2 (zeta + n) wc > 1/tau = " + format_number(1 / m.tau) + " rad/s",
                     "slower than the axis itself: no derivative filter places these poles");
  const double tf = 1 / inv_tf, tt = m.tau * tf;
  PidGains g{};
  g.ts = m.ts;
  g.tf = tf;
  g.ki = c0 * tt / m.k;
  g.kp = c1 * tt / m.k - g.ki * tf;
  g.kd = (c2 * tt - 1) / m.k - g.kp * tf;
  if (g.kp < 0 || g.kd < 0)
    throw InputError("bandwidth wc", format_number(wc) + " rad/s",
                     "a bandwidth the PID reaches with Kp, Kd >= 0 (got Kp " + format_number(g.kp) + ", Kd " +
                         format_number(g.kd) + ")");
  if (tf < m.ts / 2)
    throw InputError("bandwidth wc", format_number(wc) + " rad/s",
                     "a derivative filter Tf >= Ts/2 (got " + format_number(tf) + " s at Ts " +
                         format_number(m.ts) + " s)",
                     "too fast for the sample period");
  return g;
}

double max_bandwidth(double ts) {
  return kPi / ts;
}

double check_bandwidth(double wc, double ts, std::string_view quantity, std::string_view as_written) {
  if (!(wc > 0))
    throw InputError(std::string(quantity), as_written.empty() ? format_number(wc) : quote(as_written),
                     "rad/s above 0");
  return require_in(wc, Bounds{0, max_bandwidth(ts), "rad/s"}, quantity, as_written,
                    "the Nyquist frequency pi/Ts at the board's Ts " + format_duration(ts));
}

double default_bandwidth(const AxisModel& m) {
  require_positive("model tau", m.tau, "a finite time constant > 0 s");
  require_positive("model ts", m.ts, "a finite sample period > 0 s");
  // Three times the mechanical corner 1/tau: a loop much slower than the
  // axis' own lag gains nothing from the D term, and a much faster one asks
  // for drive peaks that grow as (wc tau)^2 and meets what the model leaves
  // out (the electrical lag, the PWM's 64-unit steps, stiction): on the
  // default axis, prediction and true plant agree at 3/tau and part above
  // about 4/tau (the true overshoot grows past 10 % while the predicted one
  // does not). Capped by the sample period (Ts at most 1/40 of the
  // closed-loop period, so that the Tustin controller is close to C(s)) and
  // by an identified fast lag (wc tau_fast <= 1/4, 14 deg of phase at most).
  double wc = std::min(3.0 / m.tau, 2 * kPi / (40 * m.ts));
  if (m.tau_fast > 0) wc = std::min(wc, 0.25 / m.tau_fast);
  return wc;
}

Prediction predict_step(const AxisModel& m, const PidGains& g, double step, double duration_s,
                        double out_limit) {
  require_positive("model gain K", m.k, "a finite gain > 0 counts/s per drive unit");
  require_positive("model tau", m.tau, "a finite time constant > 0 s");
  require_positive("step duration", duration_s, "a finite duration > 0 s");
  if (!std::isfinite(step) || step == 0 || std::fabs(step) > 1e9)
    throw InputError("step size", format_number(step), "a nonzero step of at most 1e9 counts");
  if (!std::isfinite(out_limit) || !(out_limit >= 1) || out_limit > 32767)
    throw InputError("output limit", format_number(out_limit), "1 to 32767 drive units");
  const PidDesign d = design(g);
  CoreLimits lim;
  lim.out_limit = uint32_t(std::lround(out_limit));
  const mc::PidParams par = core_params(d, lim);
  mc::PidState st;

  // The model over one sample with the drive held: v -> w + (v - w) p,
  // x -> x + w ts + (v - w) tau (1 - p), w = K (u - f sgn) the speed it tends to.
  const double ts = g.ts, p = std::exp(-ts / m.tau), f = m.coulomb;
  const auto cmd = int32_t(std::lround(step));
  double x = 0, v = 0;
  Prediction pr;
  const auto n = size_t(std::llround(duration_s / ts)) + 1;
  pr.t.reserve(n);
  pr.y.reserve(n);
  pr.u.reserve(n);
  for (size_t k = 0; k < n; ++k) {
    const auto fb = int32_t(std::floor(x));
    const double u = pid_axis_update(par, st, true, cmd, fb).u;
    pr.t.push_back(double(k) * ts);
    pr.y.push_back(double(fb));
    pr.u.push_back(u);
    if (v == 0 && std::fabs(u) <= f) continue;  // friction holds the axis
    const double dir = v != 0 ? sgn(v) : sgn(u);
    const double w = m.k * (u - f * dir);
    const double v_next = w + (v - w) * p;
    if (f > 0 && v_next * dir < 0) {
      // Friction stops the axis within the sample; it does not reverse it.
      const double t_stop = m.tau * std::log((v - w) / -w);
      x += w * t_stop + (v - w) * m.tau * (1 - std::exp(-t_stop / m.tau));
      v = 0;
    } else {
      x += w * ts + (v - w) * m.tau * (1 - p);
      v = v_next;
    }
  }
  pr.metrics = step_metrics(pr.t, pr.y, 0, double(cmd), 0);
  return pr;
}

}  // namespace mc::host
