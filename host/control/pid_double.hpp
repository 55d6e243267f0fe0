// The core's PID (hls/pid_core.hpp, pid_axis_update) computed in double
// precision with no quantization: the controller a PC runs. Same realization
// (parallel-form Tustin), the same deadband and error clamp, the same limits
// and the same conditional-integration anti-windup, so that any difference
// between the host and the FPGA platforms in the co-simulation comes from the
// sample period, jitter and latency, not from a different controller.
//
// One deliberate difference: the core's accumulator saturates every partial
// sum at +-2^17 drive units (hls/mc_fixed.hpp); a PC has no such range, so
// the two agree while the demand stays within it (4x full scale).
//
// Units as in the core: counts in, drive units out (full scale +-32767).
#pragma once

#include "host/control/pid_design.hpp"

namespace mc::host {

class PidDouble {
 public:
  // out_limit > 0; int_limit: 0 = out_limit (a larger one is capped at
  // out_limit, as the core does); deadband, err_limit in counts, 0 = none.
  // Throws InputError for invalid gains or negative/non-finite limits.
  explicit PidDouble(const PidGains& g, double out_limit = 32767, double int_limit = 0, double deadband = 0,
                     double err_limit = 0);

  // One sample; returns the drive output, saturated to +-out_limit.
  double update(double cmd_counts, double fb_counts);

  // Disabled: output 0, integrator and derivative cleared, error and command
  // history still tracked so that enabling is bumpless.
  void set_enabled(bool on) { enabled_ = on; }
  bool enabled() const { return enabled_; }
  // Clears the whole state (as after power-up); keeps the enable.
  void reset();

  double integrator() const { return i_; }
  // The last sample's output limit was active.
  bool saturated() const { return sat_; }
  // The last sample's demand P + I + D + F before the output limit (with the
  // integrator as clamped but before anti-windup): what saturated() compares.
  double demand() const { return demand_; }
  // The last processed error (after deadband and clamp), counts.
  double error() const { return e1_; }
  const Realization& realization() const { return r_; }

 private:
  Realization r_;
  double out_limit_, int_bound_, deadband_, err_limit_;
  bool enabled_ = true;
  double i_ = 0, d_ = 0, e1_ = 0, c1_ = 0, c2_ = 0;
  bool sat_ = false;
  double demand_ = 0;
};

}  // namespace mc::host
