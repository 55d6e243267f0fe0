// The machine's limits applied to what a command asks of a board: moves
// within the soft travel and the axes' speeds, checked before anything moves,
// and the following-error limit armed on the board (FERR) with the drives,
// so that a runaway axis trips a fault instead of running on.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "host/link/board_link.hpp"
#include "host/machine/machine_config.hpp"
#include "host/motion/interp_plan.hpp"

namespace mc::machine {

// What the errors of the checks below call the input ("--distance", "target",
// "--size") and how the user wrote it.
struct Asked {
  std::string_view option, as_written;
};

// InputError unless every axis of `to` (board counts; axes the machine lacks
// ignored) lies within its travel_min_m..travel_max_m. from: where the move
// starts, for the message.
void check_travel(const MachineConfig& m, const mc::host::Vec3& from, const mc::host::Vec3& to,
                  const Asked& asked);
// The fastest feed along the path from `from` to `to` (counts) at which no
// axis exceeds its max_speed_m_s, mm/min; 0 when nothing moves.
double max_feed_mm_min(const MachineConfig& m, const mc::host::Vec3& from, const mc::host::Vec3& to);
// InputError unless 0 < feed <= max_feed_mm_min(m, from, to).
void check_feed(const MachineConfig& m, const mc::host::Vec3& from, const mc::host::Vec3& to,
                double feed_mm_min, const Asked& asked);

// mm as board counts at counts_per_m, saturated at +-2^53 (far beyond any
// travel), so that the travel check, not an overflow, answers "--distance 1e300".
int64_t counts_of(double mm, double counts_per_m);

// The board's following-error limit of each axis, counts (0 for an axis the
// machine lacks): max_following_error_m at the axis' scale, at least 1.
std::array<uint32_t, 3> ferr_counts(const MachineConfig& m);
// Writes and verifies FERR on each axis the machine has (and the board):
// ferr_counts() on the axes whose PID is enabled and on stepper axes, 0
// (off) on the others,
// whose position nothing holds (a Z carriage sinks under its weight while
// its PID is off). Commands call it when they connect and after they enable
// axes, so the limit holds whenever their drives are armed.
void arm_following_limits(mc::host::BoardLink& l, const MachineConfig& m);
// The FERR a step experiment needs on an axis: the step itself is a
// following error the moment it is commanded, so the limit is |step| plus
// the machine's margin; InputError naming `asked` when that exceeds the
// register's 16 bits.
uint32_t step_ferr_counts(const MachineConfig& m, int axis, int64_t step_counts, const Asked& asked);

}  // namespace mc::machine
