// motionctl bench --quick and motionctl cosim, run as a user runs them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_run.hpp"

namespace mc::test {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(CliBench, QuickRunWritesReportCsvAndPlots) {
  const fs::path dir = fs::temp_directory_path() / ("mc_bench_" + std::to_string(::getpid()));
  const auto r = run({"bench", "--quick", "--jobs", "2", "--out", dir.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = read(dir / "results.csv");
  // Header plus 6 platforms x 4 scenarios x 2 policies, and the job on its
  // 4 default platforms without and with feed-forward.
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 6 * 4 * 2 + 4 * 2);
  EXPECT_EQ(csv.rfind("platform,scenario,policy,engine,ts_s,", 0), 0u);
  EXPECT_NE(csv.find("\nfpga-100us,job,tuned,twin,"), std::string::npos);
  const std::string md = read(dir / "report.md");
  EXPECT_NE(md.find("## circle, tuned gains"), std::string::npos);
  EXPECT_NE(md.find("| fpga-min |"), std::string::npos);
  EXPECT_NE(md.find("## job, tuned gains, without and with feed-forward"), std::string::npos);
  EXPECT_NE(md.find("| job, RMS contour error |"), std::string::npos);
  EXPECT_NE(md.find("The goal's case, the two-axis circle at 100 us on the twin: "), std::string::npos);
  EXPECT_NE(md.find("Run alone after the pool, 5 times (same gains"), std::string::npos);
  EXPECT_NE(md.find("the set-up (the machine, its trace and the model built before the kernel starts) took "),
            std::string::npos);
  // The RTL check's runs against the bare loop measured around each.
  EXPECT_NE(md.find("3 of 3 runs repeated on the Verilated RTL gave the same controller outputs"),
            std::string::npos);
  EXPECT_NE(md.find("measured in this run just before and just after each of them, each alone."),
            std::string::npos);
  EXPECT_EQ(md.find("| **yes** |"), std::string::npos) << "a job's queue ran dry";
  EXPECT_NE(r.out.find("## Reading"), std::string::npos);
  for (const char* png : {"following_step_same.png", "circle_xy_tuned.png", "contour_vs_ts.png",
                          "job_contour_vs_ts.png", "job_contour_path.png"})
    EXPECT_GT(fs::file_size(dir / "plots" / png), 1000u) << png;
  fs::remove_all(dir);
}

TEST(CliBench, CosimTraceWritesAWaveform) {
  const fs::path fst = fs::temp_directory_path() / ("mc_cosim_" + std::to_string(::getpid()) + ".fst");
  const auto r =
      run({"cosim", "--platform", "fpga-10us", "--scenario", "step", "--quick", "--trace", fst.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("tracking at the end"), std::string::npos) << r.out;
  EXPECT_GT(fs::file_size(fst), 10000u);
  fs::remove(fst);
}

TEST(CliBench, BadArgumentsGiveOneErrorLine) {
  expect_one_error_line({"bench", "--engine", "spice"}, "--engine");
  expect_one_error_line({"bench", "--platform", "fpga-1s", "--quick"}, "platform");
  expect_one_error_line({"cosim", "--scenario", "zigzag"}, "scenario");
  expect_one_error_line({"cosim", "--scenario", "job", "--job", "/nonexistent/job.nc"}, "--job");
  expect_one_error_line({"cosim", "--scenario", "job", "--feedforward", "lots"}, "--feedforward");
  expect_one_error_line({"cosim", "--platform", "host-10ms", "--trace", "x.fst"}, "--trace");
  expect_one_error_line({"bench", "--config", "/nonexistent/machine.toml"}, "machine.toml");
}

}  // namespace
}  // namespace mc::test
