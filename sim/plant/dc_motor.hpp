// One axis of the table: a brushed DC motor driving a ball screw, with
// Coulomb + viscous friction and stiction, an incremental encoder, and the
// drive stage (PWM H-bridge or DAC + linear amplifier) in front of it.
//
//   L di/dt = V - R i - Ke w
//   J dw/dt = Kt i - B w - friction - load,   dtheta/dt = w
// with J the motor inertia plus the table mass reflected through the screw.
// The linear part is discretized exactly (zero-order hold on V and on the
// friction + load torque, Eigen's matrix exponential); stiction holds w at
// exactly 0 while the driving torque stays within the breakaway torque.
// docs/plant.md derives the model and explains the stiction logic.
//
// step() is cheap (fixed-size 3x3, no allocation): the co-simulation calls it
// once per plant step (1 us) per axis.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "host/machine/machine_config.hpp"

namespace mc::sim {

// The machine description the plant is built from.
using machine::AxisConfig;
using machine::DriveConfig;
using machine::MachineConfig;
using machine::MotorParams;

class AxisPlant {
 public:
  // dt_s: the plant step (MachineConfig::plant_dt_s, 1 us by default).
  AxisPlant(const AxisConfig& cfg, double dt_s = 1e-6);

  // Advance one dt with the terminal voltage held (ZOH).
  void step(double terminal_volts);
  // Friction off = the pure linear model. Turning it on at rest sticks.
  void set_friction(bool on);
  bool friction() const { return friction_; }

  // Motor shaft.
  double time_s() const { return double(steps_) * dt_; }
  double current_a() const { return x_(0); }
  double speed_rad_s() const { return x_(1); }
  double position_rad() const { return x_(2); }
  // Table: position_rad / (2 pi) / gear_ratio * lead.
  double position_m() const;
  // floor(position_rad / (2 pi) * encoder_cpr): the exact quantization.
  int64_t encoder_count() const;
  bool stuck() const { return stuck_; }
  void reset(double position_rad = 0);

  double dt_s() const { return dt_; }
  // Motor + reflected load inertia, and the load torque at the motor shaft.
  double inertia_kg_m2() const { return j_; }
  double load_torque_nm() const { return tau_load_; }
  // The torque that would accelerate the shaft without friction: Kt i - load.
  double driving_torque_nm() const;

  // The ZOH matrices: x(k+1) = Ad x(k) + Bd [V, tau_ext]^T, x = [i, w, theta],
  // tau_ext = friction + load (opposing +w). Exposed for tests and analysis.
  const Eigen::Matrix3d& ad() const { return ad_; }
  const Eigen::Matrix<double, 3, 2>& bd() const { return bd_; }

 private:
  MotorParams m_;
  double dt_;
  double j_;         // total inertia at the motor shaft
  double tau_load_;  // load torque at the motor shaft
  double rad_to_m_, rad_to_count_;
  Eigen::Matrix3d ad_;
  Eigen::Matrix<double, 3, 2> bd_;
  double stuck_a_, stuck_b_;  // i(k+1) = a i(k) + b V with w = 0: exp(-R dt/L), (1 - a)/R

  Eigen::Vector3d x_ = Eigen::Vector3d::Zero();
  int64_t steps_ = 0;
  bool friction_ = true;
  bool stuck_ = true;
};

// Encoder output pins for a count: A/B in Gray code from count mod 4
// (0: A=0 B=0, 1: A=1 B=0, 2: A=1 B=1, 3: A=0 B=1: A leads B while counting
// up, as hls/quad_decoder.hpp counts up with dir_inv = 0); Z high on the one
// count where count mod encoder_cpr == 0.
struct QuadPins {
  bool a, b, z;
};
QuadPins quadrature_pins(int64_t count, int encoder_cpr);

// Controller output (drive units, +-32767 full scale; beyond saturates) to
// terminal volts.
//   PWM (averaged): a pwm_bits counter at the core clock is high for
//     duty = |u| >> (15 - pwm_bits) of its 2^pwm_bits counts, direction = sign:
//     V = sign(u) * duty / 2^pwm_bits * supply.
//   DAC: the top dac_bits of u (arithmetic shift, as the core feeds the DAC)
//     over +-dac_range_v, times amp_gain, saturated at +-supply.
double drive_volts(const DriveConfig& d, int32_t u);
// The PWM duty in counts of 2^pwm_bits for |u| (the switching model uses it).
int pwm_duty(const DriveConfig& d, int32_t u);
// A requested voltage through a bits-bit DAC spanning +-range_v: rounded to
// the nearest of its 2^bits levels (step 2 range / 2^bits), clamped to
// [-range, range - step]. The host loop's output stage.
double dac_volts(int bits, double range_v, double volts);

}  // namespace mc::sim
