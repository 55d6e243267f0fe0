// motionctl's board commands against the virtual board, as a user runs
// them: gains survive between runs (--sim keeps one server), a CLI killed
// mid-move trips the board's watchdog and the drives go off, and bad
// arguments, an absent port and a board that does not answer each give one
// error line and a non-zero exit.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "vboard_server.hpp"

namespace mc::test {
namespace {

using nlohmann::json;

void expect_near_rel(double got, double want, const char* what) {
  EXPECT_NEAR(got, want, 1e-5 * std::fabs(want) + 1e-12) << what;
}

TEST(CliBoard, GainsRoundTripThroughTheVirtualBoard) {
  PrivateRuntimeDir rt;
  expect_ok({"--sim", "gains", "set", "--axis", "X", "--kp", "50", "--ki", "2000", "--kd", "0.2", "--tf",
             "300us", "--ts", "200us", "--limit", "20000"});
  // A second process: the same board.
  json g = run_json({"--sim", "gains", "show", "--axis", "x", "--json"});
  expect_near_rel(g["kp"], 50, "kp");
  expect_near_rel(g["ki"], 2000, "ki");
  expect_near_rel(g["kd"], 0.2, "kd");
  expect_near_rel(g["tf"], 300e-6, "tf");
  EXPECT_DOUBLE_EQ(g["ts"], 200e-6);
  EXPECT_EQ(g["out_limit"], 20000);

  // config save, change, load: back to what was saved.
  const std::string file = std::string(std::getenv("XDG_RUNTIME_DIR")) + "/gains.toml";
  expect_ok({"--sim", "config", "save", file});
  expect_ok({"--sim", "gains", "set", "--axis", "x", "--kp", "7", "--ki", "0"});
  EXPECT_NEAR(double(run_json({"--sim", "gains", "show", "--axis", "x", "--json"})["kp"]), 7, 1e-5);
  expect_ok({"--sim", "config", "load", file});
  json back = run_json({"--sim", "gains", "show", "--axis", "x", "--json"});
  EXPECT_EQ(back["words"], g["words"]);
  EXPECT_EQ(back["out_limit"], 20000);

  // The motion commands' --json: what was enabled, where the jog ended.
  EXPECT_EQ(run_json({"--sim", "enable", "--axis", "x", "--json"})["enabled"], json::array({"x"}));
  const json m = run_json({"--sim", "jog", "--axis", "x", "--distance", "0.1", "--feed", "600", "--json"});
  EXPECT_TRUE(m["moved"]);
  ASSERT_EQ(m["axes"].size(), 3u);  // the default machine: x, y and z
  EXPECT_EQ(m["axes"][0]["axis"], "x");
  EXPECT_NEAR(double(m["axes"][0]["position_mm"]), double(m["axes"][0]["command_mm"]), 0.05);
  const json d = run_json({"--sim", "disable", "--json"});
  EXPECT_EQ(d["disabled"], json::array({"x", "y", "z"}));
  EXPECT_TRUE(d["drives_off"]);
  EXPECT_TRUE(run_json({"--sim", "clear-fault", "--json"})["fault_word"].is_number());
}

TEST(CliBoard, KillingTheCliMidMoveTripsTheWatchdog) {
  PrivateRuntimeDir rt;
  Server sv(true);
  ASSERT_EQ(sv.pty().rfind("/dev/", 0), 0u) << sv.pty();
  const std::vector<std::string> port = {"--port", sv.pty()};
  auto with = [&](std::vector<std::string> a) {
    a.insert(a.begin(), port.begin(), port.end());
    return a;
  };
  expect_ok(with({"gains", "set", "--axis", "x", "--defaults"}));
  expect_ok(with({"enable", "--axis", "x"}));
  // 20 mm at 1200 mm/min: a second of board time. Killed as soon as it says
  // the move is under way (its first segments are on the board).
  int err[2];
  ASSERT_EQ(::pipe(err), 0);
  const pid_t jog = spawn(with({"jog", "--axis", "x", "--distance", "20", "--feed", "1200"}), -1, err[1]);
  ::close(err[1]);
  ASSERT_GT(jog, 0);
  std::string said;
  const bool moving = read_until(err[0], "note: moving", said);
  ::kill(jog, SIGKILL);
  ::waitpid(jog, nullptr, 0);
  ::close(err[0]);
  ASSERT_TRUE(moving) << "jog ended without starting the move:\n" << said;
  // Nothing feeds the watchdog now. The server says when its board is
  // dormant: the link quiet for longer than any watchdog period, the drives
  // off, the axes at rest. The bound is board time: the move itself is 1 s.
  ASSERT_TRUE(sv.wait_dormant(10.0)) << "the board did not come to rest within 10 s of board time";
  const json s = run_json(with({"status", "--json"}));
  EXPECT_EQ(s["faults"], json::array({"watchdog"}));
  EXPECT_FALSE(s["armed"]);
  EXPECT_FALSE(s["axes"][0]["drive"]) << "the drive must be off";
  EXPECT_TRUE(s["axes"][0]["enabled"]);
  const double mm = s["axes"][0]["position_mm"];
  EXPECT_GT(mm, 0.1) << "the jog had started";
  EXPECT_LT(mm, 19.5) << "the jog was cut short";
  EXPECT_TRUE(sv.stop()) << "sim serve exits cleanly on SIGTERM";
}

TEST(CliBoard, ErrorsAreOneLine) {
  PrivateRuntimeDir rt;
  expect_one_error_line({"status"}, "--port DEV");
  expect_one_error_line({"--port", "/dev/ttyUSB_motionctl_absent", "status"},
                        "no such port /dev/ttyUSB_motionctl_absent");
  expect_one_error_line({"--port", "/dev/null", "--sim", "status"}, "one of them");
  expect_one_error_line({"--port", "/dev/null", "gains", "set", "--axis", "w"}, "--axis");
  expect_one_error_line({"--port", "/dev/null", "jog", "--axis", "x"}, "--distance");
  // A PTY nobody serves: the board does not answer.
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const std::string slave = ::ptsname(master);
  const auto t0 = std::chrono::steady_clock::now();
  expect_one_error_line({"--port", slave, "status"}, "board at " + slave + " does not answer after");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(10));
  ::close(master);
}

}  // namespace
}  // namespace mc::test
