// The machine config format (sim/machine_config.hpp): the built-in default
// parses to the cited values with sane units, and every kind of bad input is
// an error naming the file, the line and the key.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "host/base/errors.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::machine {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<std::string> lines_of(std::string_view text) {
  std::vector<std::string> v;
  std::istringstream in{std::string(text)};
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& l : v) s += l + "\n";
  return s;
}

// The default text with one key's line in one table replaced (or removed
// when `line` is empty); returns the 1-based line number it had.
struct Edit {
  std::string text;
  int line;
};
Edit edit(const std::string& table, const std::string& key, const std::string& line) {
  auto v = lines_of(default_machine_toml());
  size_t i = 0;
  while (i < v.size() && v[i] != "[" + table + "]") ++i;
  const int header = int(i) + 1;
  while (i < v.size() && v[i].rfind(key + " ", 0) != 0) ++i;
  if (i == v.size()) {
    ADD_FAILURE() << key << " not in [" << table << "]";
    return {"", 0};
  }
  if (line.empty()) {
    v.erase(v.begin() + long(i));
    return {join(v), header};
  }
  v[i] = line;
  return {join(v), int(i) + 1};
}

Edit insert_after(const std::string& table, const std::string& line) {
  auto v = lines_of(default_machine_toml());
  size_t i = 0;
  while (i < v.size() && v[i] != "[" + table + "]") ++i;
  v.insert(v.begin() + long(i) + 1, line);
  return {join(v), int(i) + 2};
}

// Parses `text` as "test.toml", expects an InputError that starts with
// "test.toml:<line>: <key>" and mentions `mentions`.
void expect_error(const Edit& e, const std::string& key, const std::string& mentions) {
  try {
    parse_machine(e.text, "test.toml");
    ADD_FAILURE() << "no error for " << key;
  } catch (const mc::host::InputError& err) {
    const std::string msg = err.what();
    const std::string where = "test.toml:" + std::to_string(e.line) + ": " + key;
    EXPECT_EQ(msg.rfind(where, 0), 0u) << msg << "\n  want prefix: " << where;
    EXPECT_NE(msg.find(mentions), std::string::npos) << msg << "\n  want: " << mentions;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(SimConfig, DefaultParsesToTheDatasheetValues) {
  const MachineConfig m = default_machine();
  EXPECT_EQ(m.source, "built-in default");
  EXPECT_EQ(m.clock_hz, 12e6);
  EXPECT_EQ(m.plant_dt_s, 1e-6);
  EXPECT_EQ(m.host_period_s, 0.01);
  EXPECT_EQ(m.host_io_latency_s, 0.001);
  EXPECT_EQ(m.host_dac_bits, 12);
  EXPECT_EQ(m.host_dac_range_v, 10);
  ASSERT_EQ(m.axes.size(), 3u);
  EXPECT_EQ(m.axes[0].name, "x");
  EXPECT_EQ(m.axes[1].name, "y");
  EXPECT_EQ(m.axes[2].name, "z");
  for (const AxisConfig& a : m.axes) {
    // maxon RE 40 148867 (configs/default.toml cites the datasheet lines).
    EXPECT_EQ(a.motor.r_ohm, 1.13);
    EXPECT_EQ(a.motor.l_h, 0.33e-3);
    EXPECT_EQ(a.motor.kt_nm_per_a, 0.0603);
    EXPECT_NEAR(a.motor.ke_v_s_per_rad, 60 / (2 * kPi * 158), 1e-6);
    EXPECT_EQ(a.motor.j_kg_m2, 137e-7);
    EXPECT_NEAR(a.motor.coulomb_nm, 0.0603 * 0.0686, 1e-7);  // Kt * no-load current
    EXPECT_GE(a.motor.stiction_nm, a.motor.coulomb_nm);
    EXPECT_EQ(a.drive.kind, DriveConfig::Kind::Pwm);
    EXPECT_EQ(a.drive.supply_v, 48);
    EXPECT_EQ(a.drive.pwm_bits, 9);
    EXPECT_FALSE(a.drive.pwm_switching);
    EXPECT_EQ(a.drive.dac_bits, 12);
    EXPECT_EQ(a.encoder_cpr, 2000);
    EXPECT_EQ(a.lead_m_per_rev, 0.005);
    EXPECT_EQ(a.pid.ts_s, 1e-4);
  }
  // X and Y are identical; Z carries what is left of the spindle's weight.
  EXPECT_GT(m.axes[2].load_force_n, 0);
  // Counterbalanced: with the drives off, gravity's torque is under the stiction.
  EXPECT_LT(reflected_torque_nm(m.axes[2]), m.axes[2].motor.stiction_nm);
  EXPECT_EQ(m.axes[0].pid.kp, m.axes[1].pid.kp);
  EXPECT_EQ(m.axes[0].load_kg, m.axes[1].load_kg);
}

// Every value in its unit's plausible range for a small servo axis: catches
// a value typed in the wrong unit (mH for H, gcm^2 for kg m^2, rpm/V for V s/rad).
TEST(SimConfig, DefaultUnitsAreSane) {
  for (const AxisConfig& a : default_machine().axes) {
    const MotorParams& mo = a.motor;
    EXPECT_GT(mo.r_ohm, 0.05);
    EXPECT_LT(mo.r_ohm, 50);
    EXPECT_GT(mo.l_h, 1e-5);
    EXPECT_LT(mo.l_h, 1e-1);
    // In SI units the torque and back-EMF constants are the same number.
    EXPECT_NEAR(mo.ke_v_s_per_rad / mo.kt_nm_per_a, 1, 0.01);
    EXPECT_GT(mo.j_kg_m2, 1e-7);
    EXPECT_LT(mo.j_kg_m2, 1e-3);
    // The datasheet's mechanical time constant, 4.28 ms, within rounding.
    EXPECT_NEAR(mo.r_ohm * mo.j_kg_m2 / (mo.kt_nm_per_a * mo.ke_v_s_per_rad), 4.28e-3, 0.05e-3);
    // No-load speed at the supply: 7590 rpm on the datasheet.
    const double w0 = (a.drive.supply_v - mo.r_ohm * mo.coulomb_nm / mo.kt_nm_per_a) / mo.ke_v_s_per_rad;
    EXPECT_NEAR(w0 * 60 / (2 * kPi), 7590, 0.01 * 7590);
    EXPECT_LE(a.max_speed_m_s, w0 / (2 * kPi) / a.gear_ratio * a.lead_m_per_rev);
    EXPECT_GT(a.lead_m_per_rev, 1e-3);
    EXPECT_LT(a.lead_m_per_rev, 5e-2);
    EXPECT_DOUBLE_EQ(a.drive.pwm_hz, 12e6 / 512);
    // The DAC variant maps +-dac_range_v to +-supply_v.
    EXPECT_DOUBLE_EQ(a.drive.dac_range_v * a.drive.amp_gain, a.drive.supply_v);
    EXPECT_DOUBLE_EQ(counts_per_m(a), 400000);
    EXPECT_NEAR(reflected_inertia_kg_m2(a), a.load_kg * std::pow(0.005 / (2 * kPi), 2), 1e-15);
    if (a.name == "z")
      EXPECT_NEAR(reflected_torque_nm(a), a.load_force_n * 0.005 / (2 * kPi), 1e-12);
    else
      EXPECT_EQ(reflected_torque_nm(a), 0);
  }
}

TEST(SimConfig, AxisLookupIsCaseInsensitive) {
  const MachineConfig m = default_machine();
  EXPECT_EQ(axis(m, "X").name, "x");
  EXPECT_EQ(axis(m, "y").name, "y");
  try {
    axis(m, "q");
    ADD_FAILURE();
  } catch (const mc::host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x, y"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("\"q\""), std::string::npos) << e.what();
  }
}

TEST(SimConfig, OptionalZAxis) {
  // The built-in router without its Z tables: an XY table.
  std::string text(default_machine_toml());
  for (const std::string t : {"", ".motor", ".drive", ".pid", ".home"}) {
    const auto from = text.find("[axis.z" + t + "]");
    ASSERT_NE(from, std::string::npos);
    const auto to = text.find("\n[", from + 1);
    text.erase(from, to == std::string::npos ? std::string::npos : to - from + 1);
  }
  const MachineConfig m = parse_machine(text, "xy.toml");
  ASSERT_EQ(m.axes.size(), 2u);
  EXPECT_EQ(m.axes[1].name, "y");
  // The planner's keys are optional: an older file without them loads with
  // the documented defaults.
  for (const std::string key : {"max_accel_m_s2", "travel_min_m", "travel_max_m"}) {
    for (size_t at = text.find("\n" + key); at != std::string::npos; at = text.find("\n" + key))
      text.erase(at + 1, text.find('\n', at + 1) - at);
  }
  const auto planner = text.find("\n[planner]");
  ASSERT_NE(planner, std::string::npos);
  text.erase(planner + 1);
  const MachineConfig old = parse_machine(text, "old.toml");
  EXPECT_EQ(old.axes[0].max_accel_m_s2, 1.0);
  EXPECT_EQ(old.axes[0].travel_min_m, -1.0);
  EXPECT_EQ(old.planner.junction_deviation_m, 1e-5);
  std::string inverted(default_machine_toml());
  inverted.replace(inverted.find("travel_max_m = 0.3"), 18, "travel_max_m = -0.5");
  try {
    parse_machine(inverted, "inv.toml");
    ADD_FAILURE() << "an inverted travel was accepted";
  } catch (const mc::host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("travel_max_m > travel_min_m"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inv.toml:"), std::string::npos) << e.what();
  }
}

TEST(SimConfig, UnknownKeyIsAnError) {
  expect_error(insert_after("axis.x.motor", "resistnce_ohm = 1.13"), "axis.x.motor.resistnce_ohm",
               "unknown key; expected one of: resistance_ohm, inductance_h");
  expect_error(insert_after("machine", "clock_mhz = 12"), "machine.clock_mhz", "unknown key");
  expect_error(insert_after("axis.y.pid", "kpp = 1"), "axis.y.pid.kpp", "unknown key");
}

TEST(SimConfig, MissingKeyIsAnError) {
  expect_error(edit("axis.x.motor", "resistance_ohm", ""), "axis.x.motor.resistance_ohm", "missing key");
  expect_error(edit("host_loop", "period_s", ""), "host_loop.period_s", "missing key");
  expect_error(edit("axis.y.drive", "kind", ""), "axis.y.drive.kind", "missing key");
}

TEST(SimConfig, WrongTypeIsAnError) {
  expect_error(edit("axis.x.motor", "resistance_ohm", "resistance_ohm = \"1.13\""),
               "axis.x.motor.resistance_ohm", "wrong type");
  expect_error(edit("axis.x", "encoder_counts_per_rev", "encoder_counts_per_rev = 2000.5"),
               "axis.x.encoder_counts_per_rev", "a whole number");
  expect_error(edit("axis.x.drive", "pwm_switching", "pwm_switching = 1"), "axis.x.drive.pwm_switching",
               "true or false");
  expect_error(edit("axis.x.drive", "kind", "kind = \"pmw\""), "axis.x.drive.kind",
               "one of \"pwm\", \"dac\"");
}

TEST(SimConfig, OutOfRangeValuesAreErrors) {
  expect_error(edit("axis.x.motor", "resistance_ohm", "resistance_ohm = -1.13"),
               "axis.x.motor.resistance_ohm", "= -1.13: expected a number > 0 (ohm)");
  expect_error(edit("axis.y.motor", "inertia_kg_m2", "inertia_kg_m2 = 0"), "axis.y.motor.inertia_kg_m2",
               "a number > 0");
  expect_error(edit("axis.x", "load_kg", "load_kg = -15"), "axis.x.load_kg", "a number >= 0 (kg)");
  expect_error(edit("axis.x.motor", "stiction_nm", "stiction_nm = 0.001"), "axis.x.motor.stiction_nm",
               "stiction_nm >= coulomb_nm");
  expect_error(edit("axis.x.drive", "pwm_bits", "pwm_bits = 16"), "axis.x.drive.pwm_bits", "1..15");
  expect_error(edit("axis.x.pid", "ki", "ki = -1"), "axis.x.pid.ki", "a number >= 0");
  expect_error(edit("axis.x.pid", "ts_s", "ts_s = 1.00001e-4"), "axis.x.pid.ts_s",
               "whole number of core clock");
  expect_error(edit("axis.x.pid", "out_limit", "out_limit = 40000"), "axis.x.pid.out_limit", "<= 32767");
  expect_error(edit("machine", "plant_dt_s", "plant_dt_s = nan"), "machine.plant_dt_s", "a number > 0");
}

// Values no board or small machine can have are refused with the file and
// line, before a simulation or a board is set up with them (issue 18:
// clock_hz = 1e15 used to be accepted and left `sim serve` deaf to signals).
TEST(SimConfig, PhysicallyAbsurdValuesAreErrors) {
  expect_error(edit("machine", "clock_hz", "clock_hz = 1e15"), "machine.clock_hz",
               "up to 167772150 (the watchdog");
  expect_error(edit("machine", "clock_hz", "clock_hz = 1e3"), "machine.clock_hz", "at least 2000000 Hz");
  expect_error(edit("machine", "plant_dt_s", "plant_dt_s = 1.5e-7"), "machine.plant_dt_s",
               "a whole number of at least 2 clock cycles");
  expect_error(edit("machine", "plant_dt_s", "plant_dt_s = 1e-3"), "machine.plant_dt_s",
               "at most the axes' sample period (axis.x.pid.ts_s = 0.0001 s)");
  expect_error(edit("host_loop", "period_s", "period_s = 3600"), "host_loop.period_s", "up to 1");
  expect_error(edit("axis.x", "lead_m_per_rev", "lead_m_per_rev = 5"), "axis.x.lead_m_per_rev", "up to 1");
  expect_error(edit("axis.x.motor", "inductance_h", "inductance_h = 0.33e3"), "axis.x.motor.inductance_h",
               "above the range");
  expect_error(edit("axis.y.drive", "supply_v", "supply_v = 48e3"), "axis.y.drive.supply_v", "up to 1000");
  // 1 m of following error is 400000 counts: more than FERR's 16 bits hold.
  expect_error(edit("axis.x", "max_following_error_m", "max_following_error_m = 1"),
               "axis.x.max_following_error_m", "65535 counts");
  expect_error(edit("axis.x", "max_following_error_m", "max_following_error_m = 1e-7"),
               "axis.x.max_following_error_m", "at least one encoder count");
  // 750 000 iterations/s at 12 MHz over 400 000 counts/m: 1.875 m/s.
  expect_error(edit("axis.x", "max_speed_m_s", "max_speed_m_s = 5"), "axis.x.max_speed_m_s", "up to 1.875");
  expect_error(edit("axis.x", "travel_max_m", "travel_max_m = -0.4"), "axis.x.travel_max_m",
               "travel_max_m > travel_min_m = -0.3");
  expect_error(edit("axis.y", "travel_min_m", "travel_min_m = -1e4"), "axis.y.travel_min_m",
               "within the board's 32-bit positions");
  // The PID: Ts the core runs (its 70-cycle sweep .. 10 ms), Kp it realizes as a controller.
  expect_error(edit("axis.x.pid", "ts_s", "ts_s = 1e-6"), "axis.x.pid.ts_s", "too short");
  expect_error(edit("axis.x.pid", "ts_s", "ts_s = 10"), "axis.x.pid.ts_s", "to 10 ms");
  expect_error(edit("axis.x.pid", "kp", "kp = 8000000"), "axis.x.pid.kp", "0..32767");
}

// Where the board's 32-bit counters reach less than the +-1 m default (a
// 2^24-count encoder on a 1 mm lead: 16.8e9 counts/m), the default is what
// they reach.
TEST(SimConfig, DefaultTravelStaysWithinTheCounters) {
  std::string text(default_machine_toml());
  const auto y = text.find("[axis.y]");
  const auto set = [&](const std::string& key, const std::string& value) {
    const auto at = text.find("\n" + key + " ", y) + 1;
    text.replace(at, text.find('\n', at) - at, value.empty() ? "" : key + " = " + value);
  };
  set("lead_m_per_rev", "0.001");
  set("encoder_counts_per_rev", "16777216");
  set("max_following_error_m", "1e-6");  // 16777 counts: within FERR
  set("max_speed_m_s", "1e-5");          // within the interpolator's rate at this scale
  set("travel_min_m", "");
  set("travel_max_m", "");
  const auto home = text.find("[axis.y.home]");  // its switch and speeds are for the real axis
  text.erase(home, text.find("\n\n", home) + 1 - home);
  const MachineConfig m = parse_machine(text, "fine.toml");
  const double reach = 2147483647.0 / (16777216 / 0.001);
  EXPECT_DOUBLE_EQ(m.axes[1].travel_max_m, reach);
  EXPECT_DOUBLE_EQ(m.axes[1].travel_min_m, -reach);
  EXPECT_EQ(m.axes[0].travel_max_m, 0.3);
}

TEST(SimConfig, StructureErrors) {
  const std::string text0(default_machine_toml());
  expect_error({text0 + "[axis.w]\nlead_m_per_rev = 0.005\n", int(lines_of(text0).size()) + 1}, "axis.w",
               "unknown axis");
  // Bad TOML: the parser's line and description.
  expect_error(edit("axis.x.motor", "inductance_h", "inductance_h = = 1"), "TOML", "expected valid TOML");
  // A whole axis missing.
  std::string text(default_machine_toml());
  const auto from = text.find("[axis.y]");
  text = text.substr(0, from);
  try {
    parse_machine(text, "x_only.toml");
    ADD_FAILURE();
  } catch (const mc::host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x_only.toml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("axis.y"), std::string::npos) << e.what();
  }
}

TEST(SimConfig, LoadFromFile) {
  const std::string path = ::testing::TempDir() + "mc_sim_config_test.toml";
  {
    std::ofstream out(path);
    out << default_machine_toml();
  }
  const MachineConfig m = load_machine(path);
  EXPECT_EQ(m.source, path);
  EXPECT_EQ(m.axes.size(), 3u);
  EXPECT_EQ(machine_or_default("").source, "built-in default");
  std::remove(path.c_str());
  try {
    load_machine(path);
    ADD_FAILURE();
  } catch (const mc::host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

// [axis.N.home] and [probe] (issue 17): the built-in machine's switches, the
// defaults of the optional keys, and every bad value refused with its line.
TEST(SimConfig, HomeSwitchesAndTheProbe) {
  const MachineConfig m = default_machine();
  for (const AxisConfig& a : m.axes) {
    ASSERT_TRUE(a.home) << a.name;
    EXPECT_EQ(a.home->direction, 1) << a.name << ": every switch at the + end";
    EXPECT_GT(a.home->switch_m, 0) << a.name;
    EXPECT_LT(a.home->switch_m, a.travel_max_m) << a.name << ": inside travel";
    EXPECT_LE(a.home->locate_m_s, a.home->seek_m_s) << a.name;
  }
  EXPECT_EQ(m.axes[2].home->order, 0) << "Z homes first";
  EXPECT_EQ(m.axes[0].home->order, 1);
  EXPECT_EQ(m.probe.bounce_s, 0.0002);

  // Only switch_m and direction are required; a file without [probe] has its default.
  std::string text(default_machine_toml());
  const auto from = text.find('\n', text.find("direction", text.find("[axis.y.home]"))) + 1;
  text.erase(from, text.find("\n\n", from) + 1 - from);
  text.erase(text.find("\n[probe]") + 1);
  const MachineConfig d = parse_machine(text, "defaults.toml");
  const HomeConfig& h = *d.axes[1].home;
  EXPECT_EQ(h.switch_m, 0.29);
  EXPECT_EQ(h.bounce_s, 0.0005);
  EXPECT_EQ(h.order, 0);
  EXPECT_DOUBLE_EQ(h.seek_m_s, 0.5 / 60);      // Grbl's $25, 500 mm/min
  EXPECT_DOUBLE_EQ(h.locate_m_s, 0.025 / 60);  // $24, 25 mm/min
  EXPECT_EQ(h.pull_off_m, 0.001);              // $27, 1 mm
  EXPECT_EQ(d.probe.bounce_s, 0.0002);
  // Without [home] an axis has no switch.
  std::string none(default_machine_toml());
  const auto z = none.find("[axis.z.home]");
  none.erase(z, none.find("\n\n", z) - z);
  EXPECT_FALSE(parse_machine(none, "none.toml").axes[2].home);

  expect_error(insert_after("axis.x.home", "swich_m = 0.1"), "axis.x.home.swich_m",
               "unknown key; expected one of: switch_m, direction, bounce_s");
  expect_error(insert_after("probe", "debounce_s = 1"), "probe.debounce_s", "unknown key");
  // `key = value` in `table` (no value: the line removed) is refused, naming the key.
  const auto refused = [](const std::string& table, const std::string& key, const std::string& value,
                          const std::string& mentions) {
    expect_error(edit(table, key, value.empty() ? "" : key + " = " + value), table + "." + key, mentions);
  };
  refused("axis.x.home", "switch_m", "", "missing key");
  refused("axis.x.home", "switch_m", "0.5", "within the axis's travel -0.3..0.3 m");
  refused("axis.x.home", "direction", "0", "+1");
  refused("axis.x.home", "direction", "2", "-1..1");
  refused("axis.y.home", "bounce_s", "5", "up to 0.1");
  refused("axis.y.home", "bounce_s", "-1e-3", "a number >= 0");
  refused("axis.y.home", "order", "3", "0..2");
  refused("axis.z.home", "seek_m_s", "1", "at most the axis's max_speed_m_s = 0.25 m/s");
  refused("axis.z.home", "locate_m_s", "0.05", "at most seek_m_s = 0.01 m/s");
  refused("axis.z.home", "pull_off_m", "0.2", "less than the axis's travel, 0.12 m");
  refused("probe", "bounce_s", "0.5", "up to 0.1");
}

// Every machine file shipped in configs/ loads (make test parses each).
TEST(SimConfig, EveryShippedConfigLoads) {
  int n = 0;
  for (const auto& f : std::filesystem::directory_iterator(std::string(MC_SOURCE_DIR) + "/configs")) {
    if (f.path().extension() != ".toml") continue;
    SCOPED_TRACE(f.path().string());
    const MachineConfig m = load_machine(f.path().string());
    EXPECT_GE(m.axes.size(), 2u);
    ++n;
  }
  EXPECT_GE(n, 3) << "default, stepper_router and drill at least";
}

// configs/drill.toml: the source document's drill (seed 000) as its
// section 6.11 computes it: 3200 steps per motor rev, belts 15:25 onto a
// 7 mm screw on X and Z (760 steps/mm in the firmware, 761.9 exactly) and
// 15:30 onto 10 mm on Y (640), 400 mm of travel, switches at the origin.
TEST(SimConfig, TheDrillIsTheDocumentsMachine) {
  const MachineConfig m = load_machine(std::string(MC_SOURCE_DIR) + "/configs/drill.toml");
  ASSERT_EQ(m.axes.size(), 3u);
  EXPECT_NEAR(counts_per_m(m.axes[0]) / 1e3, 3200.0 * 25 / 15 / 7, 1e-3);
  EXPECT_NEAR(counts_per_m(m.axes[1]) / 1e3, 640.0, 1e-9);
  EXPECT_NEAR(counts_per_m(m.axes[2]) / 1e3, 3200.0 * 25 / 15 / 7, 1e-3);
  for (const AxisConfig& a : m.axes) {
    SCOPED_TRACE(a.name);
    ASSERT_TRUE(a.stepper && a.home);
    EXPECT_EQ(a.stepper->steps_per_rev(), 3200);
    EXPECT_NEAR(a.travel_max_m - a.travel_min_m, 0.4, 1e-12);
    EXPECT_EQ(a.home->bounce_s, 0.0) << "the anti-bounce circuit";
    // The firmware's FAST_SPEED, 10000 steps/s.
    EXPECT_NEAR(a.max_speed_m_s * counts_per_m(a), 10000, 5);
  }
  EXPECT_EQ(m.axes[0].home->direction, -1);
  EXPECT_EQ(m.axes[0].home->switch_m, m.axes[0].travel_min_m) << "the origin at the - end";
  EXPECT_EQ(m.axes[1].home->direction, -1);
  EXPECT_EQ(m.axes[2].home->direction, 1) << "Z homes up";
  EXPECT_EQ(m.axes[2].home->switch_m, m.axes[2].travel_max_m);
}

}  // namespace
}  // namespace mc::machine
