// motionctl gains show|set and config save|load: the PID gains and limits
// of the board's axes, designed and quantized as `coeffs` does, written,
// read back and verified.
#include <toml++/toml.h>
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "board_cli.hpp"
#include "board_ops.hpp"
#include "commands.hpp"
#include "errors.hpp"
#include "pid_regs.hpp"
#include "units.hpp"

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

// Writes the sample period (shared by all axes) when it changes.
void set_ts(BoardLink& l, double ts) {
  const double clk = double(l.read(br::CLK_HZ));
  const uint32_t cycles = uint32_t(std::llround(ts * clk));
  const uint16_t addr = pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS);
  if (l.read(addr) != cycles) l.write_verify(addr, cycles);
}

// Designs, writes, verifies, warns. Returns what the board holds afterwards.
AxisGains apply(BoardLink& l, int a, const PidGains& g, const CoreLimits& lim) {
  const PidDesign d = design(g);
  for (const std::string& w : design_warnings(d)) warn("axis " + std::string(axis_name(a)) + ": " + w);
  set_ts(l, g.ts);
  write_gains(l, a, d, lim);
  return read_gains(l, a);
}

void set(const GainsOptions& o) {
  parse_axis(o.axis);
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  AxisGains cur = read_gains(l, a);
  PidGains g = cur.gains;
  if (o.defaults) {
    const mc::sim::MachineConfig m = machine();
    if (size_t(a) >= m.axes.size())
      throw InputError("--defaults", "axis " + std::string(axis_name(a)), "an axis of " + m.source);
    const mc::sim::PidConfig& p = m.axes[size_t(a)].pid;
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
  if (!o.ts.empty() || o.defaults) {
    const uint32_t old = read_ts_cycles(l);
    bool others = false;  // another axis has gains designed for the old period
    for (int x = 0; x < int(l.read(br::INFO) & 0xF); ++x)
      others = others || (x != a && l.read(pid_reg::addr(uint8_t(x), pid_reg::KP)) != 0);
    if (others && std::llround(g.ts * double(l.read(br::CLK_HZ))) != old)
      warn("Ts is shared by every axis: the other axes' gains now run at the new period (set them again)");
  }
  const AxisGains now = apply(l, a, g, cur.limits);
  if (o.json)
    std::cout << gains_json(a, now).dump(2) << '\n';
  else {
    print_gains(a, now, std::cout);
    std::cout << "written and verified (read back word by word)\n";
  }
}

// ---- config save / load ---------------------------------------------------------------
void save(const std::string& file) {
  Board b = open_board();
  BoardLink& l = *b.link;
  const int naxes = int(l.read(br::INFO) & 0xF);
  toml::table root;
  root.insert("ts_s", double(read_ts_cycles(l)) / double(l.read(br::CLK_HZ)));
  toml::table axes;
  for (int a = 0; a < naxes; ++a) {
    const AxisGains g = read_gains(l, a);
    toml::table t;
    t.insert("kp", g.gains.kp);
    t.insert("ki", g.gains.ki);
    t.insert("kd", g.gains.kd);
    t.insert("tf_s", g.gains.tf);
    t.insert("ff1", g.gains.ff1);
    t.insert("ff2", g.gains.ff2);
    t.insert("out_limit", int64_t(g.limits.out_limit));
    t.insert("int_limit", int64_t(g.limits.int_limit));
    t.insert("deadband_counts", int64_t(g.limits.deadband));
    t.insert("error_clamp_counts", int64_t(g.limits.err_limit));
    t.insert("following_error_counts", int64_t(g.ferr));
    axes.insert(axis_name(a), t);
  }
  root.insert("axis", axes);
  std::ofstream f(file);
  if (!f) throw InputError("FILE", quote(file), "a writable path");
  f << "# MotionCore board gains and limits (motionctl config save); core units: drive units\n"
       "# (+-32767) per encoder count, Ki per count*s, Kd per count/s, times in s. Load with\n"
       "# 'motionctl config load FILE'.\n"
    << root << '\n';
  std::cout << "saved " << naxes << " axes to " << file << '\n';
}

double num(const toml::table& t, const char* key, const std::string& where, double def) {
  const toml::node* n = t.get(key);
  if (!n) return def;
  if (auto v = n->value<double>()) return *v;
  throw InputError(where + ": " + key, "not a number", "a number");
}

void load(const std::string& file) {
  toml::table root;
  try {
    root = toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    throw InputError(file + ":" + std::to_string(e.source().begin.line), "TOML", "valid TOML",
                     std::string(e.description()));
  }
  for (const auto& [k, v] : root)
    if (k != "ts_s" && k != "axis") throw InputError(file + ": key", quote(k.str()), "ts_s or [axis.x|y|z]");
  const toml::table* axes = root["axis"].as_table();
  if (!axes) throw InputError(file, "no [axis.*] tables", "[axis.x] etc. as 'config save' writes");
  Board b = open_board();
  BoardLink& l = *b.link;
  const int naxes = int(l.read(br::INFO) & 0xF);
  const double ts = num(root, "ts_s", file, 0);
  if (!(ts > 0)) throw InputError(file + ": ts_s", "missing or not above 0", "the sample period in s");
  static const char* const keys[] = {"kp",
                                     "ki",
                                     "kd",
                                     "tf_s",
                                     "ff1",
                                     "ff2",
                                     "out_limit",
                                     "int_limit",
                                     "deadband_counts",
                                     "error_clamp_counts",
                                     "following_error_counts"};
  int n = 0;
  for (const auto& [name, node] : *axes) {
    const std::string where = file + ": [axis." + std::string(name.str()) + "]";
    const int a = parse_axis(std::string(name.str()), where.c_str());
    if (a >= naxes) throw InputError(where, "axis " + std::string(name.str()), "one of the board's axes");
    const toml::table* t = node.as_table();
    if (!t) throw InputError(where, "not a table", "a table of gains");
    for (const auto& [k, v] : *t) {
      bool known = false;
      for (const char* key : keys) known = known || k.str() == key;
      if (!known) throw InputError(where + ": key", quote(k.str()), "one of the keys 'config save' writes");
    }
    PidGains g{num(*t, "kp", where, 0),
               num(*t, "ki", where, 0),
               num(*t, "kd", where, 0),
               num(*t, "tf_s", where, 0),
               ts,
               num(*t, "ff1", where, 0),
               num(*t, "ff2", where, 0)};
    CoreLimits lim;
    lim.out_limit = uint32_t(num(*t, "out_limit", where, 0));
    lim.int_limit = uint32_t(num(*t, "int_limit", where, 0));
    lim.deadband = uint32_t(num(*t, "deadband_counts", where, 0));
    lim.err_limit = uint32_t(num(*t, "error_clamp_counts", where, 0));
    apply(l, a, g, lim);
    l.write_verify(br::axis(a, br::AX_FERR), uint32_t(num(*t, "following_error_counts", where, 0)), 0xFFFF);
    ++n;
  }
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
      "Ts is one register for every axis.");
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
