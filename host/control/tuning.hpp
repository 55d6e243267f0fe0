// Gain tuning for `motionctl tune`: pure analysis of captured samples, no I/O.
//
// Relay method (Astrom-Hagglund): under relay control u = +-d (drive units,
// hysteresis eps counts) the axis settles into a limit cycle whose period Tu
// and amplitude a give, by the describing function of the relay, the point of
// the loop's frequency response where it crosses the negative real axis:
// the ultimate gain Ku and period Tu. Classical rules turn them into gains.
//
// Model method: least squares on a captured open-loop excitation identifies
// the axis as P(s) = K / (s (tau s + 1)) (counts from drive units, the DC
// motor position loop of docs/plant.md), a PID with derivative filter is
// designed by pole placement on it, and the step response of the designed
// loop is predicted with the quantized controller the core runs.
//
// docs/tuning.md gives the equations, their limits and the measured numbers.
// Units as in host/pid_design.hpp: counts, drive units (+-32767), seconds.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "host/control/pid_design.hpp"
#include "host/control/step_metrics.hpp"

namespace mc::host {

// --- Relay feedback -----------------------------------------------------------

// The relay: +d while the error exceeds eps, -d below -eps, unchanged in
// between (starts at +d).
class Relay {
 public:
  // d > 0, eps >= 0; throws InputError.
  Relay(double d, double eps);
  double update(double error);
  double d() const { return d_; }
  double eps() const { return eps_; }

 private:
  double d_, eps_, out_;
};

struct RelayResult {
  double ku;             // 4 d / (pi sqrt(a^2 - eps^2)), drive units per count
  double tu;             // oscillation period, s (mean over the settled periods)
  double amplitude;      // a: first-harmonic amplitude of the position about its mean, counts
  double phase_deg;      // phase of the loop point found: -180 + asin(eps / a)
  double period_spread;  // (longest - shortest) / mean of the settled periods
  int periods;           // settled periods the estimate averages
};

// y: positions (counts) sampled every ts under relay control of amplitude d
// and hysteresis eps about a fixed setpoint. The first third of the periods
// (at least one) counts as the transient and is skipped. Throws InputError
// for fewer than 3 settled periods, a period shorter than 4 samples, or an
// amplitude not above eps.
RelayResult relay_analyse(const std::vector<double>& y, double ts, double d, double eps);

// The rules were made for self-regulating plants. A position axis has an
// integrator of its own, and a rule with Ti = Tu/2 puts a second one close
// to the crossover: on the default axis the "no overshoot" variant
// overshoots most (docs/tuning.md). Tyreus-Luyben's slow integral suits it
// best and is the default.
enum class RelayRule {
  ZieglerNichols,  // Kp 0.6 Ku, Ti Tu/2, Td Tu/8: quarter-decay, aggressive
  TyreusLuyben,    // Kp Ku/2.2, Ti 2.2 Tu, Td Tu/6.3: more damping, slow integral
  NoOvershoot,     // Kp 0.2 Ku, Ti Tu/2, Td Tu/3 (the ZN variant so named for self-regulating plants)
};
// Ki = Kp/Ti, Kd = Kp Td, Tf = Td / n_filter but at least ts (a filter faster
// than the sample period only adds a sign-alternating pole).
PidGains design_relay(const RelayResult& r, double ts, RelayRule rule = RelayRule::TyreusLuyben,
                      double n_filter = 10);

// --- Excitation ---------------------------------------------------------------

// What the tests validate on the default machine (docs/tuning.md): a
// balanced PRBS of 4096 drive units (6 V at 48 V) with 10 ms bits (longer
// than the axis' tau) for 1 s, and a relay of 8192 drive units without
// hysteresis for 0.3 s (about 30 periods).
struct TuneDefaults {
  static constexpr double prbs_amplitude = 4096, prbs_bit_s = 10e-3, prbs_duration_s = 1.0;
  static constexpr double relay_amplitude = 8192, relay_hysteresis = 0, relay_duration_s = 0.3;
};

// A maximal-length PRBS (10-bit LFSR, period 1023 bits) of +-amplitude, each
// bit held for round(bit_s / ts) samples, duration_s long. balanced: every
// bit is followed by its negation, so that the open-loop position returns
// after each pair instead of wandering like a random walk (the table's travel
// is finite). Throws InputError for non-positive or non-finite arguments.
std::vector<double> prbs(double amplitude, double bit_s, double duration_s, double ts, bool balanced = true);
// A Schroeder-phased multisine: `tones` equal-amplitude sines log-spaced
// from f_lo_hz to f_hi_hz (each rounded to a whole number of cycles over
// duration_s), scaled so the peak is amplitude.
std::vector<double> multisine(double amplitude, double f_lo_hz, double f_hi_hz, int tones, double duration_s,
                              double ts);

// --- Identification -----------------------------------------------------------

struct AxisModel {
  double k;         // counts/s per drive unit (steady speed gain)
  double tau;       // s, time constant: the sum of the identified velocity lags
  double tau_fast;  // s, the faster of two velocity lags (the motor's L/R); 0: none identified
  double ts;        // s, the capture's sample period
  double coulomb;   // drive units of friction offset (0 when not estimated)
  double fit_rms;   // counts, RMS of measured minus simulated position over the capture
  int samples;      // samples in the regression
};

// u(k): drive output (drive units) applied from sample k to k+1; y(k):
// position (counts) at sample k; open loop. Least squares on the ZOH
// discretization of K/(s (tau s + 1)),
//   y(k) = (1 + p) y(k-1) - p y(k-2) + b1 u(k-1) + b2 u(k-2) [+ c sgn v(k-1)],
// i.e. the brief's a1 = 1 + p, a2 = -p with the integrator's pole fixed at 1,
// refined by instrumental variables so that encoder quantization does not
// bias tau. Throws InputError for mismatched or too short captures, no
// excitation, or data that do not fit a stable DC-motor axis (p outside (0,1)).
AxisModel identify(const std::vector<double>& u, const std::vector<double>& y, double ts, bool coulomb = true,
                   bool fast_pole = true);

// --- Design and prediction ----------------------------------------------------

// Pole placement on K/(s (tau s + 1)) with C(s) = Kp + Ki/s + Kd s/(Tf s + 1):
// the closed loop's four poles at s^2 + 2 zeta wc s + wc^2 and a double real
// pole at -n wc; g.ts = m.ts. The default damping is 2 (the "pair" is two
// real poles, 0.27 wc and 3.7 wc): the PID acts on the error, so its zeros
// are zeros of the command response too and add overshoot that the poles do
// not show; with zeta = 2, n = 2 the default axis overshoots about 6 %
// (docs/tuning.md). Throws InputError when the specification needs negative
// gains or a negative Tf (wc too low for tau) or gives Tf below ts/2.
PidGains design_model(const AxisModel& m, double wc, double zeta = 2.0, double n = 2.0);
// The bandwidth `tune --method model` uses without options (reasons in tuning.cpp).
double default_bandwidth(const AxisModel& m);
// The fastest closed loop a PID sampled every ts can be asked for: the
// Nyquist frequency pi/ts, rad/s. Beyond it no design exists, whatever the
// model; tune refuses such a --bandwidth before its experiment.
double max_bandwidth(double ts);
// wc unless it is outside 0 < wc <= max_bandwidth(ts): InputError naming `quantity`.
double check_bandwidth(double wc, double ts, std::string_view quantity, std::string_view as_written = {});

// The step response of the loop with the core's quantized controller
// (pid_design + the hls twin), output limit out_limit, integer encoder
// feedback, and the model as the plant (Coulomb offset included): what a
// `step --size step` capture on the board should show.
struct Prediction {
  StepMetrics metrics;
  std::vector<double> t, y, u;  // the simulated capture
};
Prediction predict_step(const AxisModel& m, const PidGains& g, double step, double duration_s,
                        double out_limit = 32767);

}  // namespace mc::host
