// The board set up for the machine's axes: which are servo loops and which
// stepper drivers, as [axis.N.stepper] in the machine file says.
//
// A servo axis is enabled through its PID (host/link/board_state.hpp's
// enable_axes); a stepper axis has no loop to enable: STEP_CFG makes its
// PWM/DIR pins STEP/DIR from the interpolator's command, and arming the
// drives starts it. The board must have been built for the machine: a step
// generator on every stepper axis, the loops when a servo axis exists
// (INFO; `make synth` builds the servo board, `make synth-stepper` the
// stepper one).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::machine {

// STEP_CFG for the machine: stepper bits, closed-loop bits, polarities, and
// the pulse and setup times in board clocks, the longest any stepper axis
// asks for (the register holds one pair for every driver).
uint32_t step_cfg_word(const MachineConfig& m);

// InputError unless a board whose INFO register reads `info` can drive the
// machine's axes: the axis count, a step generator on each stepper axis,
// the loops for a servo axis.
void check_board(const MachineConfig& m, uint32_t info);

// check_board on the board's INFO, then STEP_CFG := step_cfg_word(m),
// verified (written only when it differs, so it never interrupts a
// running generator for nothing).
void setup_axes(mc::host::BoardLink& l, const MachineConfig& m);

// Arms the drives with the machine's axes of `axes` ready to follow the
// command: servo axes PID-enabled (gains required), stepper axes just
// armed. Returns where the axes are (enable_axes' result).
std::array<int64_t, 3> enable_machine_axes(mc::host::BoardLink& l, const MachineConfig& m,
                                           const std::vector<int>& axes, const mc::host::Note& note);

// InputError unless axis a of the machine is a servo axis: `command`
// measures or tunes a PID loop, which a stepper axis has none of.
void require_servo(const MachineConfig& m, int a, std::string_view command);

// InputError if `alone` (one axis, the others left armed) names a stepper
// axis: its driver's enable is the shared DRV_EN, so only turning every
// drive off stops it.
void require_disable_alone(const MachineConfig& m, const std::vector<int>& axes, bool alone);

// Before a move of axis a: InputError if a servo axis's PID is disabled (a
// stepper axis is always ready: the move arms it).
void require_ready(mc::host::BoardLink& l, const MachineConfig& m, int a);

}  // namespace mc::machine
