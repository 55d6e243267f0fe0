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
// The state is kept as runs: from an anchor (the state where the input last
// changed, or friction started or stopped the shaft) the state k steps on is
// Ad^k x0 + (Ad^(k-1) + ... + I) Bd u, from tables of those powers. So where
// a caller looks at the state (every step, or once after hold() has taken
// many) does not change it: the co-simulation's engines, which look at
// different steps, move the plant identically. hold() takes a whole run of
// steps at once, stepping one at a time only where friction acts or the
// encoder count changes (docs/plant.md, "Runs").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

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
  // Up to n steps with the terminal voltage held, exactly as n step() calls,
  // stopping after the first step at whose end the encoder count differs
  // from the count before the call. Returns the steps taken.
  uint64_t hold(double terminal_volts, uint64_t n);
  // The same, also writing the table position (position_m()) after each
  // of the steps first, first + every, ... of the call (counted from 1)
  // that it takes to out[0], out[1], ... (out then points past the last;
  // room counts down; no out: none): a trace sampled along a held stretch
  // without ending it. first is left counting from the end of the call, so
  // the next call goes on with the same samples.
  struct Samples {
    uint64_t first = 1, every = 1;
    double* out = nullptr;
    size_t room = 0;
  };
  uint64_t hold(double terminal_volts, uint64_t n, Samples& samples);
  // The same through the count changes: each step at whose end the count
  // differs from the step before goes to `changes`, its step numbered from
  // step0 + 1. Stops after n steps, or after a step that moves the count by
  // more than one (big then). One call takes a whole window with the
  // search's pieces found once, where hold() would start again at each.
  struct CountChange {
    uint64_t step;
    int64_t count;
  };
  struct Held {
    uint64_t steps;
    bool big;
  };
  Held hold_counting(double terminal_volts, uint64_t n, Samples& samples, std::vector<CountChange>& changes,
                     uint64_t step0 = 0);
  // The motion of o, a copy of this plant (the same axis): its state, run
  // and friction, for much less than a copy of the whole model.
  void take_motion(const AxisPlant& o) {
    x_ = o.x_;
    x0_ = o.x0_;
    u0_ = o.u0_;
    v_ = o.v_;
    dir_ = o.dir_;
    k_ = o.k_;
    anchored_ = o.anchored_;
    steps_ = o.steps_;
    friction_ = o.friction_;
    stuck_ = o.stuck_;
  }
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
  int64_t encoder_count() const { return count_at(x_(2)); }
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
  const Eigen::Matrix3d& ad() const { return pw_->ad_1; }
  const Eigen::Matrix<double, 3, 2>& bd() const { return pw_->bd_1; }

 private:
  MotorParams m_;
  double dt_;
  double j_;         // total inertia at the motor shaft
  double tau_load_;  // load torque at the motor shaft
  double rad_to_m_, rad_to_count_;

  // The longest run: a new anchor is taken every kRun steps.
  static constexpr uint32_t kRun = 2048;
  // Ad^k and the sum of Ad^j Bd for j < k, k = 0..kRun, row by row (the
  // searches read one state at a time); the stuck current's a^k and b (1 +
  // a + .. + a^(k-1)). Shared by copies, and by plants of the same one-step
  // matrices (powers_for). Filled a chunk at a time as runs reach it
  // (reach()): a loop sampled every 100 us starts a run every 100 steps or
  // so and never needs the rest, whose fresh pages were most of the
  // plants' part of a short co-simulation's set-up.
  struct Power {
    double ad[3][3];
    double bd[3][2];
  };
  static constexpr uint32_t kChunks = 5;
  static constexpr uint32_t kChunkEnd[kChunks] = {128, 256, 512, 1024, kRun + 1};
  struct Powers {
    Eigen::Matrix3d ad_1;  // the one-step matrices (k = 1), also the key
    Eigen::Matrix<double, 3, 2> bd_1;
    double stuck_a_1, stuck_b_1;
    // kRun + 1 of each, uninitialized until their chunk is filled: the
    // pointers are const, what they point to is written once, under its
    // chunk's flag.
    std::unique_ptr<Power[]> k;
    std::unique_ptr<double[]> stuck_a, stuck_b;
    mutable std::once_flag filled[kChunks];
    // Fills the chunks up to the one holding step; returns that chunk's end.
    uint32_t fill_to(uint32_t step) const;
  };
  static std::shared_ptr<const Powers> powers_for(const Eigen::Matrix3d& ad_1,
                                                  const Eigen::Matrix<double, 3, 2>& bd_1, double stuck_a,
                                                  double stuck_b);
  // A new run from the current state with this input; the shaft moves in
  // direction dir (friction), or is stuck.
  void anchor(double volts, double dir);
  // step() of a shaft that moves, in its run: the state from the run,
  // whatever it was, and friction stopping it.
  void moving_step();
  // The tables hold step k of a run (k <= kRun).
  void reach(uint32_t k) {
    if (k >= reached_) reached_ = pw_->fill_to(k);
  }
  // The current run goes on with this input (else a step anchors anew).
  bool in_run(double volts) const { return anchored_ && volts == v_ && k_ < kRun; }
  // State i (0 current, 1 speed, 2 angle) of a run: row i of Ad^k x0 +
  // Bd_k u0 (p: k's powers). The sums go in the order Eigen's product takes
  // them (the figures the plant gave before it was read by rows), and every
  // path reads the run through here.
  static double run_row(const Power& p, int i, const double* x0, const double* u0) {
    const double* a = p.ad[i];
    const double ax =
        i < 2 ? a[0] * x0[0] + a[1] * x0[1] + a[2] * x0[2] : a[0] * x0[0] + (a[1] * x0[1] + a[2] * x0[2]);
    return ax + (p.bd[i][0] * u0[0] + p.bd[i][1] * u0[1]);
  }
  // State i k steps into this run.
  double run_x(uint32_t k, int i) const { return run_row(pw_->k[k], i, x0_.data(), u0_.data()); }
  Eigen::Vector3d run_state(uint32_t k) const { return {run_x(k, 0), run_x(k, 1), run_x(k, 2)}; }
  // The table positions (m) at steps k, k + every, ... of the run, count of
  // them. The anchor is read into locals once: stores through out might
  // alias the plant's own doubles, and run_x would read them again each time.
  void run_positions(uint32_t k, uint32_t every, uint64_t count, double* out) const {
    const double x0[3] = {x0_(0), x0_(1), x0_(2)}, u0[2] = {u0_(0), u0_(1)}, to_m = rad_to_m_;
    const Power* pk = pw_->k.get();
    for (uint64_t i = 0; i < count; ++i) out[i] = run_row(pk[k + i * every], 2, x0, u0) * to_m;
  }
  double run_stuck_current(uint32_t k) const { return pw_->stuck_a[k] * x0_(0) + pw_->stuck_b[k] * v_; }
  // hold() and hold_counting(): with changes, through the count changes.
  Held hold_through(double volts, uint64_t n, Samples& samples, std::vector<CountChange>* changes,
                    uint64_t step0);
  // Steps lo .. hi of the run cut into pieces on which the angle is
  // monotone: each piece ends at a cut (ascending, the last hi).
  struct Pieces {
    uint32_t cut[4];
    int n;
  };
  Pieces pieces(uint32_t lo, uint32_t hi) const;
  // Of the steps from k_ to the last cut of p (pieces of this run from at
  // most k_ on), how many end without an event (a count other than
  // `count`, or friction stopping the shaft); how many stuck steps come
  // before the breakaway.
  uint32_t steps_before_event(const Pieces& p, int64_t count) const;
  // An event at step j of the run: a count other than `count`, or (stops)
  // friction stopping the shaft.
  bool event_at(uint32_t j, int64_t count, bool stops) const {
    return (stops && run_x(j, 1) * dir_ <= 0) || count_at(run_x(j, 2)) != count;
  }
  // The first step of from + 1 .. to with the event, which `to` has and
  // `from` has not, on a piece of the run where the angle is monotone.
  // Without stops the speed keeps its sign over the piece: only the count
  // can change.
  uint32_t first_event(uint32_t from, uint32_t to, int64_t count, bool stops) const;
  // Stretches shorter than this go by step().
  static constexpr uint64_t kSearchFrom = 3;
  uint32_t steps_before_breakaway(uint32_t lim) const;

  // floor(theta * counts per radian), as floor() gives it but without a
  // library call (the searches ask it often): truncation, one down for a
  // negative fraction. Exact for any count an int64 holds.
  int64_t count_at(double theta_rad) const {
    const double c = theta_rad * rad_to_count_;
    const int64_t t = int64_t(c);
    return double(t) > c ? t - 1 : t;
  }

  std::shared_ptr<const Powers> pw_;
  uint32_t reached_ = 0;        // steps of a run below this are in the tables
  bool monotone_runs_ = false;  // real poles: a run's speed has at most one extremum
  // The motion (take_motion() copies each of these).
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d x0_ = Eigen::Vector3d::Zero();  // the run's anchor
  Eigen::Vector2d u0_ = Eigen::Vector2d::Zero();  // its input [V, tau_ext]
  double v_ = 0, dir_ = 0;                        // its volts; its direction of motion
  uint32_t k_ = 0;                                // steps into the run
  uint64_t runs_ = 0;                             // anchors taken: a run's identity within a hold
  bool anchored_ = false;
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
