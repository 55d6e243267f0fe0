// The board's live state as the link reads it, its fault names, arming the
// drives, and loading the interpolator's position: the register sequences
// every board command shares.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "host/link/board_link.hpp"

namespace mc::host {

// Where a board operation says what it did on the way ("clearing the
// watchdog fault ..."); may be empty.
using Note = std::function<void(const std::string&)>;

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

// The number of axes the board was built with (INFO's NAXES field).
int read_naxes(BoardLink& l);

// What the board was built with, from INFO: "servo loops; step generators
// on x, y, z; handwheel" (the loops, the axes with a step generator, the
// handwheel decoder; "no loops", "no step generators" when absent).
std::string build_text(uint32_t info);

// "watchdog, limit x": the FAULT bits by name ("none" for 0).
std::string fault_names(uint32_t fault);

// The sample period register, cycles (the core clamps it to its latency).
uint32_t read_ts_cycles(BoardLink& l);

// Loads the interpolator's position registers of the listed (axis, counts)
// pairs and applies them with one IP_CTRL.set strobe: the commands jump
// there at the next sample. Axes not listed keep the value last loaded, so
// callers that must not move them list them with their current command.
void set_position(BoardLink& l, const std::vector<std::pair<int, int32_t>>& axes);

// Arms the drives. A watchdog fault alone (left by the previous command's
// exit, by design) is cleared first, with a note through `note`; any other
// latched fault is an error naming it. When the drives were off, the
// interpolator is aborted and set to the encoder positions first, so the
// command starts where the axes are, and IO_CTRL is cleared, so the spindle
// and coolant a command left on (the board dropped them when it disarmed)
// do not start again by themselves. Returns the interpolator position.
std::array<int64_t, 3> arm(BoardLink& l, const Note& note);
// A stopped axis counts as arrived within kInPosition counts of its
// command (a servo settles there within a few counts; senders compare the
// position with the program's end point to the micrometre they print), or
// kSettleTimeout after the command stopped: a stuck axis must not hold
// anything forever.
constexpr int32_t kInPosition = 2;
constexpr std::chrono::milliseconds kSettleTimeout{500};

// Aborts the interpolator (queue flushed, command held) and returns where
// its command stands, once AX_CMD shows it (from the next PID sample on).
std::array<int64_t, 3> abort_interpolator(BoardLink& l);
// Where arm() would start a command, without changing anything: the
// interpolator's command when armed, else the encoder positions. Commands
// check a move against the machine's limits from here before they arm.
std::array<int64_t, 3> start_position(BoardLink& l);

// The machine frame the board keeps for the host (HOMED, ORIGIN): each
// axis's board count (POS, CMD) at machine zero, and which axes a homing
// cycle set it for. A board at power-up has none homed and every origin 0,
// so machine coordinates then count from where the axes were; the frame
// goes with the board's counts, which is why the board keeps it and no file
// on the host does.
struct MachineOrigin {
  std::array<int64_t, 3> counts{};
  uint32_t homed = 0;  // bit a: axis a homed
  bool is_homed(int a) const { return homed >> a & 1; }
  // Board counts to machine counts and back.
  std::array<int64_t, 3> machine(const std::array<int64_t, 3>& board) const {
    return {board[0] - counts[0], board[1] - counts[1], board[2] - counts[2]};
  }
  std::array<int64_t, 3> board(const std::array<int64_t, 3>& machine) const {
    return {machine[0] + counts[0], machine[1] + counts[1], machine[2] + counts[2]};
  }
  // Axis a's board count as machine mm, at counts_per_m.
  double mm(int a, int64_t board, double counts_per_m) const {
    return double(board - counts[size_t(a)]) / counts_per_m * 1e3;
  }
};
MachineOrigin read_origin(BoardLink& l);
// Sets axis a's origin and marks it homed, verified by reading back.
void write_origin(BoardLink& l, int a, int64_t counts);
// Forgets the homing of the axes in `mask` (origins kept, as a sender's
// position does not jump): a cycle that fails part way starts it.
void clear_homed(BoardLink& l, uint32_t mask);

// InputError unless axis a has gains (Kp or Ki nonzero), naming the commands
// that set them.
void require_gains(BoardLink& l, int a);
// InputError unless axis a's PID is enabled.
void require_enabled(BoardLink& l, int a);
// Checks every axis has gains, arms the drives, then enables the axes' PIDs.
// Returns the interpolator position, as arm() does (AX_CMD reads the new
// position only from the next sample on).
std::array<int64_t, 3> enable_axes(BoardLink& l, const std::vector<int>& axes, const Note& note);
// Disables the axes' PIDs; with drives_off, first turns the drives off.
void disable_axes(BoardLink& l, const std::vector<int>& axes, bool drives_off);
// Clears the latched faults; returns what was latched (0: none). BoardError
// when a fault's cause is still present.
uint32_t clear_faults(BoardLink& l);

}  // namespace mc::host
