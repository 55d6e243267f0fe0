// motionctl gains show|set and config save|load: the PID gains and limits
// of the board's axes, designed and quantized as `coeffs` does, written,
// read back and verified.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "hls/pid_regs.hpp"
#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"
#include "host/cli/commands.hpp"
#include "host/control/board_gains.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/gains_file.hpp"
#include "host/motion/board_run.hpp"

namespace mc::host::cli {
namespace {

namespace br = board::reg;

struct GainsOptions {
  std::string axis, kp, ki, kd, tf, ts, ff1, ff2, limit;
  bool defaults = false, json = false;
};

void warn(const std::string& s) {
  std::cerr << "motionctl: warning: " << s << '\n';
}

nlohmann::ordered_json gains_json(int axis, const AxisGains& g) {
  nlohmann::ordered_json j;
  j["axis"] = axis_name(axis);
  j["ts"] = g.gains.ts;
  j["kp"] = g.gains.kp;
  j["ki"] = g.gains.ki;
  j["kd"] = g.gains.kd;
  j["tf"] = g.gains.tf;
  j["ff1"] = g.gains.ff1;
  j["ff2"] = g.gains.ff2;
  j["out_limit"] = g.limits.out_limit;
  j["int_limit"] = g.limits.int_limit;
  j["following_error_limit_counts"] = g.ferr;
  j["words"] = g.words;
  return j;
}

void print_gains(int axis, const AxisGains& g, std::ostream& os) {
  char b[400];
  const PidGains& p = g.gains;
  std::snprintf(b, sizeof b,
                "axis %s: Ts = %s  Kp = %.8g  Ki = %.8g  Kd = %.8g  Tf = %.8g s  FF1 = %.8g  FF2 = %.8g  "
                "limit = %u\n",
                axis_name(axis), format_duration(p.ts).c_str(), p.kp, p.ki, p.kd, p.tf, p.ff1, p.ff2,
                unsigned(g.limits.out_limit));
  os << b;
}

void show(const GainsOptions& o) {
  parse_axis(o.axis);  // a bad name is an error before any port is opened
  Board b = open_board();
  const int a = board_axis(*b.link, o.axis);
  const AxisGains g = read_gains(*b.link, a);
  if (o.json)
    std::cout << gains_json(a, g).dump(2) << '\n';
  else
    print_gains(a, g, std::cout);
}

void set(const GainsOptions& o) {
  parse_axis(o.axis);
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  AxisGains cur = read_gains(l, a);
  PidGains g = cur.gains;
  if (o.defaults) {
    const mc::machine::MachineConfig m = machine();
    if (size_t(a) >= m.axes.size())
      throw InputError("--defaults", "axis " + std::string(axis_name(a)), "an axis of " + m.source);
    const mc::machine::PidConfig& p = m.axes[size_t(a)].pid;
    g = PidGains{p.kp, p.ki, p.kd, p.tf_s, p.ts_s, p.ff1, p.ff2};
    cur.limits.out_limit = uint32_t(std::lround(p.out_limit));
  }
  if (!o.kp.empty()) g.kp = parse_number(o.kp, "--kp");
  if (!o.ki.empty()) g.ki = parse_number(o.ki, "--ki");
  if (!o.kd.empty()) g.kd = parse_number(o.kd, "--kd");
  if (!o.ff1.empty()) g.ff1 = parse_number(o.ff1, "--ff1");
  if (!o.ff2.empty()) g.ff2 = parse_number(o.ff2, "--ff2");
  if (!o.tf.empty()) g.tf = parse_duration(o.tf, "--tf", Zero::allow);
  if (!o.ts.empty()) g.ts = parse_duration(o.ts, "--ts");
  if (!o.limit.empty()) {
    const double lim = parse_number(o.limit, "--limit");
    if (!(lim >= 0 && lim <= 32767))
      throw InputError("--limit", quote(o.limit), "drive units 0..32767 (0: none)");
    cur.limits.out_limit = uint32_t(std::lround(lim));
  }
  const GainNames names{"--ts", o.ts, "--kp", o.kp};
  check_gains(l, g, names);  // before the warning: a refused Ts changes nothing
  if ((!o.ts.empty() || o.defaults) && ts_change_affects_other_axes(l, a, g.ts))
    warn("Ts is shared by every axis: the other axes' gains now run at the new period (set them again)");
  const AxisGains now = apply_gains(l, a, g, cur.limits, warn, names);
  if (o.json)
    std::cout << gains_json(a, now).dump(2) << '\n';
  else {
    print_gains(a, now, std::cout);
    std::cout << "written and verified (read back word by word)\n";
  }
}

// ---- config save / load ---------------------------------------------------------------
void save(const std::string& file) {
  require_writable_file(file, "FILE");
  Board b = open_board();
  const int n = mc::machine::save_gains(*b.link, file);
  std::cout << "saved " << n << " axes to " << file << '\n';
}

void load(const std::string& file) {
  const mc::machine::GainsFile f = mc::machine::read_gains_file(file);
  Board b = open_board();
  const int n = mc::machine::load_gains(*b.link, f, file, warn);
  std::cout << "loaded " << n << " axes from " << file << " (written and verified)\n";
}

constexpr const char* kFooter =
    "Talks to the board: give --port DEV (a real board) or --sim (the virtual board) before the command.";

}  // namespace

void add_gains_commands(CLI::App& app) {
  CLI::App* gains = app.add_subcommand("gains", "Show or set an axis' PID gains on the board");
  gains->require_subcommand(1);
  auto so = std::make_shared<GainsOptions>();
  CLI::App* sh = gains->add_subcommand("show", "The gains the board's coefficient words realize");
  sh->footer(kFooter);
  sh->add_option("--axis", so->axis, "x, y or z")->required()->type_name("AXIS");
  sh->add_flag("--json", so->json, "One JSON object");
  sh->callback([so] { show(*so); });

  auto o = std::make_shared<GainsOptions>();
  CLI::App* st = gains->add_subcommand("set", "Design, quantize (as 'coeffs'), write, read back and verify");
  st->footer(
      std::string(kFooter) +
      "\nOptions not given keep the board's current values (or, with --defaults, the machine config's).\n"
      "Gains in drive units (+-32767) per count: Kp per count, Ki per count*s, Kd per count/s.\n"
      "Ts is one register for every axis: whole clock cycles from the core's sweep (70 cycles) to 10 ms.\n"
      "Kp at most 32767. Everything is checked before the first write; a write the board refuses\n"
      "half-way puts the previous Ts and words back.");
  st->add_option("--axis", o->axis, "x, y or z")->required()->type_name("AXIS");
  st->add_option("--kp", o->kp, "Proportional gain")->type_name("GAIN");
  st->add_option("--ki", o->ki, "Integral gain")->type_name("GAIN");
  st->add_option("--kd", o->kd, "Derivative gain")->type_name("GAIN");
  st->add_option("--tf", o->tf, "Derivative filter time constant, e.g. 500us")->type_name("TIME");
  st->add_option("--ts", o->ts, "Sample period (all axes), e.g. 1ms")->type_name("TIME");
  st->add_option("--ff1", o->ff1, "Velocity feedforward")->type_name("GAIN");
  st->add_option("--ff2", o->ff2, "Acceleration feedforward")->type_name("GAIN");
  st->add_option("--limit", o->limit, "Output limit, drive units (0: none)")->type_name("UNITS");
  st->add_flag("--defaults", o->defaults, "Start from the machine config's gains for this axis");
  st->add_flag("--json", o->json, "One JSON object");
  st->callback([o] { set(*o); });

  CLI::App* cfg = app.add_subcommand("config", "Save or load every axis' gains and limits (TOML)");
  cfg->require_subcommand(1);
  auto file = std::make_shared<std::string>();
  CLI::App* sv = cfg->add_subcommand("save", "Read the board's gains and limits into FILE.toml");
  sv->footer(kFooter);
  sv->add_option("FILE", *file, "TOML file to write")->required();
  sv->callback([file] { save(*file); });
  auto lfile = std::make_shared<std::string>();
  CLI::App* ld = cfg->add_subcommand("load", "Write FILE.toml's gains and limits to the board, verified");
  ld->footer(kFooter);
  ld->add_option("FILE", *lfile, "TOML file from 'config save'")->required();
  ld->callback([lfile] { load(*lfile); });
}

}  // namespace mc::host::cli
