// What the interpreter says when a line is wrong: where, which word, what was
// expected, and the Grbl 1.1 error number when one fits so that a Grbl-style
// line server can answer "error:N".
#pragma once

#include <string>

namespace mc::gcode {

// Grbl 1.1 status codes (gcode.c's STATUS_*), for the errors that have one.
namespace grbl {
inline constexpr int none = 0;
inline constexpr int expected_command_letter = 1;
inline constexpr int bad_number_format = 2;
inline constexpr int negative_value = 4;
inline constexpr int unsupported_command = 20;
inline constexpr int modal_group_violation = 21;
inline constexpr int undefined_feed_rate = 22;
inline constexpr int command_value_not_integer = 23;
inline constexpr int axis_command_conflict = 24;
inline constexpr int word_repeated = 25;
inline constexpr int no_axis_words = 26;
inline constexpr int invalid_line_number = 27;
inline constexpr int value_word_missing = 28;
inline constexpr int unsupported_coord_sys = 29;
inline constexpr int g53_invalid_motion_mode = 30;
inline constexpr int axis_words_exist = 31;
inline constexpr int no_axis_words_in_plane = 32;
inline constexpr int invalid_target = 33;
inline constexpr int arc_radius_error = 34;
inline constexpr int no_offsets_in_plane = 35;
inline constexpr int unused_words = 36;
inline constexpr int g43_dynamic_axis_error = 37;
}  // namespace grbl

struct Error {
  std::string file;     // as given to the interpreter ("" for a line server)
  int line = 0;         // 1-based
  int column = 0;       // 1-based, of the offending word (1 if the line as a whole)
  std::string word;     // the offending word as written, upper case: "G41", "#", "R"
  int grbl_code = 0;    // grbl::* or 0 when none fits
  std::string message;  // what is wrong and what was expected

  // "FILE:LINE:COLUMN: error: WORD: MESSAGE (grbl error:N)"; parts that are
  // empty are left out.
  std::string format() const;
};

}  // namespace mc::gcode
