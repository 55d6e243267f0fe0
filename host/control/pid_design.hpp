// PID coefficient design for the pid_core (hls/pid_core.hpp): the Tustin
// discretization of C(s) = Kp + Ki/s + Kd s/(Tf s + 1), its parallel-form
// realization, and the quantization of that realization into the core's
// coefficient words (mantissa * 2^(fx - shift), hls/mc_fixed.hpp).
//
// Units are those of the core: the controller maps encoder counts to drive
// units (full scale +-32767). Kp is per count, Ki per count*s, Kd per count/s,
// FF1 per count/s (of command velocity), FF2 per count/s^2; Tf, Ts in seconds.
#pragma once

#include <array>
#include <complex>
#include <cstdint>
#include <optional>
#include <string_view>

#include "hls/mc_fixed.hpp"
#include "hls/pid_core.hpp"

namespace mc::host {

struct PidGains {
  double kp, ki, kd, tf, ts;
  double ff1 = 0, ff2 = 0;
};

// Throws InputError unless ts > 0 and finite, tf >= 0 and finite, kp, ki,
// kd >= 0 and finite, ff1, ff2 finite.
void validate(const PidGains& g);

// The parallel-form parameters the core realizes, in double precision:
//   kp, ki = Ki*Ts/2, kd_a = alpha = (2Tf-Ts)/(2Tf+Ts), kd_b = beta = 2Kd/(2Tf+Ts),
//   kf1 = FF1/Ts, kf2 = FF2/Ts^2.
struct Realization {
  double kp, ki, kd_a, kd_b, kf1, kf2;
};
Realization realization(const PidGains& g);

// A second-order discrete transfer function in powers of z^-1:
//   (b0 + b1 z^-1 + b2 z^-2) / (a0 + a1 z^-1 + a2 z^-2), a0 = 1.
struct TransferFunction {
  std::array<double, 3> b, a;
};

// The Tustin-discretized C(s) for these gains (feedforward is not part of C).
TransferFunction tustin(const PidGains& g);
// The same transfer function from realization parameters (kp, ki, kd_a, kd_b),
// which is how the controller realized by quantized coefficients is obtained.
TransferFunction transfer_function(const Realization& r);

// With Tf = 0: u(k) = KA e(k) + KB e(k-1) + KC e(k-2) + u(k-2).
struct SeedForm {
  double ka, kb, kc;
};
// nullopt unless g.tf == 0, where the form exists.
std::optional<SeedForm> seed_form(const PidGains& g);

// --- Frequency response --------------------------------------------------
// H(z) at z = e^{j omega ts}.
std::complex<double> eval_z(const TransferFunction& h, double omega, double ts);
// The parallel form at z = e^{j omega ts}; unlike eval_z it does not lose
// digits to the near-cancelling polynomial coefficients at omega*ts << 1.
std::complex<double> eval_z(const Realization& r, double omega, double ts);
// C(s) at s = j omega (omega > 0).
std::complex<double> eval_s(const PidGains& g, double omega);
// C(s) at an arbitrary complex s != 0.
std::complex<double> eval_s(const PidGains& g, std::complex<double> s);

// --- Quantization -----------------------------------------------------------
// value = m * 2^(fx - s), m in [-2^23, 2^23-1], s in 0..63: the largest s whose
// rounded m fits (the most precision the word can hold). 0 -> {0, 0}. A value
// that rounds to 0 even at s = 63 also gives {0, 0} (see is_lost). Throws
// InputError naming `name` when |value| is too large for s = 0 or not finite.
mc::Coef quantize(double value, int fx, std::string_view name = "coefficient");
double realize(mc::Coef c, int fx);
// |realized - design| / |design|; 0 when design is 0.
double rel_error(double design, double realized);
// The largest magnitude the word can hold for operand fraction bits fx.
double coef_max(int fx);

// One coefficient of the core, designed and quantized.
struct FixedCoef {
  std::string_view name;     // register name: "kp", "ki", "kd_a", "kd_b", "kf1", "kf2"
  std::string_view formula;  // how it derives from the gains, for reports
  uint8_t reg;               // address within the axis (hls/pid_regs.hpp)
  int fx;                    // fraction bits of the operand it multiplies
  double design;             // ideal value
  mc::Coef coef;
  uint32_t word;
  double value;      // realized value
  double rel_error;  // |value - design| / |design|
  bool lost;         // design != 0 but realized as 0: below the word's resolution
};

struct PidDesign {
  PidGains gains;
  Realization ideal;
  TransferFunction tf;
  std::optional<SeedForm> seed;
  std::array<FixedCoef, 6> fixed;  // in register order KP..KF2
  Realization realized;            // from the quantized words
  TransferFunction fixed_tf;       // transfer_function(realized)
  double max_rel_error;
};

// Validates, designs and quantizes. Throws InputError.
PidDesign design(const PidGains& g);

// --- What the core runs ---------------------------------------------------------
// The longest sample period the core is built for (DESIGN.md: from 10 ms down
// to the shortest its datapath allows, the sweep latency G_LATENCY).
constexpr double kMaxTs = 10e-3;
// The largest Kp: at Kp = 32767 one count of error already gives full-scale
// output, so a larger Kp only turns the loop into a relay on the encoder's
// last count. The coefficient word would hold up to 2^23 - 1.
constexpr double kMaxKp = 32767;
// The Ts register value for ts: InputError naming `quantity` (quoting
// `as_written` when given) unless ts is a whole number of clock cycles at
// clk_hz from latency_cycles up to kMaxTs.
uint32_t core_ts_cycles(double ts, double clk_hz, uint32_t latency_cycles, std::string_view quantity,
                        std::string_view as_written = {});
// InputError naming `quantity` unless 0 <= kp <= kMaxKp.
void check_core_kp(double kp, std::string_view quantity, std::string_view as_written = {});

// The limit registers of one axis, as written to the core (output units for
// the limits, counts for deadband and clamp; 0 = no limit, see
// hls/pid_regs.hpp).
struct CoreLimits {
  uint32_t out_limit = 0, int_limit = 0, deadband = 0, err_limit = 0;
};

// The coefficient RAM of one axis loaded with the design's words and these
// limits: what a host writes before enabling the axis.
mc::PidParams core_params(const PidDesign& d, const CoreLimits& lim = {});

}  // namespace mc::host
