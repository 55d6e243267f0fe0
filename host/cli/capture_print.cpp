#include "host/cli/capture_print.hpp"

#include <algorithm>

#include <sstream>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "host/base/errors.hpp"
#include "host/base/units.hpp"
#include "host/cli/board_cli.hpp"

namespace mc::host::cli {

double machine_scale(int a, const std::string& axis) {
  const double s = axis_scales()[size_t(a)];
  if (s == 0)
    throw InputError("--axis", quote(axis), "an axis of the machine config (" + machine().source + ")");
  return s;
}

std::string num_or_dash(double v, const char* fmt, double scale) {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, fmt, v * scale);
  return b;
}

nlohmann::ordered_json metrics_json(const StepMetrics& m) {
  const auto n = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  return {{"rise_s", n(m.rise_s)},
          {"overshoot_pct", m.overshoot_pct},
          {"peak_s", n(m.peak_s)},
          {"settling_s", n(m.settling_s)},
          {"ss_error_counts", m.ss_error},
          {"iae_counts_s", m.iae},
          {"rose", m.rose},
          {"settled", m.settled}};
}

void print_metrics(const StepMetrics& m, double cpm, std::ostream& os, const char* indent) {
  char b[400];
  std::snprintf(b, sizeof b,
                "%srise time (10-90 %%)   %s ms\n%sovershoot             %.2f %% (peak at %s ms)\n"
                "%ssettling time (2 %%)   %s ms\n%ssteady-state error    %.2f counts (%.2f um)\n"
                "%sIAE                   %.4f count*s (%.3f um*s)\n",
                indent, num_or_dash(m.rise_s, "%.2f", 1e3).c_str(), indent, m.overshoot_pct,
                num_or_dash(m.peak_s, "%.2f", 1e3).c_str(), indent,
                m.settled ? num_or_dash(m.settling_s, "%.2f", 1e3).c_str() : "not settled", indent,
                m.ss_error, m.ss_error / cpm * 1e6, indent, m.iae, m.iae / cpm * 1e6);
  os << b;
}

nlohmann::ordered_json pid_json(const PidGains& g) {
  return {{"kp", g.kp}, {"ki", g.ki}, {"kd", g.kd}, {"tf", g.tf}, {"ts", g.ts}};
}

std::string gains_line(const PidGains& g) {
  char b[200];
  std::snprintf(b, sizeof b, "Kp = %.5g  Ki = %.5g  Kd = %.5g  Tf = %s", g.kp, g.ki, g.kd,
                format_duration(g.tf).c_str());
  return b;
}

void run_gnuplot_script(const std::string& script, const std::string& what) {
  const std::string cmd = "gnuplot 2>&1";
  FILE* p = ::popen(cmd.c_str(), "w");
  if (!p) throw std::runtime_error("cannot run gnuplot for " + what);
  std::fwrite(script.data(), 1, script.size(), p);
  if (::pclose(p) != 0)
    throw std::runtime_error("gnuplot failed writing " + what + " (is gnuplot-nox installed?)");
}

std::string watchdog_text(const BoardState& s) {
  char b[200];
  std::snprintf(b, sizeof b, "%s (WDOG = %u cycles)", format_duration(double(s.wdog) / s.clk_hz).c_str(),
                unsigned(s.wdog));
  return b;
}

void plot_xy(const std::string& out, const std::string& title, const std::vector<XySeries>& series) {
  std::ostringstream g;
  g << "set terminal pngcairo size 1000,800\nset output '" << out << "'\n"
    << "set title '" << title << "'\n"
    << "set xlabel 'X (mm)'\nset ylabel 'Y (mm)'\nset size ratio -1\nset key outside\n";
  for (size_t i = 0; i < series.size(); ++i) g << "$d" << i << " << EOD\n" << series[i].data << "EOD\n";
  g << "plot ";
  for (size_t i = 0; i < series.size(); ++i)
    g << (i ? ", " : "") << "$d" << i << " using 1:2 with " << series[i].style << " title '"
      << series[i].title << "'";
  g << "\n";
  run_gnuplot_script(g.str(), out);
}

std::string moves_xy(const std::vector<mc::host::Move>& moves, bool rapid) {
  std::ostringstream d;
  for (const mc::host::Move& mv : moves) {
    if (!mv.is_motion() || mv.rapid != rapid) continue;
    const int n = mv.kind == mc::host::Move::Kind::arc ? std::max(2, int(std::ceil(mv.sweep / 0.02))) : 1;
    for (int i = 0; i <= n; ++i) {
      const mc::host::Vec3d p = mc::host::point_at(mv, mv.length * i / n);
      d << p[0] << ' ' << p[1] << '\n';
    }
    d << "\n";
  }
  return d.str();
}

}  // namespace mc::host::cli
