// The board set up for the machine's axes (host/machine/board_setup.hpp):
// STEP_CFG from [axis.N.stepper], and a board refused when it was not built
// for the machine (INFO), with the make target that builds the right one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "hls/board_regs.hpp"
#include "host/base/errors.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/machine_config.hpp"
#include "host/machine/spindle.hpp"

namespace mc::machine {
namespace {

namespace bb = board::bits;

MachineConfig stepper_router() {
  return load_machine(std::string(MC_SOURCE_DIR) + "/configs/stepper_router.toml");
}

// INFO of a three-axis board: the servo bitstream, the stepper one.
constexpr uint32_t kServoInfo = bb::info_word(3, 9, board::proto::VERSION, 0, true, true);
constexpr uint32_t kStepperInfo = bb::info_word(3, 9, board::proto::VERSION, 7, false, true);

std::string refusal(const MachineConfig& m, uint32_t info) {
  try {
    check_board(m, info);
  } catch (const host::InputError& e) {
    return e.what();
  }
  return {};
}

TEST(BoardSetup, StepCfgFromTheStepperTables) {
  MachineConfig m = stepper_router();
  // 2 us pulses and 1 us direction setup at 12 MHz: 24 and 12 clocks.
  EXPECT_EQ(step_cfg_word(m), 7u | 24u << bb::SC_PW_LSB | 12u << bb::SC_SETUP_LSB);
  m.axes[1].stepper->closed_loop = true;
  m.axes[2].stepper->step_active_low = true;
  m.axes[0].stepper->dir_reversed = true;
  EXPECT_EQ(step_cfg_word(m), 7u | 1u << (bb::SC_CLOSED_LSB + 1) | 1u << (bb::SC_STEP_INV_LSB + 2) |
                                  1u << bb::SC_DIR_INV_LSB | 24u << bb::SC_PW_LSB | 12u << bb::SC_SETUP_LSB);
  // A time that is not a whole number of clocks rounds up: the driver gets
  // at least what it asked for.
  for (AxisConfig& a : m.axes) a.stepper->step_pulse_s = 1.01e-6;
  EXPECT_EQ(step_cfg_word(m) >> bb::SC_PW_LSB & 0x3F, 13u);
  // One pair of times serves every driver: the slowest one's.
  m.axes[2].stepper->step_pulse_s = 5e-6;
  m.axes[1].stepper->dir_setup_s = 3e-6;
  EXPECT_EQ(step_cfg_word(m) >> bb::SC_PW_LSB & 0x3F, 60u);
  EXPECT_EQ(step_cfg_word(m) >> bb::SC_SETUP_LSB & 0x3F, 36u);
  // A servo machine: no stepper bits, no timing.
  EXPECT_EQ(step_cfg_word(default_machine()), 0u);
}

TEST(BoardSetup, TheBoardMustBeBuiltForTheMachine) {
  EXPECT_EQ(refusal(default_machine(), kServoInfo), "");
  EXPECT_EQ(refusal(stepper_router(), kStepperInfo), "");
  // The Verilated board has both: it runs either machine.
  const uint32_t both = bb::info_word(3, 9, board::proto::VERSION, 7, true, true);
  EXPECT_EQ(refusal(default_machine(), both), "");
  EXPECT_EQ(refusal(stepper_router(), both), "");

  const std::string s = refusal(stepper_router(), kServoInfo);
  EXPECT_NE(s.find("axis x"), std::string::npos) << s;
  EXPECT_NE(s.find("make synth-stepper"), std::string::npos) << s;
  const std::string v = refusal(default_machine(), kStepperInfo);
  EXPECT_NE(v.find("PID loops"), std::string::npos) << v;
  EXPECT_NE(v.find("make synth "), std::string::npos) << v;
  // A generator on X and Y only: Z is refused by name.
  const std::string z = refusal(stepper_router(), bb::info_word(3, 9, board::proto::VERSION, 3, false, true));
  EXPECT_NE(z.find("axis z"), std::string::npos) << z;
  // A machine of both kinds: no bitstream here has both, and the hint says so.
  MachineConfig mixed = default_machine();
  mixed.axes[2].stepper = stepper_router().axes[2].stepper;
  const std::string mx = refusal(mixed, kStepperInfo);
  EXPECT_NE(mx.find("neither make synth nor make synth-stepper"), std::string::npos) << mx;
  EXPECT_EQ(refusal(mixed, both), "");
  // Fewer axes than the machine.
  const std::string n = refusal(default_machine(), bb::info_word(2, 9, board::proto::VERSION, 0, true, true));
  EXPECT_NE(n.find("built with 2"), std::string::npos) << n;
}

// DRV_EN enables every driver: a stepper axis cannot be turned off alone.
TEST(BoardSetup, AStepperAxisIsNotDisabledAlone) {
  EXPECT_NO_THROW(require_disable_alone(stepper_router(), {0, 1, 2}, false));
  EXPECT_NO_THROW(require_disable_alone(default_machine(), {0}, true));
  try {
    require_disable_alone(stepper_router(), {1}, true);
    ADD_FAILURE() << "a stepper axis was disabled alone";
  } catch (const host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("DRV_EN"), std::string::npos) << e.what();
  }
}

TEST(BoardSetup, StepperTimesBeyondTheRegisterAreRefusedWithTheLine) {
  std::string text;
  {
    std::ifstream in(std::string(MC_SOURCE_DIR) + "/configs/stepper_router.toml");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  // STEP_CFG holds 63 clocks: 5.25 us at 12 MHz. Each case replaces X's
  // value (the file sets every key) and expects the check's own words.
  struct Case {
    const char *key, *from, *to, *says;
  };
  for (const Case& c :
       {Case{"step_pulse_s", "step_pulse_s = 2e-6", "step_pulse_s = 6e-6", "5.25e-06 s (63 board"},
        Case{"dir_setup_s", "dir_setup_s = 1e-6", "dir_setup_s = 1e-5", "5.25e-06 s (63 board"},
        Case{"closed_loop", "closed_loop = false", "closed_loop = 1", "true or false"}}) {
    std::string toml = text;
    const size_t at = toml.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    toml.replace(at, std::strlen(c.from), c.to);
    const size_t line = size_t(std::count(toml.begin(), toml.begin() + long(at), '\n')) + 1;
    try {
      parse_machine(toml, "router.toml");
      ADD_FAILURE() << c.to << " was accepted";
    } catch (const host::InputError& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("router.toml:" + std::to_string(line) + ": axis.x.stepper." + c.key),
                std::string::npos)
          << w;
      EXPECT_NE(w.find(c.says), std::string::npos) << w;
    }
  }
  // Back within range, the file loads (the replacements above were the only fault).
  EXPECT_NO_THROW(parse_machine(text, "router.toml"));
}

// Grbl's $30/$31 mapping: the pin high duty/1024 of the time, linear from
// min_rpm to max_rpm (1023: always on), at least 1 for a turning spindle.
TEST(Spindle, DutyFromTheSWord) {
  SpindleConfig c;  // 0..24000 rpm
  EXPECT_EQ(spindle_duty(c, 0), 0u);
  EXPECT_EQ(spindle_duty(c, 12000), 512u);  // half: 512 of 1024 clocks
  EXPECT_EQ(spindle_duty(c, 6000), 256u);
  EXPECT_EQ(spindle_duty(c, 1), 1u) << "a spindle asked to turn gets the least duty";
  EXPECT_EQ(spindle_duty(c, 23990), 1023u);
  EXPECT_EQ(spindle_duty(c, 24000), 1023u);
  EXPECT_EQ(spindle_duty(c, 30000), 1023u);
  c.min_rpm = 6000;
  EXPECT_EQ(spindle_duty(c, 3000), 1u);
  EXPECT_EQ(spindle_duty(c, 15000), 512u);
}

TEST(Spindle, ProgramActionsSetIoCtrl) {
  namespace gc = mc::gcode;
  SpindleConfig c;
  SpindleState s;
  s.apply(gc::StartSpindle{false, 12000});
  s.apply(gc::SetCoolant{false, true});
  EXPECT_EQ(io_ctrl_word(c, s),
            1u << bb::IO_SPINDLE | 1u << bb::IO_SPINDLE_REV | 1u << bb::IO_FLOOD | 512u << bb::IO_DUTY_LSB);
  EXPECT_EQ(io_ctrl_word(c, s, 0.5) >> bb::IO_DUTY_LSB, 256u) << "the override scales the speed";
  s.apply(gc::SetSpindleSpeed{24000});
  EXPECT_EQ(io_ctrl_word(c, s) >> bb::IO_DUTY_LSB, 1023u);
  s.apply(gc::ChangeTool{2});  // M6 stops the spindle, not the coolant
  EXPECT_EQ(io_ctrl_word(c, s), 1u << bb::IO_FLOOD);
  s.apply(gc::StartSpindle{true, 6000});
  s.apply(gc::ProgramStop{gc::StopKind::end});  // M2: everything off
  EXPECT_EQ(io_ctrl_word(c, s), 0u);
  c.mist_on_dir = true;
  s.apply(gc::SetCoolant{true, false});
  EXPECT_EQ(io_ctrl_word(c, s), 1u << bb::IO_MIST | 1u << bb::IO_MIST_ON_DIR);
}

TEST(Spindle, ConfigIsReadAndChecked) {
  std::string toml;
  {
    std::ifstream in(std::string(MC_SOURCE_DIR) + "/configs/default.toml");
    toml.assign(std::istreambuf_iterator<char>(in), {});
  }
  EXPECT_EQ(parse_machine(toml, "m.toml").spindle.max_rpm, 24000);
  const size_t at = toml.find("min_rpm = 0.0");
  ASSERT_NE(at, std::string::npos);
  toml.replace(at, 13, "min_rpm = 30000");
  try {
    parse_machine(toml, "m.toml");
    ADD_FAILURE() << "min_rpm above max_rpm was accepted";
  } catch (const host::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("min_rpm < max_rpm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mc::machine
