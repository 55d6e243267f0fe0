// Board operations the motionctl board commands share, on top of BoardLink:
// reading the live state, the PID gains as stored in the board's coefficient
// words, arming safely, and running planned segments to completion.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "board_link.hpp"
#include "interp_plan.hpp"
#include "pid_design.hpp"

namespace mc::host {

struct AxisState {
  int32_t pos = 0, cmd = 0, err = 0;
  int16_t u = 0;
  bool sat = false, pid_en = false, drv_en = false;
};

struct BoardState {
  uint32_t id = 0, clk_hz = 0, ts_cycles = 0, wdog = 0;
  int naxes = 0;
  uint32_t status = 0, fault = 0, ip_stat = 0, ip_segs = 0;
  uint32_t link_crc = 0, link_cmd = 0, link_junk = 0;
  std::vector<AxisState> axes;
  bool armed() const;
  double ts_s() const { return double(ts_cycles) / clk_hz; }
};
BoardState read_state(BoardLink& l);

// "watchdog, limit x": the FAULT bits by name ("none" for 0).
std::string fault_names(uint32_t fault);

// The sample period register, cycles (the core clamps it to its latency).
uint32_t read_ts_cycles(BoardLink& l);

// An axis' gains and limits as the board holds them.
struct AxisGains {
  PidGains gains{};
  CoreLimits limits;
  std::array<uint32_t, 6> words{};  // KP..KF2
  uint32_t ferr = 0;                // following-error limit, counts (0 off)
};
// The gains the coefficient words realize, inverting the design's formulas
// (kd_a = (2Tf-Ts)/(2Tf+Ts), ...); ts from the sample-period register.
AxisGains read_gains(BoardLink& l, int axis);
// Writes the design's words and the limits, reads each back and throws
// BoardError on a difference.
void write_gains(BoardLink& l, int axis, const PidDesign& d, const CoreLimits& lim);
// Warnings about a design whose quantized controller departs from it (empty: none).
std::vector<std::string> design_warnings(const PidDesign& d);

// Arms the drives. A watchdog fault alone (left by the previous command's
// exit, by design) is cleared first, with a note through `note`; any other
// latched fault is an error naming it. When the drives were off, the
// interpolator is aborted and set to the encoder positions first, so the
// command starts where the axes are. Returns the interpolator position.
std::array<int64_t, 3> arm(BoardLink& l, const std::function<void(const std::string&)>& note);

// Queues the segments (waiting while the queue is full), then polls until
// the interpolator has finished them, keeping the watchdog fed. Throws
// BoardError when a fault stops the motion. progress(done, total).
void run_segments(BoardLink& l, const std::vector<PlannedSegment>& segs,
                  const std::function<void(int, int)>& progress = {});

// A straight move split into segments the core accepts.
std::vector<PlannedSegment> plan_move(const Vec3& from, const Vec3& to, double feed_counts_s, double clk_hz);

}  // namespace mc::host
