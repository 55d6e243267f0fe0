// motionctl step: a step response captured from the board's telemetry, with
// its metrics, CSV and plot.
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
#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/capture_print.hpp"
#include "host/cli/commands.hpp"
#include "host/control/board_experiments.hpp"
#include "host/control/board_gains.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/limits.hpp"

namespace mc::host::cli {
namespace {

namespace br = board::reg;

// ---- step ---------------------------------------------------------------------------
struct StepOptions {
  std::string axis, size = "1", duration = "0.2s", plot, csv;
  bool json = false;
};

void write_step_csv(const std::string& file, const StepCapture& c) {
  std::ofstream f(file);
  if (!f) throw InputError("--csv", quote(file), "a writable path");
  f << "t_s,cmd_counts,pos_counts,err_counts,out_drive_units\n";
  char b[160];
  for (size_t i = 0; i < c.s.size(); ++i) {
    std::snprintf(b, sizeof b, "%.7f,%d,%d,%d,%d\n", c.t[i], int(c.s[i].cmd), int(c.s[i].pos),
                  int(c.s[i].err), int(c.s[i].u));
    f << b;
  }
}

void write_step_plot(const std::string& png, const StepCapture& c, double cpm) {
  const std::string dat = png + ".dat";
  {
    std::ofstream f(dat);
    if (!f) throw InputError("--plot", quote(png), "a writable path");
    for (size_t i = 0; i < c.s.size(); ++i)
      f << c.t[i] * 1e3 << ' ' << (c.s[i].cmd - c.y0) / cpm * 1e3 << ' ' << (c.s[i].pos - c.y0) / cpm * 1e3
        << ' ' << c.s[i].u << '\n';
  }
  char title[200];
  std::snprintf(title, sizeof title, "step %.4g mm: overshoot %.1f %%, settling %s ms", c.counts / cpm * 1e3,
                c.m.overshoot_pct, num_or_dash(c.m.settling_s, "%.1f", 1e3).c_str());
  std::string gp = "set terminal pngcairo size 900,600\nset output '" + png + "'\nset title '" + title +
                   "'\nset xlabel 'time from the step (ms)'\nset ylabel 'mm'\nset y2label 'PID output (drive "
                   "units)'\nset ytics nomirror\nset y2tics\nset grid\nset key bottom right\nplot '" +
                   dat +
                   "' u 1:2 w l t 'command', '' u 1:3 w lp pt 7 ps 0.4 t 'position', '' u 1:4 axes x1y2 w l "
                   "lc rgb '#999999' t 'output'\n";
  run_gnuplot_script(gp, png);
  std::remove(dat.c_str());
}

void step(const StepOptions& o) {
  const int a0 = parse_axis(o.axis);
  mc::machine::require_servo(machine(), a0, "motionctl step");
  const double mm = parse_number(o.size, "--size");
  const double duration = parse_duration(o.duration, "--duration");
  if (duration > 10) throw InputError("--duration", quote(o.duration), "at most 10 s");
  const double cpm = machine_scale(a0, o.axis);
  const int64_t counts = mc::machine::counts_of(mm, cpm);
  if (counts == 0) throw InputError("--size", quote(o.size), "a step of at least one encoder count");
  // The outputs and the machine's limits, before the board is touched.
  if (!o.csv.empty()) require_writable_file(o.csv, "--csv");
  if (!o.plot.empty()) require_writable_file(o.plot, "--plot");
  const mc::machine::MachineConfig m = machine();
  const mc::machine::Asked asked{"--size", o.size};
  const uint32_t ferr = mc::machine::step_ferr_counts(m, a0, counts, asked);
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  const Vec3 from = start_position(l);
  Vec3 to = from;
  to[size_t(a)] += counts;
  mc::machine::check_travel(m, from, to, asked);
  catch_interrupts();
  // Within FERR's 16 bits (step_ferr_counts), so within 32.
  const StepCapture c = capture_step(l, a, int32_t(counts), duration, note, ferr);
  if (!o.csv.empty()) write_step_csv(o.csv, c);
  if (!o.plot.empty()) write_step_plot(o.plot, c, cpm);
  if (o.json) {
    nlohmann::ordered_json j;
    j["axis"] = axis_name(a);
    j["step_counts"] = counts;
    j["step_mm"] = double(counts) / cpm * 1e3;
    j["ts_s"] = c.ts;
    j["decimation"] = c.decim;
    j["decimation_frames_alone"] = c.decim_needed;
    j["samples"] = c.s.size();
    j["gaps"] = c.gaps;
    j["missing_samples"] = c.missing;
    j["faults"] = c.fault ? fault_names(c.fault) : "none";
    j["metrics"] = metrics_json(c.m);
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << "step of " << counts << " counts (" << double(counts) / cpm * 1e3 << " mm) on axis "
              << axis_name(a) << " at Ts " << format_duration(c.ts) << ", captured "
              << format_duration(duration) << " of board time\n";
    std::cout << "telemetry every " << c.decim << (c.decim == 1 ? " sample" : " samples") << " ("
              << format_duration(c.decim * c.ts) << "): a frame takes " << format_duration(c.frame_s)
              << " on the link (alone it fits every " << c.decim_needed
              << " samples); two replies may queue in front of it; " << c.s.size() << " samples, ";
    if (c.gaps)
      std::cout << "GAPS: " << c.gaps << " jumps of the sample counter, " << c.missing
                << " frames lost (the metrics use the samples received, nothing is interpolated)\n";
    else
      std::cout << "no gaps\n";
    print_metrics(c.m, cpm, std::cout);
    if (c.fault) std::cout << "FAULT during the capture: " << fault_names(c.fault) << '\n';
    if (!o.csv.empty()) std::cout << "wrote " << o.csv << '\n';
    if (!o.plot.empty()) std::cout << "wrote " << o.plot << '\n';
  }
}

}  // namespace

void add_step_commands(CLI::App& app) {
  auto o = std::make_shared<StepOptions>();
  CLI::App* st = app.add_subcommand("step", "Step response of an axis: rise, overshoot, settling, IAE");
  st->footer(
      std::string(kBoardFooter) +
      "\nArms the drives, enables the axis' PID, streams telemetry (POS, CMD, ERR, OUT) at the finest\n"
      "decimation the link carries at the board's Ts, steps the command by --size from where it is,\n"
      "and captures --duration of board time. Gaps in the telemetry are reported, never filled in.\n"
      "The step must end within the axis' travel; during it the following-error limit (FERR) is the\n"
      "step plus max_following_error_m, which must fit FERR's 16 bits, and is put back afterwards.");
  st->add_option("--axis", o->axis, "x, y or z")->required()->type_name("AXIS");
  st->add_option("--size", o->size, "Step size, mm, signed (default 1)")->type_name("MM");
  st->add_option("--duration", o->duration, "Capture after the step, board time (default 0.2s)")
      ->type_name("TIME");
  st->add_option("--plot", o->plot, "Write a PNG of command, position and output (gnuplot)")
      ->type_name("F.png");
  st->add_option("--csv", o->csv, "Write t,cmd,pos,err,out as CSV")->type_name("F.csv");
  st->add_flag("--json", o->json, "One JSON object");
  st->callback([o] { step(*o); });
}

}  // namespace mc::host::cli
