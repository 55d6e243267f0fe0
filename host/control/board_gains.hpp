// The PID gains as the board stores them: read back and inverted into
// gains, written and verified word by word, and the warnings a quantized
// design deserves.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "host/control/pid_design.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"

namespace mc::host {

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

// How errors name the gains: option names and the user's text for a CLI,
// keys for a file.
struct GainNames {
  std::string ts = "ts", ts_text, kp = "kp", kp_text;
};
// What the board can run, checked without writing: Ts a whole number of its
// clock cycles from its sweep latency (G_LATENCY) to kMaxTs, Kp up to
// kMaxKp, every coefficient within its word. Returns the Ts register value.
uint32_t check_gains(BoardLink& l, const PidGains& g, const GainNames& names = {});
// check_gains, then writes the sample period (shared by all axes) when it
// changes, designs and writes the axis' gains and limits, verifies them word
// by word, and sends each design warning to `warn`. Returns what the board
// holds afterwards. A write that fails half-way puts back the previous Ts
// and words, and the BoardError says whether that worked.
AxisGains apply_gains(BoardLink& l, int axis, const PidGains& g, const CoreLimits& lim, const Note& warn,
                      const GainNames& names = {});
// Whether writing Ts = ts for `axis` changes the period under another axis
// that has gains (Ts is shared: their gains then run at the new period).
bool ts_change_affects_other_axes(BoardLink& l, int axis, double ts);

}  // namespace mc::host
