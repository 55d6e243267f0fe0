// One stepper axis: a two-phase hybrid stepper behind a current-chopping
// microstep driver (A4988, DRV8825, TMC in its classic mode), driving the
// same ball screw and load as a servo axis (dc_motor.hpp).
//
// Driver: each step input advances the electrical angle phi by
// (pi / 2) / microsteps; the phase currents are commanded to
// I cos(phi) and I sin(phi). The chopper reaches its command in one plant
// step whenever the supply allows, and otherwise applies the full supply
// (deadbeat within the supply). At speed the back-EMF and the phase's
// reactance both grow with the step rate while the supply does not: the
// power the driver can deliver levels off near V Kt / (Nr L) and the
// torque falls as 1 / w, the pull-out curve of a datasheet. (Iron losses
// and the chopper's mid-band resonance are not modelled.)
//
//   L di_a/dt = v_a - R i_a - e_a,  e_a = -Kt w sin(Nr theta)
//   L di_b/dt = v_b - R i_b - e_b,  e_b =  Kt w cos(Nr theta)
//   T = Kt (i_b cos(Nr theta) - i_a sin(Nr theta)) - Td sin(4 Nr theta)
//   J dw/dt = T - B w - friction - load,  dtheta/dt = w
//
// Nr is the rotor's tooth count (50: 200 full steps per revolution). With
// both currents at their command the torque is Kt I sin(phi - Nr theta):
// the holding torque Kt I pulls the rotor to within a fraction of a step of
// phi / Nr. A step train faster than the torque can accelerate the load
// leaves the rotor more than half an electrical period behind; it then
// slips to the next stable point, a whole electrical period (four full
// steps) away: lost steps, as a real motor loses them.
#pragma once

#include <cstdint>

#include "sim/plant/dc_motor.hpp"

namespace mc::sim {

// What a stepper adds to the motor parameters (MotorParams): there r_ohm,
// l_h are one phase's, kt_nm_per_a the torque per ampere of phase current
// (holding torque / rated current), j_kg_m2 the rotor's inertia; b, coulomb
// and stiction the same frictions as a servo axis's. A machine file's
// [axis.N.stepper] table.
using StepperParams = machine::StepperConfig;

class StepperPlant {
 public:
  StepperPlant(const AxisConfig& axis, const StepperParams& stepper, double dt_s = 1e-6);

  // Advance one dt with the driver at `steps` steps of its STEP input from
  // power-up (the position it was commanded to) and enabled or not
  // (disabled: no current, the rotor held by detent and friction only).
  void step(int64_t steps, bool enabled = true);

  double time_s() const { return double(n_) * dt_; }
  double position_rad() const { return theta_; }
  double speed_rad_s() const { return w_; }
  // Table: position_rad / (2 pi) / gear_ratio * lead, as a servo axis's.
  double position_m() const { return theta_ * rad_to_m_; }
  double current_a(int phase) const { return phase == 0 ? ia_ : ib_; }
  // Full steps the rotor has slipped behind (positive) or ahead of the
  // command: the whole electrical periods between them, times four. A
  // rotor within half a period of its command has lost nothing.
  int64_t lost_full_steps(int64_t steps) const;
  // The rotor's position in driver steps, rounded: what an encoder on the
  // shaft would report in step units.
  int64_t position_steps() const;

  // Small-signal stiffness of the energized motor about its equilibrium,
  // N m/rad, detent aside: Nr Kt I.
  double stiffness_nm_per_rad() const;
  double inertia_kg_m2() const { return j_; }
  void reset(double position_rad = 0);

 private:
  MotorParams m_;
  StepperParams s_;
  double dt_, j_, tau_load_, supply_, rad_to_m_;
  double a_;  // exp(-R dt / L): one phase's current decay over a step
  double ia_ = 0, ib_ = 0, w_ = 0, theta_ = 0;
  int64_t n_ = 0;

  double chop(double i, double i_ref, double emf) const;
  // The commanded shaft angle for `steps` driver steps.
  double commanded_rad(int64_t steps) const;
};

}  // namespace mc::sim
