// Experiments on a live board, each a function of a BoardLink: the step
// response capture of `motionctl step`, the identification and relay
// experiments of `motionctl tune` (with the snapshot that puts the board back
// as it was), and the jog that `motionctl hostloop` runs under the host's PID
// or the board's own. The CLI parses options, calls these and prints.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hls/pid_regs.hpp"
#include "host/control/metrics.hpp"
#include "host/control/pid_double.hpp"
#include "host/control/step_metrics.hpp"
#include "host/link/board_capture.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"

namespace mc::host {

// Loads the interpolator with `target` for axis a and the current command
// for the others: the command steps at the next sample. BoardError while
// the interpolator is busy.
void set_command(BoardLink& l, int a, int32_t target);

// ---- step ---------------------------------------------------------------------------
struct StepCapture {
  double ts = 0;       // PID sample period, s
  double frame_s = 0;  // a one-axis telemetry frame's time on the line
  uint32_t decim = 1, decim_needed = 1;
  int32_t y0 = 0, counts = 0;
  std::vector<double> t;  // s from the step
  std::vector<TlmSample> s;
  int64_t gaps = 0, missing = 0;
  uint16_t fault = 0;
  StepMetrics m{};
};
// Arms axis a, streams telemetry at the finest decimation the link carries,
// steps the command by `counts` from where it is and captures `duration_s`
// of board time after the step. ferr_counts > 0: the axis' following-error
// limit during the capture (the step is itself a following error of
// |counts| the moment it is commanded); the previous limit is put back.
StepCapture capture_step(BoardLink& l, int a, int32_t counts, double duration_s, const Note& note,
                         uint32_t ferr_counts = 0);

// ---- tune ---------------------------------------------------------------------------
// What an experiment changes and restore() puts back: the sample period,
// the axis' coefficient RAM and following-error limit, every axis' enable.
struct Snapshot {
  uint32_t ts_reg = 0;
  std::array<uint32_t, pid_reg::NREGS_RAM> ram{};
  uint32_t ferr = 0;
  std::vector<uint32_t> ctrl;
};
Snapshot snapshot(BoardLink& l, int a);
void restore(BoardLink& l, int a, const Snapshot& s);

// Runs the axis alone under a P-only controller with an error clamp, so
// that far from its command it gets exactly +-Kp * clamp (docs/tuning.md).
void p_only(BoardLink& l, int a, double kp, double ts, uint32_t out_limit, uint32_t err_clamp,
            const Note& note);

struct Experiment {
  std::vector<double> u, y;
  double ts = 0;  // of the capture
};
// Open loop through the clamp under a PRBS (identification).
Experiment model_experiment(BoardLink& l, int a, double ts_board, const Note& note);
// A relay on the board at its own Ts (Ku, Tu).
Experiment relay_experiment(BoardLink& l, int a, double ts_board, const Note& note);
// One of the two ("model" or "relay"), with the board's state restored
// afterwards, whether the experiment succeeded or threw.
Experiment tune_experiment(BoardLink& l, int a, const std::string& method, double ts_board, const Note& note);

// ---- hostloop -----------------------------------------------------------------------
struct LoopRun {
  ErrorStats follow;  // counts
  std::vector<double> period_s, latency_s, wall_period_s;
  int64_t gaps = 0;
  uint16_t fault = 0;
};

// One jog of `counts` on axis a, captured every decim samples for
// `samples` board samples. With host_every > 0 the host runs `pid` every
// host_every samples on the frame's CMD and POS and writes the result
// through the DRV override; otherwise the board's PID drives.
LoopRun run_jog(BoardLink& l, int a, int32_t counts, double feed_counts_s, uint32_t decim, int64_t samples,
                int64_t host_every, PidDouble* pid, const Note& note);

// Mean, 99th percentile and maximum of v scaled by `scale`.
struct Dist {
  double mean = 0, p99 = 0, max = 0;
};
Dist dist(std::vector<double> v, double scale);

}  // namespace mc::host
