// Grbl's `$` settings and the rest of what Grbl keeps in EEPROM (start-up
// blocks, build info, work offsets), with their defaults taken from the
// machine TOML and their persistence: a small TOML file next to the machine
// file (settings_path_for()), rewritten whole on every change.
//
// Numbers follow Grbl 1.1 ($0..$32, $100..$132 for X, Y, Z), so that a
// sender's settings page shows and edits them unchanged. docs/grbl.md lists
// which ones act on MotionCore and which are kept only for senders.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "host/gcode/interpreter.hpp"
#include "host/machine/machine_config.hpp"

namespace mc::grbl {

struct Settings {
  int step_pulse_us = 10;                   // $0   kept for senders (no step pulses here)
  int step_idle_delay_ms = 25;              // $1   kept for senders
  int step_invert_mask = 0;                 // $2   kept for senders
  int dir_invert_mask = 0;                  // $3   kept for senders
  bool invert_enable = false;               // $4   kept for senders
  bool invert_limits = false;               // $5
  bool invert_probe = false;                // $6
  int report_mask = 1;                      // $10  bit 0: MPos (else WPos), bit 1: Bf:
  double junction_deviation_mm = 0.010;     // $11
  double arc_tolerance_mm = 0.002;          // $12
  bool report_inches = false;               // $13
  bool soft_limits = false;                 // $20  needs $22
  bool hard_limits = false;                 // $21
  bool homing = false;                      // $22
  int homing_dir_mask = 0;                  // $23
  double homing_feed_mm_min = 25;           // $24
  double homing_seek_mm_min = 500;          // $25
  int homing_debounce_ms = 250;             // $26
  double homing_pulloff_mm = 1;             // $27
  double spindle_max_rpm = 1000;            // $30
  double spindle_min_rpm = 0;               // $31
  bool laser_mode = false;                  // $32
  std::array<double, 3> counts_per_mm{};    // $100..$102 (Grbl's steps/mm)
  std::array<double, 3> max_rate_mm_min{};  // $110..$112
  std::array<double, 3> accel_mm_s2{};      // $120..$122
  std::array<double, 3> max_travel_mm{};    // $130..$132
  // Not a Grbl setting: the machine coordinate of each axis' positive end
  // (the machine TOML's travel_max_m). Soft limits allow travel_top_mm - $13x
  // up to travel_top_mm; Grbl's 0 at the top is the case travel_top_mm = 0.
  std::array<double, 3> travel_top_mm{};
};

// Defaults for `machine`: counts per mm from encoder, gear and lead, max rate
// from max_speed_m_s, acceleration from max_accel_m_s2, travel from
// travel_min_m..travel_max_m, junction deviation and arc tolerance from
// [planner], homing ($23 direction, $24 locate and $25 seek feeds, $27
// pull-off) from the [home] tables (the slowest feeds, the longest
// pull-off); an axis the machine lacks takes the last axis' values.
Settings default_settings(const mc::machine::MachineConfig& machine);

// The setting numbers, in the order `$$` prints them.
const std::vector<int>& setting_numbers();
// `$N=value`: 0 when stored, else Grbl's status code (3 no such setting,
// 4 negative value, 10 soft limits without homing).
int set_setting(Settings& s, int number, double value);
// The value of setting `number` (which must exist).
double get_setting(const Settings& s, int number);
// "$11=0.010": integers plainly, others with 3 decimals, as Grbl.
std::string format_setting(const Settings& s, int number);

// All that persists across resets and restarts: Grbl's EEPROM.
struct Stored {
  Settings settings;
  std::array<std::string, 2> startup;  // $N0, $N1
  std::string build_info;              // $I=
  mc::gcode::PersistentData offsets;   // G54..G59.3, G28, G30 (G92 is not kept, as Grbl)
};

// MACHINE.toml -> MACHINE.grbl.toml; the built-in machine (empty path) ->
// $XDG_CONFIG_HOME/motionctl/grbl.toml (else ~/.config/motionctl/grbl.toml).
std::string settings_path_for(const std::string& machine_path);

// Reads `path` over `defaults`: a key that is absent keeps its default. A
// missing file gives the defaults. Bad TOML, an unknown key or a bad value is
// an mc::host::InputError naming the file, the line and the key.
Stored load_stored(const std::string& path, const Stored& defaults);
// Writes the whole file (to a temporary, then renamed); throws
// std::runtime_error naming the file when it cannot.
void save_stored(const std::string& path, const Stored& stored);

}  // namespace mc::grbl
