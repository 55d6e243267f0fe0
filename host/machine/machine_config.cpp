#include "host/machine/machine_config.hpp"

#include <toml++/toml.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <tuple>

#include "hls/board_regs.hpp"
#include "hls/pid_core.hpp"
#include "host/base/errors.hpp"
#include "host/control/pid_design.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::machine {
namespace {

using mc::host::format_number;
using mc::host::InputError;
using mc::host::quote;

constexpr double kPi = 3.14159265358979323846;

// The board as built (rtl/motioncore_icebreaker.v): three axes share the
// PID's sweep, and the host link runs at 1 Mbit/s.
constexpr int kBoardAxes = 3;
constexpr double kLinkBaud = 1e6;
// The clock range a board can run: the link's UART needs at least two
// clocks per bit, and the watchdog's reset period CLK_HZ/10 must fit its
// WDOG_W-bit register.
constexpr double kMinClockHz = 2 * kLinkBaud;
constexpr double kMaxClockHz = 10.0 * double((1u << mc::board::WDOG_W) - 1);
// The FERR register holds the following-error limit in 16 bits of counts.
constexpr double kMaxFerrCounts = 65535;
static_assert(kStepTimeMaxClocks == (1 << mc::board::bits::SC_TIME_BITS) - 1);
// Positions are 32-bit counts on the board.
constexpr double kMaxPosCounts = 2147483647.0;

enum class Range { positive, non_negative, any };

std::string describe(Range r, std::string_view unit) {
  std::string s = r == Range::positive       ? "a number > 0"
                  : r == Range::non_negative ? "a number >= 0"
                                             : "a number";
  if (!unit.empty()) s += " (" + std::string(unit) + ")";
  return s;
}

// The text of a value as the user wrote it, for messages.
std::string as_written(const toml::node& n) {
  if (const auto* s = n.as_string()) return quote(s->get());
  if (const auto* i = n.as_integer()) return std::to_string(i->get());
  if (const auto* f = n.as_floating_point()) return format_number(f->get());
  if (const auto* b = n.as_boolean()) return b->get() ? "true" : "false";
  if (n.is_table()) return "a table";
  if (n.is_array()) return "an array";
  return "a date/time";
}

// One TOML table being read: hands out typed values with their ranges
// checked, remembers which keys were read, and in finish() rejects the rest,
// so that a misspelt key is an error instead of a silently unused line.
class Reader {
 public:
  Reader(const toml::table& t, std::string path, const std::string& file, int64_t line)
      : t_(t), path_(std::move(path)), file_(file) {
    const auto l = t.source().begin.line;
    line_ = l > 0 ? int64_t(l) : line;
  }

  // hi: the largest value that is physically sane, and why (for the message).
  double number(std::string_view key, Range r, std::string_view unit,
                double hi = std::numeric_limits<double>::infinity(), std::string_view why = {}) {
    const toml::node& n = need(key);
    double v;
    if (const auto* i = n.as_integer()) {
      v = double(i->get());
    } else if (const auto* f = n.as_floating_point()) {
      v = f->get();
    } else {
      throw bad(key, n, describe(r, unit), "wrong type");
    }
    const bool ok = std::isfinite(v) && (r == Range::any || (r == Range::positive ? v > 0 : v >= 0));
    if (!ok) throw bad(key, n, describe(r, unit));
    if (v > hi) {
      std::string expected = describe(r, unit) + " up to " + format_number(hi);
      if (!why.empty()) expected += " (" + std::string(why) + ")";
      throw bad(key, n, expected, "above the range");
    }
    return v;
  }

  // A key added after the first release: files written before it keep
  // loading, with the documented default (configs/default.toml names it).
  double number_or(std::string_view key, double fallback, Range r, std::string_view unit,
                   double hi = std::numeric_limits<double>::infinity(), std::string_view why = {}) {
    return absent(key) ? fallback : number(key, r, unit, hi, why);
  }
  int integer_or(std::string_view key, int fallback, int lo, int hi, std::string_view unit) {
    return absent(key) ? fallback : integer(key, lo, hi, unit);
  }

  int integer(std::string_view key, int lo, int hi, std::string_view unit) {
    const toml::node& n = need(key);
    const std::string expected = "a whole number " + std::to_string(lo) + ".." + std::to_string(hi) +
                                 (unit.empty() ? "" : " (" + std::string(unit) + ")");
    const auto* i = n.as_integer();
    if (!i) throw bad(key, n, expected, "wrong type");
    if (i->get() < lo || i->get() > hi) throw bad(key, n, expected);
    return int(i->get());
  }

  bool boolean(std::string_view key) {
    const toml::node& n = need(key);
    const auto* b = n.as_boolean();
    if (!b) throw bad(key, n, "true or false", "wrong type");
    return b->get();
  }
  bool boolean_or(std::string_view key, bool fallback) { return absent(key) ? fallback : boolean(key); }

  std::string string(std::string_view key, const std::vector<std::string>& allowed) {
    const toml::node& n = need(key);
    std::string expected;
    for (const auto& a : allowed) expected += (expected.empty() ? "one of " : ", ") + quote(a);
    const auto* s = n.as_string();
    if (!s) throw bad(key, n, expected, "wrong type");
    if (std::find(allowed.begin(), allowed.end(), s->get()) == allowed.end()) throw bad(key, n, expected);
    return s->get();
  }

  Reader table(std::string_view key) {
    const toml::node& n = need(key);
    const auto* t = n.as_table();
    if (!t) throw bad(key, n, "a table [" + full(key) + "]", "wrong type");
    return Reader(*t, full(key), file_, line_);
  }

  // The keys of this table, in file order, for tables of named entries.
  std::vector<std::string> keys() const {
    std::vector<std::string> k;
    for (const auto& [key, node] : t_) k.emplace_back(key.str());
    return k;
  }

  bool has(std::string_view key) const { return t_.contains(key); }

  // Every key not read is an error: a typo must not fall back to a default.
  void finish() const {
    for (const auto& [key, node] : t_) {
      if (used_.count(std::string(key.str()))) continue;
      std::string known;
      for (const auto& u : order_) known += (known.empty() ? "" : ", ") + u;
      throw InputError(where(node) + full(key.str()), as_written(node), "one of: " + known, "unknown key");
    }
  }

  // An error about this table as a whole, or about a relation between keys.
  InputError error(std::string_view key, const std::string& value, const std::string& expected,
                   const std::string& problem = {}) const {
    const toml::node* n = t_.get(key);
    return InputError((n ? where(*n) : where_table()) + full(key), value, expected, problem);
  }

  const std::string& path() const { return path_; }
  int64_t line() const { return line_; }

 private:
  // An optional key left out: known (listed in "expected one of"), not an
  // error.
  bool absent(std::string_view key) {
    if (has(key)) return false;
    used_.insert(std::string(key));
    order_.emplace_back(key);
    return true;
  }

  const toml::node& need(std::string_view key) {
    const std::string k(key);
    if (!used_.count(k)) order_.push_back(k);
    used_.insert(k);
    const toml::node* n = t_.get(key);
    if (!n)
      throw InputError(where_table() + full(key), "(none)", "the key in [" + path_ + "]", "missing key");
    return *n;
  }

  InputError bad(std::string_view key, const toml::node& n, const std::string& expected,
                 const std::string& problem = {}) const {
    return InputError(where(n) + full(key), as_written(n), expected, problem);
  }

  std::string where(const toml::node& n) const {
    const auto l = n.source().begin.line;
    return file_ + ":" + std::to_string(l > 0 ? int64_t(l) : line_) + ": ";
  }
  std::string where_table() const { return file_ + ":" + std::to_string(line_) + ": "; }
  std::string full(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }

  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  int64_t line_ = 1;
  std::set<std::string> used_;
  std::vector<std::string> order_;  // keys asked for, in order, for "expected one of"
};

// A mechanical contact settles within milliseconds: beyond this a bounce
// time is a value in the wrong unit.
constexpr double kMaxBounceS = 0.1;
constexpr const char* kBounceWhy = "a contact settles within milliseconds";

// The axis's travel and top speed are read: the switch must lie where the
// homing cycle can drive to it, at speeds the axis may run.
HomeConfig read_home(Reader r, const AxisConfig& a) {
  HomeConfig h;
  h.switch_m = r.number("switch_m", Range::any, "m");
  if (h.switch_m < a.travel_min_m || h.switch_m > a.travel_max_m)
    throw r.error("switch_m", format_number(h.switch_m),
                  "a position within the axis's travel " + format_number(a.travel_min_m) + ".." +
                      format_number(a.travel_max_m) + " m (travel_min_m..travel_max_m)");
  h.direction = r.integer("direction", -1, 1, "+1: closed at >= switch_m, -1: closed at <= switch_m");
  if (h.direction == 0) throw r.error("direction", "0", "+1 (the switch at the + end) or -1 (at the - end)");
  h.bounce_s = r.number_or("bounce_s", h.bounce_s, Range::non_negative, "s", kMaxBounceS, kBounceWhy);
  h.order = r.integer_or("order", h.order, 0, kBoardAxes - 1, "homing pass: one per axis at most");
  h.seek_m_s = r.number_or("seek_m_s", h.seek_m_s, Range::positive, "m/s");
  if (h.seek_m_s > a.max_speed_m_s)
    throw r.error("seek_m_s", format_number(h.seek_m_s),
                  "at most the axis's max_speed_m_s = " + format_number(a.max_speed_m_s) + " m/s",
                  "above the range");
  h.locate_m_s = r.number_or("locate_m_s", std::min(h.locate_m_s, h.seek_m_s), Range::positive, "m/s");
  if (h.locate_m_s > h.seek_m_s)
    throw r.error("locate_m_s", format_number(h.locate_m_s),
                  "at most seek_m_s = " + format_number(h.seek_m_s) +
                      " m/s (the second approach is the slow, precise one)",
                  "above the range");
  h.pull_off_m = r.number_or("pull_off_m", h.pull_off_m, Range::positive, "m");
  if (h.pull_off_m >= a.travel_max_m - a.travel_min_m)
    throw r.error("pull_off_m", format_number(h.pull_off_m),
                  "less than the axis's travel, " + format_number(a.travel_max_m - a.travel_min_m) + " m",
                  "above the range");
  r.finish();
  return h;
}

ProbeConfig read_probe(Reader r) {
  ProbeConfig p;
  p.bounce_s = r.number_or("bounce_s", p.bounce_s, Range::non_negative, "s", kMaxBounceS, kBounceWhy);
  r.finish();
  return p;
}

SpindleConfig read_spindle(Reader r) {
  SpindleConfig s;
  s.max_rpm = r.number_or("max_rpm", s.max_rpm, Range::positive, "rpm");
  s.min_rpm = r.number_or("min_rpm", s.min_rpm, Range::non_negative, "rpm");
  if (!(s.min_rpm < s.max_rpm))
    throw r.error("min_rpm", format_number(s.min_rpm), "min_rpm < max_rpm = " + format_number(s.max_rpm));
  s.mist_on_dir = r.boolean_or("mist_on_dir", s.mist_on_dir);
  r.finish();
  return s;
}

MotorParams read_motor(Reader r) {
  MotorParams m{};
  // The upper bounds are a decade or more beyond any motor a small machine
  // carries: they catch a value typed in the wrong unit, not a big motor.
  constexpr const char* kMotor = "beyond any motor of a small machine";
  m.r_ohm = r.number("resistance_ohm", Range::positive, "ohm", 1e3, kMotor);
  m.l_h = r.number("inductance_h", Range::positive, "H", 1, kMotor);
  m.kt_nm_per_a = r.number("torque_constant_nm_per_a", Range::positive, "N*m/A", 100, kMotor);
  m.ke_v_s_per_rad = r.number("back_emf_v_s_per_rad", Range::positive, "V*s/rad", 100, kMotor);
  m.j_kg_m2 = r.number("inertia_kg_m2", Range::positive, "kg*m^2", 1, kMotor);
  m.b_nm_s_per_rad = r.number("viscous_nm_s_per_rad", Range::non_negative, "N*m*s/rad", 100, kMotor);
  m.coulomb_nm = r.number("coulomb_nm", Range::non_negative, "N*m", 1e3, kMotor);
  m.stiction_nm = r.number("stiction_nm", Range::non_negative, "N*m", 1e3, kMotor);
  if (m.stiction_nm < m.coulomb_nm) {
    throw r.error("stiction_nm", format_number(m.stiction_nm),
                  "stiction_nm >= coulomb_nm = " + format_number(m.coulomb_nm) +
                      " (the breakaway torque is at least the sliding friction)");
  }
  r.finish();
  return m;
}

DriveConfig read_drive(Reader r, double clock_hz) {
  DriveConfig d{};
  d.kind = r.string("kind", {"pwm", "dac"}) == "pwm" ? DriveConfig::Kind::Pwm : DriveConfig::Kind::Dac;
  d.supply_v = r.number("supply_v", Range::positive, "V", 1e3, "a drive of a small machine");
  d.pwm_bits = r.integer("pwm_bits", 1, 15, "bits of the PWM counter");
  d.pwm_hz = clock_hz / std::ldexp(1.0, d.pwm_bits);
  d.pwm_switching = r.boolean("pwm_switching");
  d.dac_bits = r.integer("dac_bits", 1, 16, "bits");
  d.dac_range_v = r.number("dac_range_v", Range::positive, "V", 100, "a DAC's output");
  d.amp_gain = r.number("amp_gain", Range::positive, "V/V", 1e3, "a linear amplifier");
  r.finish();
  return d;
}

PidConfig read_pid(Reader r, double clock_hz) {
  PidConfig p{};
  p.kp = r.number("kp", Range::positive, "drive units per count");
  p.ki = r.number("ki", Range::non_negative, "drive units per count*s");
  p.kd = r.number("kd", Range::non_negative, "drive units per count/s");
  p.tf_s = r.number("tf_s", Range::non_negative, "s");
  p.ts_s = r.number("ts_s", Range::positive, "s");
  try {
    mc::host::core_ts_cycles(p.ts_s, clock_hz, uint32_t(mc::pid_latency(kBoardAxes)), "ts_s");
    mc::host::check_core_kp(p.kp, "kp");
  } catch (const InputError& e) {
    const std::string& key = e.quantity();
    throw r.error(key, format_number(key == "kp" ? p.kp : p.ts_s), e.expected(), e.problem());
  }
  p.ff1 = r.number("ff1", Range::any, "drive units per count/s");
  p.ff2 = r.number("ff2", Range::any, "drive units per count/s^2");
  p.out_limit = r.number("out_limit", Range::positive, "drive units");
  if (p.out_limit > 32767) throw r.error("out_limit", format_number(p.out_limit), "0 < out_limit <= 32767");
  // The core must be able to hold the coefficients these gains give.
  try {
    mc::host::design({p.kp, p.ki, p.kd, p.tf_s, p.ts_s, p.ff1, p.ff2});
  } catch (const InputError& e) {
    throw r.error("kp", format_number(p.kp), "gains the core's coefficient words can hold", e.what());
  }
  r.finish();
  return p;
}

StepperConfig read_stepper(Reader r, double clock_hz) {
  StepperConfig s;
  s.rotor_teeth = r.integer("rotor_teeth", 1, 1000, "rotor teeth: 50 for 200 full steps per rev");
  s.microsteps = r.integer("microsteps", 1, 256, "STEP pulses per full step");
  s.current_a = r.number("current_a", Range::positive, "A", 100, "a stepper driver's phase current");
  s.detent_nm = r.number("detent_nm", Range::non_negative, "N*m", 100, "a stepper's cogging torque");
  // STEP_CFG holds each time as 1..63 board clocks.
  const double longest = double(kStepTimeMaxClocks) / clock_hz;
  const std::string why = std::to_string(kStepTimeMaxClocks) + " board clocks, what STEP_CFG holds";
  s.step_pulse_s = r.number_or("step_pulse_s", s.step_pulse_s, Range::positive, "s");
  s.dir_setup_s = r.number_or("dir_setup_s", s.dir_setup_s, Range::positive, "s");
  for (const auto& [key, v] :
       {std::pair{"step_pulse_s", s.step_pulse_s}, std::pair{"dir_setup_s", s.dir_setup_s}})
    if (v > longest)
      throw r.error(key, format_number(v),
                    "0 < " + std::string(key) + " <= " + format_number(longest) + " s (" + why + ")");
  s.closed_loop = r.boolean_or("closed_loop", s.closed_loop);
  s.step_active_low = r.boolean_or("step_active_low", s.step_active_low);
  s.dir_reversed = r.boolean_or("dir_reversed", s.dir_reversed);
  r.finish();
  return s;
}

AxisConfig read_axis(Reader r, const std::string& name, double clock_hz) {
  AxisConfig a{};
  a.name = name;
  constexpr const char* kSmall = "a small machine";
  a.lead_m_per_rev = r.number("lead_m_per_rev", Range::positive, "m", 1, kSmall);
  a.gear_ratio = r.number("gear_ratio", Range::positive, "motor revs per screw rev", 1e3, kSmall);
  a.load_kg = r.number("load_kg", Range::non_negative, "kg", 1e4, kSmall);
  a.load_force_n = r.number("load_force_n", Range::any, "N", 1e5, kSmall);
  if (a.load_force_n < -1e5) throw r.error("load_force_n", format_number(a.load_force_n), "-1e5..1e5 N");
  a.encoder_cpr = r.integer("encoder_counts_per_rev", 4, 1 << 24, "counts per motor rev after 4x decoding");
  const double cpm = counts_per_m(a);
  a.max_following_error_m =
      r.number("max_following_error_m", Range::positive, "m", kMaxFerrCounts / cpm,
               "65535 counts, what the board's FERR register holds, at " + format_number(cpm) + " counts/m");
  if (a.max_following_error_m * cpm < 1)
    throw r.error("max_following_error_m", format_number(a.max_following_error_m),
                  "at least one encoder count (" + format_number(1 / cpm) + " m)");
  const double top = mc::host::max_iteration_rate(clock_hz) / cpm;
  a.max_speed_m_s =
      r.number("max_speed_m_s", Range::positive, "m/s", top,
               "the interpolator's top rate " + format_number(mc::host::max_iteration_rate(clock_hz)) +
                   " counts/s at clock_hz");
  a.max_accel_m_s2 = r.number_or("max_accel_m_s2", 1.0, Range::positive, "m/s^2");
  // Travel: machine coordinates from where the axes were when the board
  // started (there is no homing yet), within what the board's 32-bit
  // counters hold; default +-1 m (less where the counters reach less).
  const double reach = kMaxPosCounts / cpm;
  a.travel_min_m = r.number_or("travel_min_m", -std::min(1.0, reach), Range::any, "m");
  a.travel_max_m = r.number_or("travel_max_m", std::min(1.0, reach), Range::any, "m");
  if (a.travel_min_m < -reach || a.travel_max_m > reach)
    throw r.error(a.travel_min_m < -reach ? "travel_min_m" : "travel_max_m",
                  format_number(a.travel_min_m < -reach ? a.travel_min_m : a.travel_max_m),
                  "a travel within the board's 32-bit positions: +-" + format_number(reach) + " m");
  if (!(a.travel_min_m < a.travel_max_m))
    throw r.error("travel_max_m", format_number(a.travel_max_m),
                  "travel_max_m > travel_min_m = " + format_number(a.travel_min_m));
  if (r.has("home")) a.home = read_home(r.table("home"), a);
  a.motor = read_motor(r.table("motor"));
  a.drive = read_drive(r.table("drive"), clock_hz);
  a.pid = read_pid(r.table("pid"), clock_hz);
  if (r.has("stepper")) {
    a.stepper = read_stepper(r.table("stepper"), clock_hz);
    if (a.encoder_cpr != a.stepper->steps_per_rev())
      throw r.error("encoder_counts_per_rev", std::to_string(a.encoder_cpr),
                    std::to_string(a.stepper->steps_per_rev()) +
                        " on a stepper axis: one count per STEP pulse, 4 * rotor_teeth * microsteps");
  }
  r.finish();
  return a;
}

PlannerSettings read_planner(Reader r) {
  PlannerSettings p;
  p.junction_deviation_m = r.number_or("junction_deviation_m", p.junction_deviation_m, Range::positive, "m");
  p.arc_tolerance_m = r.number_or("arc_tolerance_m", p.arc_tolerance_m, Range::positive, "m");
  p.ramp_piece_s = r.number_or("ramp_piece_s", p.ramp_piece_s, Range::positive, "s");
  p.accel_window_s = r.number_or("accel_window_s", p.accel_window_s, Range::positive, "s");
  p.queue_ahead_s = r.number_or("queue_ahead_s", p.queue_ahead_s, Range::positive, "s");
  if (p.ramp_piece_s > p.accel_window_s)
    throw r.error("ramp_piece_s", format_number(p.ramp_piece_s),
                  "ramp_piece_s <= accel_window_s = " + format_number(p.accel_window_s));
  r.finish();
  return p;
}

WorkpieceConfig read_workpiece(Reader r) {
  WorkpieceConfig w;
  w.min_x_m = r.number("min_x_m", Range::any, "m");
  w.min_y_m = r.number("min_y_m", Range::any, "m");
  w.max_x_m = r.number("max_x_m", Range::any, "m");
  w.max_y_m = r.number("max_y_m", Range::any, "m");
  w.top_z_m = r.number("top_z_m", Range::any, "m");
  w.tilt_x = r.number("tilt_x", Range::any, "m/m");
  w.tilt_y = r.number("tilt_y", Range::any, "m/m");
  w.bow_m = r.number("bow_m", Range::any, "m");
  w.noise_m = r.number("noise_m", Range::non_negative, "m", 1e-3, "a machined or cast face");
  w.noise_seed = r.integer("noise_seed", 0, 1 << 30, "");
  for (const auto& [lo, hi, a, b] : {std::tuple{"min_x_m", "max_x_m", w.min_x_m, w.max_x_m},
                                     std::tuple{"min_y_m", "max_y_m", w.min_y_m, w.max_y_m}})
    if (!(b > a))
      throw r.error(hi, format_number(b), std::string(hi) + " > " + lo + " = " + format_number(a));
  // A bed a few tenths out, not a ramp: beyond these a probe would not find it.
  for (const auto& [key, v, most] : {std::tuple{"tilt_x", w.tilt_x, 0.1}, std::tuple{"tilt_y", w.tilt_y, 0.1},
                                     std::tuple{"bow_m", w.bow_m, 0.01}})
    if (std::abs(v) > most)
      throw r.error(key, format_number(v), "at most " + format_number(most) + " either way",
                    "above the range");
  r.finish();
  return w;
}

std::string lower(std::string_view s) {
  std::string l(s);
  for (char& c : l) c = char(std::tolower(static_cast<unsigned char>(c)));
  return l;
}

}  // namespace

MachineConfig parse_machine(std::string_view toml_text, const std::string& source_name) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(source_name + ":" + std::to_string(e.source().begin.line) + ": TOML",
                     "column " + std::to_string(e.source().begin.column), "valid TOML",
                     std::string(e.description()));
  }
  Reader top(root, "", source_name, 1);
  MachineConfig m;
  m.source = source_name;
  {
    Reader r = top.table("machine");
    m.clock_hz = r.number("clock_hz", Range::positive, "Hz", kMaxClockHz,
                          "the watchdog's reset period clock_hz/10 must fit its 24-bit register");
    if (m.clock_hz < kMinClockHz)
      throw r.error(
          "clock_hz", format_number(m.clock_hz),
          "at least " + format_number(kMinClockHz) + " Hz (two clocks per bit of the 1 Mbit/s link)",
          "below the range");
    m.plant_dt_s = r.number("plant_dt_s", Range::positive, "s");
    const double k = m.plant_dt_s * m.clock_hz;
    if (k < 2 || std::fabs(k - std::round(k)) > 1e-6 * k)
      throw r.error(
          "plant_dt_s", format_number(m.plant_dt_s),
          "a whole number of at least 2 clock cycles (1/clock_hz = " + format_number(1 / m.clock_hz) + " s)",
          format_number(k) + " cycles");
    r.finish();
  }
  {
    Reader r = top.table("host_loop");
    m.host_period_s = r.number("period_s", Range::positive, "s", 1, "a host loop");
    m.host_io_latency_s = r.number("io_latency_s", Range::non_negative, "s", 1, "a host's I/O");
    m.host_dac_bits = r.integer("dac_bits", 1, 16, "bits");
    m.host_dac_range_v = r.number("dac_range_v", Range::positive, "V", 100, "a DAC's output");
    r.finish();
  }
  if (top.has("planner")) m.planner = read_planner(top.table("planner"));
  if (top.has("workpiece")) m.workpiece = read_workpiece(top.table("workpiece"));
  if (top.has("probe")) m.probe = read_probe(top.table("probe"));
  if (top.has("spindle")) m.spindle = read_spindle(top.table("spindle"));
  Reader axes = top.table("axis");
  const std::vector<std::string> names = {"x", "y", "z"};
  for (const std::string& k : axes.keys()) {
    if (std::find(names.begin(), names.end(), k) == names.end()) {
      throw axes.error(k, "[axis." + k + "]", "axes x, y and optionally z", "unknown axis");
    }
  }
  for (const std::string& n : names) {
    if (n == "z" && !axes.has(n)) continue;
    m.axes.push_back(read_axis(axes.table(n), n, m.clock_hz));
  }
  // The plant must move at least as often as the loops sample it.
  for (const AxisConfig& a : m.axes) {
    if (m.plant_dt_s > a.pid.ts_s * (1 + 1e-9)) {
      Reader r = top.table("machine");
      throw r.error("plant_dt_s", format_number(m.plant_dt_s),
                    "at most the axes' sample period (axis." + a.name +
                        ".pid.ts_s = " + format_number(a.pid.ts_s) + " s)");
    }
  }
  axes.finish();
  top.finish();
  return m;
}

MachineConfig load_machine(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("--config", quote(path), "a readable machine config file (TOML)", "cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_machine(text.str(), path);
}

MachineConfig machine_or_default(const std::string& path) {
  return path.empty() ? default_machine() : load_machine(path);
}

const AxisConfig& axis(const MachineConfig& m, std::string_view name) {
  std::string valid;
  for (const AxisConfig& a : m.axes) {
    if (lower(a.name) == lower(name)) return a;
    valid += (valid.empty() ? "" : ", ") + a.name;
  }
  throw InputError("axis", quote(name), "one of the axes in " + m.source + ": " + valid, "no such axis");
}

int step_time_clocks(double seconds, double clock_hz) {
  // A hair below a whole clock counts as that clock: 2 us at 12 MHz is 24.
  return std::clamp(int(std::ceil(seconds * clock_hz - 1e-6)), 1, kStepTimeMaxClocks);
}

double counts_per_m(const AxisConfig& a) {
  return a.encoder_cpr * a.gear_ratio / a.lead_m_per_rev;
}

double reflected_inertia_kg_m2(const AxisConfig& a) {
  const double r = a.lead_m_per_rev / (2 * kPi * a.gear_ratio);  // m of travel per rad of motor
  return a.load_kg * r * r;
}

double reflected_torque_nm(const AxisConfig& a) {
  return a.load_force_n * a.lead_m_per_rev / (2 * kPi * a.gear_ratio);
}

AxisModel axis_model(const AxisConfig& a) {
  const MotorParams& m = a.motor;
  const double j = m.j_kg_m2 + reflected_inertia_kg_m2(a);
  const double den = m.kt_nm_per_a * m.ke_v_s_per_rad + m.r_ohm * m.b_nm_s_per_rad;
  const double k_dc = m.kt_nm_per_a / den;  // rad/s per V
  const double volts_per_unit = a.drive.supply_v / 32767.0;
  const double counts_per_rad = a.encoder_cpr / (2 * M_PI);
  return {volts_per_unit * k_dc * counts_per_rad, m.r_ohm * j / den};
}

mc::host::PidGains tuned_gains(const AxisConfig& a, double ts_s, double delay_s) {
  const AxisModel g = axis_model(a);
  const double w0 = 3 * a.pid.ki / a.pid.kp;
  const double w = std::min(w0, 1 / (4 * delay_s));
  mc::host::PidGains out{};
  out.kp = 3 * g.tau * w * w / g.kg;
  out.ki = g.tau * w * w * w / g.kg;
  out.kd = std::max(0.0, (3 * g.tau * w - 1) / g.kg);
  out.tf = 1 / (10 * w);
  out.ts = ts_s;
  return out;
}

}  // namespace mc::machine
