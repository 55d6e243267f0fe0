#include "host/control/board_experiments.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "host/base/errors.hpp"
#include "host/control/board_gains.hpp"
#include "host/control/tuning.hpp"
#include "host/link/board_state.hpp"
#include "host/motion/board_run.hpp"

namespace mc::host {

namespace br = board::reg;
namespace bb = board::bits;

// Loads the interpolator with `target` for axis a and the current command
// for the others: the command steps at the next sample.
void set_command(BoardLink& l, int a, int32_t target) {
  if (l.read(br::IP_STAT) >> bb::IS_BUSY & 1)
    throw BoardError("the interpolator is busy: wait until the motion is done");
  std::vector<std::pair<int, int32_t>> at;
  for (int x = 0; x < read_naxes(l) && x < 3; ++x)
    at.emplace_back(x, x == a ? target : int32_t(l.read(br::axis(x, br::AX_CMD))));
  set_position(l, at);
}

namespace {

// work(), then restore(), whether work succeeded or threw; when both throw,
// work's error says more.
template <class Work, class Restore>
auto then_restore(const Work& work, const Restore& restore) {
  auto r = [&] {
    try {
      return work();
    } catch (...) {
      try {
        restore();
      } catch (...) {
      }
      throw;
    }
  }();
  restore();
  return r;
}

StepCapture capture_step_as_is(BoardLink& l, int a, int32_t counts, double duration, const Note& note) {
  StepCapture c;
  c.counts = counts;
  const double clk = double(l.read(br::CLK_HZ));
  c.ts = double(read_ts_cycles(l)) / clk;
  const double baud = double(l.read(br::BAUD));
  c.frame_s = board_tx_seconds(telemetry_frame_bytes(1), 1, clk, baud);
  c.decim_needed = telemetry_decimation(c.ts, clk, baud, 0);
  // Two replies may queue in front of a frame: the step's writes, a PING.
  c.decim = telemetry_decimation(c.ts, clk, baud, 2);
  enable_axes(l, {a}, note);
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
}  // namespace

StepCapture capture_step(BoardLink& l, int a, int32_t counts, double duration, const Note& note,
                         uint32_t ferr_counts) {
  if (ferr_counts == 0) return capture_step_as_is(l, a, counts, duration, note);
  const uint16_t ferr = br::axis(a, br::AX_FERR);
  const uint32_t ferr_before = l.read(ferr) & 0xFFFF;
  l.write_verify(ferr, ferr_counts, 0xFFFF);
  return then_restore([&] { return capture_step_as_is(l, a, counts, duration, note); },
                      [&] { l.write_verify(ferr, ferr_before, 0xFFFF); });
}

Snapshot snapshot(BoardLink& l, int a) {
  Snapshot s;
  s.ts_reg = l.read(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS));
  for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
    s.ram[size_t(r)] = l.read(pid_reg::addr(uint8_t(a), uint8_t(r)));
  s.ferr = l.read(br::axis(a, br::AX_FERR));
  for (int x = 0; x < read_naxes(l); ++x) s.ctrl.push_back(l.read(pid_reg::addr(uint8_t(x), pid_reg::CTRL)));
  return s;
}

void restore(BoardLink& l, int a, const Snapshot& s) {
  set_position(l, {{a, int32_t(l.read(br::axis(a, br::AX_POS)))}});
  l.write_verify(pid_reg::addr(pid_reg::GLOBAL_AXIS, pid_reg::G_TS), s.ts_reg);
  for (int r = 0; r < pid_reg::NREGS_RAM; ++r)
    l.write_verify(pid_reg::addr(uint8_t(a), uint8_t(r)), s.ram[size_t(r)]);
  l.write_verify(br::axis(a, br::AX_FERR), s.ferr, 0xFFFF);
  for (size_t x = 0; x < s.ctrl.size(); ++x)
    l.write_verify(pid_reg::addr(uint8_t(x), pid_reg::CTRL), s.ctrl[x], 1);
}

// Runs the axis alone under a P-only controller with an error clamp, so
// that far from its command it gets exactly +-Kp * clamp (docs/tuning.md).
void p_only(BoardLink& l, int a, double kp, double ts, uint32_t out_limit, uint32_t err_clamp,
            const Note& note) {
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

// Open loop through the clamp: the command jumps 2^20 counts either side of
// the start at the PRBS' bit changes (paced on the board's sample count),
// so the error stays clamped and u = +-amplitude; u and y come from the same
// telemetry frames, every sample.
Experiment model_experiment(BoardLink& l, int a, double ts_board, const Note& note) {
  constexpr uint32_t kClamp = 64;
  const double amp = TuneDefaults::prbs_amplitude;
  Experiment e;
  // Two writes per bit change may queue in front of a frame.
  e.ts = ts_board * telemetry_decimation(l, ts_board, 2);
  p_only(l, a, amp / kClamp, e.ts, 32767, kClamp, note);
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
      set_position(l, {{a, start + int32_t(sign * (1 << 20))}});
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
Experiment relay_experiment(BoardLink& l, int a, double ts_board, const Note& note) {
  const double d = TuneDefaults::relay_amplitude;
  p_only(l, a, d, ts_board, uint32_t(d), 0, note);
  Experiment e;
  // Two replies may queue in front of a frame, as in step: the start's
  // reads and writes follow each other as fast as the link carries them.
  const uint32_t decim = telemetry_decimation(l, ts_board, 2);
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

Experiment tune_experiment(BoardLink& l, int a, const std::string& method, double ts_board,
                           const Note& note) {
  if (method != "model" && method != "relay")
    throw InputError("tune method", quote(method), "model or relay");
  const Snapshot snap = snapshot(l, a);
  return then_restore(
      [&] {
        return method == "model" ? model_experiment(l, a, ts_board, note)
                                 : relay_experiment(l, a, ts_board, note);
      },
      [&] { restore(l, a, snap); });
}

// One jog of `counts` on axis a, captured every decim samples for
// `samples` board samples. With host_every > 0 the host runs `pid` every
// host_every samples on the frame's CMD and POS and writes the result
// through the DRV override; otherwise the board's PID drives.
LoopRun run_jog(BoardLink& l, int a, int32_t counts, double feed_counts_s, uint32_t decim, int64_t samples,
                int64_t host_every, PidDouble* pid, const Note& note) {
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
  r.follow = following_error(t, c, y);
  return r;
}

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

}  // namespace mc::host
