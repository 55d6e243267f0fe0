#include "host/grbl/settings.hpp"

#include <toml++/toml.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "host/base/errors.hpp"

namespace mc::grbl {
namespace {

using mc::host::InputError;
using mc::host::quote;

// Grbl status codes used here.
constexpr int kInvalidStatement = 3;
constexpr int kNegativeValue = 4;
constexpr int kSoftLimitNeedsHoming = 10;

bool is_integer_setting(int n) {
  switch (n) {
    case 0:
    case 1:
    case 2:
    case 3:
    case 4:
    case 5:
    case 6:
    case 10:
    case 13:
    case 20:
    case 21:
    case 22:
    case 23:
    case 26:
    case 32:
      return true;
    default:
      return false;
  }
}

// Setting `n` as a pointer into `s`: exactly one of the two is set.
struct Slot {
  int* i = nullptr;
  bool* b = nullptr;
  double* d = nullptr;
};

Slot slot(Settings& s, int n) {
  if (n >= 100 && n <= 132 && n % 10 <= 2) {
    const size_t axis = size_t(n % 10);
    switch (n / 10) {
      case 10:
        return {nullptr, nullptr, &s.counts_per_mm[axis]};
      case 11:
        return {nullptr, nullptr, &s.max_rate_mm_min[axis]};
      case 12:
        return {nullptr, nullptr, &s.accel_mm_s2[axis]};
      case 13:
        return {nullptr, nullptr, &s.max_travel_mm[axis]};
      default:
        return {};
    }
  }
  switch (n) {
    case 0:
      return {&s.step_pulse_us};
    case 1:
      return {&s.step_idle_delay_ms};
    case 2:
      return {&s.step_invert_mask};
    case 3:
      return {&s.dir_invert_mask};
    case 4:
      return {nullptr, &s.invert_enable};
    case 5:
      return {nullptr, &s.invert_limits};
    case 6:
      return {nullptr, &s.invert_probe};
    case 10:
      return {&s.report_mask};
    case 11:
      return {nullptr, nullptr, &s.junction_deviation_mm};
    case 12:
      return {nullptr, nullptr, &s.arc_tolerance_mm};
    case 13:
      return {nullptr, &s.report_inches};
    case 20:
      return {nullptr, &s.soft_limits};
    case 21:
      return {nullptr, &s.hard_limits};
    case 22:
      return {nullptr, &s.homing};
    case 23:
      return {&s.homing_dir_mask};
    case 24:
      return {nullptr, nullptr, &s.homing_feed_mm_min};
    case 25:
      return {nullptr, nullptr, &s.homing_seek_mm_min};
    case 26:
      return {&s.homing_debounce_ms};
    case 27:
      return {nullptr, nullptr, &s.homing_pulloff_mm};
    case 30:
      return {nullptr, nullptr, &s.spindle_max_rpm};
    case 31:
      return {nullptr, nullptr, &s.spindle_min_rpm};
    case 32:
      return {nullptr, &s.laser_mode};
    default:
      return {};
  }
}

bool exists(int n) {
  Settings s;
  const Slot p = slot(s, n);
  return p.i || p.b || p.d;
}

const char* const kCoordNames[9] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59_1", "G59_2", "G59_3"};

std::string vec_text(const gcode::Vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g]", v[0], v[1], v[2]);
  return buf;
}

std::string toml_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

Settings default_settings(const mc::machine::MachineConfig& machine) {
  Settings s;
  s.junction_deviation_mm = machine.planner.junction_deviation_m * 1000.0;
  s.arc_tolerance_mm = machine.planner.arc_tolerance_m * 1000.0;
  s.spindle_max_rpm = machine.spindle.max_rpm;
  s.spindle_min_rpm = machine.spindle.min_rpm;
  for (size_t a = 0; a < 3; ++a) {
    if (machine.axes.empty()) break;
    const auto& ax = machine.axes[std::min(a, machine.axes.size() - 1)];
    s.counts_per_mm[a] = mc::machine::counts_per_m(ax) / 1000.0;
    s.max_rate_mm_min[a] = ax.max_speed_m_s * 60000.0;
    s.accel_mm_s2[a] = ax.max_accel_m_s2 * 1000.0;
    s.max_travel_mm[a] = (ax.travel_max_m - ax.travel_min_m) * 1000.0;
    s.travel_top_mm[a] = ax.travel_max_m * 1000.0;
  }
  // $23..$27 from the axes' [home] tables: one value for all, as Grbl, so
  // the slowest speeds and the longest pull-off; the board backend keeps
  // each axis's own while these stay at these defaults.
  bool first = true;
  for (size_t a = 0; a < machine.axes.size() && a < 3; ++a) {
    const auto& h = machine.axes[a].home;
    if (!h) continue;
    if (h->direction < 0) s.homing_dir_mask |= 1 << a;
    const double seek = h->seek_m_s * 60e3, locate = h->locate_m_s * 60e3, pull = h->pull_off_m * 1e3;
    s.homing_seek_mm_min = first ? seek : std::min(s.homing_seek_mm_min, seek);
    s.homing_feed_mm_min = first ? locate : std::min(s.homing_feed_mm_min, locate);
    s.homing_pulloff_mm = first ? pull : std::max(s.homing_pulloff_mm, pull);
    first = false;
  }
  return s;
}

const std::vector<int>& setting_numbers() {
  static const std::vector<int> v = {0,   1,   2,   3,   4,   5,   6,   10,  11,  12, 13,  20,
                                     21,  22,  23,  24,  25,  26,  27,  30,  31,  32, 100, 101,
                                     102, 110, 111, 112, 120, 121, 122, 130, 131, 132};
  return v;
}

int set_setting(Settings& s, int number, double value) {
  if (!exists(number)) return kInvalidStatement;
  if (!(value >= 0) || !std::isfinite(value)) return kNegativeValue;
  // Scales and rates of zero would divide by zero in any planner; Grbl lets
  // them through, we answer as for a negative value.
  if (number >= 100 && number <= 122 && value == 0) return kNegativeValue;
  const Slot p = slot(s, number);
  const int int_value = int(std::min(std::trunc(value), 255.0));  // Grbl keeps these in a byte
  if (number == 20 && int_value && !s.homing) return kSoftLimitNeedsHoming;
  if (p.i) *p.i = int_value;
  if (p.b) *p.b = int_value != 0;
  if (p.d) *p.d = value;
  if (number == 22 && !int_value) s.soft_limits = false;  // as Grbl: no soft limits without homing
  return 0;
}

double get_setting(const Settings& s, int number) {
  const Slot p = slot(const_cast<Settings&>(s), number);
  if (p.i) return *p.i;
  if (p.b) return *p.b ? 1 : 0;
  if (p.d) return *p.d;
  throw std::logic_error("get_setting: no setting $" + std::to_string(number));
}

std::string format_setting(const Settings& s, int number) {
  char buf[64];
  const double v = get_setting(s, number);
  if (is_integer_setting(number))
    std::snprintf(buf, sizeof buf, "$%d=%d", number, int(v));
  else
    std::snprintf(buf, sizeof buf, "$%d=%.3f", number, v);
  return buf;
}

std::string settings_path_for(const std::string& machine_path) {
  if (!machine_path.empty()) {
    const std::string ext = ".toml";
    if (machine_path.size() > ext.size() &&
        machine_path.compare(machine_path.size() - ext.size(), ext.size(), ext) == 0)
      return machine_path.substr(0, machine_path.size() - ext.size()) + ".grbl.toml";
    return machine_path + ".grbl.toml";
  }
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  if (xdg && *xdg) return std::string(xdg) + "/motionctl/grbl.toml";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.config/motionctl/grbl.toml";
}

Stored load_stored(const std::string& path, const Stored& defaults) {
  Stored st = defaults;
  std::ifstream f(path);
  if (!f) return st;
  std::stringstream text;
  text << f.rdbuf();
  toml::table root;
  try {
    root = toml::parse(text.str(), path);
  } catch (const toml::parse_error& e) {
    throw InputError(path + ":" + std::to_string(e.source().begin.line), quote(std::string(e.description())),
                     "a Grbl settings file as 'motionctl serve' writes it", "not valid TOML");
  }
  const auto where = [&](const toml::node& n, const std::string& key) {
    return path + ":" + std::to_string(n.source().begin.line) + ": " + key;
  };
  const auto number = [&](const toml::node& n, const std::string& key) {
    if (const auto* i = n.as_integer()) return double(i->get());
    if (const auto* d = n.as_floating_point()) return d->get();
    throw InputError(where(n, key), "a non-number", "a number");
  };
  const auto vec = [&](const toml::node& n, const std::string& key) {
    const auto* a = n.as_array();
    if (!a || a->size() != 3) throw InputError(where(n, key), "not [x, y, z]", "an array of 3 numbers (mm)");
    gcode::Vec3 v{};
    for (size_t i = 0; i < 3; ++i) v[i] = number(*a->get(i), key);
    return v;
  };
  for (const auto& [k, node] : root) {
    const std::string key(k.str());
    if (key == "settings") {
      const auto* t = node.as_table();
      if (!t) throw InputError(where(node, key), "not a table", "a table [settings]");
      for (const auto& [sk, sn] : *t) {
        const std::string name(sk.str());
        char* end = nullptr;
        const long n = name.size() > 1 && name[0] == '$' ? std::strtol(name.c_str() + 1, &end, 10) : -1;
        if (n < 0 || (end && *end) || !exists(int(n)))
          throw InputError(where(sn, "settings." + name), quote(name), "a Grbl setting such as \"$110\"");
        const double v = number(sn, name);
        const int code = set_setting(st.settings, int(n), v);
        if (code != 0)
          throw InputError(where(sn, "settings." + name), mc::host::format_number(v),
                           "a value Grbl accepts (status " + std::to_string(code) + ")");
      }
    } else if (key == "startup") {
      const auto* t = node.as_table();
      if (!t) throw InputError(where(node, key), "not a table", "a table [startup]");
      for (const auto& [sk, sn] : *t) {
        const std::string name(sk.str());
        const auto* s = sn.as_string();
        if (!s) throw InputError(where(sn, "startup." + name), "a non-string", "a string");
        if (name == "n0")
          st.startup[0] = s->get();
        else if (name == "n1")
          st.startup[1] = s->get();
        else if (name == "build_info")
          st.build_info = s->get();
        else
          throw InputError(where(sn, "startup." + name), quote(name), "n0, n1 or build_info");
      }
    } else if (key == "offsets") {
      const auto* t = node.as_table();
      if (!t) throw InputError(where(node, key), "not a table", "a table [offsets]");
      for (const auto& [sk, sn] : *t) {
        const std::string name(sk.str());
        bool found = false;
        for (size_t i = 0; i < 9; ++i)
          if (name == kCoordNames[i]) {
            st.offsets.coord_offsets[i] = vec(sn, "offsets." + name);
            found = true;
          }
        if (name == "G28") {
          st.offsets.g28 = vec(sn, "offsets." + name);
          found = true;
        } else if (name == "G30") {
          st.offsets.g30 = vec(sn, "offsets." + name);
          found = true;
        }
        if (!found)
          throw InputError(where(sn, "offsets." + name), quote(name), "G54..G59, G59_1..G59_3, G28 or G30");
      }
    } else {
      throw InputError(where(node, key), quote(key), "settings, startup or offsets");
    }
  }
  return st;
}

void save_stored(const std::string& path, const Stored& st) {
  std::ostringstream o;
  o << "# Grbl settings ($$), start-up blocks ($N) and offsets ($#) of 'motionctl serve'.\n"
       "# Rewritten by the server whenever a sender changes them; docs/grbl.md lists the keys.\n\n"
       "[settings]\n";
  for (int n : setting_numbers()) {
    const std::string line = format_setting(st.settings, n);
    const size_t eq = line.find('=');
    o << '"' << line.substr(0, eq) << "\" = " << (is_integer_setting(n) ? line.substr(eq + 1) : [&] {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", get_setting(st.settings, n));
      std::string s = buf;
      if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
      return s;
    }()) << "\n";
  }
  o << "\n[startup]\nn0 = " << toml_string(st.startup[0]) << "\nn1 = " << toml_string(st.startup[1])
    << "\nbuild_info = " << toml_string(st.build_info) << "\n\n[offsets]  # machine mm\n";
  for (size_t i = 0; i < 9; ++i)
    o << kCoordNames[i] << " = " << vec_text(st.offsets.coord_offsets[i]) << "\n";
  o << "G28 = " << vec_text(st.offsets.g28) << "\nG30 = " << vec_text(st.offsets.g30) << "\n";

  const std::string tmp = path + ".tmp";
  std::error_code ec;  // a directory that cannot be made shows up as a write error below
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  {
    std::ofstream f(tmp, std::ios::trunc);
    f << o.str();
    if (!f.flush()) throw std::runtime_error("cannot write the Grbl settings file " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw std::runtime_error("cannot replace the Grbl settings file " + path);
}

}  // namespace mc::grbl
