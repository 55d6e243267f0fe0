// The reference test: every program of tests/gcode/ goes through LinuxCNC's
// own interpreter (rs274, Debian package linuxcnc-uspace) and through ours;
// the motions must agree one by one (kind, end point, arc centre, plane,
// direction and turns) within 1e-4 mm in machine coordinates, and both must
// refuse the same programs.
//
// rs274 prints canonical calls in program units and program coordinates with
// four decimals. The offsets it applies are in its other calls
// (SET_G5X_OFFSET, SET_G92_OFFSET, USE_TOOL_LENGTH_OFFSET, USE_LENGTH_UNITS,
// SELECT_PLANE), so this file rebuilds machine millimetres from them.
//
// Corpus naming: err_*.ngc must be refused by both (at the same line);
// refused_*.ngc must be refused by us and accepted by rs274 (a documented
// difference, docs/gcode.md); every other program must be accepted by both.
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "host/gcode/interpreter.hpp"

namespace fs = std::filesystem;
using namespace mc::gcode;

namespace {

constexpr double kTolerance = 1e-4;  // mm

std::string corpus_dir() {
  return MC_GCODE_CORPUS_DIR;
}

std::vector<std::string> corpus() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(corpus_dir()))
    if (e.path().extension() == ".ngc") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A motion as both sides can say it: kind T(raverse) F(eed) A(rc) P(robe)
// D(well); arcs also carry the plane, the signed turns (LinuxCNC's
// "rotation": negative clockwise) and the centre in the plane's two axes.
struct Motion {
  char kind = 0;
  Vec3 end{};
  int plane = 17;
  int rotation = 0;
  double c1 = 0;
  double c2 = 0;
  double seconds = 0;
  int line = 0;  // ours only
};

std::string describe(const Motion& m) {
  std::ostringstream s;
  s.precision(6);
  s << std::fixed << m.kind;
  if (m.kind == 'D') {
    s << " " << m.seconds << " s";
    return s.str();
  }
  s << " end=(" << m.end[0] << "," << m.end[1] << "," << m.end[2] << ")";
  if (m.kind == 'A')
    s << " plane=G" << m.plane << " rot=" << m.rotation << " centre=(" << m.c1 << "," << m.c2 << ")";
  if (m.line > 0) s << " [line " << m.line << "]";
  return s.str();
}

int plane_code(Plane p) {
  return p == Plane::xy ? 17 : p == Plane::xz ? 18 : 19;
}
PlaneAxes axes_of(int plane) {
  return plane_axes(plane == 17 ? Plane::xy : plane == 18 ? Plane::xz : Plane::yz);
}

std::vector<Motion> our_motions(const std::vector<CanonCall>& calls) {
  std::vector<Motion> out;
  for (const CanonCall& c : calls) {
    Motion m;
    m.line = c.line;
    if (const auto* t = std::get_if<StraightTraverse>(&c.op)) {
      m.kind = 'T';
      m.end = t->end;
    } else if (const auto* f = std::get_if<StraightFeed>(&c.op)) {
      m.kind = 'F';
      m.end = f->end;
    } else if (const auto* p = std::get_if<StraightProbe>(&c.op)) {
      m.kind = 'P';
      m.end = p->end;
    } else if (const auto* a = std::get_if<ArcFeed>(&c.op)) {
      m.kind = 'A';
      m.end = a->end;
      m.plane = plane_code(a->plane);
      m.rotation = a->clockwise ? -a->turns : a->turns;
      const PlaneAxes ax = plane_axes(a->plane);
      m.c1 = a->centre.at(ax.first);
      m.c2 = a->centre.at(ax.second);
    } else if (const auto* d = std::get_if<Dwell>(&c.op)) {
      m.kind = 'D';
      m.seconds = d->seconds;
    } else {
      continue;
    }
    out.push_back(m);
  }
  return out;
}

std::vector<double> numbers(const std::string& args) {
  std::vector<double> v;
  std::string cleaned = args;
  std::replace(cleaned.begin(), cleaned.end(), ',', ' ');
  std::istringstream in(cleaned);
  std::string tok;
  while (in >> tok) v.push_back(std::strtod(tok.c_str(), nullptr));
  return v;
}

// rs274's canonical calls to machine-mm motions.
std::vector<Motion> reference_motions(const std::string& output) {
  static const std::regex call(R"(^\s*\d+\s+N\S*\s+([A-Z_0-9]+)\((.*)\)\s*$)");
  std::vector<Motion> out;
  double unit = 1.0;  // mm per program unit
  Vec3 g5x{};
  Vec3 g92{};
  Vec3 tool{};
  int plane = 17;
  auto machine = [&](const Vec3& prog) {
    Vec3 m{};
    for (int a = 0; a < 3; ++a) m.at(a) = prog.at(a) * unit + g5x.at(a) + g92.at(a) + tool.at(a);
    return m;
  };
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line)) {
    std::smatch mt;
    if (!std::regex_match(line, mt, call)) continue;
    const std::string name = mt[1];
    const std::string args = mt[2];
    if (name == "USE_LENGTH_UNITS") {
      unit = args.find("INCHES") != std::string::npos ? 25.4 : 1.0;
    } else if (name == "SELECT_PLANE") {
      plane = args.find("XZ") != std::string::npos ? 18 : args.find("YZ") != std::string::npos ? 19 : 17;
    } else if (name == "SET_G5X_OFFSET") {
      const auto v = numbers(args);  // index, x, y, z, ...
      for (int a = 0; a < 3; ++a) g5x.at(a) = v.at(a + 1) * unit;
    } else if (name == "SET_G92_OFFSET") {
      const auto v = numbers(args);
      for (int a = 0; a < 3; ++a) g92.at(a) = v.at(a) * unit;
    } else if (name == "USE_TOOL_LENGTH_OFFSET") {
      const auto v = numbers(args);  // x y z, a b c, u v w
      for (int a = 0; a < 3; ++a) tool.at(a) = v.at(a) * unit;
    } else if (name == "STRAIGHT_TRAVERSE" || name == "STRAIGHT_FEED" || name == "STRAIGHT_PROBE") {
      const auto v = numbers(args);
      Motion m;
      m.kind = name == "STRAIGHT_TRAVERSE" ? 'T' : name == "STRAIGHT_FEED" ? 'F' : 'P';
      m.end = machine({v.at(0), v.at(1), v.at(2)});
      out.push_back(m);
    } else if (name == "ARC_FEED") {
      // first_end, second_end, first_centre, second_centre, rotation, normal_end, ...
      const auto v = numbers(args);
      const PlaneAxes ax = axes_of(plane);
      Vec3 prog{};
      prog.at(ax.first) = v.at(0);
      prog.at(ax.second) = v.at(1);
      prog.at(ax.normal) = v.at(5);
      Motion m;
      m.kind = 'A';
      m.plane = plane;
      m.end = machine(prog);
      m.rotation = static_cast<int>(v.at(4));
      Vec3 centre{};
      centre.at(ax.first) = v.at(2);
      centre.at(ax.second) = v.at(3);
      const Vec3 cm = machine(centre);
      m.c1 = cm.at(ax.first);
      m.c2 = cm.at(ax.second);
      out.push_back(m);
    } else if (name == "DWELL") {
      Motion m;
      m.kind = 'D';
      m.seconds = numbers(args).at(0);
      out.push_back(m);
    }
  }
  return out;
}

// MC_RS274 names another rs274 (or a missing one, to see the failure).
std::string find_rs274() {
  if (const char* env = std::getenv("MC_RS274")) return access(env, X_OK) == 0 ? env : "";
  for (const char* p : {"/usr/bin/rs274", "/usr/local/bin/rs274"})
    if (access(p, X_OK) == 0) return p;
  return "";
}

struct RefRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// rs274 in a fresh directory: its own HOME and a minimal fresh .var file
// (coordinate system 1 selected; everything else defaults to zero).
RefRun run_rs274(const std::string& rs274, const fs::path& program) {
  std::string tmpl = (fs::temp_directory_path() / "mc_rs274_XXXXXX").string();
  std::vector<char> buf(tmpl.begin(), tmpl.end());
  buf.push_back('\0');
  const char* dir = mkdtemp(buf.data());
  RefRun r;
  if (dir == nullptr) return r;
  const fs::path d(dir);
  fs::create_directory(d / "home");
  std::ofstream(d / "fresh.var") << "5220\t1.000000\n";
  const std::string cmd = "cd '" + d.string() + "' && HOME='" + (d / "home").string() + "' '" + rs274 +
                          "' -g -n 2 -v fresh.var '" + fs::absolute(program).string() +
                          "' > out.txt 2> err.txt < /dev/null";
  const int status = std::system(cmd.c_str());
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(d / "out.txt");
  r.err = read_text(d / "err.txt");
  fs::remove_all(d);
  return r;
}

// The line rs274 names after its error message (the last line of stderr).
std::string reference_error_line(const std::string& err) {
  std::istringstream in(err);
  std::string line;
  std::string last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) out.push_back(trim(line));
  return out;
}

bool near(double a, double b) {
  return std::fabs(a - b) <= kTolerance;
}

class GcodeReference : public ::testing::TestWithParam<std::string> {};

TEST_P(GcodeReference, AgreesWithLinuxCnc) {
  const std::string rs274 = find_rs274();
  ASSERT_FALSE(rs274.empty())
      << "rs274 (LinuxCNC's interpreter, Debian package linuxcnc-uspace) is not installed: "
         "run scripts/deps.sh";
  const std::string name = GetParam();
  const fs::path program = fs::path(corpus_dir()) / (name + ".ngc");
  const RefRun ref = run_rs274(rs274, program);
  ASSERT_TRUE(ref.exit_code == 0 || ref.exit_code == 1)
      << "rs274 failed to run: exit " << ref.exit_code << "\n"
      << ref.err;
  const ProgramResult ours = interpret_file(program.string());
  const bool ref_ok = ref.exit_code == 0;

  if (name.rfind("err_", 0) == 0) {
    ASSERT_FALSE(ref_ok) << "rs274 accepted a program that must be refused";
    ASSERT_FALSE(ours.ok()) << "we accepted a program that rs274 refuses: " << reference_error_line(ref.err);
    // Same line: rs274 prints the offending line's text.
    const auto text = lines_of(read_text(program));
    const Error& e = ours.errors.front();
    ASSERT_GE(e.line, 1);
    EXPECT_EQ(text.at(static_cast<size_t>(e.line - 1)), trim(reference_error_line(ref.err)))
        << "ours: " << e.format() << "\nrs274: " << ref.err;
    return;
  }
  if (name.rfind("refused_", 0) == 0) {
    EXPECT_TRUE(ref_ok) << "rs274 refuses it too; rename to err_: " << ref.err;
    ASSERT_FALSE(ours.ok()) << "we must refuse this (documented difference)";
    return;
  }
  ASSERT_TRUE(ref_ok) << "rs274 refused: " << ref.err;
  ASSERT_TRUE(ours.ok()) << ours.errors.front().format();

  const std::vector<Motion> want = reference_motions(ref.out);
  const std::vector<Motion> got = our_motions(ours.calls);
  ASSERT_FALSE(want.empty()) << "rs274 produced no motion";
  const size_t n = std::min(want.size(), got.size());
  for (size_t i = 0; i < n; ++i) {
    const Motion& w = want[i];
    const Motion& o = got[i];
    const std::string where =
        "motion " + std::to_string(i + 1) + "\n  rs274: " + describe(w) + "\n  ours:  " + describe(o);
    ASSERT_EQ(w.kind, o.kind) << where;
    if (w.kind == 'D') {
      ASSERT_TRUE(near(w.seconds, o.seconds)) << where;
      continue;
    }
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(near(w.end.at(a), o.end.at(a))) << where;
    if (w.kind == 'A') {
      ASSERT_EQ(w.plane, o.plane) << where;
      ASSERT_EQ(w.rotation, o.rotation) << where;
      ASSERT_TRUE(near(w.c1, o.c1) && near(w.c2, o.c2)) << where;
    }
  }
  ASSERT_EQ(want.size(), got.size()) << "motion count differs";
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s)
    if (std::isalnum(static_cast<unsigned char>(c)) == 0) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Corpus, GcodeReference, ::testing::ValuesIn(corpus()), test_name);

// The corpus must use every word the dialect supports, and be large enough.
TEST(GcodeReferenceCorpus, UsesEverySupportedWord) {
  const std::vector<std::string> names = corpus();
  int accepted = 0;
  std::string all;
  for (const std::string& n : names) {
    if (n.rfind("err_", 0) != 0 && n.rfind("refused_", 0) != 0) ++accepted;
    std::string text = read_text(fs::path(corpus_dir()) / (n + ".ngc"));
    for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    all += "\n" + text;
  }
  EXPECT_GE(names.size(), 32U);
  EXPECT_GE(accepted, 30);
  // Words as they are written; the regex makes G1 not match G10 and G38.2 not G38.
  const std::vector<std::string> words = {
      "G0",    "G1",    "G2",    "G3",    "G4",    "G10",   "G17",   "G18",   "G19",   "G20",
      "G21",   "G28",   "G28.1", "G30",   "G30.1", "G38.2", "G38.3", "G38.4", "G38.5", "G40",
      "G43.1", "G49",   "G53",   "G54",   "G55",   "G56",   "G57",   "G58",   "G59",   "G59.1",
      "G59.2", "G59.3", "G61",   "G61.1", "G64",   "G73",   "G80",   "G81",   "G82",   "G83",
      "G90",   "G90.1", "G91",   "G91.1", "G92",   "G92.1", "G92.2", "G92.3", "G93",   "G94",
      "G98",   "G99",   "M0",    "M1",    "M2",    "M30",   "M3",    "M4",    "M5",    "M6",
      "M7",    "M8",    "M9",    "L2",    "L20",   "F",     "N",     "S",     "T",     "I",
      "J",     "K",     "R",     "P",     "Q",     "(",     ";",     "/",     "%"};
  for (const std::string& w : words) {
    std::string pattern;
    for (char c : w)
      pattern +=
          (std::isalnum(static_cast<unsigned char>(c)) != 0) ? std::string(1, c) : "\\" + std::string(1, c);
    if (std::isdigit(static_cast<unsigned char>(w.back())) != 0) pattern += "(?![0-9.])";
    if (std::isalpha(static_cast<unsigned char>(w.back())) != 0) pattern += "(?=[-+.0-9])";
    // G0 is also written G00, M3 as M03.
    if (w.size() >= 2 && (w[0] == 'G' || w[0] == 'M') && std::isdigit(static_cast<unsigned char>(w[1])) != 0)
      pattern = std::string(1, w[0]) + "0*" + pattern.substr(1);
    EXPECT_TRUE(std::regex_search(all, std::regex(pattern))) << "no corpus program uses " << w;
  }
}

}  // namespace
