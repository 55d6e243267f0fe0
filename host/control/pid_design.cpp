#include "host/control/pid_design.hpp"

#include <cmath>
#include <string>

#include "hls/pid_regs.hpp"
#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"

namespace mc::host {
namespace {

void require_finite(const char* name, double v, const char* expected) {
  if (!std::isfinite(v)) throw InputError(name, format_number(v), expected, "not finite");
}

void require_gain(const char* name, double v) {
  const std::string expected = std::string(name) +
                               " >= 0 (the loop sign is set by the drive and encoder wiring, "
                               "not by the gains)";
  require_finite(name, v, expected.c_str());
  if (v < 0) throw InputError(name, format_number(v), expected, "negative gains are rejected");
}

}  // namespace

void validate(const PidGains& g) {
  constexpr const char* ts_expected = "a finite sample period > 0 s";
  require_finite("ts", g.ts, ts_expected);
  if (!(g.ts > 0)) throw InputError("ts", format_number(g.ts), ts_expected);
  constexpr const char* tf_expected = "a finite derivative filter time constant >= 0 s (0: no filter)";
  require_finite("tf", g.tf, tf_expected);
  if (g.tf < 0) throw InputError("tf", format_number(g.tf), tf_expected);
  require_gain("kp", g.kp);
  require_gain("ki", g.ki);
  require_gain("kd", g.kd);
  require_finite("ff1", g.ff1, "a finite velocity feedforward gain");
  require_finite("ff2", g.ff2, "a finite acceleration feedforward gain");
}

Realization realization(const PidGains& g) {
  const double den = 2 * g.tf + g.ts;
  return Realization{g.kp,           g.ki * g.ts / 2, (2 * g.tf - g.ts) / den,
                     2 * g.kd / den, g.ff1 / g.ts,    g.ff2 / (g.ts * g.ts)};
}

// Over the common denominator (1 - z^-1)(1 - alpha z^-1) of the three branches
//   Kp + kiT (1 + z^-1)/(1 - z^-1) + beta (1 - z^-1)/(1 - alpha z^-1).
TransferFunction transfer_function(const Realization& r) {
  const double kp = r.kp, kit = r.ki, alpha = r.kd_a, beta = r.kd_b;
  TransferFunction h;
  h.b = {kp + kit + beta, -kp * (1 + alpha) + kit * (1 - alpha) - 2 * beta, kp * alpha - kit * alpha + beta};
  h.a = {1.0, -1 - alpha, alpha};  // not -(1 + alpha): that prints as -0 for Tf = 0
  return h;
}

TransferFunction tustin(const PidGains& g) {
  return transfer_function(realization(g));
}

std::optional<SeedForm> seed_form(const PidGains& g) {
  if (g.tf != 0) return std::nullopt;
  const double kit = g.ki * g.ts / 2, kd2 = 2 * g.kd / g.ts;
  return SeedForm{g.kp + kit + kd2, g.ki * g.ts - 2 * kd2, -g.kp + kit + kd2};
}

std::complex<double> eval_z(const TransferFunction& h, double omega, double ts) {
  const std::complex<double> q = std::polar(1.0, -omega * ts);  // z^-1
  const auto num = h.b[0] + q * (h.b[1] + q * h.b[2]);
  const auto den = h.a[0] + q * (h.a[1] + q * h.a[2]);
  return num / den;
}

std::complex<double> eval_z(const Realization& r, double omega, double ts) {
  const double th = omega * ts, sh = std::sin(th / 2), ch = std::cos(th / 2);
  // 1 - z^-1 and 1 + z^-1 in half-angle form: no cancellation as th -> 0 or pi.
  const std::complex<double> dm{2 * sh * sh, std::sin(th)};
  const std::complex<double> dp{2 * ch * ch, -std::sin(th)};
  const auto integ = r.ki * dp / dm;
  // 1 - alpha z^-1 = (1 - alpha) + alpha (1 - z^-1), exact for alpha near 1.
  const auto deriv = r.kd_b * dm / ((1 - r.kd_a) + r.kd_a * dm);
  return r.kp + integ + deriv;
}

std::complex<double> eval_s(const PidGains& g, std::complex<double> s) {
  return g.kp + g.ki / s + g.kd * s / (g.tf * s + 1.0);
}

std::complex<double> eval_s(const PidGains& g, double omega) {
  return eval_s(g, std::complex<double>{0.0, omega});
}

double coef_max(int fx) {
  return std::ldexp(double((int64_t(1) << (COEF_M_W - 1)) - 1), fx);
}

mc::Coef quantize(double value, int fx, std::string_view name) {
  const std::string expected = "|value| <= " + format_number(coef_max(fx)) + " (24-bit mantissa, shift 0)";
  if (!std::isfinite(value))
    throw InputError(std::string(name), format_number(value), expected, "not finite");
  if (value == 0) return {0, 0};
  constexpr double mmax = double((int64_t(1) << (COEF_M_W - 1)) - 1);
  constexpr double mmin = -double(int64_t(1) << (COEF_M_W - 1));
  // |m| doubles with each step of s, so the first fit from the top is the
  // largest s, i.e. the finest resolution.
  for (int s = COEF_S_MAX; s >= 0; --s) {
    const double m = std::round(std::ldexp(value, s - fx));
    if (m >= mmin && m <= mmax) {
      if (m == 0) return {0, 0};  // below the finest step: lost
      return {int32_t(m), s};
    }
  }
  throw InputError(std::string(name), format_number(value), expected, "too large for the coefficient word");
}

double realize(mc::Coef c, int fx) {
  return std::ldexp(double(c.m), fx - c.s);
}

double rel_error(double design, double realized) {
  return design == 0 ? 0.0 : std::fabs(realized - design) / std::fabs(design);
}

PidDesign design(const PidGains& g) {
  validate(g);
  PidDesign d{};
  d.gains = g;
  d.ideal = realization(g);
  d.tf = tustin(g);
  d.seed = seed_form(g);

  struct Spec {
    std::string_view name, formula;
    uint8_t reg;
    int fx;
    double design;
    double Realization::*field;
  };
  const Spec specs[] = {
      {"kp", "Kp", pid_reg::KP, 0, d.ideal.kp, &Realization::kp},
      {"ki", "Ki*Ts/2", pid_reg::KI, 0, d.ideal.ki, &Realization::ki},
      {"kd_a", "(2Tf-Ts)/(2Tf+Ts)", pid_reg::KD_A, D_OPER_FRAC, d.ideal.kd_a, &Realization::kd_a},
      {"kd_b", "2Kd/(2Tf+Ts)", pid_reg::KD_B, 0, d.ideal.kd_b, &Realization::kd_b},
      {"kf1", "FF1/Ts", pid_reg::KF1, 0, d.ideal.kf1, &Realization::kf1},
      {"kf2", "FF2/Ts^2", pid_reg::KF2, 0, d.ideal.kf2, &Realization::kf2},
  };
  static_assert(sizeof specs / sizeof specs[0] == std::tuple_size_v<decltype(d.fixed)>);

  d.max_rel_error = 0;
  for (std::size_t i = 0; i < d.fixed.size(); ++i) {
    const Spec& sp = specs[i];
    FixedCoef& f = d.fixed[i];
    f.name = sp.name;
    f.formula = sp.formula;
    f.reg = sp.reg;
    f.fx = sp.fx;
    f.design = sp.design;
    const bool trivial = sp.name == "kp";  // "kp = Kp" says nothing
    f.coef =
        quantize(sp.design, sp.fx,
                 trivial ? std::string(sp.name) : std::string(sp.name) + " = " + std::string(sp.formula));
    f.word = coef_pack(f.coef);
    f.value = realize(f.coef, sp.fx);
    f.rel_error = rel_error(f.design, f.value);
    f.lost = f.design != 0 && f.value == 0;
    d.realized.*sp.field = f.value;
    if (f.rel_error > d.max_rel_error) d.max_rel_error = f.rel_error;
  }
  d.fixed_tf = transfer_function(d.realized);
  return d;
}

mc::PidParams core_params(const PidDesign& d, const CoreLimits& lim) {
  mc::PidParams p;
  for (const FixedCoef& f : d.fixed) p.word[f.reg] = f.word;
  p.word[mc::pid_reg::OLIM] = lim.out_limit;
  p.word[mc::pid_reg::ILIM] = lim.int_limit;
  p.word[mc::pid_reg::DBAND] = lim.deadband;
  p.word[mc::pid_reg::ELIM] = lim.err_limit;
  return p;
}

uint32_t core_ts_cycles(double ts, double clk_hz, uint32_t latency_cycles, std::string_view quantity,
                        std::string_view as_written) {
  const double min_s = latency_cycles / clk_hz;
  const std::string range = "a sample period from " + format_duration(min_s) + " (" +
                            std::to_string(latency_cycles) +
                            " clock cycles, the core's sweep of every axis) to " + format_duration(kMaxTs);
  const std::string value = as_written.empty() ? format_number(ts) + " s" : quote(as_written);
  if (!std::isfinite(ts) || ts > kMaxTs * (1 + 1e-9))
    throw InputError(std::string(quantity), value, range, "too long");
  const double cycles = ts * clk_hz;
  if (cycles < latency_cycles * (1 - 1e-9))
    throw InputError(std::string(quantity), value, range, "too short");
  if (std::fabs(cycles - std::round(cycles)) > 1e-6 * cycles)
    throw InputError(std::string(quantity), value,
                     "a whole number of core clock cycles (1/clock_hz = " + format_duration(1 / clk_hz) + ")",
                     format_number(cycles) + " cycles");
  return uint32_t(std::llround(cycles));
}

void check_core_kp(double kp, std::string_view quantity, std::string_view as_written) {
  require_in(kp, Bounds{0, kMaxKp, "drive units per count"}, quantity, as_written,
             "beyond 32767 one count of error already saturates the output");
}

}  // namespace mc::host
