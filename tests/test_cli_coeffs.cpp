// motionctl coeffs, run as a user runs it: the built binary, its stdout parsed
// as JSON, its stderr and exit code checked against the error contract (one
// line "motionctl: error: ...", non-zero exit).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_run.hpp"

namespace {

using mc::test::count_lines;
using mc::test::expect_one_error_line;
using mc::test::Result;
using mc::test::run;

void expect_near_rel(double got, double want, double rel = 1e-12) {
  EXPECT_NEAR(got, want, rel * std::fabs(want)) << "want " << want;
}

}  // namespace

TEST(CliCoeffs, JsonTfZeroHasSeedForm) {
  const Result r = run({"coeffs", "--kp", "2", "--ki", "30", "--kd", "0.05", "--ts", "100us", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["ts"].get<double>(), 1e-4);
  EXPECT_EQ(j["kp"].get<double>(), 2.0);
  EXPECT_EQ(j["ki"].get<double>(), 30.0);
  EXPECT_EQ(j["kd"].get<double>(), 0.05);
  EXPECT_EQ(j["tf"].get<double>(), 0.0);
  // KA = Kp + Ki Ts/2 + 2Kd/Ts, KB = Ki Ts - 4Kd/Ts, KC = -Kp + Ki Ts/2 + 2Kd/Ts.
  const double ka = 2 + 0.0015 + 1000, kb = 0.003 - 2000, kc = -2 + 0.0015 + 1000;
  ASSERT_TRUE(j.contains("seed_form"));
  expect_near_rel(j["seed_form"]["ka"], ka);
  expect_near_rel(j["seed_form"]["kb"], kb);
  expect_near_rel(j["seed_form"]["kc"], kc);
  const auto b = j["b"].get<std::vector<double>>();
  const auto a = j["a"].get<std::vector<double>>();
  ASSERT_EQ(b.size(), 3u);
  ASSERT_EQ(a.size(), 3u);
  expect_near_rel(b[0], ka);
  expect_near_rel(b[1], kb);
  expect_near_rel(b[2], kc);
  EXPECT_EQ(a, (std::vector<double>{1, 0, -1}));

  // kp = 2: mantissa 2^22 at shift 21 (2^23 would not fit), word 0x15400000.
  const auto& kp = j["fixed"]["kp"];
  EXPECT_EQ(kp["word"].get<uint32_t>(), 0x15400000u);
  EXPECT_EQ(kp["mantissa"].get<int>(), 1 << 22);
  EXPECT_EQ(kp["shift"].get<int>(), 21);
  EXPECT_EQ(kp["value"].get<double>(), 2.0);
  EXPECT_EQ(kp["design"].get<double>(), 2.0);
  EXPECT_EQ(kp["rel_error"].get<double>(), 0.0);
  // alpha = -1 with Tf = 0, exact: the most negative mantissa, fx = 15.
  const auto& kda = j["fixed"]["kd_a"];
  EXPECT_EQ(kda["mantissa"].get<int>(), -(1 << 23));
  EXPECT_EQ(kda["shift"].get<int>(), 38);
  EXPECT_EQ(kda["value"].get<double>(), -1.0);
  for (const char* name : {"kp", "ki", "kd_a", "kd_b", "kf1", "kf2"}) {
    const auto& f = j["fixed"][name];
    ASSERT_TRUE(f.is_object()) << name;
    const uint32_t word = f["word"];
    const int m = f["mantissa"], s = f["shift"];
    EXPECT_EQ(word, (uint32_t(s) << 24) | (uint32_t(m) & 0xFFFFFFu)) << name;
    const int fx = std::string(name) == "kd_a" ? 15 : 0;
    EXPECT_EQ(f["value"].get<double>(), std::ldexp(double(m), fx - s)) << name;
    EXPECT_LE(f["rel_error"].get<double>(), std::ldexp(1.0, -23)) << name;
  }
  expect_near_rel(j["fixed"]["ki"]["design"], 0.0015);
  expect_near_rel(j["fixed"]["kd_b"]["design"], 1000);
  EXPECT_EQ(j["fixed"]["kf1"]["word"].get<uint32_t>(), 0u);
  const auto fb = j["fixed_b"].get<std::vector<double>>();
  for (int i = 0; i < 3; ++i) expect_near_rel(fb[i], b[i], 1e-6);
  EXPECT_EQ(j["fixed_a"].get<std::vector<double>>(), (std::vector<double>{1, 0, -1}));
  EXPECT_LE(j["max_rel_error"].get<double>(), std::ldexp(1.0, -23));
}

TEST(CliCoeffs, JsonWithFilter) {
  const Result r =
      run({"coeffs", "--kp", "2", "--ki", "30", "--kd", "0.05", "--ts", "100us", "--tf", "0.0005", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j.contains("seed_form"));
  EXPECT_EQ(j["tf"].get<double>(), 5e-4);
  // alpha = (2Tf - Ts)/(2Tf + Ts) = 0.9/1.1, beta = 2Kd/(2Tf + Ts) = 0.1/1.1e-3.
  const double alpha = 9.0 / 11, beta = 1000.0 / 11, kit = 0.0015;
  const auto a = j["a"].get<std::vector<double>>();
  EXPECT_EQ(a[0], 1.0);
  expect_near_rel(a[1], -(1 + alpha));
  expect_near_rel(a[2], alpha);
  const auto b = j["b"].get<std::vector<double>>();
  expect_near_rel(b[0], 2 + kit + beta);
  expect_near_rel(b[1], -2 * (1 + alpha) + kit * (1 - alpha) - 2 * beta);
  expect_near_rel(b[2], 2 * alpha - kit * alpha + beta);
  expect_near_rel(j["fixed"]["kd_a"]["design"], alpha);
  expect_near_rel(j["fixed"]["kd_b"]["design"], beta);
  const auto fa = j["fixed_a"].get<std::vector<double>>();
  expect_near_rel(fa[2], alpha, std::ldexp(1.0, -23));
}

TEST(CliCoeffs, HumanTable) {
  Result r = run({"coeffs", "--kp", "2", "--ki", "30", "--kd", "0.05", "--ts", "100us"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  for (const char* s : {"seed form", "KA = 1002.0015", "KB = -1999.997", "KC = 998.0015", "0x15400000",
                        "kd_a", "pole at z = -1"}) {
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
  }
  r = run({"coeffs", "--kp", "2", "--ki", "30", "--kd", "0.05", "--ts", "100us", "--tf", "500us"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("seed form"), std::string::npos);
  EXPECT_EQ(r.out.find("pole at z = -1"), std::string::npos);
}

TEST(CliCoeffs, Defaults) {
  const Result r = run({"coeffs", "--kp", "1", "--ts", "1ms", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["ki"].get<double>(), 0.0);
  EXPECT_EQ(j["kd"].get<double>(), 0.0);
  EXPECT_EQ(j["tf"].get<double>(), 0.0);
  EXPECT_TRUE(j.contains("seed_form"));
}

TEST(CliCoeffs, LostCoefficientWarns) {
  const Result r = run({"coeffs", "--kp", "1", "--ts", "100us", "--ff2", "1e-30", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("motionctl: warning: kf2", 0), 0u) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["fixed"]["kf2"]["word"].get<uint32_t>(), 0u);
  EXPECT_EQ(j["fixed"]["kf2"]["rel_error"].get<double>(), 1.0);
  EXPECT_EQ(j["max_rel_error"].get<double>(), 1.0);
}

TEST(CliCoeffs, ErrorsAreOneLine) {
  const std::vector<std::string> good = {"coeffs", "--kp", "2", "--ki", "30", "--kd", "0.05"};
  const auto with = [&](std::vector<std::string> extra) {
    auto v = good;
    v.insert(v.end(), extra.begin(), extra.end());
    return v;
  };
  expect_one_error_line(with({"--ts", "-100us"}), "negative");
  expect_one_error_line(with({"--ts", "-1e-4"}), "--ts");
  expect_one_error_line(with({"--ts", "0"}), "--ts");
  expect_one_error_line(with({"--ts", "100usec"}), "\"100usec\"");
  expect_one_error_line(with({"--ts", "100us", "--tf", "-1"}), "--tf");
  expect_one_error_line(with({"--ts", "100us", "--bogus"}), "--bogus");
  expect_one_error_line(with({}), "--ts is required");
  expect_one_error_line({"coeffs", "--kp", "abc", "--ts", "100us"}, "--kp = \"abc\"");
  expect_one_error_line({"coeffs", "--kp", "-2", "--ts", "100us"}, "negative gains are rejected");
  expect_one_error_line({"coeffs", "--kp", "nan", "--ts", "100us"}, "--kp");
  expect_one_error_line({"coeffs", "--ts", "100us"}, "--kp is required");
  expect_one_error_line({"coeffs", "--kp", "1", "--kd", "100", "--ts", "1us"}, "kd_b");
  expect_one_error_line({"coeffs", "--kp"}, "--kp");
  expect_one_error_line({}, "no command given");
  expect_one_error_line({"frobnicate"}, "unknown command \"frobnicate\"");
}

TEST(CliCoeffs, HelpExitsZero) {
  Result r = run({"--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("coeffs"), std::string::npos) << r.out;
  r = run({"coeffs", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  for (const char* s : {"--kp", "--ki", "--kd", "--tf", "--ts", "--json"}) {
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
  }
}
