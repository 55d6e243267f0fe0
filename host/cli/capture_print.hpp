// What motionctl step, tune and hostloop print alike: step metrics as text
// and JSON, gains on one line, and the machine's scale of an axis.
#pragma once

#include "host/motion/planner.hpp"

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "host/control/pid_design.hpp"
#include "host/control/step_metrics.hpp"
#include "host/link/board_state.hpp"

namespace mc::host::cli {

constexpr const char* kBoardFooter =
    "Talks to the board: give --port DEV (a real board) or --sim (the virtual board) before the command.";

// Counts per metre of the axis named `axis` (index a); InputError naming
// --axis when the machine config has no such axis.
double machine_scale(int a, const std::string& axis);
// v * scale printed with fmt, or "-" when v is not finite (a metric the
// response never reached).
std::string num_or_dash(double v, const char* fmt, double scale = 1);
nlohmann::ordered_json metrics_json(const StepMetrics& m);
void print_metrics(const StepMetrics& m, double cpm, std::ostream& os, const char* indent = "  ");
nlohmann::ordered_json pid_json(const PidGains& g);
std::string gains_line(const PidGains& g);
// "100 ms (WDOG = 1200000 cycles)"
std::string watchdog_text(const BoardState& s);
// Runs gnuplot on `script`; `what` names the output in the error.
void run_gnuplot_script(const std::string& script, const std::string& what);

// A curve of an XY plot: gnuplot data ("x y" lines, a blank line between
// pieces), its key title and its gnuplot style ("lines dt 2 lc rgb '#d62728'").
struct XySeries {
  std::string title, data, style;
};
// A PNG of the series on equal X and Y scales (mm), through gnuplot.
void plot_xy(const std::string& out, const std::string& title, const std::vector<XySeries>& series);
// The XY points of the motion moves (arcs sampled every 0.02 rad), rapids
// or not as `rapid` says.
std::string moves_xy(const std::vector<mc::host::Move>& moves, bool rapid);

}  // namespace mc::host::cli
