// motionctl gcode and run, as a user runs them: a program with an error is
// refused with FILE:LINE:COLUMN and exit 2 before the board is touched; a
// job runs on the virtual board without underruns, on time against its plan,
// within the acceleration limits, and ends at the program's end point;
// Ctrl-C stops it part-way with the drives off.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_run.hpp"
#include "vboard_server.hpp"

namespace mc::test {
namespace {

using nlohmann::json;

std::string write_program(const std::string& name, const std::string& text) {
  std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(CliRun, ProgramWithAnErrorIsRefusedWithItsPlace) {
  const std::string f = write_program("bad.nc", "G21 G90\nG1 X1 F100\nG1 X2 G2\nG0 X0\n");
  const Result r = run({"gcode", "check", f});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(f + ":3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("motionctl: error: 1 error(s) in " + f + "; nothing was run"), std::string::npos)
      << r.err;
}

TEST(CliRun, CheckSummarizesAndPathListsEveryMotion) {
  const std::string f =
      write_program("ok.nc", "G21 G90 G17\nG0 X10 Y0\nG1 Z-1 F300\nG2 X20 Y0 I5 J0 F600\nG4 P0.5\nM30\n");
  const Result c = run({"gcode", "check", f});
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.out.find("moves: 3 (1 arcs), 1 dwells"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("planned time"), std::string::npos) << c.out;
  const Result p = run({"gcode", "path", f, "--csv"});
  ASSERT_EQ(p.exit_code, 0) << p.err;
  EXPECT_EQ(p.out,
            "kind,x,y,z,feed_mm_min,cx,cy,cz,dir,plane\n"
            "rapid,10.0000,0.0000,0.0000,,,,,,\n"
            "feed,10.0000,0.0000,-1.0000,300.0000,,,,,\n"
            "arc,20.0000,0.0000,-1.0000,600.0000,15.0000,0.0000,-1.0000,cw,17\n"
            "dwell,20.0000,0.0000,-1.0000,,,,,,\n");
  // Outside the built-in machine's travel (X +-300 mm): the line and the axis.
  const std::string far = write_program("far.nc", "G0 X100\nG1 X400 F100\n");
  const Result t = run({"gcode", "check", far});
  EXPECT_EQ(t.exit_code, 2);
  EXPECT_NE(t.err.find(far + ":2: X (machine) = 400 mm"), std::string::npos) << t.err;
}

// A height map that is a plane, z = 0.01 x + 0.02 y (bilinear interpolation
// reproduces it exactly): gcode path --level adds it to every Z and splits
// the cut at the grid lines; a cut leaving the map is refused with its line.
TEST(CliRun, PathFollowsAHeightMapAndRefusesCutsOutsideIt) {
  const std::string map = write_program("plane.toml",
                                        "[map]\nx0_mm = 0\ny0_mm = 0\ndx_mm = 10\ndy_mm = 10\n"
                                        "heights_mm = [[0, 0.1, 0.2], [0.2, 0.3, 0.4], [0.4, 0.5, 0.6]]\n");
  const std::string f = write_program("lev.nc", "G21 G90\nG0 X1 Y1\nG1 Z-1 F300\nG1 X19 Y15 F600\n");
  const Result p = run({"gcode", "path", f, "--csv", "--level", map});
  ASSERT_EQ(p.exit_code, 0) << p.err;
  EXPECT_EQ(p.out,
            "kind,x,y,z,feed_mm_min,cx,cy,cz,dir,plane\n"
            "rapid,1.0000,1.0000,0.0300,,,,,,\n"
            "feed,1.0000,1.0000,-0.9700,300.0000,,,,,\n"
            "feed,10.0000,8.0000,-0.7400,600.0000,,,,,\n"  // x = 10, then y = 10
            "feed,12.5714,10.0000,-0.6743,600.0000,,,,,\n"
            "feed,19.0000,15.0000,-0.5100,600.0000,,,,,\n");
  const std::string out = write_program("out.nc", "G21 G90\nG0 X1 Y1\nG1 Z-1 F300\nG1 X25 F600\n");
  const Result r = run({"gcode", "check", out, "--level", map});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(out + ":4: cut at X25 Y1"), std::string::npos) << r.err;
}

// A square with rounded corners, 1 mm deep, after a dwell: about 2.3 s.
const char* kJob =
    "G21 G90 G17 G64\n"
    "G1 Z-0.5 F600\n"
    "G4 P0.3\n"  // a dwell: the queue behind it must not run dry when it ends
    "G1 X8 F3000\n"
    "G3 X10 Y2 I0 J2\n"
    "G1 Y8\n"
    "G3 X8 Y10 I-2 J0\n"
    "G1 X2\n"
    "G3 X0 Y8 I0 J-2\n"
    "G1 Y2\n"
    "G3 X2 Y0 I2 J0\n"
    "G1 X5 Y5 Z-0.2\n"
    "M30\n";

TEST(CliRun, AJobRunsOnTimeWithinItsLimitsAndEndsAtItsEndPoint) {
  PrivateRuntimeDir rt;
  // A bad program leaves a fresh board as it was: no gains written.
  const std::string bad = write_program("bad2.nc", "G1 X1 F100\nG1 Q\n");
  EXPECT_EQ(run({"--sim", "run", bad}).exit_code, 2);
  const Result g = run({"--sim", "gains", "show", "--axis", "x", "--json"});
  ASSERT_EQ(g.exit_code, 0) << g.err;
  EXPECT_EQ(json::parse(g.out)["kp"], 0.0);

  const std::string f = write_program("job.nc", kJob);
  const Result r = run({"--sim", "run", f, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_FALSE(j["stopped"]);
  EXPECT_EQ(j["underruns"], 0);
  EXPECT_NEAR(j["board_s"].get<double>() / j["planned_s"].get<double>(), 1.0, 0.03) << r.out;
  for (int k = 0; k < 3; ++k)
    EXPECT_LE(j["peak_accel_mm_s2"][k].get<double>(), 1.01 * j["accel_limit_mm_s2"][k].get<double>())
        << r.out;
  // The servo follows the path: tens of micrometres, not millimetres.
  EXPECT_LT(j["contour_max_um"].get<double>(), 100) << r.out;
  EXPECT_GT(j["samples"].get<int>(), 100);
  // Ends at X5 Y5 Z-0.2 (400 counts/mm), as the status shows.
  const Result s = run({"--sim", "status", "--json"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const json st = json::parse(s.out);
  const int want[3] = {2000, 2000, -80};
  for (int k = 0; k < 3; ++k) EXPECT_EQ(st["axes"][k]["command"], want[k]) << s.out;
}

TEST(CliRun, InterruptStopsAlongThePathWithTheDrivesOff) {
  PrivateRuntimeDir rt;
  const std::string f = write_program("long.nc", "G1 X200 F3000\nM30\n");  // 4 s
  int fds[2];
  // Close-on-exec: the background virtual board this run starts must not
  // inherit the write end, or the read below would wait for it to exit.
  ASSERT_EQ(::pipe2(fds, O_CLOEXEC), 0);
  const pid_t pid = spawn({"--sim", "run", f}, fds[1]);
  ::close(fds[1]);
  // The handler is in place once the "running" line is out.
  std::string first;
  for (char c; ::read(fds[0], &c, 1) == 1 && c != '\n';) first += c;
  ASSERT_NE(first.find("running"), std::string::npos) << first;
  ::kill(pid, SIGINT);
  std::string rest;
  for (char c; ::read(fds[0], &c, 1) == 1;) rest += c;
  ::close(fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << rest;
  EXPECT_NE(rest.find("stopped on request"), std::string::npos) << rest;
  const json st = json::parse(run({"--sim", "status", "--json"}).out);
  EXPECT_FALSE(st["armed"]) << st.dump();
  EXPECT_LT(st["axes"][0]["command"].get<int>(), 200 * 400) << "ran to the end despite Ctrl-C";
}

}  // namespace
}  // namespace mc::test
