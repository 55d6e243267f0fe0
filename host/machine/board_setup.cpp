#include "host/machine/board_setup.hpp"

#include <algorithm>
#include <string>

#include "hls/board_regs.hpp"
#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/control/pid_design.hpp"

namespace mc::machine {

namespace br = mc::board::reg;
namespace bb = mc::board::bits;
using mc::host::InputError;

namespace {

bool is_stepper(const MachineConfig& m, int a) {
  return a < int(m.axes.size()) && m.axes[size_t(a)].stepper.has_value();
}

// Whether the machine has servo axes, stepper axes.
struct Kinds {
  bool servo = false, stepper = false;
};
Kinds kinds(const MachineConfig& m) {
  Kinds k;
  for (const AxisConfig& a : m.axes) (a.stepper ? k.stepper : k.servo) = true;
  return k;
}

std::string build_hint(const MachineConfig& m, bool stepper) {
  const Kinds k = kinds(m);
  if (k.servo && k.stepper)
    return " (neither make synth nor make synth-stepper builds both on the iCEBreaker: docs/board.md; the "
           "virtual board has both)";
  return stepper ? " (make synth-stepper builds one)" : " (make synth builds one)";
}

}  // namespace

uint32_t step_cfg_word(const MachineConfig& m) {
  uint32_t w = 0;
  int pw = 0, setup = 0;
  for (size_t a = 0; a < m.axes.size() && a < 3; ++a) {
    if (!m.axes[a].stepper) continue;
    const StepperConfig& s = *m.axes[a].stepper;
    w |= 1u << (bb::SC_STEPPER_LSB + a);
    if (s.closed_loop) w |= 1u << (bb::SC_CLOSED_LSB + a);
    if (s.step_active_low) w |= 1u << (bb::SC_STEP_INV_LSB + a);
    if (s.dir_reversed) w |= 1u << (bb::SC_DIR_INV_LSB + a);
    // One pair of times for every driver: the slowest driver's.
    pw = std::max(pw, step_time_clocks(s.step_pulse_s, m.clock_hz));
    setup = std::max(setup, step_time_clocks(s.dir_setup_s, m.clock_hz));
  }
  return w | uint32_t(pw) << bb::SC_PW_LSB | uint32_t(setup) << bb::SC_SETUP_LSB;
}

void check_board(const MachineConfig& m, uint32_t info) {
  const int naxes = bb::info_naxes(info);
  if (int(m.axes.size()) > naxes)
    throw InputError("machine config", m.source, "a board with " + std::to_string(m.axes.size()) + " axes",
                     "the board was built with " + std::to_string(naxes));
  for (int a = 0; a < int(m.axes.size()); ++a) {
    const bool stepper = is_stepper(m, a);
    const bool built = stepper ? (bb::info_steppers(info) >> a & 1) != 0 : bb::info_servo(info);
    if (built) continue;
    const std::string& name = m.axes[size_t(a)].name;
    throw InputError(
        "axis " + name + " (" + m.source + ")", stepper ? "a stepper axis" : "a servo axis",
        std::string(stepper ? "a board built with a step generator on axis " + name
                            : "a board built with the PID loops") +
            build_hint(m, stepper),
        "the board's INFO says it has " + std::string(stepper ? "no step generator there" : "no loops"));
  }
}

void setup_axes(mc::host::BoardLink& l, const MachineConfig& m) {
  check_board(m, l.read(br::INFO));
  const uint32_t want = step_cfg_word(m);
  if (l.read(br::STEP_CFG) != want) l.write_verify(br::STEP_CFG, want);
  // A machine of steppers only loads no gains, and with them no sample
  // period: the board would sample (telemetry, FERR) at its power-up
  // period, its sweep time, faster than the link carries. The machine's
  // ts_s is its sample period.
  const Kinds k = kinds(m);
  if (!k.stepper || k.servo) return;
  const uint16_t ts_addr = mc::pid_reg::addr(mc::pid_reg::GLOBAL_AXIS, mc::pid_reg::G_TS);
  const uint32_t latency = l.read(mc::pid_reg::addr(mc::pid_reg::GLOBAL_AXIS, mc::pid_reg::G_LATENCY));
  const uint32_t ts =
      mc::host::core_ts_cycles(m.axes[0].pid.ts_s, double(l.read(br::CLK_HZ)), latency,
                               "ts_s ([axis." + m.axes[0].name + ".pid] in " + m.source + ")");
  if (l.read(ts_addr) != ts) l.write_verify(ts_addr, ts);
}

std::array<int64_t, 3> enable_machine_axes(mc::host::BoardLink& l, const MachineConfig& m,
                                           const std::vector<int>& axes, const mc::host::Note& note) {
  std::vector<int> servo;
  for (int a : axes)
    if (!is_stepper(m, a)) servo.push_back(a);
  return servo.empty() ? mc::host::arm(l, note) : mc::host::enable_axes(l, servo, note);
}

void require_servo(const MachineConfig& m, int a, std::string_view command) {
  if (!is_stepper(m, a)) return;
  const std::string& name = m.axes[size_t(a)].name;
  throw InputError("--axis", name, "a servo axis: " + std::string(command) + " works on a PID loop",
                   "axis " + name + " is a stepper ([axis." + name + ".stepper] in " + m.source + ")");
}

void require_disable_alone(const MachineConfig& m, const std::vector<int>& axes, bool alone) {
  if (!alone) return;
  for (int a : axes) {
    if (!is_stepper(m, a)) continue;
    const std::string& name = m.axes[size_t(a)].name;
    throw InputError("--axis", name, "a servo axis, or no --axis to turn every drive off",
                     "axis " + name +
                         " is a stepper: its driver is enabled by DRV_EN with every other, "
                         "so it cannot be disabled alone");
  }
}

void require_ready(mc::host::BoardLink& l, const MachineConfig& m, int a) {
  if (!is_stepper(m, a)) mc::host::require_enabled(l, a);
}

}  // namespace mc::machine
