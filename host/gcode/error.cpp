#include "host/gcode/error.hpp"

namespace mc::gcode {

std::string Error::format() const {
  std::string out;
  if (!file.empty()) out += file + ":";
  out += std::to_string(line) + ":" + std::to_string(column) + ": error: ";
  if (!word.empty()) out += word + ": ";
  out += message;
  if (grbl_code != 0) out += " (grbl error:" + std::to_string(grbl_code) + ")";
  return out;
}

}  // namespace mc::gcode
