#include "host/control/pid_double.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/base/errors.hpp"

namespace mc::host {
namespace {

double check_limit(double v, const char* what, bool zero_ok) {
  if (!std::isfinite(v) || v < 0 || (!zero_ok && v == 0)) {
    throw InputError(what, format_number(v), zero_ok ? "a finite number >= 0" : "a finite number > 0");
  }
  return v;
}

double clamp(double v, double lim) {
  return std::min(std::max(v, -lim), lim);
}

}  // namespace

PidDouble::PidDouble(const PidGains& g, double out_limit, double int_limit, double deadband, double err_limit)
    : r_(mc::host::realization(g)),
      out_limit_(check_limit(out_limit, "out_limit", false)),
      int_bound_(check_limit(int_limit, "int_limit", true)),
      deadband_(check_limit(deadband, "deadband", true)),
      err_limit_(check_limit(err_limit, "err_limit", true)) {
  validate(g);
  // As the core: the integrator is bounded by the output limit at most.
  if (int_bound_ == 0 || int_bound_ > out_limit_) int_bound_ = out_limit_;
}

void PidDouble::reset() {
  i_ = d_ = e1_ = c1_ = c2_ = 0;
  sat_ = false;
  demand_ = 0;
}

double PidDouble::update(double cmd, double fb) {
  const double e_raw = cmd - fb;
  double e = e_raw > deadband_ ? e_raw - deadband_ : (e_raw < -deadband_ ? e_raw + deadband_ : 0.0);
  if (err_limit_ != 0) e = clamp(e, err_limit_);
  const double vel = cmd - c1_;
  const double acc = cmd - 2 * c1_ + c2_;
  const double e_prev = e1_;
  e1_ = e;
  c2_ = c1_;
  c1_ = cmd;
  if (!enabled_) {
    i_ = d_ = 0;
    sat_ = false;
    demand_ = 0;
    return 0;
  }
  const double i_c = clamp(i_ + r_.ki * (e + e_prev), int_bound_);
  const double dn = r_.kd_a * d_ + r_.kd_b * (e - e_prev);
  const double rest = r_.kp * e + dn + (r_.kf1 * vel + r_.kf2 * acc);
  const double v = rest + i_c;
  // Conditional integration: beyond the limit, the integrator may not grow
  // past the headroom the other terms leave, unless it already was there.
  double i_n = i_c;
  if (v > out_limit_) {
    i_n = std::min(i_c, std::max(out_limit_ - rest, i_));
  } else if (v < -out_limit_) {
    i_n = std::max(i_c, std::min(-out_limit_ - rest, i_));
  }
  sat_ = v > out_limit_ || v < -out_limit_;
  demand_ = v;
  i_ = i_n;
  d_ = dn;
  return clamp(rest + i_n, out_limit_);
}

}  // namespace mc::host
