// The checks commands run on their options before any work (issue 18): ranges,
// output paths, text inputs, the sample periods and gains the core runs, the
// closed-loop bandwidths a PID can be asked for, and the machine's travel,
// speeds and following-error limits. Each refusal is an InputError naming
// the input, with the bound it broke.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>

#include "host/base/checks.hpp"
#include "host/base/errors.hpp"
#include "host/control/pid_design.hpp"
#include "host/control/tuning.hpp"
#include "host/machine/limits.hpp"
#include "host/machine/machine_config.hpp"

namespace {

// The message of the mc::host::InputError f throws ("" and a failure when none).
template <class F>
std::string refusal(const F& f) {
  try {
    f();
  } catch (const mc::host::InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no mc::host::InputError";
  return "";
}

}  // namespace

namespace mc::host {
namespace {

#define EXPECT_HAS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << (text)

TEST(InputChecks, RequireInAcceptsTheClosedRangeOnly) {
  const Bounds b{-2, 3, "mm"};
  EXPECT_EQ(require_in(-2, b, "x"), -2);
  EXPECT_EQ(require_in(3, b, "x"), 3);
  EXPECT_HAS(refusal([&] { require_in(3.0000001, b, "--size", "3.0000001"); }),
             "--size = \"3.0000001\": above the range; expected -2..3 mm");
  EXPECT_HAS(refusal([&] { require_in(-7, b, "x", {}, "why"); }),
             "x = -7: below the range; expected -2..3 mm (why)");
  EXPECT_HAS(refusal([&] { require_in(std::nan(""), b, "x"); }), "not finite");
  EXPECT_HAS(refusal([&] { require_in(INFINITY, b, "x"); }), "not finite");
}

class TempDir {
 public:
  TempDir() {
    char t[] = "/tmp/mc-checks-XXXXXX";
    dir_ = ::mkdtemp(t);
  }
  ~TempDir() { std::system(("rm -rf '" + dir_ + "'").c_str()); }
  const std::string& path() const { return dir_; }

 private:
  std::string dir_;
};

TEST(InputChecks, WritableFileAndDirectory) {
  TempDir t;
  const std::string d = t.path();
  require_writable_file(d + "/new.csv", "--csv");  // may be created
  EXPECT_FALSE(std::ifstream(d + "/new.csv")) << "a check creates nothing";
  EXPECT_HAS(refusal([&] { require_writable_file(d + "/no/such/dir/x.csv", "--csv"); }),
             "--csv = \"" + d + "/no/such/dir/x.csv\": no directory \"" + d + "/no/such/dir\"");
  EXPECT_HAS(refusal([&] { require_writable_file(d, "--plot"); }), "a directory");
  EXPECT_HAS(refusal([&] { require_writable_file("", "--plot"); }), "a file path");
  require_writable_dir(d, "--out");
  require_writable_dir(d + "/a/b/c", "--out");  // created with its parents at the end
  std::ofstream(d + "/file") << "x";
  EXPECT_HAS(refusal([&] { require_writable_dir(d + "/file", "--out"); }), "a file");
  EXPECT_HAS(refusal([&] { require_writable_dir(d + "/file/sub", "--out"); }), "no directory");
  if (::geteuid() != 0) {  // root writes anywhere
    ::chmod(d.c_str(), 0500);
    EXPECT_HAS(refusal([&] { require_writable_file(d + "/x.csv", "--csv"); }), "cannot write in");
    ::chmod(d.c_str(), 0700);
  }
}

TEST(InputChecks, TextFileRefusesTheFirstBinaryByteWithItsOffset) {
  TempDir t;
  const std::string text = t.path() + "/h.csv", bin = t.path() + "/h.bin";
  std::ofstream(text) << "# period_s: 0.01\r\nlateness_ns,count\n\t1,2\n\xC2\xB5s\n";
  require_text_file(text, "--jitter");
  // 5000 bytes of text, then the first NUL of a binary file.
  std::string b(5000, 'a');
  b += '\0';
  b += std::string(100, '\x01');
  std::ofstream(bin, std::ios::binary) << b;
  EXPECT_HAS(refusal([&] { require_text_file(bin, "--jitter"); }),
             "--jitter = \"" + bin + "\": byte 0x00 at offset 5000 is not text; expected a text file");
  require_text_file(t.path() + "/absent", "--jitter");  // the reader names a missing file
}

TEST(InputChecks, QuoteKeepsMessagesOneShortReadableLine) {
  EXPECT_EQ(quote("a\"b\\c\n"), "\"a\\\"b\\\\c\\x0A\"");
  EXPECT_EQ(quote("100 \xC2\xB5s"), "\"100 \xC2\xB5s\"");  // UTF-8 stays
  EXPECT_EQ(quote("\xFF\xC2"), "\"\\xFF\\xC2\"");          // stray bytes do not
  // Random bytes: never a raw control or non-UTF-8 byte, never longer than
  // 200 bytes of value plus escapes and the length note.
  std::mt19937 rng(18);
  for (int i = 0; i < 200; ++i) {
    std::string s(size_t(rng() % 4000), '\0');
    for (char& c : s) c = char(rng());
    const std::string q = quote(s);
    for (const char c : q) EXPECT_GE(static_cast<unsigned char>(c), 0x20);
    EXPECT_LE(q.size(), 4 * 200 + 40u);
    if (s.size() > 200) {
      EXPECT_HAS(q, "... (" + std::to_string(s.size()) + " bytes)");
    }
  }
}

TEST(InputChecks, SamplePeriodsTheCoreRuns) {
  // 12 MHz, a 70-cycle sweep: 70 cycles .. 10 ms, whole cycles.
  EXPECT_EQ(core_ts_cycles(100e-6, 12e6, 70, "--ts"), 1200u);
  EXPECT_EQ(core_ts_cycles(70 / 12e6, 12e6, 70, "--ts"), 70u);
  EXPECT_EQ(core_ts_cycles(10e-3, 12e6, 70, "--ts"), 120000u);
  EXPECT_HAS(refusal([] { core_ts_cycles(1e-9, 12e6, 70, "--ts", "1ns"); }),
             "--ts = \"1ns\": too short; expected a sample period from 5.83333 us (70 clock cycles");
  EXPECT_HAS(refusal([] { core_ts_cycles(69 / 12e6, 12e6, 70, "--ts"); }), "too short");
  EXPECT_HAS(refusal([] { core_ts_cycles(10, 12e6, 70, "--ts", "10s"); }), "too long; expected");
  EXPECT_HAS(refusal([] { core_ts_cycles(1.00001e-4, 12e6, 70, "ts_s"); }),
             "a whole number of core clock cycles");
  EXPECT_HAS(refusal([] { core_ts_cycles(INFINITY, 12e6, 70, "ts_s"); }), "too long");
}

TEST(InputChecks, KpUpToOneCountAtFullScale) {
  check_core_kp(0, "--kp");
  check_core_kp(kMaxKp, "--kp");
  EXPECT_HAS(refusal([] { check_core_kp(8e6, "--kp", "8000000"); }), "--kp = \"8000000\": above the range");
  EXPECT_HAS(refusal([] { check_core_kp(-1, "--kp"); }), "below the range");
}

TEST(InputChecks, BandwidthBelowNyquist) {
  EXPECT_EQ(check_bandwidth(100, 1e-4, "--bandwidth"), 100);
  EXPECT_DOUBLE_EQ(max_bandwidth(1e-4), 31415.926535897932);
  EXPECT_HAS(refusal([] { check_bandwidth(1e12, 1e-4, "--bandwidth", "1e12"); }),
             "--bandwidth = \"1e12\": above the range; expected 0..31415.92654 rad/s");
  EXPECT_HAS(refusal([] { check_bandwidth(0, 1e-4, "--bandwidth"); }), "above 0");
}

}  // namespace
}  // namespace mc::host

namespace mc::machine {
namespace {

using mc::host::Vec3;

// The default machine: x, y and z at 400 000 counts/m; x and y travel
// -300..300 mm at 0.5 m/s, z -100..20 mm at 0.25 m/s; following error 1 mm
// = 400 counts.
const MachineConfig& m() {
  static const MachineConfig c = default_machine();
  return c;
}

TEST(MachineLimits, TravelIsCheckedOnEveryAxisOfTheTarget) {
  check_travel(m(), {0, 0, 0}, {120000, -120000, -40000}, {"target", "300,-300,-100"});  // the edges
  check_travel(m(), {0, 0, 0}, {0, 0, 8000}, {"target", "0,0,20"});
  EXPECT_HAS(
      refusal([] {
        check_travel(m(), {0, 0, 0}, {120001, 0, 0}, {"--distance", "300.0025"});
      }),
      "--distance = \"300.0025\": axis x would end at 300.0025 mm, from 0 mm; expected a move that ends "
      "within axis x's travel -300 mm..300 mm");
  EXPECT_HAS(
      refusal([] {
        check_travel(m(), {0, 0, 4000}, {0, 0, 8001}, {"--size", "10.0025"});
      }),
      "axis z would end at 20.0025 mm, from 10 mm; expected a move that ends within axis z's travel -100 "
      "mm..20 mm");
  EXPECT_HAS(refusal([] {
               check_travel(m(), {4000, 0, 0}, {4000, -400000000000, 0}, {"target", "10,-1e6"});
             }),
             "axis y would end at -1000000000 mm, from 0 mm");
}

TEST(MachineLimits, FeedKeepsEveryAxisWithinItsSpeed) {
  // One axis: its own limit, 0.5 m/s = 30000 mm/min.
  EXPECT_DOUBLE_EQ(max_feed_mm_min(m(), {0, 0, 0}, {4000, 0, 0}), 30000);
  // 45 degrees: each axis at 0.5 m/s is sqrt(2) * 0.5 m/s along the path.
  EXPECT_NEAR(max_feed_mm_min(m(), {0, 0, 0}, {4000, -4000, 0}), 30000 * std::sqrt(2.0), 1e-6);
  EXPECT_EQ(max_feed_mm_min(m(), {7, 7, 0}, {7, 7, 0}), 0);
  // x with z: z's 0.25 m/s binds; along (3, 0, 4) z moves 4/5 of the path.
  EXPECT_NEAR(max_feed_mm_min(m(), {0, 0, 0}, {1200, 0, 1600}), 15000 * 5 / 4.0, 1e-6);
  check_feed(m(), {0, 0, 0}, {4000, 0, 0}, 30000, {"--feed", "30000"});
  EXPECT_HAS(
      refusal([] {
        check_feed(m(), {0, 0, 0}, {4000, 0, 0}, 1e5, {"--feed", "1e5"});
      }),
      "--feed = \"1e5\": above the range; expected 0..30000 mm/min (max_speed_m_s of the moving axes: x 0.5 "
      "m/s)");
}

TEST(MachineLimits, FollowingErrorLimitsInCounts) {
  const auto c = ferr_counts(m());
  EXPECT_EQ(c[0], 400u);  // 1 mm at 400 counts/mm
  EXPECT_EQ(c[1], 400u);
  EXPECT_EQ(c[2], 400u);
  // A step needs its own size on top: 1 mm -> 800 counts.
  EXPECT_EQ(step_ferr_counts(m(), 0, 400, {"--size", "1"}), 800u);
  EXPECT_EQ(step_ferr_counts(m(), 0, -400, {"--size", "-1"}), 800u);
  EXPECT_EQ(step_ferr_counts(m(), 0, 65135, {"--size", ""}), 65535u);
  EXPECT_HAS(refusal([] {
               step_ferr_counts(m(), 0, 65136, {"--size", "162.84"});
             }),
             "--size = \"162.84\": expected a step of at most 162.8375 mm");
  EXPECT_HAS(refusal([] { step_ferr_counts(m(), 1, 400000, {"--size", "1000"}); }), "16-bit FERR");
}

}  // namespace
}  // namespace mc::machine
