#include "host/machine/spindle.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <variant>

#include "hls/board_regs.hpp"

namespace mc::machine {

namespace bb = mc::board::bits;
namespace gc = mc::gcode;

void SpindleState::apply(const gc::CanonOp& op) {
  std::visit(
      [this](const auto& o) {
        using T = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<T, gc::StartSpindle>) {
          dir = o.clockwise ? 1 : -1;
          rpm = o.rpm;
        } else if constexpr (std::is_same_v<T, gc::StopSpindle> || std::is_same_v<T, gc::ChangeTool>) {
          dir = 0;
        } else if constexpr (std::is_same_v<T, gc::SetSpindleSpeed>) {
          rpm = o.rpm;
        } else if constexpr (std::is_same_v<T, gc::SetCoolant>) {
          flood = o.flood;
          mist = o.mist;
        } else if constexpr (std::is_same_v<T, gc::ProgramStop>) {
          if (o.kind == gc::StopKind::end || o.kind == gc::StopKind::end_rewind) {
            dir = 0;
            flood = mist = false;
          }
        }
      },
      op);
}

uint32_t spindle_duty(const SpindleConfig& c, double rpm) {
  // The pin is high `duty` clocks of every 1024 (1023: always on), so the
  // fraction f is duty / 1024; a spindle asked to turn gets at least 1, as
  // Grbl's minimum PWM value.
  constexpr long kPeriod = 1 << bb::IO_DUTY_BITS;
  if (!(rpm > 0)) return 0;
  const double f = std::clamp((rpm - c.min_rpm) / (c.max_rpm - c.min_rpm), 0.0, 1.0);
  return uint32_t(std::clamp(std::lround(f * double(kPeriod)), 1L, kPeriod - 1));
}

uint32_t io_ctrl_word(const SpindleConfig& c, const SpindleState& s, double speed_override) {
  uint32_t w = 0;
  if (s.dir != 0) {
    w |= 1u << bb::IO_SPINDLE;
    if (s.dir < 0) w |= 1u << bb::IO_SPINDLE_REV;
    w |= spindle_duty(c, s.rpm * speed_override) << bb::IO_DUTY_LSB;
  }
  if (s.flood) w |= 1u << bb::IO_FLOOD;
  if (s.mist) w |= 1u << bb::IO_MIST;
  if (c.mist_on_dir) w |= 1u << bb::IO_MIST_ON_DIR;
  return w;
}

void write_spindle(mc::host::BoardLink& l, const MachineConfig& m, const SpindleState& s,
                   double speed_override) {
  namespace br = mc::board::reg;
  const uint32_t want = io_ctrl_word(m.spindle, s, speed_override);
  if (l.read(br::IO_CTRL) != want) l.write_verify(br::IO_CTRL, want);
}

}  // namespace mc::machine
