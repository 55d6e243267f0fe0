// The handwheel (MPG, manual pulse generator) jog as the operator sets it:
// which axis the wheel moves and how far a detent goes. The board does the
// jogging itself (MPG, MPG_INC and IO_STAT in docs/protocol.md, rtl/mc_io.v):
// each detent adds `step` counts to a pending count, and while the drives
// are armed and no program runs it moves the axis's command by what is
// pending, under the usual following-error and limit checks.
//
// A step is in board counts, not in mm: x1, x10, x100 move 1, 10, 100
// encoder counts a detent, which is mm_per_detent() mm on the machine's
// axis (Grbl's 0.001/0.01/0.1 mm holds only for an axis of 1000 counts/mm).
//
//   set_mpg(link, machine, parse_mpg("x10"));  // the wheel on X, 10 counts a detent
//   mpg_pending(link);                         // counts the board has still to move
//   set_mpg(link, machine, {});                // off: what is pending is dropped
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "host/link/board_link.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::machine {

struct MpgSetting {
  int axis = -1;  // 0, 1, 2: x, y, z; -1: the handwheel off
  int step = 1;   // board counts a detent: 1, 10 or 100
  bool on() const { return axis >= 0; }
  bool operator==(const MpgSetting&) const = default;
};

// "off", or an axis letter and a step with an optional comma or space
// between: "x10", "X,10", "z 1". InputError naming `what` otherwise.
MpgSetting parse_mpg(std::string_view text, std::string_view what = "handwheel");
// "off", "x10": what parse_mpg reads back.
std::string mpg_text(const MpgSetting& s);
// A step as typed ("10"): InputError naming `what` unless 1, 10 or 100.
int parse_mpg_step(std::string_view text, std::string_view what = "handwheel step");

// The table travel of one detent on the setting's axis, mm (0 when off).
double mm_per_detent(const MachineConfig& m, const MpgSetting& s);
// MPG's rate field for the axis: 16-clock units between the counts it
// moves, the fewest that keep the axis within its max_speed_m_s.
uint32_t mpg_rate(const MachineConfig& m, int axis);

// Sets the board's handwheel jog (written when it differs, verified):
// InputError for an axis the machine or the board lacks or a step not 1,
// 10 or 100, BoardError for a board built without the handwheel decoder.
// Turning it off, or to another axis or step, drops what is pending.
void set_mpg(mc::host::BoardLink& l, const MachineConfig& m, const MpgSetting& s);
// The setting the board holds (a step set through MPG_INC reads as its value).
MpgSetting read_mpg(mc::host::BoardLink& l);
// Counts the board has still to move for the handwheel (IO_STAT), signed.
int32_t mpg_pending(mc::host::BoardLink& l);

// The jogged axis as the board reports it.
struct MpgSample {
  double wall_s = 0;         // since follow_mpg started
  int32_t pending = 0;       // mpg_pending
  int64_t cmd = 0, pos = 0;  // AX_CMD, AX_POS: board counts
  bool operator==(const MpgSample&) const = default;
};
// Keeps the link alive (the board's watchdog holds the drives armed only
// while frames come) for `seconds` of wall time while the board jogs `axis`,
// calling on_change (may be empty) with each sample that differs from the
// one before; then until nothing is pending and the axis stands within
// kInPosition of its command (or kSettleTimeout passed), so the last
// sample, returned, is where the axis stays.
MpgSample follow_mpg(mc::host::BoardLink& l, int axis, double seconds,
                     const std::function<void(const MpgSample&)>& on_change);

}  // namespace mc::machine
