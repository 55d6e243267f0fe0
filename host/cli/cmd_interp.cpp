// motionctl interp line|arc: preview a move through the interpolator twin (no
// hardware): the points the core visits, or a summary of the path.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/commands.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::host::cli {
namespace {

struct InterpOptions {
  std::string from, to, center, feed = "10000";
  bool cw = false, ccw = false, csv = false, json = false;
};

// "X,Y" or "X,Y,Z" in integer counts.
std::vector<int64_t> parse_point(const std::string& text, const char* what, size_t min_n, size_t max_n) {
  std::vector<int64_t> v;
  size_t i = 0;
  const std::string expected = max_n == 2 ? "X,Y in integer counts" : "X,Y or X,Y,Z in integer counts";
  while (i <= text.size()) {
    const size_t j = std::min(text.find(',', i), text.size());
    const std::string tok = text.substr(i, j - i);
    size_t used = 0;
    long long x = 0;
    try {
      x = std::stoll(tok, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (tok.empty() || used != tok.size()) throw InputError(what, quote(text), expected);
    v.push_back(x);
    i = j + 1;
  }
  if (v.size() < min_n || v.size() > max_n) throw InputError(what, quote(text), expected);
  return v;
}

Vec3 to_vec3(const std::vector<int64_t>& v) {
  return {v[0], v[1], v.size() > 2 ? v[2] : 0};
}

double parse_feed(const std::string& text) {
  const double f = parse_number(text, "--feed");
  if (!(f > 0)) throw InputError("--feed", quote(text), "a positive number of counts per second");
  return f;
}

std::string g6(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string pt(const Vec3& p, int n) {
  std::string s = "(" + std::to_string(p[0]) + ", " + std::to_string(p[1]);
  if (n > 2) s += ", " + std::to_string(p[2]);
  return s + ")";
}

// Visit the points once: print them (--csv) and measure the path.
struct PathStats {
  int64_t steps = 0;
  double max_dev = 0;  // arcs: radial deviation, steps
  Vec3 worst{};
  Vec3 last{};
};

PathStats run(const PlannedSegment& p, int dims, bool csv, const std::array<double, 3>* circle) {
  PathStats st;
  if (csv) std::cout << (dims > 2 ? "k,x,y,z\n" : "k,x,y\n");
  int64_t k = 0;
  std::string line;
  walk(p, [&](const Vec3& q) {
    if (csv) {
      line = std::to_string(k) + ',' + std::to_string(q[0]) + ',' + std::to_string(q[1]);
      if (dims > 2) line += ',' + std::to_string(q[2]);
      line += '\n';
      std::cout << line;
    }
    if (circle) {
      const double d =
          std::fabs(std::hypot(double(q[0]) - (*circle)[0], double(q[1]) - (*circle)[1]) - (*circle)[2]);
      if (d > st.max_dev) {
        st.max_dev = d;
        st.worst = q;
      }
    }
    st.last = q;
    ++k;
  });
  st.steps = k - 1;
  return st;
}

void line_command(const InterpOptions& o) {
  const auto a = parse_point(o.from, "--from", 2, 3), b = parse_point(o.to, "--to", 2, 3);
  const int dims = a.size() > 2 || b.size() > 2 ? 3 : 2;
  const PlannedSegment p = plan_line(to_vec3(a), to_vec3(b), parse_feed(o.feed));
  const PathStats st = run(p, dims, o.csv, nullptr);
  if (o.csv) return;
  const double rate = double(p.seg.inc) / std::ldexp(1.0, seg::PH_W) * kDefaultClockHz;
  if (o.json) {
    nlohmann::ordered_json j;
    j["type"] = "line";
    j["from"] = p.start;
    j["to"] = p.end;
    j["iterations"] = p.seg.n;
    j["steps"] = st.steps;
    j["length_counts"] = p.length;
    j["feed_counts_per_s"] = parse_feed(o.feed);
    j["iteration_rate_hz"] = rate;
    j["duration_s"] = p.duration;
    j["feed_rel_error"] = p.feed_rel_error;
    j["end_exact"] = st.last == p.end;
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::cout << "line " << pt(p.start, dims) << " -> " << pt(p.end, dims) << " (Bresenham, twin)\n"
            << "  iterations N = max|d| = " << p.seg.n << ", points visited " << st.steps + 1
            << " (8-connected, one count per axis per iteration at most)\n"
            << "  length " << g6(p.length) << " counts; feed " << g6(parse_feed(o.feed))
            << " counts/s -> iteration rate " << g6(rate) << " /s, duration " << format_duration(p.duration)
            << "\n"
            << "  rate word realizes the feed to a relative " << g6(p.feed_rel_error) << "\n"
            << "  end point " << pt(st.last, dims) << (st.last == p.end ? ": exact" : ": MISSED") << '\n';
}

void arc_command(const InterpOptions& o) {
  if (o.cw == o.ccw)
    throw InputError("direction", o.cw ? "--cw and --ccw" : "none", "exactly one of --cw, --ccw");
  const auto a = parse_point(o.from, "--from", 2, 2), b = parse_point(o.to, "--to", 2, 2);
  const auto c = parse_point(o.center, "--center", 2, 2);
  const double feed = parse_feed(o.feed);
  const PlannedSegment p = plan_arc(to_vec3(a), to_vec3(b), {c[0], c[1]}, o.ccw, feed);
  const ArcGeometry& g = p.arc;
  const std::array<double, 3> circle{double(c[0]), double(c[1]), g.radius};
  const PathStats st = run(p, 2, o.csv, &circle);
  if (o.csv) return;
  const double sweep_deg = g.sweep * 180 / M_PI;
  if (o.json) {
    nlohmann::ordered_json j;
    j["type"] = "arc";
    j["direction"] = o.ccw ? "ccw" : "cw";
    j["from"] = {a[0], a[1]};
    j["to"] = {b[0], b[1]};
    j["center"] = {c[0], c[1]};
    j["radius_counts"] = g.radius;
    j["sweep_deg"] = sweep_deg;
    j["quadrant_crossings"] = g.nq;
    j["steps"] = st.steps;
    j["steps_formula"] = g.n;
    j["max_radial_deviation_steps"] = st.max_dev;
    j["length_counts"] = p.length;
    j["feed_counts_per_s"] = feed;
    j["duration_s"] = p.duration;
    j["feed_rel_error"] = p.feed_rel_error;
    j["end_exact"] = st.last == p.end;
    std::cout << j.dump(2) << '\n';
    return;
  }
  std::cout << "arc " << (o.ccw ? "ccw" : "cw") << " " << pt(p.start, 2) << " -> " << pt(p.end, 2)
            << " about " << pt(to_vec3(c), 2) << " (stairs approximation, twin)\n"
            << "  radius " << g6(g.radius) << " counts, swept " << g6(sweep_deg) << " deg across " << g.nq
            << " quadrant boundar" << (g.nq == 1 ? "y" : "ies") << "\n"
            << "  steps " << st.steps << " (formula, per quadrant |dx|+|dy|: " << g.n
            << "), 4-connected, one axis per step\n"
            << "  max radial deviation " << g6(st.max_dev) << " steps, at " << pt(st.worst, 2) << '\n'
            << "  length " << g6(p.length) << " counts; feed " << g6(feed)
            << " counts/s held along the tangent, duration " << format_duration(p.duration) << '\n'
            << "  rate words realize the feed to a relative " << g6(p.feed_rel_error) << '\n'
            << "  end point " << pt(st.last, 2) << (st.last == p.end ? ": exact" : ": MISSED") << '\n';
}

void add_common(CLI::App* sub, InterpOptions& o) {
  sub->add_option("--feed", o.feed, "Feed along the path, counts per second (default 10000)");
  auto* csv = sub->add_flag("--csv", o.csv, "Print every visited point: header k,x,y[,z], one line each");
  auto* json = sub->add_flag("--json", o.json, "Print the summary as JSON");
  csv->excludes(json);
}

}  // namespace

void add_interp_command(CLI::App& app) {
  auto opt = std::make_shared<InterpOptions>();
  CLI::App* cmd =
      app.add_subcommand("interp", "Preview a line or arc through the interpolator twin (no hardware)");
  cmd->require_subcommand(1);

  CLI::App* line =
      cmd->add_subcommand("line", "Bresenham line: the points the core visits from --from to --to");
  line->add_option("--from", opt->from, "Start point X,Y[,Z], counts")->required();
  line->add_option("--to", opt->to, "End point X,Y[,Z], counts")->required();
  add_common(line, *opt);
  line->callback([opt] { line_command(*opt); });

  CLI::App* arc =
      cmd->add_subcommand("arc", "Stairs-approximation arc in the XY plane, as the core walks it");
  arc->add_option("--from", opt->from, "Start point X,Y, counts; defines the radius")->required();
  arc->add_option("--to", opt->to, "End point X,Y, counts; within one step of the circle")->required();
  arc->add_option("--center", opt->center, "Centre point I,J in absolute counts (not an offset)")->required();
  auto* cw = arc->add_flag("--cw", opt->cw, "Clockwise");
  auto* ccw = arc->add_flag("--ccw", opt->ccw, "Counter-clockwise");
  cw->excludes(ccw);
  add_common(arc, *opt);
  arc->callback([opt] { arc_command(*opt); });
}

}  // namespace mc::host::cli
