// motionctl tune: gain tuning on the board, by identification or relay,
// with the predicted step of the current and proposed gains.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/control/board_experiments.hpp"
#include "host/control/board_gains.hpp"
#include "host/control/tuning.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"

namespace mc::host::cli {
namespace {

// ---- tune ---------------------------------------------------------------------------
struct TuneOptions {
  std::string axis, method = "model", bandwidth, zeta = "2";
  bool apply = false, json = false;
};

void tune(const TuneOptions& o) {
  const int a0 = parse_axis(o.axis);
  mc::machine::require_servo(machine(), a0, "motionctl tune");
  if (o.method != "model" && o.method != "relay")
    throw InputError("--method", quote(o.method), "model or relay");
  const double zeta = parse_number(o.zeta, "--zeta");
  if (!(zeta > 0)) throw InputError("--zeta", quote(o.zeta), "a damping above 0");
  double wc = 0;
  if (!o.bandwidth.empty()) {
    wc = parse_number(o.bandwidth, "--bandwidth");
    if (o.method == "relay")
      throw InputError("--bandwidth", quote(o.bandwidth), "no --bandwidth with --method relay");
  }
  const double cpm = machine_scale(a0, o.axis);
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  const AxisGains cur = read_gains(l, a);
  const double ts = cur.gains.ts;
  if (!o.bandwidth.empty()) check_bandwidth(wc, ts, "--bandwidth", o.bandwidth);  // before the experiment
  catch_interrupts();
  note("tuning axis " + std::string(axis_name(a)) + " (" + o.method +
       "): the experiment runs now; Ctrl-C stops it and restores the gains");
  const Experiment e = tune_experiment(l, a, o.method, ts, note);

  const int32_t step = int32_t(std::llround(1e-3 * cpm));
  const double horizon = 0.2;
  nlohmann::ordered_json j;
  j["axis"] = axis_name(a);
  j["method"] = o.method;
  PidGains g{};
  AxisModel m{};
  RelayResult r{};
  if (o.method == "model") {
    // One lag: the capture period (link-bound, >= 0.48 ms at 1 Mbaud) cannot resolve a motor's
    // L/R, and a second lag then only lets the fit wander (docs/tuning.md).
    m = identify(e.u, e.y, e.ts, true, false);
    // The default bandwidth's cap 2 pi / (40 Ts) taken at the capture's
    // period: the model is trusted no faster than its samples show it, and
    // the electrical lag the one-lag fit leaves out stays well beyond wc.
    if (wc == 0) wc = default_bandwidth(m);
    m.ts = ts;  // the board runs the design at its own period
    g = design_model(m, wc, zeta);
    j["model"] = {{"k_counts_per_s_per_du", m.k}, {"tau_s", m.tau},
                  {"tau_fast_s", m.tau_fast},     {"coulomb_du", m.coulomb},
                  {"fit_rms_counts", m.fit_rms},  {"samples", m.samples},
                  {"capture_ts_s", e.ts}};
    j["bandwidth_rad_s"] = wc;
    j["zeta"] = zeta;
  } else {
    r = relay_analyse(e.y, e.ts, TuneDefaults::relay_amplitude, 0);
    g = design_relay(r, ts);
    j["relay"] = {{"ku", r.ku}, {"tu_s", r.tu}, {"amplitude_counts", r.amplitude}, {"periods", r.periods}};
  }
  const PidDesign d = design(g);
  const std::vector<std::string> warnings = design_warnings(d);
  const double olim = cur.limits.out_limit ? double(cur.limits.out_limit) : 32767;
  const bool have_cur = cur.gains.kp > 0 || cur.gains.ki > 0;
  Prediction p_new{}, p_cur{};
  if (o.method == "model") {
    p_new = predict_step(m, g, step, horizon, olim);
    if (have_cur) p_cur = predict_step(m, cur.gains, step, horizon, olim);
  }
  if (o.apply) write_gains(l, a, d, CoreLimits{cur.limits});
  if (o.json) {
    j["current"] = pid_json(cur.gains);
    j["proposed"] = pid_json(d.gains);
    if (o.method == "model") {
      j["prediction_step_counts"] = step;
      if (have_cur) j["current"]["predicted"] = metrics_json(p_cur.metrics);
      j["proposed"]["predicted"] = metrics_json(p_new.metrics);
    }
    j["warnings"] = warnings;
    j["applied"] = o.apply;
    std::cout << j.dump(2) << '\n';
    return;
  }
  char line[300];
  if (o.method == "model") {
    std::snprintf(line, sizeof line,
                  "identified axis %s (open loop, PRBS +-%.0f drive units, %zu samples at %s):\n"
                  "  P(s) = K / (s (tau s + 1)): K = %.4f counts/s per drive unit, tau = %.3f ms; Coulomb "
                  "friction %.1f drive units; fit %.3f counts RMS\n",
                  axis_name(a), TuneDefaults::prbs_amplitude, e.u.size(), format_duration(e.ts).c_str(), m.k,
                  m.tau * 1e3, m.coulomb, m.fit_rms);
    std::cout << line;
    std::snprintf(line, sizeof line, "design: pole placement, bandwidth %.1f rad/s, damping %.2g, at Ts %s\n",
                  wc, zeta, format_duration(ts).c_str());
    std::cout << line;
  } else {
    std::snprintf(
        line, sizeof line,
        "relay on axis %s (+-%.0f drive units at Ts %s): Ku = %.2f drive units/count, Tu = %.3f ms, "
        "amplitude %.1f counts over %d periods\ndesign: Tyreus-Luyben\n",
        axis_name(a), TuneDefaults::relay_amplitude, format_duration(ts).c_str(), r.ku, r.tu * 1e3,
        r.amplitude, r.periods);
    std::cout << line;
  }
  std::cout << "current:  " << gains_line(cur.gains) << '\n' << "proposed: " << gains_line(d.gains) << '\n';
  for (const std::string& w : warnings) std::cout << "warning: quantized: " << w << '\n';
  if (o.method == "model") {
    std::cout << "predicted 1 mm (" << step
              << "-count) step, quantized controller on the identified model:\n";
    std::snprintf(line, sizeof line, "  %-10s %10s %12s %12s %14s\n", "gains", "overshoot", "settling 2%",
                  "rise", "IAE count*s");
    std::cout << line;
    const auto row = [&](const char* name, const StepMetrics& sm) {
      std::snprintf(line, sizeof line, "  %-10s %9.1f %% %9s ms %9s ms %14.3f\n", name, sm.overshoot_pct,
                    num_or_dash(sm.settling_s, "%.1f", 1e3).c_str(),
                    num_or_dash(sm.rise_s, "%.2f", 1e3).c_str(), sm.iae);
      std::cout << line;
    };
    if (have_cur) row("current", p_cur.metrics);
    row("proposed", p_new.metrics);
  }
  std::cout << (o.apply ? "applied: written and verified (read back word by word)\n"
                        : "not applied (the previous gains are back on the board); --apply writes them\n");
}

}  // namespace

void add_tune_command(CLI::App& app) {
  auto t = std::make_shared<TuneOptions>();
  CLI::App* tu =
      app.add_subcommand("tune", "Autotune an axis: identify (or relay), design, predict; --apply writes");
  tu->footer(
      std::string(kBoardFooter) +
      "\nmodel: the axis runs open loop under a PRBS of +-4096 drive units for 1 s of board time (an\n"
      "error-clamped P-only controller far from its command), is identified as K/(s(tau s+1)), and\n"
      "gains are placed for --bandwidth (rad/s; default from the model) and --zeta (default 2).\n"
      "relay: the board itself runs a relay of +-8192 drive units for 0.3 s; Ku, Tu -> Tyreus-Luyben.\n"
      "The previous gains are restored after the experiment unless --apply. docs/tuning.md explains.");
  tu->add_option("--axis", t->axis, "x, y or z")->required()->type_name("AXIS");
  tu->add_option("--method", t->method, "model (default) or relay")->type_name("METHOD");
  tu->add_option("--bandwidth", t->bandwidth, "Closed-loop bandwidth wc, rad/s (model)")->type_name("RAD/S");
  tu->add_option("--zeta", t->zeta, "Damping of the dominant pair (model, default 2)")->type_name("Z");
  tu->add_flag("--apply", t->apply, "Write the proposed gains (read back and verified)");
  tu->add_flag("--json", t->json, "One JSON object");
  tu->callback([t] { tune(*t); });
}

}  // namespace mc::host::cli
