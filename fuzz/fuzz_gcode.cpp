// libFuzzer target: the G-code interpreter (host/gcode) on arbitrary text,
// as a whole program (interpret_program) and line by line as a sender feeds
// it (Interpreter::execute_line). Beyond "no crash, no undefined behaviour":
// - a program with an error yields no calls;
// - a line with an error changes nothing: no calls, the same modal state,
//   the same position (the interpreter's own contract);
// - an accepted line leaves the machine at a finite position;
// - every error names its line.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "host/gcode/interpreter.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const mc::gcode::ProgramResult p = mc::gcode::interpret_program(text, "fuzz.ngc");
  check(p.ok() || p.calls.empty());
  for (const mc::gcode::Error& e : p.errors) check(e.line >= 1);

  mc::gcode::Interpreter in({}, "fuzz.ngc");
  int line_no = 0;
  for (size_t at = 0; at <= text.size() && !in.program_ended();) {
    const size_t nl = std::min(text.find('\n', at), text.size());
    const std::string_view line = text.substr(at, nl - at);
    at = nl + 1;
    // Copied, and formatted only when the line fails (5 % of the time on
    // a replay of the grown corpus went into formatting it for every line).
    const mc::gcode::ModalState modal = in.modal();
    const mc::gcode::Vec3 pos = in.machine_position();
    const mc::gcode::LineResult r = in.execute_line(line, ++line_no);
    if (r.ok()) {
      for (double v : in.machine_position()) check(std::isfinite(v));
    } else {
      check(r.calls.empty());
      check(mc::gcode::modal_report(in.modal()) == mc::gcode::modal_report(modal));
      check(in.machine_position() == pos);
      check(r.error->line == line_no);
    }
  }
  return 0;
}
