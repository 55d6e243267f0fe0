// Bad input refused before anything is written or run (issue 18), as a user
// meets it: motionctl on the virtual board gives one error line for each bad
// option, and the board reads back exactly as before (gains words, Ts, the
// following-error limit, every axis' command, enable and position). The
// following-error limit of the machine TOML is armed on the board, so a
// runaway trips a fault; the virtual board's server answers SIGTERM even at
// the fastest clock a machine file may give, and `sim stop` says the truth.
//
// Every wait is on an event: a command's exit, the server's first line, a
// process' exit status.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "vboard_server.hpp"

namespace mc::test {
namespace {

using nlohmann::json;

std::vector<std::string> sim(std::vector<std::string> args) {
  args.insert(args.begin(), "--sim");
  return args;
}

// What a refused command must leave as it was. Not the drives' arming or a
// watchdog fault: the watchdog turns the drives off 100 ms of board time after
// any command, refused or not, by design.
json board_state() {
  const json s = run_json(sim({"status", "--json"}));
  json out;
  out["ts_cycles"] = s["ts_cycles"];
  json faults = json::array();
  for (const auto& f : s["faults"])
    if (f != "watchdog") faults.push_back(f);
  out["faults"] = faults;
  // Positions of the horizontal axes only: z's carriage sinks under its
  // weight whenever the watchdog has turned its drive off.
  for (const auto& a : s["axes"])
    out["axes"].push_back({{"command", a["command"]},
                           {"position", a["axis"] == "z" ? json() : a["position"]},
                           {"enabled", a["enabled"]}});
  for (const char* axis : {"x", "y", "z"}) {
    const json g = run_json(sim({"gains", "show", "--axis", axis, "--json"}));
    out["gains"][axis] = {{"words", g["words"]},
                          {"ts", g["ts"]},
                          {"out_limit", g["out_limit"]},
                          {"ferr", g["following_error_limit_counts"]}};
  }
  return out;
}

std::string temp_dir() {
  return std::getenv("XDG_RUNTIME_DIR");
}

// configs/default.toml with `from` replaced by `to`, written to `name` in the
// private runtime directory; returns its path.
std::string machine_file_with(const std::string& from, const std::string& to, const std::string& name) {
  std::ifstream in(std::string(MC_SOURCE_DIR) + "/configs/default.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  s.replace(s.find(from), from.size(), to);
  const std::string path = temp_dir() + "/" + name;
  std::ofstream(path) << s;
  return path;
}

// Where motionctl registers the server --sim uses (board_cli.hpp).
std::string state_file() {
  const std::string dir = temp_dir() + "/motionctl";
  ::mkdir(dir.c_str(), 0700);
  return dir + "/sim.state";
}

TEST(CliRefusals, EachBadInputIsRefusedAndTheBoardIsUnchanged) {
  PrivateRuntimeDir rt;
  expect_ok(sim({"gains", "set", "--axis", "x", "--defaults"}));
  expect_ok(sim({"gains", "set", "--axis", "y", "--defaults"}));
  expect_ok(sim({"gains", "set", "--axis", "z", "--defaults"}));
  expect_ok(sim({"enable"}));
  const json before = board_state();
  ASSERT_EQ(before["gains"]["x"]["ferr"], 400) << "1 mm of the default machine at 400 counts/mm";
  ASSERT_EQ(before["gains"]["z"]["ferr"], 400);
  const std::string dir = temp_dir();
  const struct {
    std::vector<std::string> args;
    std::string mentions;
  } refusals[] = {
      // Ts and gains the core cannot run: nothing written (the Ts of 1 ns used
      // to leave Ts at 70 cycles after "PID 0xF0 reads back 0x46").
      {{"gains", "set", "--axis", "x", "--ts", "1ns"}, "--ts = \"1ns\": too short"},
      {{"gains", "set", "--axis", "x", "--ts", "10s"}, "--ts = \"10s\": too long"},
      {{"gains", "set", "--axis", "x", "--kp", "8000000"}, "--kp = \"8000000\": above the range"},
      {{"gains", "set", "--axis", "y", "--ki", "1e30"}, "too large for the coefficient word"},
      // Travel and speed, before the drives are armed.
      {{"jog", "--axis", "x", "--distance", "1e9", "--feed", "600"}, "axis x would end at 1000000000 mm"},
      {{"jog", "--axis", "x", "--distance", "-300.01", "--feed", "600"}, "within axis x's travel"},
      {{"jog", "--axis", "z", "--distance", "200", "--feed", "600"}, "within axis z's travel -100 mm..20 mm"},
      {{"move", "1e9,0", "--feed", "600"}, "within axis x's travel"},
      {{"move", "0,-1e300", "--feed", "600"}, "within axis y's travel"},
      {{"jog", "--axis", "x", "--distance", "1", "--feed", "1e5"}, "--feed = \"1e5\": above the range"},
      {{"jog", "--axis", "z", "--distance", "-1", "--feed", "15001"},
       "max_speed_m_s of the moving axes: z 0.25"},
      {{"move", "10,10", "--feed", "42427"}, "0..42426.40687 mm/min"},
      {{"hostloop", "--axis", "x", "--distance", "1e9"}, "within axis x's travel"},
      // A step: within FERR's 16 bits with its margin, and within travel.
      {{"step", "--axis", "x", "--size", "1000"}, "16-bit FERR"},
      {{"step", "--axis", "z", "--size", "50"}, "within axis z's travel"},
      // Outputs checked before the capture.
      {{"step", "--axis", "x", "--csv", dir + "/no/such/dir/s.csv"}, "--csv"},
      {{"step", "--axis", "x", "--plot", dir}, "--plot"},
      {{"config", "save", dir + "/no/such/dir/gains.toml"}, "FILE"},
      // A bandwidth no PID sampled at 100 us reaches, before the experiment.
      {{"tune", "--axis", "x", "--bandwidth", "1e12"}, "Nyquist"},
      // An empty axis name is not "every axis".
      {{"level", "probe", "--area", "5,5,1", "-o", dir + "/m.toml"},
       "--area = \"5,5,1\": expected X0,Y0,X1,Y1"},
      {{"level", "probe", "--area", "5,5,1,1", "-o", dir + "/m.toml"}, "X0 < X1 and Y0 < Y1"},
      {{"level", "probe", "--area", "5,5,10,10", "--grid", "1x3", "-o", dir + "/m.toml"}, "--grid = \"1x3\""},
      {{"level", "probe", "--area", "5,5,500,10", "-o", dir + "/m.toml"}, "within axis x's travel"},
      {{"level", "probe", "--area", "5,5,10,10", "--feed", "0", "-o", dir + "/m.toml"}, "--feed = 0"},
      {{"level", "probe", "--area", "5,5,10,10", "-o", dir + "/no/such/dir/m.toml"}, "-o"},
      {{"disable", "--axis", ""}, "--axis = \"\""},
      {{"enable", "--axis", ""}, "--axis = \"\""},
  };
  for (const auto& r : refusals) {
    expect_one_error_line(sim(r.args), r.mentions);
    EXPECT_EQ(board_state(), before) << r.args[0] << " " << r.args[1] << " " << r.mentions;
  }
  EXPECT_FALSE(std::ifstream(dir + "/no/such/dir/s.csv"));
}

TEST(CliRefusals, FollowingErrorLimitIsArmedFromTheMachine) {
  PrivateRuntimeDir rt;
  expect_ok(sim({"gains", "set", "--axis", "x", "--defaults"}));
  expect_ok(sim({"enable", "--axis", "x"}));
  // A 2 mm step is 800 counts of following error the moment it is commanded:
  // the step widens the limit by its own size and puts it back.
  const json st = run_json(sim({"step", "--axis", "x", "--size", "2", "--json"}));
  EXPECT_EQ(st["faults"], "none");
  EXPECT_LT(double(st["metrics"]["overshoot_pct"]), 50);
  EXPECT_EQ(run_json(sim({"gains", "show", "--axis", "x", "--json"}))["following_error_limit_counts"], 400);
  // z's PID is off: nothing holds its carriage, which sinks under its weight,
  // so its limit is off too (a following error there is no runaway).
  EXPECT_EQ(run_json(sim({"gains", "show", "--axis", "z", "--json"}))["following_error_limit_counts"], 0);
  // A runaway: a loop too weak to follow 50 mm at 20 m/min. The fault stops
  // it at the limit instead of letting the error grow.
  expect_ok(sim({"gains", "set", "--axis", "x", "--kp", "0.05", "--ki", "0", "--kd", "0"}));
  const Result jog = run(sim({"jog", "--axis", "x", "--distance", "50", "--feed", "20000"}));
  EXPECT_EQ(jog.exit_code, 1) << jog.out << jog.err;
  EXPECT_NE(jog.err.find("motion stopped by a fault: following error x"), std::string::npos) << jog.err;
  const json s = run_json(sim({"status", "--json"}));
  EXPECT_NE(std::find(s["faults"].begin(), s["faults"].end(), "following error x"), s["faults"].end()) << s;
  EXPECT_FALSE(s["armed"]);
  const int err = s["axes"][0]["command"].get<int>() - s["axes"][0]["position"].get<int>();
  EXPECT_GT(err, 400) << "the trip is past the limit";
  EXPECT_LT(err, 2 * 400) << "and the command stopped near it, not 50 mm on";
}

TEST(CliRefusals, BadMachineFileIsReportedBeforeAServerStarts) {
  PrivateRuntimeDir rt;
  const std::string bad = machine_file_with("clock_hz = 12e6", "clock_hz = 1e15", "bad.toml");
  expect_one_error_line(sim({"--config", bad, "status"}), bad + ":");
  expect_one_error_line(sim({"--config", bad, "status"}), "machine.clock_hz = 1e+15: above the range");
  EXPECT_FALSE(std::ifstream(state_file())) << "no server was started";
  // sim serve refuses it too, with the same line.
  expect_one_error_line({"sim", "serve", "--config", bad}, "machine.clock_hz");
}

TEST(CliRefusals, BinaryJitterFileIsRefusedAsText) {
  PrivateRuntimeDir rt;
  const std::string bin = temp_dir() + "/jitter.bin";
  std::string bytes(3600, '\0');
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = char(i * 37 + 11);
  std::ofstream(bin, std::ios::binary) << bytes;
  const Result r = run({"cosim", "--quick", "--jitter", bin});
  expect_one_error_line({"cosim", "--quick", "--jitter", bin}, "byte 0x0B at offset 0 is not text");
  EXPECT_LT(r.err.size(), 300u) << "a line, not the file";
}

// `sim serve` at the fastest clock a machine file may give: it starts
// (prints its PTY) and exits cleanly on SIGTERM.
TEST(CliRefusals, SimServeAnswersSigtermAtTheFastestClock) {
  PrivateRuntimeDir rt;
  const std::string fast = machine_file_with("clock_hz = 12e6", "clock_hz = 160e6", "fast.toml");
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = spawn({"--config", fast, "sim", "serve", "--fast", "--no-register"}, fds[1]);
  ::close(fds[1]);
  std::string pty;
  char c;
  while (::read(fds[0], &c, 1) == 1 && c != '\n') pty += c;
  ::close(fds[0]);
  EXPECT_EQ(pty.rfind("/dev/", 0), 0u) << pty;
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  int st = 0;
  ASSERT_EQ(::waitpid(pid, &st, 0), pid);
  EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << "status " << st;
}

// A registered server that ignores SIGTERM: `sim stop` kills it, says so,
// and forgets it; one that stops is reported as stopped.
TEST(CliRefusals, SimStopSaysWhatHappened) {
  PrivateRuntimeDir rt;
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t deaf = ::fork();
  ASSERT_GE(deaf, 0);
  if (deaf == 0) {
    ::signal(SIGTERM, SIG_IGN);
    const char c = 'r';
    if (::write(ready[1], &c, 1) != 1) ::_exit(1);
    for (;;) ::pause();
  }
  ::close(ready[1]);
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1) << "the child ignores SIGTERM from here on";
  ::close(ready[0]);
  std::ofstream(state_file()) << "/dev/null\n" << deaf << "\n\n";
  ASSERT_TRUE(std::ifstream(state_file()));
  const Result killed = run({"sim", "stop"});
  EXPECT_EQ(killed.exit_code, 0) << killed.err;
  EXPECT_NE(killed.out.find("killed the virtual board (pid " + std::to_string(deaf)), std::string::npos)
      << killed.out;
  EXPECT_NE(killed.out.find("SIGKILL"), std::string::npos) << killed.out;
  int st = 0;
  // Dead already (a zombie until reaped here); if not, the test ends it.
  const pid_t reaped = ::waitpid(deaf, &st, WNOHANG);
  EXPECT_EQ(reaped, deaf) << "sim stop left the process running";
  if (reaped != deaf) {
    ::kill(deaf, SIGKILL);
    ::waitpid(deaf, &st, 0);
  }
  EXPECT_TRUE(WIFSIGNALED(st) && WTERMSIG(st) == SIGKILL);
  EXPECT_FALSE(std::ifstream(state_file())) << "unregistered";

  expect_ok(sim({"status"}));  // starts a server in the background
  const Result stopped = run({"sim", "stop"});
  EXPECT_EQ(stopped.exit_code, 0) << stopped.err;
  EXPECT_EQ(stopped.out.rfind("stopped the virtual board (pid ", 0), 0u) << stopped.out;
  EXPECT_EQ(run({"sim", "stop"}).out.rfind("no virtual board registered", 0), 0u);
}

}  // namespace
}  // namespace mc::test
