// motionctl interp line|arc, run as a user runs it: the CSV of visited points
// checked against the geometry, the summary and JSON against the formulas,
// and bad geometry against the one-line error contract.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"

namespace {

using mc::test::expect_one_error_line;
using mc::test::Result;
using mc::test::run;

// "k,x,y[,z]" rows after the header.
std::vector<std::vector<long long>> parse_csv(const std::string& out, const std::string& header) {
  std::istringstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, header);
  std::vector<std::vector<long long>> rows;
  while (std::getline(in, line)) {
    std::vector<long long> row;
    std::istringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) row.push_back(std::stoll(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(CliInterp, LineCsvIsEightConnectedAndExact) {
  const Result r = run({"interp", "line", "--from", "-5,7", "--to", "40,-13", "--csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = parse_csv(r.out, "k,x,y");
  ASSERT_EQ(rows.size(), 46u);  // N = max|d| = 45 iterations, plus the start
  for (size_t k = 0; k < rows.size(); ++k) {
    ASSERT_EQ(rows[k].size(), 3u);
    EXPECT_EQ(rows[k][0], (long long)k);
    if (k > 0) {
      EXPECT_EQ(rows[k][1] - rows[k - 1][1], 1);  // major axis: one count every iteration
      EXPECT_LE(std::llabs(rows[k][2] - rows[k - 1][2]), 1);
    }
  }
  EXPECT_EQ(rows.front(), (std::vector<long long>{0, -5, 7}));
  EXPECT_EQ(rows.back(), (std::vector<long long>{45, 40, -13}));
}

TEST(CliInterp, Line3dCsvHasZ) {
  const Result r = run({"interp", "line", "--from", "0,0,0", "--to", "3,-2,9", "--csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = parse_csv(r.out, "k,x,y,z");
  ASSERT_EQ(rows.size(), 10u);
  EXPECT_EQ(rows.back(), (std::vector<long long>{9, 3, -2, 9}));
}

TEST(CliInterp, ArcCsvIsFourConnectedOnTheCircle) {
  const Result r =
      run({"interp", "arc", "--from", "110,20", "--to", "10,-80", "--center", "10,20", "--cw", "--csv"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = parse_csv(r.out, "k,x,y");
  // Clockwise a quarter from (R, 0) to (0, -R) about the centre: 2R steps.
  ASSERT_EQ(rows.size(), 201u);
  for (size_t k = 1; k < rows.size(); ++k) {
    EXPECT_EQ(std::llabs(rows[k][1] - rows[k - 1][1]) + std::llabs(rows[k][2] - rows[k - 1][2]), 1);
    const double rr = std::hypot(double(rows[k][1] - 10), double(rows[k][2] - 20));
    EXPECT_LE(std::fabs(rr - 100), 1.0);
    EXPECT_LE(rows[k][2], rows[k - 1][2]);  // clockwise from 3 o'clock: y only falls
  }
  EXPECT_EQ(rows.back(), (std::vector<long long>{200, 10, -80}));
}

TEST(CliInterp, ArcSummaryAndJson) {
  Result r = run({"interp", "arc", "--from", "1000,0", "--to", "0,1000", "--center", "0,0", "--ccw"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("steps 2000"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("max radial deviation"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("exact"), std::string::npos) << r.out;
  r = run({"interp", "arc", "--from", "1000,0", "--to", "1000,0", "--center", "0,0", "--ccw", "--json",
           "--feed", "5000"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["steps"].get<long long>(), 8000);  // full circle: 4 quadrants of 2R
  EXPECT_EQ(j["steps_formula"].get<long long>(), 8000);
  EXPECT_EQ(j["quadrant_crossings"].get<int>(), 4);
  EXPECT_LE(j["max_radial_deviation_steps"].get<double>(), std::sqrt(0.5));
  EXPECT_NEAR(j["duration_s"].get<double>(), 2 * M_PI * 1000 / 5000, 1e-9);
  EXPECT_TRUE(j["end_exact"].get<bool>());
}

TEST(CliInterp, BadGeometryAndArgumentsAreOneLineErrors) {
  expect_one_error_line({"interp", "arc", "--from", "1000,0", "--to", "0,1002", "--center", "0,0", "--ccw"},
                        "off the circle");
  expect_one_error_line({"interp", "arc", "--from", "5,5", "--to", "5,5", "--center", "5,5", "--cw"},
                        "zero radius");
  expect_one_error_line({"interp", "arc", "--from", "1,0", "--to", "0,1", "--center", "0,0"}, "--cw, --ccw");
  expect_one_error_line(
      {"interp", "arc", "--from", "1,0", "--to", "0,1", "--center", "0,0", "--cw", "--ccw"});
  expect_one_error_line({"interp", "arc", "--from", "1,0,0", "--to", "0,1", "--center", "0,0", "--cw"},
                        "--from");
  expect_one_error_line({"interp", "line", "--from", "1,x", "--to", "3,4"}, "--from");
  expect_one_error_line({"interp", "line", "--from", "0,0", "--to", "3,4", "--feed", "-2"}, "--feed");
  expect_one_error_line({"interp", "line", "--from", "0,0"}, "--to");
  expect_one_error_line({"interp"});
}

}  // namespace
