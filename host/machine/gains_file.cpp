#include "host/machine/gains_file.hpp"

#include <toml++/toml.h>

#include <cctype>
#include <fstream>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"

namespace mc::machine {

using mc::host::InputError;
using mc::host::quote;
namespace br = board::reg;

namespace {

const char* const kAxisNames[] = {"x", "y", "z"};

double num(const toml::table& t, const char* key, const std::string& where, double def) {
  const toml::node* n = t.get(key);
  if (!n) return def;
  if (auto v = n->value<double>()) return *v;
  throw InputError(where + ": " + key, "not a number", "a number");
}

}  // namespace

GainsFile read_gains_file(const std::string& file) {
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
  GainsFile f;
  f.ts_s = num(root, "ts_s", file, 0);
  if (!(f.ts_s > 0)) throw InputError(file + ": ts_s", "missing or not above 0", "the sample period in s");
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
  for (const auto& [name, node] : *axes) {
    const std::string where = file + ": [axis." + std::string(name.str()) + "]";
    int a = -1;
    for (int i = 0; i < 3; ++i)
      if (name.str().size() == 1 &&
          std::tolower(static_cast<unsigned char>(name.str()[0])) == kAxisNames[i][0])
        a = i;
    if (a < 0) throw InputError(where, quote(name.str()), "an axis x, y or z");
    const toml::table* t = node.as_table();
    if (!t) throw InputError(where, "not a table", "a table of gains");
    for (const auto& [k, v] : *t) {
      bool known = false;
      for (const char* key : keys) known = known || k.str() == key;
      if (!known) throw InputError(where + ": key", quote(k.str()), "one of the keys 'config save' writes");
    }
    GainsEntry e;
    e.axis = a;
    e.gains = {num(*t, "kp", where, 0),
               num(*t, "ki", where, 0),
               num(*t, "kd", where, 0),
               num(*t, "tf_s", where, 0),
               f.ts_s,
               num(*t, "ff1", where, 0),
               num(*t, "ff2", where, 0)};
    e.limits.out_limit = uint32_t(num(*t, "out_limit", where, 0));
    e.limits.int_limit = uint32_t(num(*t, "int_limit", where, 0));
    e.limits.deadband = uint32_t(num(*t, "deadband_counts", where, 0));
    e.limits.err_limit = uint32_t(num(*t, "error_clamp_counts", where, 0));
    e.ferr = uint32_t(num(*t, "following_error_counts", where, 0));
    f.axes.push_back(e);
  }
  return f;
}

int save_gains(mc::host::BoardLink& l, const std::string& file) {
  const int naxes = mc::host::read_naxes(l);
  toml::table root;
  root.insert("ts_s", double(mc::host::read_ts_cycles(l)) / double(l.read(br::CLK_HZ)));
  toml::table axes;
  for (int a = 0; a < naxes && a < 3; ++a) {
    const mc::host::AxisGains g = mc::host::read_gains(l, a);
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
    axes.insert(kAxisNames[a], t);
  }
  root.insert("axis", axes);
  std::ofstream f(file);
  if (!f) throw InputError("FILE", quote(file), "a writable path");
  f << "# MotionCore board gains and limits (motionctl config save); core units: drive units\n"
       "# (+-32767) per encoder count, Ki per count*s, Kd per count/s, times in s. Load with\n"
       "# 'motionctl config load FILE'.\n"
    << root << '\n';
  return naxes;
}

int load_gains(mc::host::BoardLink& l, const GainsFile& f, const std::string& file,
               const mc::host::Note& warn) {
  const int naxes = mc::host::read_naxes(l);
  for (const GainsEntry& e : f.axes)
    if (e.axis >= naxes)
      throw InputError(file + ": [axis." + kAxisNames[e.axis] + "]",
                       std::string("axis ") + kAxisNames[e.axis], "one of the board's axes");
  for (const GainsEntry& e : f.axes) {
    mc::host::apply_gains(l, e.axis, e.gains, e.limits, warn);
    l.write_verify(br::axis(e.axis, br::AX_FERR), e.ferr, 0xFFFF);
  }
  return int(f.axes.size());
}

int gains_where_missing(mc::host::BoardLink& l, const MachineConfig& m, const mc::host::Note& note) {
  int n = 0;
  for (size_t a = 0; a < m.axes.size(); ++a) {
    if (m.axes[a].stepper) continue;  // no loop to give gains to
    mc::host::AxisGains cur = mc::host::read_gains(l, int(a));
    if (cur.gains.kp != 0 || cur.gains.ki != 0) continue;
    const PidConfig& p = m.axes[a].pid;
    cur.limits.out_limit = uint32_t(std::lround(p.out_limit));
    mc::host::apply_gains(l, int(a), mc::host::PidGains{p.kp, p.ki, p.kd, p.tf_s, p.ts_s, p.ff1, p.ff2},
                          cur.limits, note);
    if (note) note("axis " + m.axes[a].name + " had no gains: loaded those of " + m.source);
    ++n;
  }
  return n;
}

}  // namespace mc::machine
