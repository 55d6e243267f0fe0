// Properties of the interpreter over random programs (fixed seeds):
//  - a G91 program reaches the same end points as its G90 twin;
//  - an R arc ends exactly on its programmed point, and its centre is at |R|
//    from both ends, on the side the sign of R says;
//  - work offsets are pure translations, canned cycles included;
//  - a file and the same lines fed one by one to an Interpreter agree.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "gcode_helpers.hpp"

using namespace gcode_test;

namespace {

// Coordinates are whole micrometres so that both twins print exact decimals.
using Um = int;

std::string mm(Um v) {
  std::ostringstream s;
  if (v < 0) s << '-';
  const Um a = v < 0 ? -v : v;
  s << a / 1000 << '.';
  s.width(3);
  s.fill('0');
  s << a % 1000;
  return s.str();
}

struct Twin {
  std::string absolute;
  std::string incremental;
};

const char* plane_g(int p) {
  return p == 0 ? "G17" : p == 1 ? "G18" : "G19";
}

// A random path of lines and arcs (all planes, helices), written twice.
Twin random_twin(std::mt19937& rng) {
  std::uniform_int_distribution<Um> coord(-100000, 100000);
  std::uniform_int_distribution<int> kind(0, 3);
  std::uniform_real_distribution<double> angle(0.0, 2 * M_PI);
  std::uniform_int_distribution<Um> radius(500, 40000);
  Twin t;
  const std::string head = "G21 G17 F500\nG10 L2 P1 X" + mm(coord(rng)) + " Y" + mm(coord(rng)) + " Z" +
                           mm(coord(rng)) + "\nG92 X" + mm(coord(rng)) + "\n";
  t.absolute = head + "G90\n";
  t.incremental = head + "G91\n";
  std::array<Um, 3> pos{0, 0, 0};
  // Start from a known point: G92 moved the work origin, so go there first.
  t.absolute += "G0 X0 Y0 Z0\n";
  t.incremental += "G90 G0 X0 Y0 Z0\nG91\n";
  for (int step = 0; step < 25; ++step) {
    const int k = kind(rng);
    std::array<Um, 3> next = pos;
    std::string abs_line;
    std::string inc_line;
    if (k <= 1) {
      for (Um& v : next) v = coord(rng);
      const char* g = k == 0 ? "G0" : "G1";
      abs_line = std::string(g) + " X" + mm(next[0]) + " Y" + mm(next[1]) + " Z" + mm(next[2]);
      inc_line = std::string(g) + " X" + mm(next[0] - pos[0]) + " Y" + mm(next[1] - pos[1]) + " Z" +
                 mm(next[2] - pos[2]);
    } else {
      const int plane = std::uniform_int_distribution<int>(0, 2)(rng);
      const PlaneAxes ax = plane_axes(plane == 0 ? Plane::xy : plane == 1 ? Plane::xz : Plane::yz);
      const Um r = radius(rng);
      const double a0 = angle(rng);
      const double a1 = angle(rng);
      // Centre offset from the start, end on the same circle (to 1 um).
      const Um i1 = -static_cast<Um>(std::lround(r * std::cos(a0)));
      const Um i2 = -static_cast<Um>(std::lround(r * std::sin(a0)));
      const Um c1 = pos.at(ax.first) + i1;
      const Um c2 = pos.at(ax.second) + i2;
      next.at(ax.first) = c1 + static_cast<Um>(std::lround(r * std::cos(a1)));
      next.at(ax.second) = c2 + static_cast<Um>(std::lround(r * std::sin(a1)));
      next.at(ax.normal) = pos.at(ax.normal) + coord(rng) / 10;
      const char letters[] = {'I', 'J', 'K'};
      const std::string g = std::string(plane_g(plane)) + (k == 2 ? " G2" : " G3");
      const std::string offsets =
          std::string(" ") + letters[ax.first] + mm(i1) + " " + letters[ax.second] + mm(i2);
      abs_line = g;
      abs_line += " X" + mm(next[0]);
      abs_line += " Y" + mm(next[1]);
      abs_line += " Z" + mm(next[2]);
      abs_line += offsets;
      inc_line = g;
      inc_line += " X" + mm(next[0] - pos[0]);
      inc_line += " Y" + mm(next[1] - pos[1]);
      inc_line += " Z" + mm(next[2] - pos[2]);
      inc_line += offsets;
    }
    t.absolute += abs_line + "\n";
    t.incremental += inc_line + "\n";
    pos = next;
  }
  t.absolute += "M2\n";
  t.incremental += "M2\n";
  return t;
}

}  // namespace

TEST(GcodeProperties, IncrementalTwinReachesTheSameEndPoints) {
  std::mt19937 rng(15);
  for (int trial = 0; trial < 200; ++trial) {
    const Twin t = random_twin(rng);
    const auto a = calls_of(t.absolute);
    const auto i = calls_of(t.incremental);
    const auto ea = ends(a);
    const auto ei = ends(i);
    ASSERT_EQ(ea.size(), ei.size()) << t.absolute;
    for (size_t k = 0; k < ea.size(); ++k)
      ASSERT_TRUE(near3(ea[k], ei[k], 1e-9)) << "trial " << trial << " motion " << k;
    const auto arcs_a = only<ArcFeed>(a);
    const auto arcs_i = only<ArcFeed>(i);
    for (size_t k = 0; k < arcs_a.size(); ++k) ASSERT_TRUE(near3(arcs_a[k].centre, arcs_i[k].centre, 1e-9));
  }
}

TEST(GcodeProperties, RArcsEndOnTheirPointWithTheCentreAtRFromBothEnds) {
  std::mt19937 rng(274);
  std::uniform_int_distribution<Um> coord(-50000, 50000);
  std::uniform_real_distribution<double> stretch(1.0, 3.0);
  for (int trial = 0; trial < 500; ++trial) {
    const int plane = trial % 3;
    const Plane p = plane == 0 ? Plane::xy : plane == 1 ? Plane::xz : Plane::yz;
    const PlaneAxes ax = plane_axes(p);
    std::array<Um, 3> s{coord(rng), coord(rng), coord(rng)};
    std::array<Um, 3> e{coord(rng), coord(rng), coord(rng)};
    const double half = 0.5 * std::hypot(static_cast<double>(e.at(ax.first) - s.at(ax.first)),
                                         static_cast<double>(e.at(ax.second) - s.at(ax.second)));
    if (half < 1.0) continue;
    // |R| rounded up to a micrometre, so it reaches; sometimes a semicircle.
    Um r =
        trial % 7 == 0 ? static_cast<Um>(std::ceil(half)) : static_cast<Um>(std::ceil(half * stretch(rng)));
    const bool negative = trial % 2 == 1;
    const bool cw = trial % 4 < 2;
    const std::string text = std::string("G21 G90 F100 ") + plane_g(plane) + "\nG0 X" + mm(s[0]) + " Y" +
                             mm(s[1]) + " Z" + mm(s[2]) + "\n" + (cw ? "G2" : "G3") + " X" + mm(e[0]) + " Y" +
                             mm(e[1]) + " Z" + mm(e[2]) + " R" + mm(negative ? -r : r) + "\n";
    const auto arcs = only<ArcFeed>(calls_of(text));
    ASSERT_EQ(arcs.size(), 1U) << text;
    const ArcFeed& a = arcs[0];
    const Vec3 start{s[0] / 1000.0, s[1] / 1000.0, s[2] / 1000.0};
    const Vec3 end{e[0] / 1000.0, e[1] / 1000.0, e[2] / 1000.0};
    ASSERT_TRUE(near3(a.end, end, 1e-12)) << text;
    const double r1 =
        std::hypot(start.at(ax.first) - a.centre.at(ax.first), start.at(ax.second) - a.centre.at(ax.second));
    const double r2 =
        std::hypot(end.at(ax.first) - a.centre.at(ax.first), end.at(ax.second) - a.centre.at(ax.second));
    ASSERT_NEAR(r1, r2, 1e-7) << text;
    // The radius is |R| unless R was a hair short of the half chord.
    ASSERT_NEAR(r1, std::max(r / 1000.0, half / 1000.0), 1e-6) << text;
    // R > 0 is at most a half turn, R < 0 at least one.
    const double sweep = arc_sweep(start, a);
    if (negative)
      ASSERT_GE(sweep, M_PI - 1e-6) << text;
    else
      ASSERT_LE(sweep, M_PI + 1e-6) << text;
  }
}

TEST(GcodeProperties, WorkOffsetsTranslateEveryMotionCyclesIncluded) {
  std::mt19937 rng(92);
  std::uniform_int_distribution<Um> coord(-20000, 20000);
  std::uniform_int_distribution<int> kind(0, 4);
  for (int trial = 0; trial < 200; ++trial) {
    std::string body = "G0 X0 Y0 Z30\n";
    for (int step = 0; step < 15; ++step) {
      switch (kind(rng)) {
        case 0:
          body += "G0 X" + mm(coord(rng)) + " Y" + mm(coord(rng)) + " Z" + mm(coord(rng)) + "\n";
          break;
        case 1:
          body += "G1 X" + mm(coord(rng)) + " Y" + mm(coord(rng)) + "\n";
          break;
        case 2:
          body += "G2 X" + mm(coord(rng)) + " Y" + mm(coord(rng)) + " R-" + mm(60000) + "\n";
          break;
        case 3:
          body += "G98 G83 X" + mm(coord(rng)) + " Y" + mm(coord(rng)) + " Z-25 R25 Q" +
                  mm(3000 + coord(rng) / 20 + 1000) + "\nG80\n";
          break;
        default:
          body += "G99 G81 X" + mm(coord(rng)) + " Y" + mm(coord(rng)) + " Z-10 R22 L2\nG80\n";
          break;
      }
    }
    const Um ox = coord(rng);
    const Um oy = coord(rng);
    const Um oz = coord(rng);
    const auto plain = ends(calls_of("G21 G90 G17 F300\n" + body));
    const auto moved = ends(calls_of("G21 G90 G17 F300\nG10 L2 P4 X" + mm(ox) + " Y" + mm(oy) + " Z" +
                                     mm(oz) + "\nG57\n" + body));
    ASSERT_EQ(plain.size(), moved.size());
    const Vec3 shift{ox / 1000.0, oy / 1000.0, oz / 1000.0};
    for (size_t k = 0; k < plain.size(); ++k) {
      const Vec3 want{plain[k][0] + shift[0], plain[k][1] + shift[1], plain[k][2] + shift[2]};
      ASSERT_TRUE(near3(moved[k], want, 1e-9)) << "trial " << trial << " motion " << k;
    }
  }
}

TEST(GcodeProperties, FileAndLineServerAgree) {
  std::mt19937 rng(30);
  for (int trial = 0; trial < 100; ++trial) {
    const Twin t = random_twin(rng);
    const auto whole = calls_of(t.incremental);
    Interpreter in;
    std::vector<CanonCall> lines;
    std::istringstream text(t.incremental);
    std::string line;
    int n = 0;
    while (std::getline(text, line)) {
      const LineResult r = in.execute_line(line, ++n);
      ASSERT_TRUE(r.ok()) << r.error->format();
      lines.insert(lines.end(), r.calls.begin(), r.calls.end());
    }
    ASSERT_EQ(whole.size(), lines.size());
    for (size_t k = 0; k < whole.size(); ++k) ASSERT_EQ(to_string(whole[k]), to_string(lines[k]));
  }
}
