// The machine description: axes (motor, transmission, encoder, drive, gains),
// the co-simulation's time base and the host-loop model, read from one TOML
// file. configs/default.toml is the reference for every key (unit, meaning)
// and is compiled in as the built-in default.
//
// All values are SI; each key's name carries its unit. Reading is strict:
// a missing key, an unknown key (a typo), a value of the wrong type or out of
// range is an mc::host::InputError that names the file, the line and the key,
// so that a misspelt key can never fall back to a default silently.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "host/control/pid_design.hpp"

namespace mc::machine {

struct MotorParams {
  double r_ohm;           // terminal resistance
  double l_h;             // terminal inductance
  double kt_nm_per_a;     // torque constant
  double ke_v_s_per_rad;  // back-EMF constant
  double j_kg_m2;         // rotor inertia (the motor alone)
  double b_nm_s_per_rad;  // viscous friction at the motor shaft
  double coulomb_nm;      // Coulomb (sliding) friction at the motor shaft
  double stiction_nm;     // static friction: breakaway torque, >= coulomb_nm
};

struct DriveConfig {
  enum class Kind { Pwm, Dac } kind;
  double supply_v;  // the bridge supply: the terminal voltage saturates here
  // PWM H-bridge: a pwm_bits counter at the core clock, duty = |u| >> (15 - pwm_bits).
  int pwm_bits;
  double pwm_hz;       // derived: clock_hz / 2^pwm_bits
  bool pwm_switching;  // true: the co-sim applies +-supply/0 per plant step; false: the average
  // DAC + linear amplifier (the paper's drive).
  int dac_bits;
  double dac_range_v;  // the DAC spans +-dac_range_v
  double amp_gain;     // V at the motor per V from the DAC
};

// [axis.N.stepper], optional: the axis is a two-phase hybrid stepper behind
// a microstep driver on the board's STEP/DIR pins (sim/plant/stepper_motor.hpp;
// [axis.N.motor] then gives one phase's R, L, the torque per ampere, the
// rotor's inertia and the frictions). One STEP pulse is one count, so the
// axis's encoder_counts_per_rev is 4 * rotor_teeth * microsteps; a
// closed-loop axis's shaft encoder counts in the same units.
struct StepperConfig {
  int rotor_teeth = 50;     // 200 full steps per revolution
  int microsteps = 16;      // steps of the STEP input per full step
  double current_a = 1.5;   // the driver's phase current setting (peak)
  double detent_nm = 0.01;  // unpowered cogging torque
  // The driver's timing and wiring (STEP_CFG). Defaults suit the A4988,
  // DRV8825 and TMC drivers: 2 us pulses (the DRV8825 needs 1.9 us) and
  // 1 us from a direction change to the next pulse (it needs 650 ns).
  double step_pulse_s = 2e-6;
  double dir_setup_s = 1e-6;
  bool closed_loop = false;      // a shaft encoder on the axis's encoder pins: lost steps trip FERR
  bool step_active_low = false;  // the STEP input pulses low (an optocoupled input to ground)
  bool dir_reversed = false;     // the motor turns the other way for +travel
  int steps_per_rev() const { return 4 * rotor_teeth * microsteps; }
};
// STEP_CFG's pulse and setup fields: 1..kStepTimeMaxClocks board clocks.
constexpr int kStepTimeMaxClocks = 63;
// A driver time as STEP_CFG clocks: rounded up, so the driver gets at least
// what it needs.
int step_time_clocks(double seconds, double clock_hz);

// In core units (host/pid_design.hpp): drive units (+-32767) per encoder count.
struct PidConfig {
  double kp, ki, kd, tf_s, ts_s, ff1 = 0, ff2 = 0;
  double out_limit = 32767;
};

// [axis.N.home], optional: the axis's home switch, wired to its limit input
// (which the board filters and can latch on, docs/board.md), and how the
// homing cycle seeks it. Positions are table positions in the plant's frame,
// the frame of travel_min_m/travel_max_m.
struct HomeConfig {
  double switch_m = 0;       // where the switch closes
  int direction = 1;         // +1: closed at positions >= switch_m (the + end); -1: closed at <= switch_m
  double bounce_s = 0.0005;  // the contacts chatter this long after each crossing
  int order = 0;             // homing pass: axes of the same order home together, lowest first
  // Grbl's defaults ($25, $24, $27): 500 mm/min, 25 mm/min, 1 mm.
  double seek_m_s = 500e-3 / 60;   // fast approach, to find the switch
  double locate_m_s = 25e-3 / 60;  // slow approach after backing off, the one whose latch counts
  double pull_off_m = 0.001;       // how far the axis backs off the switch
};

struct AxisConfig {
  std::string name;
  MotorParams motor;
  double lead_m_per_rev;  // table travel per screw revolution
  double gear_ratio;      // motor revolutions per screw revolution
  double load_kg;         // moving mass (table, carriage, workpiece)
  double load_force_n;    // constant force opposing +travel (gravity on Z, a spring...)
  int encoder_cpr;        // counts per motor revolution after 4x decoding
  DriveConfig drive;
  PidConfig pid;
  double max_following_error_m;  // armed on the board's FERR whenever motionctl arms the drives
  double max_speed_m_s;          // jog, move and the planner refuse feeds above it
  // Optional keys (older files load with these defaults).
  double max_accel_m_s2 = 1.0;  // path planner: the axis's acceleration limit
  // The home switch; no [home]: none on the axis's limit input.
  std::optional<HomeConfig> home;
  // Soft travel limits: machine coordinates the axis may reach (m from
  // machine zero once homed, host/machine/cycles.hpp; before, from where it
  // was when the board started). jog, move and step refuse targets beyond
  // them before anything moves.
  double travel_min_m = -1.0;
  double travel_max_m = 1.0;
  std::optional<StepperConfig> stepper;  // a stepper axis (else a DC servo on the H-bridge pins)
};

// [planner], optional (docs/gcode.md, "Planner"). Defaults as Grbl's.
struct PlannerSettings {
  double junction_deviation_m = 1e-5;  // Grbl $11: 0.010 mm
  double arc_tolerance_m = 2e-6;       // Grbl $12: 0.002 mm, for arcs the core cannot run whole
  double ramp_piece_s = 0.004;         // a feed ramp is chopped into constant-feed pieces this long
  double accel_window_s = 0.02;        // acceleration is limited as an average over this window
  double queue_ahead_s = 0.25;         // motion kept queued on the board while streaming
};

// [workpiece], optional: the part on the bed, whose top face the virtual
// machine's probe touches and levelling follows (host/machine/workpiece.hpp).
// Its top face: a plane through top_z_m at the min corner with slopes tilt_x
// and tilt_y, a dish bow_m deep in the middle (0 at the edges), and a smooth
// random roughness of noise_m RMS.
struct WorkpieceConfig {
  double min_x_m = 0, min_y_m = 0, max_x_m = 0.2, max_y_m = 0.15;
  double top_z_m = 0;
  double tilt_x = 0, tilt_y = 0;  // m/m
  double bow_m = 0;
  double noise_m = 0;
  int noise_seed = 1;
};

// [probe], optional: the probe input's contact (a touch plate or a probe
// whose tip closes on the workpiece, [workpiece]).
struct ProbeConfig {
  double bounce_s = 0.0002;  // the contact chatters this long after each touch and lift
};

// [spindle], optional: how a program's S word becomes SP_PWM's duty
// (host/machine/spindle.hpp), as Grbl's $30 and $31: linear from min_rpm
// (the least duty) to max_rpm (always on).
struct SpindleConfig {
  double max_rpm = 24000;  // a router spindle's top speed
  double min_rpm = 0;
  bool mist_on_dir = false;  // SP_DIR carries the mist coolant (M7) instead of the direction
};

struct MachineConfig {
  std::string source;  // file path or "built-in default"
  double clock_hz = 12e6;
  double plant_dt_s = 1e-6;
  std::vector<AxisConfig> axes;  // x, y, optional z, in that order
  PlannerSettings planner;
  std::optional<WorkpieceConfig> workpiece;
  ProbeConfig probe;
  SpindleConfig spindle;
  double host_period_s = 0.01;
  double host_io_latency_s = 0.001;
  int host_dac_bits = 12;
  double host_dac_range_v = 10;
};

// Throws mc::host::InputError "file:line: key = value: ...; expected ..." on
// a missing file, bad TOML, bad/missing/unknown keys, out-of-range values.
MachineConfig load_machine(const std::string& path);
MachineConfig parse_machine(std::string_view toml_text, const std::string& source_name);
// configs/default.toml as compiled in: works from any directory.
MachineConfig default_machine();
std::string_view default_machine_toml();
// load_machine(path), or default_machine() when path is empty.
MachineConfig machine_or_default(const std::string& path);

// Case-insensitive; throws InputError listing the valid names.
const AxisConfig& axis(const MachineConfig& m, std::string_view name);

// Encoder counts per metre of table travel: encoder_cpr * gear_ratio / lead.
double counts_per_m(const AxisConfig& a);
// The load seen at the motor shaft through the screw and gear:
// m * (lead / (2 pi gear))^2, and force * lead / (2 pi gear).
double reflected_inertia_kg_m2(const AxisConfig& a);
double reflected_torque_nm(const AxisConfig& a);

// The linearized axis: Kg in counts/s per drive unit, tau in s.
struct AxisModel {
  double kg, tau;
};
AxisModel axis_model(const AxisConfig& a);

// Closed-loop poles placed at a triple real pole -w on the linearized axis
// G(s) = Kg / (s (tau s + 1)) (u in drive units, position in counts), with
// w = min(w0, 1 / (4 delay)): the loop keeps about 14 degrees of phase for
// its delay. w0 comes from the machine's gains: for this rule Ki/Kp = w/3.
mc::host::PidGains tuned_gains(const AxisConfig& a, double ts_s, double delay_s);

}  // namespace mc::machine
