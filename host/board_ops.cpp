#include "board_ops.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "errors.hpp"
#include "pid_regs.hpp"

namespace mc::host {

namespace br = board::reg;
namespace bb = board::bits;

bool BoardState::armed() const {
  return status & (1u << bb::ST_ARMED);
}

std::string fault_names(uint32_t f) {
  std::string s;
  const auto add = [&](const std::string& n) { s += (s.empty() ? "" : ", ") + n; };
  if (f & (1u << bb::F_WDOG)) add("watchdog");
  if (f & (1u << bb::F_ESTOP)) add("e-stop");
  static const char* const ax[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (f & (1u << (bb::F_LIMIT_LSB + a))) add(std::string("limit ") + ax[a]);
    if (f & (1u << (bb::F_FERR_LSB + a))) add(std::string("following error ") + ax[a]);
    if (f & (1u << (bb::F_ENC_LSB + a))) add(std::string("encoder ") + ax[a]);
  }
  return s.empty() ? "none" : s;
}

uint32_t read_ts_cycles(BoardLink& l) {
  const uint32_t ts = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS));
  const uint32_t lat = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_LATENCY));
  return std::max(ts, lat);
}

BoardState read_state(BoardLink& l) {
  BoardState s;
  s.id = l.read(br::ID);
  s.naxes = int(l.read(br::INFO) & 0xF);
  s.clk_hz = l.read(br::CLK_HZ);
  s.ts_cycles = read_ts_cycles(l);
  s.wdog = l.read(br::WDOG);
  s.status = l.read(br::STATUS);
  s.fault = l.read(br::FAULT);
  s.ip_stat = l.read(br::IP_STAT);
  s.ip_segs = l.read(br::IP_SEGS);
  s.link_crc = l.read(br::LINK_CRC);
  s.link_cmd = l.read(br::LINK_CMD);
  s.link_junk = l.read(br::LINK_JUNK);
  for (int a = 0; a < s.naxes; ++a) {
    AxisState x;
    x.pos = int32_t(l.read(br::axis(a, br::AX_POS)));
    x.cmd = int32_t(l.read(br::axis(a, br::AX_CMD)));
    x.err = int32_t(l.read(br::axis(a, br::AX_ERR)));
    const uint32_t out = l.read(br::axis(a, br::AX_OUT));
    x.u = int16_t(out & 0xFFFF);
    x.sat = out >> bb::O_SAT & 1;
    x.pid_en = out >> bb::O_PID_EN & 1;
    x.drv_en = out >> bb::O_DRV_EN & 1;
    s.axes.push_back(x);
  }
  return s;
}

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

std::array<int64_t, 3> arm(BoardLink& l, const std::function<void(const std::string&)>& note) {
  const int naxes = int(l.read(br::INFO) & 0xF);
  std::array<int64_t, 3> at{};
  const bool armed = l.read(br::STATUS) & (1u << bb::ST_ARMED);
  if (!armed) {
    const uint32_t fault = l.read(br::FAULT);
    if (fault == (1u << bb::F_WDOG)) {
      if (note)
        note("clearing the watchdog fault: the drives went off when the last command's link went quiet");
      l.write(br::FAULT, fault);
    } else if (fault != 0) {
      throw BoardError("fault latched: " + fault_names(fault) +
                       "; remove its cause, then run 'motionctl clear-fault'");
    }
    // The command starts where the axes are: nothing left over runs on.
    l.write(br::IP_CTRL, 1u << bb::I_ABORT | 1u << bb::I_CLR);
    for (int a = 0; a < naxes; ++a) {
      const int32_t pos = int32_t(l.read(br::axis(a, br::AX_POS)));
      l.write(uint16_t(br::IP_SET_X + a), uint32_t(pos));
      at[size_t(a)] = pos;
    }
    l.write(br::IP_CTRL, 1u << bb::I_SET);
    l.write(br::CTRL, 1u << bb::C_ARM);
    if (!(l.read(br::STATUS) & (1u << bb::ST_ARMED)))
      throw BoardError("the board did not arm (FAULT: " + fault_names(l.read(br::FAULT)) + ")");
  } else {
    for (int a = 0; a < naxes; ++a) at[size_t(a)] = int32_t(l.read(br::axis(a, br::AX_CMD)));
  }
  return at;
}

std::vector<PlannedSegment> plan_move(const Vec3& from, const Vec3& to, double feed, double clk_hz) {
  constexpr int64_t kMax = (int64_t(1) << seg::N_W) - 1;
  int64_t longest = 0;
  for (int a = 0; a < 3; ++a)
    longest = std::max<int64_t>(longest, std::llabs(to[size_t(a)] - from[size_t(a)]));
  const int64_t pieces = std::max<int64_t>(1, (longest + kMax - 1) / kMax);
  std::vector<PlannedSegment> v;
  Vec3 at = from;
  for (int64_t i = 1; i <= pieces; ++i) {
    Vec3 next;
    for (int a = 0; a < 3; ++a)
      next[size_t(a)] = from[size_t(a)] + (to[size_t(a)] - from[size_t(a)]) * i / pieces;
    if (next != at) v.push_back(plan_line(at, next, feed, clk_hz));
    at = next;
  }
  if (!v.empty()) v.back().seg.last = true;
  return v;
}

void run_segments(BoardLink& l, const std::vector<PlannedSegment>& segs,
                  const std::function<void(int, int)>& progress) {
  using Clock = std::chrono::steady_clock;
  const uint32_t segs0 = l.read(br::IP_SEGS) & 0xFFFF;
  const int total = int(segs.size());
  // The virtual board runs several times slower than real time: the limit
  // only catches a board that stopped moving.
  double board_s = 0;
  for (const PlannedSegment& p : segs) board_s += p.duration;
  const auto deadline = Clock::now() + std::chrono::duration<double>(30 + 100 * board_s);
  size_t sent = 0;
  int last_done = -1;
  for (;;) {
    if (sent < segs.size()) {
      std::vector<seg::Words> batch;
      for (size_t i = sent; i < segs.size() && batch.size() < 6; ++i) batch.push_back(seg::pack(segs[i].seg));
      if (l.segments(batch)) sent += batch.size();
    }
    const uint32_t fault = l.read(br::FAULT);
    if (fault) throw BoardError("motion stopped by a fault: " + fault_names(fault));
    const int done = int((l.read(br::IP_SEGS) - segs0) & 0xFFFF);
    const bool busy = l.read(br::IP_STAT) & (1u << bb::IS_BUSY);
    if (done != last_done && progress) progress(done, total);
    last_done = done;
    if (sent == segs.size() && done >= total && !busy) return;
    if (Clock::now() > deadline)
      throw BoardError("the move did not finish in time (" + std::to_string(done) + " of " +
                       std::to_string(total) + " segments done)");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

}  // namespace mc::host
