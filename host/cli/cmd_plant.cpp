// motionctl plant step: the open-loop response of one axis of the machine
// config to a terminal-voltage step at t = 0, through the same plant model
// the co-simulation uses (sim/dc_motor.hpp).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/commands.hpp"
#include "host/machine/machine_config.hpp"
#include "sim/plant/dc_motor.hpp"

namespace mc::host::cli {
namespace {

constexpr double kRowInterval = 1e-4;  // s: one CSV row per 100 us
// The longest run: 10^8 steps at the default 1 us (tens of seconds of wall
// time), and a CSV of 10^6 rows; beyond it is a typo, not an experiment.
constexpr double kMaxDurationS = 100;
constexpr double kPi = 3.14159265358979323846;

struct PlantStepOptions {
  std::string config, axis = "x", volts, duration, dt;
  bool csv = false, json = false, no_friction = false;
};

// What the linear model and the friction model predict, for the summary.
struct Prediction {
  double tau_e, tau_m;          // L/R, R J/(Kt Ke + R B)
  std::complex<double> p1, p2;  // poles of the [i, w] system, 1/s
  double w_linear;              // steady speed of the linear model
  double w_friction;            // steady speed with Coulomb friction (moving); 0 when held
  double breakaway_v;           // |V| above which the shaft leaves rest
  bool held;                    // friction on and |V| within breakaway
};

Prediction predict(const mc::machine::MotorParams& m, double j, double tau_load, double v, bool friction) {
  Prediction p{};
  p.tau_e = m.l_h / m.r_ohm;
  const double den = m.kt_nm_per_a * m.ke_v_s_per_rad + m.r_ohm * m.b_nm_s_per_rad;
  p.tau_m = m.r_ohm * j / den;
  const double a11 = -m.r_ohm / m.l_h, a12 = -m.ke_v_s_per_rad / m.l_h;
  const double a21 = m.kt_nm_per_a / j, a22 = -m.b_nm_s_per_rad / j;
  const double tr = a11 + a22, det = a11 * a22 - a12 * a21;
  const std::complex<double> disc = std::sqrt(std::complex<double>(tr * tr - 4 * det));
  p.p1 = (tr + disc) / 2.0;
  p.p2 = (tr - disc) / 2.0;
  const double g = m.kt_nm_per_a / den;  // steady speed per volt, and per R-scaled torque
  p.w_linear = g * (v - m.r_ohm * tau_load / m.kt_nm_per_a);
  // At rest the current settles at V/R: torque Kt V/R - load against stiction.
  const double drive = m.kt_nm_per_a * v / m.r_ohm - tau_load;
  p.breakaway_v = (m.stiction_nm + std::fabs(tau_load)) * m.r_ohm / m.kt_nm_per_a;
  p.held = friction && std::fabs(drive) <= m.stiction_nm;
  const double dir = drive > 0 ? 1 : -1;
  p.w_friction = friction
                     ? (p.held ? 0.0 : g * (v - m.r_ohm * (tau_load + dir * m.coulomb_nm) / m.kt_nm_per_a))
                     : p.w_linear;
  return p;
}

std::string g6(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string pole(std::complex<double> p) {
  if (p.imag() == 0) return g6(p.real()) + " 1/s (" + format_duration(-1 / p.real()) + ")";
  return g6(p.real()) + (p.imag() < 0 ? " - " : " + ") + g6(std::fabs(p.imag())) + "j 1/s";
}

void run(const PlantStepOptions& o) {
  const mc::machine::MachineConfig machine = mc::machine::machine_or_default(o.config);
  const mc::machine::AxisConfig& ax = mc::machine::axis(machine, o.axis);
  const double volts = parse_number(o.volts, "--volts");
  const double duration = require_in(parse_duration(o.duration, "--duration"), {0, kMaxDurationS, "s"},
                                     "--duration", o.duration, "of plant time");
  const double dt = o.dt.empty() ? machine.plant_dt_s : parse_duration(o.dt, "--dt");
  const double steps_per_row_f = kRowInterval / dt;
  const long steps_per_row = std::lround(steps_per_row_f);
  if (steps_per_row < 1 || std::fabs(steps_per_row_f - double(steps_per_row)) > 1e-9 * steps_per_row_f) {
    throw InputError("--dt", g6(dt) + " s",
                     "a step that divides the 100 us row interval (e.g. 1us, 10us, 100us)");
  }
  if (std::fabs(volts) > ax.drive.supply_v) {
    throw InputError(
        "--volts", g6(volts),
        "|V| <= supply_v = " + g6(ax.drive.supply_v) + " V of axis " + ax.name + " in " + machine.source,
        "beyond what the drive can apply");
  }
  const long rows = std::lround(std::floor(duration / kRowInterval + 1e-9)) + 1;
  if (rows < 2) throw InputError("--duration", g6(duration) + " s", "at least one row interval, 100 us");

  mc::sim::AxisPlant plant(ax, dt);
  plant.set_friction(!o.no_friction);
  const Prediction pred =
      predict(ax.motor, plant.inertia_kg_m2(), plant.load_torque_nm(), volts, !o.no_friction);

  std::string csv;
  char line[160];
  const auto row = [&] {
    std::snprintf(line, sizeof line, "%.6g,%.9g,%.9g,%.9g,%.9g\n", plant.time_s(), volts, plant.current_a(),
                  plant.speed_rad_s(), plant.position_rad());
    csv += line;
  };
  if (o.csv) {
    csv.reserve(size_t(rows) * 64);
    csv += "t_s,volts,current_a,speed_rad_s,position_rad\n";
    row();
  }
  double peak_i = 0, peak_t = 0, wall_ns = 0;
  for (long r = 1; r < rows; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < steps_per_row; ++k) {
      plant.step(volts);
      if (std::fabs(plant.current_a()) > std::fabs(peak_i)) {
        peak_i = plant.current_a();
        peak_t = plant.time_s();
      }
    }
    wall_ns += std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    if (o.csv) row();
  }
  const long steps = (rows - 1) * steps_per_row;
  const double ns_per_step = wall_ns / double(steps);
  if (o.csv) {
    std::cout << csv;
    return;
  }

  const double w = plant.speed_rad_s();
  const double ratio = pred.w_friction != 0 ? w / pred.w_friction : 0;
  if (o.json) {
    nlohmann::ordered_json j;
    j["config"] = machine.source;
    j["axis"] = ax.name;
    j["volts"] = volts;
    j["duration_s"] = plant.time_s();
    j["dt_s"] = dt;
    j["friction"] = !o.no_friction;
    j["steps"] = steps;
    j["inertia_kg_m2"] = plant.inertia_kg_m2();
    j["tau_electrical_s"] = pred.tau_e;
    j["tau_mechanical_s"] = pred.tau_m;
    j["poles"] = {{{"re", pred.p1.real()}, {"im", pred.p1.imag()}},
                  {{"re", pred.p2.real()}, {"im", pred.p2.imag()}}};
    j["peak_current_a"] = peak_i;
    j["peak_current_t_s"] = peak_t;
    j["final"] = {{"current_a", plant.current_a()},         {"speed_rad_s", w},
                  {"position_rad", plant.position_rad()},   {"position_m", plant.position_m()},
                  {"encoder_count", plant.encoder_count()}, {"stuck", plant.stuck()}};
    j["steady_speed_rad_s"] = pred.w_friction;
    j["steady_speed_linear_rad_s"] = pred.w_linear;
    j["breakaway_volts"] = pred.breakaway_v;
    j["held_by_stiction"] = pred.held;
    j["ns_per_step"] = ns_per_step;
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::cout << "Open-loop step of axis " << ax.name << " (" << machine.source << "): " << g6(volts)
            << " V from t = 0 for " << format_duration(plant.time_s()) << ", plant step "
            << format_duration(dt) << ", friction " << (o.no_friction ? "off" : "on") << '\n'
            << "  inertia at the shaft   " << g6(plant.inertia_kg_m2()) << " kg m^2 (motor "
            << g6(ax.motor.j_kg_m2) << " + load reflected through the screw)\n"
            << "  time constants         electrical L/R " << format_duration(pred.tau_e)
            << ", mechanical R J/(Kt Ke + R B) " << format_duration(pred.tau_m) << '\n'
            << "  poles of [i, w]        " << pole(pred.p1) << ", " << pole(pred.p2) << '\n'
            << "  peak current           " << g6(peak_i) << " A at t = " << format_duration(peak_t) << '\n'
            << "  final speed            " << g6(w) << " rad/s (" << g6(w * 60 / (2 * kPi))
            << " rpm), current " << g6(plant.current_a()) << " A, position " << g6(plant.position_rad())
            << " rad = " << g6(plant.position_m() * 1e3) << " mm\n"
            << "  steady state, analytic " << g6(pred.w_linear)
            << " rad/s = (V - R load/Kt)/(Ke + R B/Kt), linear\n";
  if (!o.no_friction) {
    if (pred.held) {
      std::cout << "  friction               held by stiction: |V| <= breakaway " << g6(pred.breakaway_v)
                << " V; the shaft " << (plant.stuck() ? "never moved" : "moved (unexpected)") << '\n';
    } else {
      std::cout << "                         " << g6(pred.w_friction)
                << " rad/s with Coulomb friction (V - R (Tc + load)/Kt)/(Ke + R B/Kt)\n"
                << "  friction               breakaway at " << g6(pred.breakaway_v) << " V; "
                << (plant.stuck() ? "the shaft is at rest (stuck)" : "the shaft is moving") << '\n';
    }
  }
  if (pred.w_friction != 0) {
    std::cout << "  final / steady state   " << g6(100 * ratio) << " %\n";
  }
  std::cout << "  plant cost             " << g6(ns_per_step) << " ns per step (" << steps << " steps)\n";
}

}  // namespace

void add_plant_command(CLI::App& app) {
  auto opt = std::make_shared<PlantStepOptions>();
  CLI::App* cmd = app.add_subcommand("plant", "Run the DC-motor axis plant model alone (open loop)");
  cmd->require_subcommand(1);
  CLI::App* step = cmd->add_subcommand("step", "Open-loop response of one axis to a voltage step at t = 0");
  step->footer(
      "Applies --volts to the motor terminals from t = 0 with the axis at rest and integrates the plant\n"
      "(exact ZOH of the linear part, Coulomb friction and stiction) at --dt. --csv prints one row per\n"
      "100 us including t = 0: t_s,volts,current_a,speed_rad_s,position_rad (motor shaft, SI units).\n"
      "Without --csv: a summary against the analytic steady state. docs/plant.md describes the model.");
  step->add_option("--config", opt->config,
                   "Machine config (TOML); default: the built-in configs/default.toml")
      ->type_name("FILE");
  step->add_option("--axis", opt->axis, "Axis name, case-insensitive (default x)")->type_name("NAME");
  step->add_option("--volts", opt->volts, "Terminal voltage applied from t = 0, V (|V| <= the drive supply)")
      ->required()
      ->type_name("V");
  step->add_option("--duration", opt->duration, "Simulated time, e.g. 0.2, 200ms")
      ->required()
      ->type_name("TIME");
  step->add_option("--dt", opt->dt, "Plant step (default: machine.plant_dt_s, 1 us); must divide 100 us")
      ->type_name("TIME");
  step->add_flag("--no-friction", opt->no_friction, "Friction off: the pure linear model");
  auto* csv = step->add_flag("--csv", opt->csv, "Print the response as CSV, one row per 100 us");
  auto* json = step->add_flag("--json", opt->json, "Print the summary as JSON");
  csv->excludes(json);
  step->callback([opt] { run(*opt); });
}

}  // namespace mc::host::cli
