// Grbl's $ settings (host/grbl/settings.hpp): defaults from the machine TOML,
// Grbl's validation, and the settings file written and read back.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "host/base/errors.hpp"
#include "host/grbl/settings.hpp"
#include "host/machine/machine_config.hpp"

namespace fs = std::filesystem;

namespace mc::grbl {
namespace {

struct TempDir {
  fs::path path = fs::temp_directory_path() /
                  ("mc_grbl_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                   "_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

TEST(GrblSettings, DefaultsComeFromTheMachine) {
  const auto m = mc::machine::default_machine();
  const Settings s = default_settings(m);
  // configs/default.toml: 2000 counts/rev, gear 1, lead 5 mm; X and Y 0.5 m/s, 2 m/s^2,
  // -0.3..0.3 m; Z 0.25 m/s, 1 m/s^2, -0.1..0.02 m; [planner] 1e-5 m and 2e-6 m.
  EXPECT_DOUBLE_EQ(s.counts_per_mm[0], 400);
  EXPECT_DOUBLE_EQ(s.counts_per_mm[2], 400);
  EXPECT_DOUBLE_EQ(s.max_rate_mm_min[1], 30000);
  EXPECT_DOUBLE_EQ(s.max_rate_mm_min[2], 15000);
  EXPECT_DOUBLE_EQ(s.accel_mm_s2[0], 2000);
  EXPECT_DOUBLE_EQ(s.accel_mm_s2[2], 1000);
  EXPECT_NEAR(s.max_travel_mm[0], 600, 1e-9);
  EXPECT_NEAR(s.max_travel_mm[2], 120, 1e-9);
  EXPECT_NEAR(s.travel_top_mm[2], 20, 1e-9);
  EXPECT_NEAR(s.junction_deviation_mm, 0.010, 1e-12);
  EXPECT_NEAR(s.arc_tolerance_mm, 0.002, 1e-12);
  EXPECT_EQ(format_setting(s, 100), "$100=400.000");
  EXPECT_EQ(format_setting(s, 10), "$10=1");
  EXPECT_EQ(format_setting(s, 11), "$11=0.010");
  // An axis the machine lacks takes the last axis' values.
  auto two = mc::machine::default_machine();
  two.axes.resize(2);
  EXPECT_DOUBLE_EQ(default_settings(two).max_rate_mm_min[2], 30000);
}

TEST(GrblSettings, SetFollowsGrblsRules) {
  Settings s;
  EXPECT_EQ(set_setting(s, 9, 1), 3);
  EXPECT_EQ(set_setting(s, 103, 1), 3);  // three axes
  EXPECT_EQ(set_setting(s, 11, -0.1), 4);
  EXPECT_EQ(set_setting(s, 110, 0), 4);  // a zero rate would divide by zero
  EXPECT_EQ(set_setting(s, 20, 1), 10);
  EXPECT_EQ(set_setting(s, 10, 2.9), 0);  // integer settings truncate, as Grbl
  EXPECT_EQ(s.report_mask, 2);
  EXPECT_EQ(set_setting(s, 23, 300), 0);  // kept in a byte
  EXPECT_EQ(s.homing_dir_mask, 255);
  EXPECT_EQ(set_setting(s, 131, 123.25), 0);
  EXPECT_EQ(s.max_travel_mm[1], 123.25);
  for (int n : setting_numbers()) EXPECT_EQ(format_setting(s, n).rfind("$" + std::to_string(n) + "=", 0), 0u);
}

TEST(GrblSettings, TheFileRoundTrips) {
  TempDir d;
  const std::string path = (d.path / "m.grbl.toml").string();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.001, 5000);
  Stored st;
  for (int n : setting_numbers()) {
    const double v = n == 20 ? 0 : (n < 100 ? double(int(u(rng)) % 2) : u(rng));
    ASSERT_EQ(set_setting(st.settings, n, v), 0) << n;
  }
  st.startup = {"G20G55", "M3S1000"};
  st.build_info = "SHOP \"A\"";
  for (auto& o : st.offsets.coord_offsets) o = {u(rng), -u(rng), u(rng)};
  st.offsets.g28 = {1, 2, 3};
  st.offsets.g30 = {-1e-9, 0.1, 1e6};
  save_stored(path, st);
  const Stored back = load_stored(path, Stored{});
  for (int n : setting_numbers()) EXPECT_EQ(get_setting(back.settings, n), get_setting(st.settings, n)) << n;
  EXPECT_EQ(back.startup, st.startup);
  EXPECT_EQ(back.build_info, st.build_info);
  EXPECT_EQ(back.offsets.coord_offsets, st.offsets.coord_offsets);
  EXPECT_EQ(back.offsets.g28, st.offsets.g28);
  EXPECT_EQ(back.offsets.g30, st.offsets.g30);
}

TEST(GrblSettings, AMissingFileGivesTheDefaultsAndAbsentKeysKeepThem) {
  TempDir d;
  Stored defaults;
  defaults.settings.max_rate_mm_min = {1, 2, 3};
  const Stored none = load_stored((d.path / "none.toml").string(), defaults);
  EXPECT_EQ(none.settings.max_rate_mm_min, defaults.settings.max_rate_mm_min);
  const std::string path = (d.path / "part.toml").string();
  std::ofstream(path) << "[settings]\n\"$111\" = 500\n";
  const Stored part = load_stored(path, defaults);
  EXPECT_EQ(part.settings.max_rate_mm_min, (std::array<double, 3>{1, 500, 3}));
}

TEST(GrblSettings, BadFilesNameTheFileLineAndKey) {
  TempDir d;
  const std::string path = (d.path / "bad.toml").string();
  const auto error_of = [&](const std::string& text) {
    std::ofstream(path) << text;
    try {
      load_stored(path, Stored{});
    } catch (const mc::host::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string e = error_of("[settings]\n\"$110\" = 100\n\"$7\" = 1\n");
  EXPECT_NE(e.find(path + ":3: settings.$7"), std::string::npos) << e;
  e = error_of("[settings]\n\"$20\" = 1\n");  // soft limits without homing
  EXPECT_NE(e.find(":2: settings.$20"), std::string::npos) << e;
  e = error_of("[offsets]\nG54 = [1, 2]\n");
  EXPECT_NE(e.find(":2: offsets.G54"), std::string::npos) << e;
  e = error_of("[startup]\nn3 = \"G20\"\n");
  EXPECT_NE(e.find(":2: startup.n3"), std::string::npos) << e;
  e = error_of("[setings]\n");
  EXPECT_NE(e.find(":1: setings"), std::string::npos) << e;
  e = error_of("[settings\n");
  EXPECT_NE(e.find(path + ":1"), std::string::npos) << e;
}

TEST(GrblSettings, TheFileSitsNextToTheMachine) {
  EXPECT_EQ(settings_path_for("/x/router.toml"), "/x/router.grbl.toml");
  EXPECT_EQ(settings_path_for("router"), "router.grbl.toml");
  ::setenv("XDG_CONFIG_HOME", "/cfg", 1);
  EXPECT_EQ(settings_path_for(""), "/cfg/motionctl/grbl.toml");
}

}  // namespace
}  // namespace mc::grbl
