// motionctl step | tune | hostloop: the board commands built on telemetry
// captures (host/board_capture.hpp): a step response with its metrics, gain
// tuning by identification or relay on the board, and the PC's control loop
// run live against the board.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "board_capture.hpp"
#include "board_cli.hpp"
#include "board_ops.hpp"
#include "commands.hpp"
#include "cosim.hpp"
#include "errors.hpp"
#include "metrics.hpp"
#include "pid_double.hpp"
#include "pid_regs.hpp"
#include "step_metrics.hpp"
#include "tuning.hpp"
#include "units.hpp"

namespace mc::host::cli {
namespace {

namespace br = board::reg;
namespace bb = board::bits;

constexpr const char* kFooter =
    "Talks to the board: give --port DEV (a real board) or --sim (the virtual board) before the command.";

double machine_scale(int a, const std::string& axis) {
  const double s = axis_scales()[size_t(a)];
  if (s == 0)
    throw InputError("--axis", quote(axis), "an axis of the machine config (" + machine().source + ")");
  return s;
}

// Loads the interpolator with `target` for axis a and the current command
// for the others: the command steps at the next sample.
void set_command(BoardLink& l, int a, int32_t target) {
  if (l.read(br::IP_STAT) >> bb::IS_BUSY & 1)
    throw BoardError("the interpolator is busy: wait until the motion is done");
  const int naxes = int(l.read(br::INFO) & 0xF);
  for (int x = 0; x < naxes && x < 3; ++x) {
    const uint32_t v = x == a ? uint32_t(target) : l.read(br::axis(x, br::AX_CMD));
    l.write(uint16_t(br::IP_SET_X + x), v);
  }
  l.write(br::IP_CTRL, 1u << bb::I_SET);
}

// Arms the drives and enables the axis' PID (its gains must be set).
void arm_axis(BoardLink& l, int a) {
  if (l.read(pid_reg::addr(uint8_t(a), pid_reg::KP)) == 0 &&
      l.read(pid_reg::addr(uint8_t(a), pid_reg::KI)) == 0)
    throw InputError(
        "axis " + std::string(axis_name(a)), "Kp = Ki = 0",
        "gains first: 'motionctl gains set --axis " + std::string(axis_name(a)) + " --defaults'");
  arm(l, note);
  l.write_verify(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1, 1);
}

std::string num_or_dash(double v, const char* fmt, double scale = 1) {
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

// ---- step ---------------------------------------------------------------------------
struct StepOptions {
  std::string axis, size = "1", duration = "0.2s", plot, csv;
  bool json = false;
};

struct StepCapture {
  double ts = 0;  // PID sample period, s
  uint32_t decim = 1, decim_needed = 1;
  int32_t y0 = 0, counts = 0;
  std::vector<double> t;  // s from the step
  std::vector<TlmSample> s;
  int64_t gaps = 0, missing = 0;
  uint16_t fault = 0;
  StepMetrics m{};
};

StepCapture capture_step(BoardLink& l, int a, int32_t counts, double duration) {
  StepCapture c;
  c.counts = counts;
  c.ts = double(read_ts_cycles(l)) / double(l.read(br::CLK_HZ));
  const double baud = double(l.read(br::BAUD));
  c.decim_needed = telemetry_decimation(c.ts, baud, 0);
  // Two replies may queue in front of a frame: the step's writes, a PING.
  c.decim = telemetry_decimation(c.ts, baud, 2);
  arm_axis(l, a);
  const double period = c.decim * c.ts;
  TelemetryStream tlm(l, a, c.decim, std::max<int64_t>(1, std::llround(0.01 / c.ts)));
  std::vector<TlmSample> v;
  const size_t pre = size_t(std::ceil(0.01 / period)) + 1;  // 10 ms before the step
  while (v.size() < pre) tlm.next(v);
  c.y0 = v.back().cmd;
  const int32_t target = c.y0 + counts;
  set_command(l, a, target);
  int64_t n_step = -1;
  const int64_t n_end_samples = std::llround(duration / c.ts);
  for (size_t i = pre;; ++i) {
    while (v.size() <= i) tlm.next(v);
    if (n_step < 0 && v[i].cmd == target) n_step = v[i].n;
    if (n_step < 0 && v[i].n - v[pre - 1].n > std::llround(0.1 / c.ts))
      throw BoardError("the command did not step within 100 ms of board time");
    if (n_step >= 0 && v[i].n - n_step >= n_end_samples) break;
  }
  c.gaps = tlm.gaps();
  c.missing = tlm.missing();
  for (const TlmSample& x : v) {
    c.fault |= x.fault;
    if (x.n - n_step > n_end_samples) break;
    c.s.push_back(x);
    c.t.push_back(double(x.n - n_step) * c.ts);
  }
  std::vector<double> y;
  for (const TlmSample& x : c.s) y.push_back(x.pos);
  c.m = step_metrics(c.t, y, c.y0, counts, 0);
  return c;
}

void write_step_csv(const std::string& file, const StepCapture& c) {
  std::ofstream f(file);
  if (!f) throw InputError("--csv", quote(file), "a writable path");
  f << "t_s,cmd_counts,pos_counts,err_counts,out_drive_units\n";
  char b[160];
  for (size_t i = 0; i < c.s.size(); ++i) {
    std::snprintf(b, sizeof b, "%.7f,%d,%d,%d,%d\n", c.t[i], int(c.s[i].cmd), int(c.s[i].pos),
                  int(c.s[i].err), int(c.s[i].u));
    f << b;
  }
}

void run_gnuplot_script(const std::string& script, const std::string& what) {
  const std::string cmd = "gnuplot 2>&1";
  FILE* p = ::popen(cmd.c_str(), "w");
  if (!p) throw std::runtime_error("cannot run gnuplot for " + what);
  std::fwrite(script.data(), 1, script.size(), p);
  if (::pclose(p) != 0)
    throw std::runtime_error("gnuplot failed writing " + what + " (is gnuplot-nox installed?)");
}

void write_step_plot(const std::string& png, const StepCapture& c, double cpm) {
  const std::string dat = png + ".dat";
  {
    std::ofstream f(dat);
    if (!f) throw InputError("--plot", quote(png), "a writable path");
    for (size_t i = 0; i < c.s.size(); ++i)
      f << c.t[i] * 1e3 << ' ' << (c.s[i].cmd - c.y0) / cpm * 1e3 << ' ' << (c.s[i].pos - c.y0) / cpm * 1e3
        << ' ' << c.s[i].u << '\n';
  }
  char title[200];
  std::snprintf(title, sizeof title, "step %.4g mm: overshoot %.1f %%, settling %s ms", c.counts / cpm * 1e3,
                c.m.overshoot_pct, num_or_dash(c.m.settling_s, "%.1f", 1e3).c_str());
  std::string gp = "set terminal pngcairo size 900,600\nset output '" + png + "'\nset title '" + title +
                   "'\nset xlabel 'time from the step (ms)'\nset ylabel 'mm'\nset y2label 'PID output (drive "
                   "units)'\nset ytics nomirror\nset y2tics\nset grid\nset key bottom right\nplot '" +
                   dat +
                   "' u 1:2 w l t 'command', '' u 1:3 w lp pt 7 ps 0.4 t 'position', '' u 1:4 axes x1y2 w l "
                   "lc rgb '#999999' t 'output'\n";
  run_gnuplot_script(gp, png);
  std::remove(dat.c_str());
}

void print_metrics(const StepMetrics& m, double cpm, std::ostream& os, const char* indent = "  ") {
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

void step(const StepOptions& o) {
  const int a0 = parse_axis(o.axis);
  const double mm = parse_number(o.size, "--size");
  const double duration = parse_duration(o.duration, "--duration");
  if (duration > 10) throw InputError("--duration", quote(o.duration), "at most 10 s");
  const double cpm = machine_scale(a0, o.axis);
  const int32_t counts = int32_t(std::llround(mm * 1e-3 * cpm));
  if (counts == 0) throw InputError("--size", quote(o.size), "a step of at least one encoder count");
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  catch_interrupts();
  const StepCapture c = capture_step(l, a, counts, duration);
  if (!o.csv.empty()) write_step_csv(o.csv, c);
  if (!o.plot.empty()) write_step_plot(o.plot, c, cpm);
  if (o.json) {
    nlohmann::ordered_json j;
    j["axis"] = axis_name(a);
    j["step_counts"] = counts;
    j["step_mm"] = counts / cpm * 1e3;
    j["ts_s"] = c.ts;
    j["decimation"] = c.decim;
    j["decimation_frames_alone"] = c.decim_needed;
    j["samples"] = c.s.size();
    j["gaps"] = c.gaps;
    j["missing_samples"] = c.missing;
    j["faults"] = c.fault ? fault_names(c.fault) : "none";
    j["metrics"] = metrics_json(c.m);
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << "step of " << counts << " counts (" << counts / cpm * 1e3 << " mm) on axis " << axis_name(a)
              << " at Ts " << format_duration(c.ts) << ", captured " << format_duration(duration)
              << " of board time\n";
    std::cout << "telemetry every " << c.decim << (c.decim == 1 ? " sample" : " samples") << " ("
              << format_duration(c.decim * c.ts) << "): a frame takes "
              << format_duration(10.0 * telemetry_frame_bytes(1) / double(l.read(br::BAUD)))
              << " on the link (alone it fits every " << c.decim_needed
              << " samples); two replies may queue in front of it; " << c.s.size() << " samples, ";
    if (c.gaps)
      std::cout << "GAPS: " << c.gaps << " jumps of the sample counter, " << c.missing
                << " frames lost (the metrics use the samples received, nothing is interpolated)\n";
    else
      std::cout << "no gaps\n";
    print_metrics(c.m, cpm, std::cout);
    if (c.fault) std::cout << "FAULT during the capture: " << fault_names(c.fault) << '\n';
    if (!o.csv.empty()) std::cout << "wrote " << o.csv << '\n';
    if (!o.plot.empty()) std::cout << "wrote " << o.plot << '\n';
  }
}

// ---- tune ---------------------------------------------------------------------------
struct TuneOptions {
  std::string axis, method = "model", bandwidth, zeta = "2";
  bool apply = false, json = false;
};

// What an experiment changes and restore() puts back: the sample period,
// the axis' coefficient RAM and following-error limit, every axis' enable.
struct Snapshot {
  uint32_t ts_reg = 0;
  std::array<uint32_t, pid_reg::NREGS_RAM> ram{};
  uint32_t ferr = 0;
  std::vector<uint32_t> ctrl;
};

Snapshot snapshot(BoardLink& l, int a) {
  Snapshot s;
  s.ts_reg = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS));
  for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
    s.ram[size_t(r)] = l.read(pid_reg::addr(uint8_t(a), uint8_t(r)));
  s.ferr = l.read(br::axis(a, br::AX_FERR));
  const int naxes = int(l.read(br::INFO) & 0xF);
  for (int x = 0; x < naxes; ++x) s.ctrl.push_back(l.read(pid_reg::addr(uint8_t(x), pid_reg::CTRL)));
  return s;
}

void restore(BoardLink& l, int a, const Snapshot& s) {
  const int32_t pos = int32_t(l.read(br::axis(a, br::AX_POS)));
  l.write(uint16_t(br::IP_SET_X + a), uint32_t(pos));
  l.write(br::IP_CTRL, 1u << bb::I_SET);
  l.write_verify(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), s.ts_reg);
  for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
    l.write_verify(pid_reg::addr(uint8_t(a), uint8_t(r)), s.ram[size_t(r)]);
  l.write_verify(br::axis(a, br::AX_FERR), s.ferr, 0xFFFF);
  for (size_t x = 0; x < s.ctrl.size(); ++x)
    l.write_verify(pid_reg::addr(uint8_t(x), pid_reg::CTRL), s.ctrl[x], 1);
}

// Runs the axis alone under a P-only controller with an error clamp, so
// that far from its command it gets exactly +-Kp * clamp (docs/tuning.md).
void p_only(BoardLink& l, int a, double kp, double ts, uint32_t out_limit, uint32_t err_clamp) {
  const Snapshot s = snapshot(l, a);
  l.write_verify(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS),
                 uint32_t(std::llround(ts * double(l.read(br::CLK_HZ)))));
  CoreLimits lim;
  lim.out_limit = out_limit;
  lim.err_limit = err_clamp;
  write_gains(l, a, design(PidGains{kp, 0, 0, 0, ts}), lim);
  l.write_verify(br::axis(a, br::AX_FERR), 0, 0xFFFF);
  for (size_t x = 0; x < s.ctrl.size(); ++x)
    if (int(x) != a) l.write_verify(pid_reg::addr(uint8_t(x), pid_reg::CTRL), 0, 1);
  arm(l, note);
  const int32_t pos = int32_t(l.read(br::axis(a, br::AX_POS)));
  set_command(l, a, pos);
  // Off and on: clears the integrator the previous gains left (Ki = 0 would
  // hold it), so the output is exactly +-Kp * clamp, a multiple of the PWM's step.
  l.write_verify(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 0, 1);
  l.write_verify(pid_reg::addr(uint8_t(a), pid_reg::CTRL), 1, 1);
}

struct Experiment {
  std::vector<double> u, y;
  double ts = 0;  // of the capture
};

// Open loop through the clamp: the command jumps 2^20 counts either side of
// the start at the PRBS' bit changes (paced on the board's sample count),
// so the error stays clamped and u = +-amplitude; u and y come from the same
// telemetry frames, every sample.
Experiment model_experiment(BoardLink& l, int a, double ts_board, double baud) {
  constexpr uint32_t kClamp = 64;
  const double amp = TuneDefaults::prbs_amplitude;
  Experiment e;
  // Two writes per bit change may queue in front of a frame.
  e.ts = ts_board * telemetry_decimation(ts_board, baud, 2);
  p_only(l, a, amp / kClamp, e.ts, 32767, kClamp);
  const int32_t start = int32_t(l.read(br::axis(a, br::AX_POS)));
  const std::vector<double> bits = prbs(1, TuneDefaults::prbs_bit_s, TuneDefaults::prbs_duration_s, e.ts);
  TelemetryStream tlm(l, a, 1, std::llround(0.01 / e.ts));
  std::vector<TlmSample> v;
  tlm.next(v);
  const int64_t n0 = v.front().n;
  double sign = 0;
  const int64_t n_end = n0 + int64_t(bits.size()) + std::llround(0.02 / e.ts);
  while (v.back().n < n_end) {
    const int64_t k = v.back().n - n0;
    const double want = k < int64_t(bits.size()) ? bits[size_t(k)] : 0;
    if (want != sign) {
      sign = want;
      l.write(uint16_t(br::IP_SET_X + a), uint32_t(start + int32_t(sign * (1 << 20))));
      l.write(br::IP_CTRL, 1u << bb::I_SET);
    }
    tlm.next(v);
  }
  if (tlm.gaps())
    throw BoardError("telemetry lost " + std::to_string(tlm.missing()) +
                     " samples during the excitation; the identification needs every sample");
  uint16_t fault = 0;
  for (const TlmSample& x : v) {
    fault |= x.fault;
    e.u.push_back(x.u);
    e.y.push_back(x.pos);
  }
  if (fault) throw BoardError("fault during the excitation: " + fault_names(fault));
  return e;
}

// Relay on the board: P-only with Kp = d per count and the output limited
// to d is a relay (zero output only at zero error) at the board's own Ts.
Experiment relay_experiment(BoardLink& l, int a, double ts_board, double baud) {
  const double d = TuneDefaults::relay_amplitude;
  p_only(l, a, d, ts_board, uint32_t(d), 0);
  Experiment e;
  const uint32_t decim = telemetry_decimation(ts_board, baud, 1);
  e.ts = ts_board * decim;
  TelemetryStream tlm(l, a, decim, std::llround(0.01 / ts_board));
  std::vector<TlmSample> v;
  tlm.next(v);
  // A small offset starts the cycle.
  set_command(l, a, v.back().pos + 10);
  const int64_t n_end = v.back().n + std::llround(TuneDefaults::relay_duration_s / ts_board);
  while (v.back().n < n_end) tlm.next(v);
  if (tlm.gaps())
    throw BoardError("telemetry lost " + std::to_string(tlm.missing()) +
                     " frames during the relay experiment");
  uint16_t fault = 0;
  for (const TlmSample& x : v) {
    fault |= x.fault;
    e.y.push_back(x.pos);
  }
  if (fault) throw BoardError("fault during the relay experiment: " + fault_names(fault));
  return e;
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

void tune(const TuneOptions& o) {
  const int a0 = parse_axis(o.axis);
  if (o.method != "model" && o.method != "relay")
    throw InputError("--method", quote(o.method), "model or relay");
  const double zeta = parse_number(o.zeta, "--zeta");
  if (!(zeta > 0)) throw InputError("--zeta", quote(o.zeta), "a damping above 0");
  double wc = 0;
  if (!o.bandwidth.empty()) {
    wc = parse_number(o.bandwidth, "--bandwidth");
    if (!(wc > 0)) throw InputError("--bandwidth", quote(o.bandwidth), "rad/s above 0");
    if (o.method == "relay")
      throw InputError("--bandwidth", quote(o.bandwidth), "no --bandwidth with --method relay");
  }
  const double cpm = machine_scale(a0, o.axis);
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  const AxisGains cur = read_gains(l, a);
  const double ts = cur.gains.ts;
  const double baud = double(l.read(br::BAUD));
  const Snapshot snap = snapshot(l, a);
  catch_interrupts();
  Experiment e;
  try {
    e = o.method == "model" ? model_experiment(l, a, ts, baud) : relay_experiment(l, a, ts, baud);
  } catch (...) {
    try {
      restore(l, a, snap);
    } catch (...) {  // the first error says more
    }
    throw;
  }
  restore(l, a, snap);

  const int32_t step = int32_t(std::llround(1e-3 * cpm));
  const double horizon = 0.2;
  nlohmann::ordered_json j;
  j["axis"] = axis_name(a);
  j["method"] = o.method;
  PidGains g{};
  AxisModel m{};
  RelayResult r{};
  if (o.method == "model") {
    // One lag: the capture period (link-bound, >= 0.48 ms at 1 Mbaud) cannot resolve a motor's
    // L/R, and a second lag then only lets the fit wander (docs/tuning.md).
    m = identify(e.u, e.y, e.ts, true, false);
    // The default bandwidth's cap 2 pi / (40 Ts) taken at the capture's
    // period: the model is trusted no faster than its samples show it, and
    // the electrical lag the one-lag fit leaves out stays well beyond wc.
    if (wc == 0) wc = default_bandwidth(m);
    m.ts = ts;  // the board runs the design at its own period
    g = design_model(m, wc, zeta);
    j["model"] = {{"k_counts_per_s_per_du", m.k}, {"tau_s", m.tau},
                  {"tau_fast_s", m.tau_fast},     {"coulomb_du", m.coulomb},
                  {"fit_rms_counts", m.fit_rms},  {"samples", m.samples},
                  {"capture_ts_s", e.ts}};
    j["bandwidth_rad_s"] = wc;
    j["zeta"] = zeta;
  } else {
    r = relay_analyse(e.y, e.ts, TuneDefaults::relay_amplitude, 0);
    g = design_relay(r, ts);
    j["relay"] = {{"ku", r.ku}, {"tu_s", r.tu}, {"amplitude_counts", r.amplitude}, {"periods", r.periods}};
  }
  const PidDesign d = design(g);
  const std::vector<std::string> warnings = design_warnings(d);
  const double olim = cur.limits.out_limit ? double(cur.limits.out_limit) : 32767;
  const bool have_cur = cur.gains.kp > 0 || cur.gains.ki > 0;
  Prediction p_new{}, p_cur{};
  if (o.method == "model") {
    p_new = predict_step(m, g, step, horizon, olim);
    if (have_cur) p_cur = predict_step(m, cur.gains, step, horizon, olim);
  }
  if (o.apply) write_gains(l, a, d, CoreLimits{cur.limits});
  if (o.json) {
    j["current"] = pid_json(cur.gains);
    j["proposed"] = pid_json(d.gains);
    if (o.method == "model") {
      j["prediction_step_counts"] = step;
      if (have_cur) j["current"]["predicted"] = metrics_json(p_cur.metrics);
      j["proposed"]["predicted"] = metrics_json(p_new.metrics);
    }
    j["warnings"] = warnings;
    j["applied"] = o.apply;
    std::cout << j.dump(2) << '\n';
    return;
  }
  char line[300];
  if (o.method == "model") {
    std::snprintf(line, sizeof line,
                  "identified axis %s (open loop, PRBS +-%.0f drive units, %zu samples at %s):\n"
                  "  P(s) = K / (s (tau s + 1)): K = %.4f counts/s per drive unit, tau = %.3f ms; Coulomb "
                  "friction %.1f drive units; fit %.3f counts RMS\n",
                  axis_name(a), TuneDefaults::prbs_amplitude, e.u.size(), format_duration(e.ts).c_str(), m.k,
                  m.tau * 1e3, m.coulomb, m.fit_rms);
    std::cout << line;
    std::snprintf(line, sizeof line, "design: pole placement, bandwidth %.1f rad/s, damping %.2g, at Ts %s\n",
                  wc, zeta, format_duration(ts).c_str());
    std::cout << line;
  } else {
    std::snprintf(
        line, sizeof line,
        "relay on axis %s (+-%.0f drive units at Ts %s): Ku = %.2f drive units/count, Tu = %.3f ms, "
        "amplitude %.1f counts over %d periods\ndesign: Tyreus-Luyben\n",
        axis_name(a), TuneDefaults::relay_amplitude, format_duration(ts).c_str(), r.ku, r.tu * 1e3,
        r.amplitude, r.periods);
    std::cout << line;
  }
  std::cout << "current:  " << gains_line(cur.gains) << '\n' << "proposed: " << gains_line(d.gains) << '\n';
  for (const std::string& w : warnings) std::cout << "warning: quantized: " << w << '\n';
  if (o.method == "model") {
    std::cout << "predicted 1 mm (" << step
              << "-count) step, quantized controller on the identified model:\n";
    std::snprintf(line, sizeof line, "  %-10s %10s %12s %12s %14s\n", "gains", "overshoot", "settling 2%",
                  "rise", "IAE count*s");
    std::cout << line;
    const auto row = [&](const char* name, const StepMetrics& sm) {
      std::snprintf(line, sizeof line, "  %-10s %9.1f %% %9s ms %9s ms %14.3f\n", name, sm.overshoot_pct,
                    num_or_dash(sm.settling_s, "%.1f", 1e3).c_str(),
                    num_or_dash(sm.rise_s, "%.2f", 1e3).c_str(), sm.iae);
      std::cout << line;
    };
    if (have_cur) row("current", p_cur.metrics);
    row("proposed", p_new.metrics);
  }
  std::cout << (o.apply ? "applied: written and verified (read back word by word)\n"
                        : "not applied (the previous gains are back on the board); --apply writes them\n");
}

// ---- hostloop -----------------------------------------------------------------------
struct HostloopOptions {
  std::string axis, ts = "10ms", duration = "0.6s", distance = "2", feed = "600";
  bool json = false;
};

struct LoopRun {
  mc::sim::ErrorStats follow;  // counts
  std::vector<double> period_s, latency_s, wall_period_s;
  int64_t gaps = 0;
  uint16_t fault = 0;
};

// One jog of `counts` on axis a, captured every decim samples for
// `samples` board samples. With host_every > 0 the host runs `pid` every
// host_every samples on the frame's CMD and POS and writes the result
// through the DRV override; otherwise the board's PID drives.
LoopRun run_jog(BoardLink& l, int a, int32_t counts, double feed_counts_s, uint32_t decim, int64_t samples,
                int64_t host_every, mc::host::PidDouble* pid) {
  using Clock = std::chrono::steady_clock;
  LoopRun r;
  const Vec3 from = arm(l, note);
  const double clk = double(l.read(br::CLK_HZ));
  Vec3 to = from;
  to[size_t(a)] += counts;
  const std::vector<PlannedSegment> segs = plan_move(from, to, feed_counts_s, clk);
  if (segs.size() > 6) throw InputError("--distance", std::to_string(counts) + " counts", "a shorter move");
  const uint16_t drv = br::axis(a, br::AX_DRV);
  const uint32_t ovr = 1u << bb::D_OVR;
  if (pid) l.write(drv, ovr);  // drive 0 until the host's first sample
  struct Off {
    BoardLink& l;
    uint16_t drv;
    bool on;
    ~Off() {
      try {
        if (on) l.write(drv, 0);
      } catch (...) {  // the watchdog turns the drive off
      }
    }
  } off{l, drv, pid != nullptr};
  const double ts = double(read_ts_cycles(l)) / clk;
  TelemetryStream tlm(l, a, decim, std::llround(0.01 / ts));
  std::vector<TlmSample> v;
  // Start from rest: within 2 counts of the command for 20 ms (at most 0.5 s).
  int64_t still_since = -1;
  for (;;) {
    tlm.next(v);
    const TlmSample& x = v.back();
    if (std::abs(x.cmd - x.pos) > 2)
      still_since = -1;
    else if (still_since < 0)
      still_since = x.n;
    if ((still_since >= 0 && x.n - still_since >= std::llround(0.02 / ts)) ||
        x.n - v.front().n > std::llround(0.5 / ts))
      break;
  }
  v.erase(v.begin(), v.end() - 1);
  std::vector<seg::Words> batch;
  batch.reserve(segs.size());
  for (const PlannedSegment& p : segs) batch.push_back(seg::pack(p.seg));
  if (!l.segments(batch)) throw BoardError("the interpolator queue is full");
  const int64_t n0 = v.front().n;
  int64_t last_w = -1;
  Clock::time_point last_wall{};
  std::vector<double> t, c, y;
  size_t done = 0;
  while (v.back().n - n0 < samples) {
    for (; done < v.size(); ++done) {
      const TlmSample& x = v[done];
      t.push_back(double(x.n - n0));
      c.push_back(x.cmd);
      y.push_back(x.pos);
      r.fault |= x.fault;
      if (!pid || (x.n - n0) % host_every != 0) continue;
      const double u = std::clamp(std::round(pid->update(x.cmd, x.pos)), -32767.0, 32767.0);
      l.write(drv, ovr | (uint32_t(int32_t(u)) & 0xFFFF));
      const auto now = Clock::now();
      const uint16_t hdr = uint16_t(l.read(br::TLM_HDR) & 0xFFFF);
      const int64_t w = x.n + int64_t(uint16_t(hdr - uint16_t(x.n)));
      r.latency_s.push_back(double(w - x.n));
      if (last_w >= 0) {
        r.period_s.push_back(double(w - last_w));
        r.wall_period_s.push_back(std::chrono::duration<double>(now - last_wall).count());
      }
      last_w = w;
      last_wall = now;
    }
    tlm.next(v);
  }
  r.gaps = tlm.gaps();
  r.follow = mc::sim::following_error(t, c, y);
  return r;
}

struct Dist {
  double mean = 0, p99 = 0, max = 0;
};
Dist dist(std::vector<double> v, double scale) {
  Dist d;
  if (v.empty()) return d;
  for (double& x : v) x *= scale;
  std::sort(v.begin(), v.end());
  for (double x : v) d.mean += x / double(v.size());
  d.p99 = v[std::min(v.size() - 1, size_t(std::ceil(0.99 * double(v.size()))) - 1)];
  d.max = v.back();
  return d;
}

void hostloop(const HostloopOptions& o) {
  const int a0 = parse_axis(o.axis);
  const double ts_host = parse_duration(o.ts, "--ts");
  const double duration = parse_duration(o.duration, "--duration");
  if (duration > 10) throw InputError("--duration", quote(o.duration), "at most 10 s");
  const double mm = parse_number(o.distance, "--distance");
  const double feed = parse_number(o.feed, "--feed");
  if (!(feed > 0)) throw InputError("--feed", quote(o.feed), "a feed above 0 mm/min");
  const double cpm = machine_scale(a0, o.axis);
  const mc::sim::MachineConfig mach = machine();
  Board b = open_board();
  BoardLink& l = *b.link;
  const int a = board_axis(l, o.axis);
  const AxisGains cur = read_gains(l, a);
  const double ts = cur.gains.ts;
  const int64_t every = std::llround(ts_host / ts);
  if (every < 1 || std::fabs(double(every) * ts - ts_host) > 1e-9)
    throw InputError("--ts", quote(o.ts), "a whole number of the board's Ts (" + format_duration(ts) + ")");
  // Two replies per host sample (the DRV write, the TLM_HDR read); the
  // host's samples must fall on frames.
  uint32_t decim = telemetry_decimation(ts, double(l.read(br::BAUD)), 2);
  while (every % decim != 0 && int64_t(decim) < every) ++decim;
  if (every % decim != 0) decim = uint32_t(every);
  const double delay = ts_host / 2 + mach.host_io_latency_s;
  const PidGains g = mc::sim::tuned_gains(mach, mach.axes.at(size_t(a)), ts_host, delay);
  const double olim = cur.limits.out_limit ? double(cur.limits.out_limit) : 32767;
  mc::host::PidDouble pid(g, olim);
  const int32_t counts = int32_t(std::llround(mm * 1e-3 * cpm));
  if (counts == 0) throw InputError("--distance", quote(o.distance), "a move of at least one count");
  arm_axis(l, a);
  catch_interrupts();
  const int64_t samples = std::llround(duration / ts);
  const double fc = feed / 60e3 * cpm;
  const LoopRun host = run_jog(l, a, counts, fc, decim, samples, every, &pid);
  const LoopRun fpga = run_jog(l, a, -counts, fc, decim, samples, 0, nullptr);
  const Dist per = dist(host.period_s, ts), lat = dist(host.latency_s, ts),
             wall = dist(host.wall_period_s, 1);
  const double um = 1e6 / cpm;
  if (o.json) {
    nlohmann::ordered_json j;
    j["axis"] = axis_name(a);
    j["ts_host_s"] = ts_host;
    j["ts_board_s"] = ts;
    j["host_gains"] = pid_json(g);
    j["decimation"] = decim;
    j["host_samples"] = host.period_s.size() + 1;
    j["period_board_s"] = {{"mean", per.mean}, {"p99", per.p99}, {"max", per.max}};
    j["latency_board_s"] = {{"mean", lat.mean}, {"p99", lat.p99}, {"max", lat.max}};
    j["period_wall_s"] = {{"mean", wall.mean}, {"p99", wall.p99}, {"max", wall.max}};
    j["host_following_error_um"] = {{"rms", host.follow.rms * um}, {"max", host.follow.max * um}};
    j["fpga_following_error_um"] = {{"rms", fpga.follow.rms * um}, {"max", fpga.follow.max * um}};
    j["gaps"] = host.gaps + fpga.gaps;
    j["faults"] = fault_names(uint32_t(host.fault | fpga.fault));
    std::cout << j.dump(2) << '\n';
    return;
  }
  char line[400];
  std::snprintf(
      line, sizeof line,
      "host loop on axis %s: PID in double precision every %s of board time (paced by telemetry, every "
      "%u board samples per frame), drive through the DRV override\n  gains (sim::tuned_gains for a "
      "%s delay): %s\n",
      axis_name(a), format_duration(ts_host).c_str(), decim, format_duration(delay).c_str(),
      gains_line(g).c_str());
  std::cout << line;
  std::snprintf(line, sizeof line,
                "  %zu host samples; period (board time, resolution %s): mean %s, p99 %s, max %s\n"
                "  latency frame -> drive written (board time): mean %s, p99 %s, max %s\n"
                "  host wall-clock period: mean %s, p99 %s, max %s (the virtual board runs slower than real "
                "time)\n",
                host.period_s.size() + 1, format_duration(ts).c_str(), format_duration(per.mean).c_str(),
                format_duration(per.p99).c_str(), format_duration(per.max).c_str(),
                format_duration(lat.mean).c_str(), format_duration(lat.p99).c_str(),
                format_duration(lat.max).c_str(), format_duration(wall.mean).c_str(),
                format_duration(wall.p99).c_str(), format_duration(wall.max).c_str());
  std::cout << line;
  std::snprintf(
      line, sizeof line,
      "following error, %.3g mm jog at %.4g mm/min, %s captured:\n  host loop %s: RMS %.1f um, max %.1f "
      "um\n  FPGA loop %s: RMS %.1f um, max %.1f um (the board's own PID, same move back)\n",
      mm, feed, format_duration(duration).c_str(), format_duration(ts_host).c_str(), host.follow.rms * um,
      host.follow.max * um, format_duration(ts).c_str(), fpga.follow.rms * um, fpga.follow.max * um);
  std::cout << line;
  if (host.gaps + fpga.gaps) std::cout << "telemetry gaps: " << host.gaps + fpga.gaps << '\n';
  if (host.fault | fpga.fault)
    std::cout << "FAULT: " << fault_names(uint32_t(host.fault | fpga.fault)) << '\n';
}

}  // namespace

void add_step_commands(CLI::App& app) {
  auto o = std::make_shared<StepOptions>();
  CLI::App* st = app.add_subcommand("step", "Step response of an axis: rise, overshoot, settling, IAE");
  st->footer(
      std::string(kFooter) +
      "\nArms the drives, enables the axis' PID, streams telemetry (POS, CMD, ERR, OUT) at the finest\n"
      "decimation the link carries at the board's Ts, steps the command by --size from where it is,\n"
      "and captures --duration of board time. Gaps in the telemetry are reported, never filled in.");
  st->add_option("--axis", o->axis, "x, y or z")->required()->type_name("AXIS");
  st->add_option("--size", o->size, "Step size, mm, signed (default 1)")->type_name("MM");
  st->add_option("--duration", o->duration, "Capture after the step, board time (default 0.2s)")
      ->type_name("TIME");
  st->add_option("--plot", o->plot, "Write a PNG of command, position and output (gnuplot)")
      ->type_name("F.png");
  st->add_option("--csv", o->csv, "Write t,cmd,pos,err,out as CSV")->type_name("F.csv");
  st->add_flag("--json", o->json, "One JSON object");
  st->callback([o] { step(*o); });

  auto t = std::make_shared<TuneOptions>();
  CLI::App* tu =
      app.add_subcommand("tune", "Autotune an axis: identify (or relay), design, predict; --apply writes");
  tu->footer(
      std::string(kFooter) +
      "\nmodel: the axis runs open loop under a PRBS of +-4096 drive units for 1 s of board time (an\n"
      "error-clamped P-only controller far from its command), is identified as K/(s(tau s+1)), and\n"
      "gains are placed for --bandwidth (rad/s; default from the model) and --zeta (default 2).\n"
      "relay: the board itself runs a relay of +-8192 drive units for 0.3 s; Ku, Tu -> Tyreus-Luyben.\n"
      "The previous gains are restored after the experiment unless --apply. docs/tuning.md explains.");
  tu->add_option("--axis", t->axis, "x, y or z")->required()->type_name("AXIS");
  tu->add_option("--method", t->method, "model (default) or relay")->type_name("METHOD");
  tu->add_option("--bandwidth", t->bandwidth, "Closed-loop bandwidth wc, rad/s (model)")->type_name("RAD/S");
  tu->add_option("--zeta", t->zeta, "Damping of the dominant pair (model, default 2)")->type_name("Z");
  tu->add_flag("--apply", t->apply, "Write the proposed gains (read back and verified)");
  tu->add_flag("--json", t->json, "One JSON object");
  tu->callback([t] { tune(*t); });

  auto h = std::make_shared<HostloopOptions>();
  CLI::App* hl =
      app.add_subcommand("hostloop", "The PC's control loop, live: the host runs the PID, the board moves");
  hl->footer(
      std::string(kFooter) +
      "\nThe board's PID output is bypassed (DRV override); every --ts of BOARD time (telemetry frames\n"
      "are the clock) the host runs the same PID in double precision on the streamed CMD and POS and\n"
      "writes the drive. A jog of --distance at --feed runs under the host loop, then the same move back\n"
      "under the board's PID. Reports the host's periods and latency (board time) and both following\n"
      "errors. docs/motionctl.md says what the jitter means on the virtual board.");
  hl->add_option("--axis", h->axis, "x, y or z")->required()->type_name("AXIS");
  hl->add_option("--ts", h->ts, "Host loop period, a whole number of the board's Ts (default 10ms)")
      ->type_name("TIME");
  hl->add_option("--duration", h->duration, "Capture per run, board time (default 0.6s)")->type_name("TIME");
  hl->add_option("--distance", h->distance, "Jog, mm (default 2)")->type_name("MM");
  hl->add_option("--feed", h->feed, "mm/min (default 600)")->type_name("MM/MIN");
  hl->add_flag("--json", h->json, "One JSON object");
  hl->callback([h] { hostloop(*h); });
}

}  // namespace mc::host::cli
