// motionctl plant step, run as a user runs it: the CSV contract, the summary
// against the analytic steady state, and one-line errors with exit code 2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"

namespace {

using mc::test::expect_one_error_line;
using mc::test::Result;
using mc::test::run;

std::vector<std::vector<double>> parse_csv(const std::string& text, std::string* header) {
  std::istringstream in(text);
  std::getline(in, *header);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<double> r;
    std::istringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) r.push_back(std::stod(cell));
    rows.push_back(r);
  }
  return rows;
}

// maxon RE 40 148867 as in configs/default.toml: the linear model's steady
// speed V/(Ke + R B/Kt) with B = 0 and no load is V/Ke.
constexpr double kKe = 0.060439;

TEST(CliPlant, StepCsvContract) {
  const Result r = run({"plant", "step", "--volts", "12", "--duration", "0.2", "--csv", "--no-friction"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  std::string header;
  const auto rows = parse_csv(r.out, &header);
  EXPECT_EQ(header, "t_s,volts,current_a,speed_rad_s,position_rad");
  ASSERT_EQ(rows.size(), 2001u);
  EXPECT_EQ(rows[0], (std::vector<double>{0, 12, 0, 0, 0}));
  for (size_t k = 0; k < rows.size(); ++k) {
    ASSERT_EQ(rows[k].size(), 5u) << k;
    EXPECT_NEAR(rows[k][0], double(k) * 1e-4, 1e-9) << k;
    EXPECT_EQ(rows[k][1], 12.0);
  }
  // 0.2 s is 29 mechanical time constants: the final speed is the steady state.
  const double w_ss = 12 / kKe;
  EXPECT_NEAR(rows.back()[3], w_ss, 0.01 * w_ss);
  EXPECT_NEAR(rows.back()[3], w_ss, 1e-6 * w_ss);
  EXPECT_NEAR(rows.back()[2], 0, 1e-6);  // no friction, no load: no steady current
}

TEST(CliPlant, WorksFromAnyDirectoryWithTheBuiltInDefault) {
  // run() does not change directory; the binary must not need configs/ near it.
  const Result r = run({"plant", "step", "--volts", "12", "--duration", "0.2", "--csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string header;
  const auto rows = parse_csv(r.out, &header);
  ASSERT_EQ(rows.size(), 2001u);
  // Friction on: the steady speed is lowered by R Tc/Kt / Ke.
  const double tc = 0.0603 * 0.0686;
  const double w_ss = (12 - 1.13 * tc / 0.0603) / kKe;
  EXPECT_NEAR(rows.back()[3], w_ss, 1e-4 * w_ss);
}

TEST(CliPlant, JsonSummary) {
  Result r = run({"plant", "step", "--axis", "Y", "--volts", "24", "--duration", "100ms", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["axis"], "y");
  EXPECT_EQ(j["config"], "built-in default");
  EXPECT_EQ(j["steps"].get<long>(), 100000);
  EXPECT_TRUE(j["friction"].get<bool>());
  EXPECT_FALSE(j["held_by_stiction"].get<bool>());
  EXPECT_NEAR(j["tau_electrical_s"].get<double>(), 0.33e-3 / 1.13, 1e-12);
  const double w = j["final"]["speed_rad_s"], w_ss = j["steady_speed_rad_s"];
  EXPECT_NEAR(w, w_ss, 1e-3 * w_ss);
  EXPECT_LT(w_ss, j["steady_speed_linear_rad_s"].get<double>());
  EXPECT_GT(j["ns_per_step"].get<double>(), 0);

  // Below breakaway: held by stiction, nothing moves.
  r = run({"plant", "step", "--volts", "0.05", "--duration", "0.05", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["held_by_stiction"].get<bool>());
  EXPECT_EQ(j["final"]["speed_rad_s"].get<double>(), 0.0);
  EXPECT_EQ(j["final"]["position_rad"].get<double>(), 0.0);
  EXPECT_TRUE(j["final"]["stuck"].get<bool>());
}

TEST(CliPlant, HumanSummary) {
  const Result r = run({"plant", "step", "--volts", "12", "--duration", "0.2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* s :
       {"steady state, analytic", "peak current", "time constants", "breakaway", "ns per step"}) {
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
  }
}

TEST(CliPlant, ConfigFileAndDt) {
  const std::string path = ::testing::TempDir() + "mc_cli_plant.toml";
  // A config file with an edited resistance changes the response.
  std::ifstream src(std::string(MC_SOURCE_DIR) + "/configs/default.toml");
  std::stringstream text;
  text << src.rdbuf();
  std::string s = text.str();
  const auto at = s.find("\nresistance_ohm = 1.13");  // axis x; the header cites it too
  ASSERT_NE(at, std::string::npos);
  s.replace(at, 22, "\nresistance_ohm = 2.26");
  std::ofstream(path) << s;
  const Result a = run({"plant", "step", "--config", path, "--volts", "12", "--duration", "0.001", "--json"});
  const Result b = run({"plant", "step", "--volts", "12", "--duration", "0.001", "--json", "--dt", "10us"});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
  EXPECT_EQ(ja["config"], path);
  EXPECT_NEAR(ja["tau_electrical_s"].get<double>(), 0.33e-3 / 2.26, 1e-12);
  EXPECT_EQ(jb["steps"].get<long>(), 100);
  std::remove(path.c_str());
}

TEST(CliPlant, BadInputIsOneErrorLine) {
  const std::vector<std::string> ok = {"plant", "step", "--volts", "12"};
  auto with = [&](std::vector<std::string> extra) {
    auto v = ok;
    v.insert(v.end(), extra.begin(), extra.end());
    return v;
  };
  expect_one_error_line(with({"--duration", "-0.2"}), "--duration");
  expect_one_error_line(with({"--duration", "0"}), "--duration");
  // Bounded (issue 18): 1e9 s of plant time is a typo, not an experiment.
  expect_one_error_line(with({"--duration", "1e9"}),
                        "--duration = \"1e9\": above the range; expected 0..100 s");
  expect_one_error_line(with({"--duration", "0.2", "--config", "/nonexistent/m.toml"}),
                        "/nonexistent/m.toml");
  expect_one_error_line(with({"--duration", "0.2", "--axis", "w"}), "x, y");
  expect_one_error_line(with({"--duration", "0.2", "--dt", "3us"}), "--dt");
  expect_one_error_line(with({"--duration", "0.2", "--csv", "--json"}), "--csv");
  expect_one_error_line({"plant", "step", "--volts", "60", "--duration", "0.2"}, "supply_v = 48");
  expect_one_error_line({"plant", "step", "--volts", "x", "--duration", "0.2"}, "--volts");
  expect_one_error_line({"plant", "step", "--duration", "0.2"}, "--volts is required");
  expect_one_error_line({"plant"}, "subcommand");

  const std::string bad = ::testing::TempDir() + "mc_cli_plant_bad.toml";
  std::ofstream(bad) << "[machine]\nclock_hz = 12e6\nplant_dt_s = = 1\n";
  expect_one_error_line(with({"--duration", "0.2", "--config", bad}), bad + ":3:");
  std::ofstream(bad) << "[machine]\nclock_hz = 12e6\nplant_dt_s = 1e-6\nplant_dtt_s = 1\n";
  expect_one_error_line(with({"--duration", "0.2", "--config", bad}), bad + ":4: machine.plant_dtt_s");
  for (const auto& args : {with({"--duration", "-1"}), with({"--duration", "0.2", "--config", bad})}) {
    EXPECT_EQ(run(args).exit_code, 2);
  }
  std::remove(bad.c_str());
}

}  // namespace
