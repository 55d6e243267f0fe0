// RS274/NGC interpreter for 3-axis mills, routers and drills, in the dialect
// Grbl 1.1 and LinuxCNC users write, with LinuxCNC's semantics (the NIST
// order of execution within a line). It turns text into canonical calls
// (canon.hpp) in machine millimetres. See docs/gcode.md for the words.
//
// Two ways to use it:
//  - a whole file: interpret_file()/interpret_program() check every line
//    before anything moves and return either all the calls or all the errors;
//  - a line server: an Interpreter keeps the modal state between
//    execute_line() calls, reports it for $G and exposes the persistent data
//    (work offsets, G28/G30 positions, G92) for the caller to save.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "host/gcode/canon.hpp"
#include "host/gcode/error.hpp"

namespace mc::gcode {

enum class Units { mm, inch };                                 // G21, G20
enum class Distance { absolute, incremental };                 // G90/G91, G90.1/G91.1
enum class RetractMode { initial_level, r_plane };             // G98, G99
enum class SpindleState { off, clockwise, counterclockwise };  // M5, M3, M4

// The motion group (group 1), as G code x 10: 0 (G0), 10, 20, 30, 382..385,
// 730, 800 (G80: none), 810, 820, 830.
using MotionCode = int;

struct ModalState {
  MotionCode motion = 800;  // G80 after power-up, as LinuxCNC (Grbl starts in G0)
  Plane plane = Plane::xy;
  Units units = Units::mm;
  Distance distance = Distance::absolute;
  Distance arc_distance = Distance::incremental;  // G91.1
  FeedMode feed_mode = FeedMode::units_per_minute;
  int coord_system = 0;  // 0..8: G54, G55, ..., G59, G59.1, G59.2, G59.3
  PathMode path_mode = PathMode::continuous;
  double path_tolerance_mm = 0.0;
  RetractMode retract = RetractMode::initial_level;
  SpindleState spindle = SpindleState::off;
  double spindle_rpm = 0.0;
  bool mist = false;
  bool flood = false;
  double feed = 0.0;            // mm/min in G94; 1/min (inverse time) in G93; 0: none yet
  int tool = 0;                 // the tool in the spindle (after M6)
  int selected_tool = 0;        // the last T word
  double tool_length_mm = 0.0;  // G43.1 Z (0 after G49)
};

// The data a controller keeps across programs and power cycles (Grbl's
// EEPROM, LinuxCNC's .var file). All in machine mm.
struct PersistentData {
  std::array<Vec3, 9> coord_offsets{};  // G54..G59.3, set by G10 L2/L20
  Vec3 g28{};                           // G28.1
  Vec3 g30{};                           // G30.1
  Vec3 g92{};                           // G92 (kept while G92.2 suspends it)
  bool g92_applied = true;              // false after G92.2
};

// G-code words of the modal state, Grbl's $G style:
// "[GC:G1 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]".
std::string modal_report(const ModalState& state);

struct Options {
  Vec3 start{};               // machine position before the first line, mm
  PersistentData data{};      // offsets and stored positions at the start
  bool block_delete = false;  // true: skip lines starting with '/'
};

struct LineResult {
  std::vector<CanonCall> calls;
  std::optional<Error> error;  // set: the line did nothing, the state is unchanged
  bool ok() const { return !error.has_value(); }
};

class Interpreter {
 public:
  explicit Interpreter(const Options& options = {}, std::string file_name = "");

  // Runs one line. On error nothing changes and no call is returned.
  LineResult execute_line(std::string_view text, int line_no);

  const ModalState& modal() const { return modal_; }
  const PersistentData& data() const { return data_; }
  void set_data(const PersistentData& data) { data_ = data; }

  // Where the interpreter believes the machine is (mm). After a probe, a
  // jog or an abort the caller sets the real position.
  const Vec3& machine_position() const { return position_; }
  void set_machine_position(const Vec3& position) { position_ = position; }

  // The position in the current work coordinates and program units, as a
  // G-code line would name it (Grbl's WPos).
  Vec3 work_position() const;

  // True once M2/M30 ran; a file ends there.
  bool program_ended() const { return ended_; }

 private:
  friend class BlockExecutor;
  Options options_;
  std::string file_;
  ModalState modal_;
  PersistentData data_;
  Vec3 position_;
  bool ended_ = false;
  // Canned-cycle words that later blocks of the same cycle inherit.
  double cycle_r_ = 0.0;
  double cycle_cc_ = 0.0;
  double cycle_q_ = 0.0;
  double cycle_p_ = 0.0;
  // The initial level of the current series of cycles (G98), program units.
  double cycle_initial_ = 0.0;
  bool cycle_initial_set_ = false;
};

struct ProgramResult {
  std::vector<CanonCall> calls;  // empty when errors is not
  std::vector<Error> errors;     // every line's first error, in line order
  int lines = 0;                 // lines read (up to M2/M30 or the closing %)
  bool ok() const { return errors.empty(); }
};

// Checks and interprets a whole program. Stops reading at M2/M30 or at the
// '%' that closes a program opened with '%'.
ProgramResult interpret_program(std::string_view text, const std::string& file_name,
                                const Options& options = {});
// Same, from a file; a file that cannot be read is one error at line 0.
ProgramResult interpret_file(const std::string& path, const Options& options = {});

}  // namespace mc::gcode
