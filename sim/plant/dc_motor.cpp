#include "sim/plant/dc_motor.hpp"

#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>

#include "host/base/errors.hpp"

namespace mc::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int32_t kFullScale = 32767;

int32_t saturate(int32_t u) {
  return std::clamp(u, -kFullScale, kFullScale);
}

// floor(v / 2^s) for v >= -2^31, without relying on how >> treats negatives.
int32_t floor_shift(int32_t v, int s) {
  return v >= 0 ? v >> s : -int32_t((uint32_t(-int64_t(v)) + (uint32_t(1) << s) - 1) >> s);
}

}  // namespace

AxisPlant::AxisPlant(const AxisConfig& cfg, double dt_s) : m_(cfg.motor), dt_(dt_s) {
  if (!(dt_s > 0) || !std::isfinite(dt_s)) {
    throw mc::host::InputError("plant dt", mc::host::format_number(dt_s), "a finite step > 0 s");
  }
  j_ = m_.j_kg_m2 + reflected_inertia_kg_m2(cfg);
  tau_load_ = reflected_torque_nm(cfg);
  rad_to_m_ = cfg.lead_m_per_rev / (2 * kPi * cfg.gear_ratio);
  rad_to_count_ = cfg.encoder_cpr / (2 * kPi);

  // Zero-order hold, exactly: exp([[A, Bc], [0, 0]] dt) = [[Ad, Bd], [0, I]].
  Eigen::Matrix<double, 5, 5> mc = Eigen::Matrix<double, 5, 5>::Zero();
  mc(0, 0) = -m_.r_ohm / m_.l_h;
  mc(0, 1) = -m_.ke_v_s_per_rad / m_.l_h;
  mc(1, 0) = m_.kt_nm_per_a / j_;
  mc(1, 1) = -m_.b_nm_s_per_rad / j_;
  mc(2, 1) = 1;
  mc(0, 3) = 1 / m_.l_h;  // input V
  mc(1, 4) = -1 / j_;     // input tau_ext, opposing +w
  const Eigen::Matrix<double, 5, 5> e = (mc * dt_s).exp();
  ad_ = e.topLeftCorner<3, 3>();
  bd_ = e.topRightCorner<3, 2>();

  // With w held at 0 only the electrical equation remains.
  stuck_a_ = std::exp(-m_.r_ohm / m_.l_h * dt_s);
  stuck_b_ = -std::expm1(-m_.r_ohm / m_.l_h * dt_s) / m_.r_ohm;
}

double AxisPlant::driving_torque_nm() const {
  return m_.kt_nm_per_a * x_(0) - tau_load_;
}

void AxisPlant::step(double v) {
  ++steps_;
  if (!friction_) {
    x_ = ad_ * x_ + bd_ * Eigen::Vector2d(v, tau_load_);
    return;
  }
  double dir;
  if (stuck_) {
    const double drive = driving_torque_nm();
    if (std::fabs(drive) <= m_.stiction_nm) {
      x_(0) = stuck_a_ * x_(0) + stuck_b_ * v;  // w and theta stay exactly where they are
      return;
    }
    stuck_ = false;  // breakaway, in the direction of the driving torque
    dir = drive > 0 ? 1.0 : -1.0;
  } else {
    dir = x_(1) > 0 ? 1.0 : -1.0;
  }
  // Coulomb friction opposes the motion for the whole step.
  x_ = ad_ * x_ + bd_ * Eigen::Vector2d(v, tau_load_ + dir * m_.coulomb_nm);
  // Friction can stop the shaft, never reverse it: a step that would cross
  // zero speed ends at rest, and the stiction test decides what comes next.
  if (x_(1) * dir <= 0) {
    x_(1) = 0;
    stuck_ = true;
  }
}

void AxisPlant::set_friction(bool on) {
  friction_ = on;
  stuck_ = on && x_(1) == 0;
}

double AxisPlant::position_m() const {
  return x_(2) * rad_to_m_;
}

int64_t AxisPlant::encoder_count() const {
  return int64_t(std::floor(x_(2) * rad_to_count_));
}

void AxisPlant::reset(double position_rad) {
  x_ = Eigen::Vector3d(0, 0, position_rad);
  steps_ = 0;
  stuck_ = friction_;
}

QuadPins quadrature_pins(int64_t count, int encoder_cpr) {
  const int64_t q = ((count % 4) + 4) % 4;
  const int64_t rev = encoder_cpr > 0 ? ((count % encoder_cpr) + encoder_cpr) % encoder_cpr : 1;
  return QuadPins{q == 1 || q == 2, q >= 2, rev == 0};
}

int pwm_duty(const DriveConfig& d, int32_t u) {
  const int32_t s = saturate(u);
  return (s < 0 ? -s : s) >> (15 - d.pwm_bits);
}

double drive_volts(const DriveConfig& d, int32_t u) {
  const int32_t s = saturate(u);
  if (d.kind == DriveConfig::Kind::Pwm) {
    const double v = std::ldexp(double(pwm_duty(d, s)), -d.pwm_bits) * d.supply_v;
    return s < 0 ? -v : v;
  }
  const int32_t code = floor_shift(s, 16 - d.dac_bits);
  const double dac = code * std::ldexp(2 * d.dac_range_v, -d.dac_bits);
  return std::clamp(dac * d.amp_gain, -d.supply_v, d.supply_v);
}

double dac_volts(int bits, double range_v, double volts) {
  const double step = std::ldexp(2 * range_v, -bits);
  const double top = std::ldexp(1.0, bits - 1);
  const double code = std::clamp(std::nearbyint(volts / step), -top, top - 1);
  return code * step;
}

}  // namespace mc::sim
