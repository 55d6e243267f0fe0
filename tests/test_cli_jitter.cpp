// motionctl jitter, run as a user runs it: a short recording parses back
// through the sim's reader, bad arguments give one error line and exit 2, an
// unwritable --out leaves nothing behind, and Ctrl-C keeps the samples.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_run.hpp"
#include "sim/plant/jitter.hpp"

namespace {

namespace fs = std::filesystem;
using mc::test::expect_one_error_line;
using mc::test::run;

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("mc_cli_jitter_" + std::to_string(getpid()));
  fs::create_directories(d);
  return d / name;
}

TEST(CliJitter, ShortRecordingParsesBack) {
  const fs::path out = scratch("short.csv");
  const auto r = run({"jitter", "--period", "2ms", "--duration", "100ms", "--out", out.string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // stderr is not a TTY: no progress
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["samples"].get<int>(), 50);
  EXPECT_EQ(j["period_s"].get<double>(), 0.002);
  const auto& lat = j["lateness_us"];
  EXPECT_LE(lat["min"].get<double>(), lat["p50"].get<double>());
  EXPECT_LE(lat["p50"].get<double>(), lat["max"].get<double>());
  EXPECT_GE(lat["min"].get<double>(), 0.0);  // absolute deadlines: never early

  const mc::sim::JitterHistogram h = mc::sim::load_jitter(out.string());
  EXPECT_EQ(h.period_s, 0.002);
  EXPECT_EQ(h.total(), 50u);
  EXPECT_EQ(h.get("samples"), "50");
  EXPECT_EQ(h.get("interrupted"), "no");
  EXPECT_FALSE(h.get("kernel").empty());
  EXPECT_FALSE(h.get("cpu_model").empty());
  EXPECT_EQ(h.get("scheduling").rfind("SCHED_OTHER", 0), 0u);
  // Nothing but the file itself in the directory: the temporary was renamed.
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(out.parent_path())) ++files;
  EXPECT_EQ(files, 1);
  fs::remove_all(out.parent_path());
}

TEST(CliJitter, BadArgumentsAreOneErrorLine) {
  const std::string out = scratch("bad.csv").string();
  expect_one_error_line({"jitter", "--period", "10xs", "--out", out}, "--period");
  expect_one_error_line({"jitter", "--period", "0", "--out", out}, "--period");
  expect_one_error_line({"jitter", "--period", "10ms", "--duration", "1ms", "--out", out}, "--duration");
  expect_one_error_line({"jitter", "--period", "1us", "--duration", "1h", "--out", out}, "--duration");
  expect_one_error_line({"jitter", "--period", "10ms"}, "--out");
  expect_one_error_line({"jitter", "--fifo", "--priority", "0", "--out", out}, "--priority");
  EXPECT_EQ(run({"jitter", "--period", "10xs", "--out", out}).exit_code, 2);
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(scratch("").parent_path());
}

TEST(CliJitter, UnwritableOutNamesThePathAndLeavesNothing) {
  const fs::path dir = scratch("missing_dir");
  const std::string out = (dir / "x.csv").string();
  expect_one_error_line({"jitter", "--duration", "20ms", "--out", out}, out);
  EXPECT_EQ(run({"jitter", "--duration", "20ms", "--out", out}).exit_code, 2);
  EXPECT_FALSE(fs::exists(dir));
  fs::remove_all(dir.parent_path());
}

TEST(CliJitter, InterruptKeepsTheSamplesSoFar) {
  const fs::path out = scratch("int.csv");
  // stderr on a terminal, as a user at the keyboard has it: the recorder
  // shows its progress there once a second, and Ctrl-C comes after the
  // first report (its handler is in place and 200 samples are in).
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const int slave = ::open(::ptsname(master), O_RDWR | O_NOCTTY);
  ASSERT_GE(slave, 0);
  termios tio{};
  ::tcgetattr(slave, &tio);
  ::cfmakeraw(&tio);  // the bytes as written: no CR added before LF
  ::tcsetattr(slave, TCSANOW, &tio);
  const int devnull = ::open("/dev/null", O_WRONLY);
  const pid_t pid = mc::test::spawn({"jitter", "--period", "5ms", "--duration", "30s", "--out", out.string()},
                                    devnull, slave);
  ::close(devnull);
  ::close(slave);
  std::string said;
  const bool reported = mc::test::read_until(master, " samples", said);
  kill(pid, SIGINT);
  said += mc::test::read_all(master);
  ::close(master);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(reported) << said;
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal instead of stopping cleanly";
  EXPECT_EQ(WEXITSTATUS(status), 1);
  // The progress line is erased; then one error line.
  const size_t erased = said.rfind("\r\033[K");
  ASSERT_NE(erased, std::string::npos) << said;
  const std::string e = said.substr(erased + 4);
  EXPECT_EQ(mc::test::count_lines(e), 1) << e;
  EXPECT_EQ(e.rfind("motionctl: error: interrupted after", 0), 0u) << e;
  const mc::sim::JitterHistogram h = mc::sim::load_jitter(out.string());
  EXPECT_GE(h.total(), 200u) << "the first report came after 1 s of 5 ms periods";
  EXPECT_LT(h.total(), 6000u);
  EXPECT_EQ(h.get("interrupted").rfind("yes", 0), 0u);
  fs::remove_all(out.parent_path());
}

}  // namespace
