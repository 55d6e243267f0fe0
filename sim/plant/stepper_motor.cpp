#include "sim/plant/stepper_motor.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/base/errors.hpp"

namespace mc::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const std::string& what, double value, const std::string& expected) {
  if (!ok) throw mc::host::InputError(what, mc::host::format_number(value), expected);
}

}  // namespace

StepperPlant::StepperPlant(const AxisConfig& axis, const StepperParams& stepper, double dt_s)
    : m_(axis.motor), s_(stepper), dt_(dt_s) {
  require(dt_s > 0 && std::isfinite(dt_s), "plant dt", dt_s, "a finite step > 0 s");
  require(s_.rotor_teeth >= 1, "stepper rotor_teeth", s_.rotor_teeth, ">= 1");
  require(s_.microsteps >= 1, "stepper microsteps", s_.microsteps, ">= 1");
  require(s_.current_a >= 0 && std::isfinite(s_.current_a), "stepper current_a", s_.current_a, ">= 0 A");
  require(s_.detent_nm >= 0 && std::isfinite(s_.detent_nm), "stepper detent_nm", s_.detent_nm, ">= 0 N m");
  require(m_.r_ohm > 0 && m_.l_h > 0, "stepper phase R, L", m_.r_ohm * m_.l_h, "both > 0");
  j_ = m_.j_kg_m2 + machine::reflected_inertia_kg_m2(axis);
  tau_load_ = machine::reflected_torque_nm(axis);
  a_ = std::exp(-m_.r_ohm / m_.l_h * dt_s);
  supply_ = axis.drive.supply_v;
  rad_to_m_ = axis.lead_m_per_rev / (2 * kPi * axis.gear_ratio);
}

void StepperPlant::reset(double position_rad) {
  ia_ = ib_ = w_ = 0;
  theta_ = position_rad;
  n_ = 0;
}

// The phase voltage that brings the current to i_ref at the end of the
// step (exact for the first-order phase with the EMF held), clamped to the
// supply; returns the current the clamped voltage gives.
double StepperPlant::chop(double i, double i_ref, double emf) const {
  const double r = m_.r_ohm;
  const double v = std::clamp(emf + r * (i_ref - a_ * i) / (1 - a_), -supply_, supply_);
  const double i_inf = (v - emf) / r;
  return i_inf + (i - i_inf) * a_;
}

void StepperPlant::step(int64_t steps, bool enabled) {
  ++n_;
  const double nr = s_.rotor_teeth;
  const double sn = std::sin(nr * theta_), cs = std::cos(nr * theta_);
  const double kt = m_.kt_nm_per_a;
  double ref_a = 0, ref_b = 0;
  if (enabled) {
    const double phi = double(steps) * (kPi / 2) / s_.microsteps;
    ref_a = s_.current_a * std::cos(phi);
    ref_b = s_.current_a * std::sin(phi);
  }
  // Disabled, the bridge is open: the windings' current dies out through
  // the driver's diodes within a step or two and none flows after.
  ia_ = chop(ia_, ref_a, -kt * w_ * sn);
  ib_ = chop(ib_, ref_b, kt * w_ * cs);
  const double torque = kt * (ib_ * cs - ia_ * sn) - s_.detent_nm * std::sin(4 * nr * theta_);

  // Mechanics: semi-implicit Euler (the rotor's resonance is some 100 Hz
  // against a 1 us step). Friction as dc_motor.cpp: at rest, the rotor
  // stays until the driving torque passes the breakaway torque; moving,
  // Coulomb opposes the speed; a sign change of the speed stops it for a
  // step, where the stiction test runs again.
  const double drive = torque - tau_load_;
  if (w_ == 0 && std::abs(drive) <= m_.stiction_nm) return;
  const double dir = w_ != 0 ? (w_ > 0 ? 1.0 : -1.0) : (drive > 0 ? 1.0 : -1.0);
  const double acc = (drive - m_.b_nm_s_per_rad * w_ - dir * m_.coulomb_nm) / j_;
  const double w_new = w_ + acc * dt_;
  w_ = (w_ != 0 && (w_new > 0) != (w_ > 0)) ? 0.0 : w_new;
  theta_ += w_ * dt_;
}

double StepperPlant::commanded_rad(int64_t steps) const {
  return double(steps) * (kPi / 2) / s_.microsteps / s_.rotor_teeth;
}

int64_t StepperPlant::lost_full_steps(int64_t steps) const {
  const double behind = (commanded_rad(steps) - theta_) * s_.rotor_teeth;  // electrical radians
  return 4 * std::llround(behind / (2 * kPi));
}

int64_t StepperPlant::position_steps() const {
  return std::llround(theta_ * s_.rotor_teeth / (kPi / 2) * s_.microsteps);
}

double StepperPlant::stiffness_nm_per_rad() const {
  return s_.rotor_teeth * m_.kt_nm_per_a * s_.current_a;
}

}  // namespace mc::sim
