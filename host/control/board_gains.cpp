#include "host/control/board_gains.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/link/board_state.hpp"

namespace mc::host {

namespace br = board::reg;

AxisGains read_gains(BoardLink& l, int axis) {
  AxisGains g;
  const uint8_t a = uint8_t(axis);
  const uint8_t regs[] = {pid_reg::KP, pid_reg::KI, pid_reg::KD_A, pid_reg::KD_B, pid_reg::KF1, pid_reg::KF2};
  for (size_t i = 0; i < 6; ++i) g.words[i] = l.read(pid_reg::addr(a, regs[i]));
  g.limits.out_limit = l.read(pid_reg::addr(a, pid_reg::OLIM));
  g.limits.int_limit = l.read(pid_reg::addr(a, pid_reg::ILIM));
  g.limits.deadband = l.read(pid_reg::addr(a, pid_reg::DBAND));
  g.limits.err_limit = l.read(pid_reg::addr(a, pid_reg::ELIM));
  g.ferr = l.read(br::axis(axis, br::AX_FERR));
  const double ts = double(read_ts_cycles(l)) / double(l.read(br::CLK_HZ));
  // The fraction bits of each word's operand, as design() quantizes them.
  PidGains probe{1, 1, 1, ts, ts, 0, 0};
  const PidDesign ref = design(probe);
  double v[6];
  for (size_t i = 0; i < 6; ++i) v[i] = realize(mc::coef_unpack(g.words[i]), ref.fixed[i].fx);
  const double kp = v[0], ki = v[1], alpha = v[2], beta = v[3], kf1 = v[4], kf2 = v[5];
  PidGains& p = g.gains;
  p.ts = ts;
  p.kp = kp;
  p.ki = 2 * ki / ts;
  p.tf = alpha >= 1 ? 0 : std::max(0.0, ts * (1 + alpha) / (2 * (1 - alpha)));
  p.kd = beta * (2 * p.tf + ts) / 2;
  p.ff1 = kf1 * ts;
  p.ff2 = kf2 * ts * ts;
  return g;
}

void write_gains(BoardLink& l, int axis, const PidDesign& d, const CoreLimits& lim) {
  const mc::PidParams p = core_params(d, lim);
  for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
    l.write_verify(pid_reg::addr(uint8_t(axis), uint8_t(r)), p.word[r]);
}

std::vector<std::string> design_warnings(const PidDesign& d) {
  std::vector<std::string> w;
  char line[256];
  for (const FixedCoef& f : d.fixed) {
    if (f.lost) {
      std::snprintf(line, sizeof line,
                    "%s = %s = %.6g is below the resolution of its word and is realized as 0",
                    std::string(f.name).c_str(), std::string(f.formula).c_str(), f.design);
      w.push_back(line);
    } else if (f.rel_error > 1e-3) {
      std::snprintf(line, sizeof line, "%s = %.6g is realized as %.6g (%.2g %% off the design)",
                    std::string(f.name).c_str(), f.design, f.value, 100 * f.rel_error);
      w.push_back(line);
    }
  }
  return w;
}

uint32_t check_gains(BoardLink& l, const PidGains& g, const GainNames& names) {
  const double clk = double(l.read(br::CLK_HZ));
  const uint32_t latency = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_LATENCY));
  const uint32_t cycles = core_ts_cycles(g.ts, clk, latency, names.ts, names.ts_text);
  check_core_kp(g.kp, names.kp, names.kp_text);
  design(g);  // every coefficient within its word
  return cycles;
}

AxisGains apply_gains(BoardLink& l, int axis, const PidGains& g, const CoreLimits& lim, const Note& warn,
                      const GainNames& names) {
  // Everything is checked before the first write: a refused input leaves
  // the board as it was.
  const uint32_t cycles = check_gains(l, g, names);
  const PidDesign d = design(g);
  if (warn)
    for (const std::string& w : design_warnings(d))
      warn("axis " + std::string(1, "xyz"[axis % 3]) + ": " + w);
  const uint16_t ts_addr = pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS);
  const uint32_t old_ts = l.read(ts_addr);
  std::array<uint32_t, pid_reg::NREGS_RAM> old{};
  for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
    old[size_t(r)] = l.read(pid_reg::addr(uint8_t(axis), uint8_t(r)));
  try {
    if (old_ts != cycles) l.write_verify(ts_addr, cycles);
    write_gains(l, axis, d, lim);
  } catch (const std::exception& e) {
    // A write the board refused half-way: put back what was there.
    std::string left;
    try {
      l.write_verify(ts_addr, old_ts);
      for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
        l.write_verify(pid_reg::addr(uint8_t(axis), uint8_t(r)), old[size_t(r)]);
      left = "restored the previous Ts and gains";
    } catch (const std::exception& r) {
      left = "could not restore the previous Ts (" + std::to_string(old_ts) +
             " cycles) and gains: " + r.what() + "; check with 'motionctl gains show'";
    }
    throw BoardError(std::string(e.what()) + "; " + left);
  }
  return read_gains(l, axis);
}

bool ts_change_affects_other_axes(BoardLink& l, int axis, double ts) {
  const uint32_t old = read_ts_cycles(l);
  bool others = false;  // another axis has gains designed for the old period
  for (int x = 0; x < read_naxes(l); ++x)
    others = others || (x != axis && l.read(pid_reg::addr(uint8_t(x), pid_reg::KP)) != 0);
  return others && std::llround(ts * double(l.read(br::CLK_HZ))) != old;
}

}  // namespace mc::host
