// The spindle and coolant as a program sets them (M3/M4/M5 and S, M7/M8/M9;
// M2/M30 and M6 stop the spindle), and the board's IO_CTRL for them: SP_EN,
// SP_DIR (or mist), FLOOD and SP_PWM's duty from the speed ([spindle] in the
// machine file). The board drops every output while disarmed and on any
// fault by itself; the host only says what a running job wants.
#pragma once

#include <cstdint>

#include "host/gcode/canon.hpp"
#include "host/link/board_link.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::machine {

struct SpindleState {
  int dir = 0;     // 1 clockwise (M3), -1 counter-clockwise (M4), 0 off
  double rpm = 0;  // the last S word
  bool flood = false, mist = false;
  bool operator==(const SpindleState&) const = default;
  // Folds one action of a program in; other calls leave the state alone.
  void apply(const mc::gcode::CanonOp& op);
};

// SP_PWM's duty for `rpm`: high `duty` clocks of each 1024-clock period,
// linear from min_rpm (1) to max_rpm (1023, always on), as Grbl's $30/$31
// map speed to PWM; 0 at 0 rpm.
uint32_t spindle_duty(const SpindleConfig& c, double rpm);
// IO_CTRL for the state, the speed scaled by `speed_override` (1: 100 %).
uint32_t io_ctrl_word(const SpindleConfig& c, const SpindleState& s, double speed_override = 1);
// Writes IO_CTRL (verified) when it differs from the board's.
void write_spindle(mc::host::BoardLink& l, const MachineConfig& m, const SpindleState& s,
                   double speed_override = 1);

}  // namespace mc::machine
