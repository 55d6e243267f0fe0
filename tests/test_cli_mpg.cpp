// motionctl mpg and sim wheel as an operator uses them on the virtual
// board: the handwheel on X at x10, five detents turned on the running
// server: what is pending and what the command moved add up to 50
// counts, and once the drives are held the board jogs what was pending;
// bad axes, steps and detents, and a wheel with no server, each one error
// line. The server runs free; `sim wheel` returns when the turn is done in
// board time, so nothing here waits on the wall clock for the board.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "hls/board_regs.hpp"
#include "vboard_server.hpp"

namespace mc::test {
namespace {

using nlohmann::json;

TEST(CliMpg, FiveDetentsAtX10MoveFiftyCounts) {
  PrivateRuntimeDir rt;
  Server sv;
  const auto with = [&](std::vector<std::string> a) {
    a.insert(a.begin(), {"--port", sv.pty()});
    return a;
  };
  expect_ok(with({"gains", "set", "--axis", "x", "--defaults"}));
  expect_ok(with({"enable", "--axis", "x"}));

  const json set = run_json(with({"mpg", "--axis", "x", "--step", "10", "--json"}));
  EXPECT_EQ(set["on"], true);
  EXPECT_EQ(set["axis"], "x");
  EXPECT_EQ(set["step_counts"], 10);
  EXPECT_DOUBLE_EQ(double(set["mm_per_detent"]), 0.025);  // 400 counts/mm on the default machine
  EXPECT_EQ(set["pending_counts"], 0);
  const int64_t cmd0 = run_json(with({"status", "--json"}))["axes"][0]["command"];

  // The board counts the detents; whether it has jogged them yet depends
  // on whether enable's drives are still armed (the watchdog's 100 ms of
  // board time), but what is pending and what moved add up.
  const Result w = run(with({"sim", "wheel", "--detents", "5", "--seconds", "0.05"}));
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_NE(w.out.find("5 detents"), std::string::npos) << w.out;
  const json turned = run_json(with({"status", "--json"}));
  EXPECT_EQ(turned["handwheel"]["setting"], "x10");
  EXPECT_EQ(int64_t(turned["handwheel"]["pending_counts"]) + int64_t(turned["axes"][0]["command"]) - cmd0,
            50);

  // Held armed, the board jogs what is pending from where arming put the
  // command: the axis's position when the drives were off (it may have
  // drifted a count or two from the old command), else the command.
  const json held = run_json(with({"mpg", "--seconds", "0.1", "--json"}));
  EXPECT_EQ(int64_t(held["command"]) - int64_t(held["start_command"]), int64_t(held["pending_counts"]));
  EXPECT_EQ(held["pending_counts"], turned["handwheel"]["pending_counts"]);
  const json st = run_json(with({"status", "--json"}));
  const json& x = st["axes"][0];
  EXPECT_EQ(x["command"], held["command"]);
  EXPECT_LE(std::llabs(int64_t(x["position"]) - int64_t(x["command"])), 2);
  // The jog tripped nothing. The watchdog may have latched since: `mpg`
  // leaves the drives to it, and how much board time passes before this
  // status's first frame depends on how long its process takes to start
  // (wall time; a sanitizer build takes long enough).
  EXPECT_EQ(uint32_t(st["fault"]) & ~(1u << mc::board::bits::F_WDOG), 0u) << st.dump();
  EXPECT_EQ(run_json(with({"mpg", "--json"}))["pending_counts"], 0);

  // --step alone keeps the axis; --off turns it off.
  const json x100 = run_json(with({"mpg", "--step", "100", "--json"}));
  EXPECT_EQ(x100["axis"], "x");
  EXPECT_DOUBLE_EQ(double(x100["mm_per_detent"]), 0.25);
  EXPECT_EQ(run_json(with({"mpg", "--off", "--json"}))["on"], false);

  expect_one_error_line(with({"mpg", "--axis", "w", "--step", "10"}), "--axis");
  expect_one_error_line(with({"mpg", "--axis", "x", "--step", "5"}), "--step");
  expect_one_error_line(with({"mpg", "--off", "--axis", "x"}), "--off");
  expect_one_error_line(with({"mpg", "--seconds", "1"}), "--axis");  // the handwheel is off
  expect_one_error_line(with({"sim", "wheel", "--detents", "1.5"}), "--detents");
  expect_one_error_line(with({"sim", "wheel", "--detents", "1", "--seconds", "2h"}), "--seconds");
}

TEST(CliMpg, WheelWithoutAServerSaysSo) {
  PrivateRuntimeDir rt;
  expect_one_error_line({"sim", "wheel", "--detents", "1"}, "motionctl sim serve");
  expect_one_error_line({"--port", "/dev/pts/999999", "sim", "wheel", "--detents", "1"}, "/dev/pts/999999");
}

}  // namespace
}  // namespace mc::test
