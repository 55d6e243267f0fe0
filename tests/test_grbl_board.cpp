// The Grbl front end on the virtual board, in process and in board time: the
// protocol engine on a BoardBackend, whose link runs the board only while it
// waits for a reply or polls (1 ms of board time per round), so every wait
// below is on the board's clock. A job streamed line by line runs on time
// (look-ahead over the queue, no stop at every line) and ends at its end
// point; a hold stops along the path and keeps the rest; overrides change
// the speed part-way; G4 answers after its dwell; faults, probes, jogs and
// resets behave as Grbl's.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "hls/board_regs.hpp"
#include "hls/pid_regs.hpp"
#include "host/base/errors.hpp"
#include "host/grbl/board_backend.hpp"
#include "host/grbl/protocol.hpp"
#include "host/grbl/settings.hpp"
#include "host/link/board_link.hpp"
#include "host/link/board_state.hpp"
#include "host/machine/board_setup.hpp"
#include "host/machine/job.hpp"
#include "host/machine/workpiece.hpp"
#include "sim/vboard/board_stream.hpp"
#include "sim/vboard/virtual_board.hpp"

namespace mc::grbl::test {
namespace {

namespace br = board::reg;

struct Report {
  std::string state;
  gcode::Vec3 mpos{};
  double feed = 0, rpm = 0;
  int ln = 0;
};

Report parse(const std::string& r) {
  Report p;
  std::smatch m;
  if (std::regex_search(r, m, std::regex("^<([^|>]*)"))) p.state = m[1];
  if (std::regex_search(r, m, std::regex("MPos:([-0-9.]+),([-0-9.]+),([-0-9.]+)")))
    p.mpos = {std::stod(m[1]), std::stod(m[2]), std::stod(m[3])};
  if (std::regex_search(r, m, std::regex("FS:([-0-9.]+),([-0-9.]+)"))) {
    p.feed = std::stod(m[1]);
    p.rpm = std::stod(m[2]);
  }
  if (std::regex_search(r, m, std::regex("Ln:([0-9]+)"))) p.ln = std::stoi(m[1]);
  return p;
}

// A machine's virtual board (the default machine's unless told) in this
// process, on board time, and a link to it.
struct InProcessBoard {
  const machine::MachineConfig m;
  sim::VirtualBoard board{m};
  sim::BoardStream stream{board};
  host::BoardLink link{stream};
  explicit InProcessBoard(machine::MachineConfig mc = machine::default_machine(),
                          const std::array<double, 3>& start_m = {})
      : m(std::move(mc)) {
    for (int a = 0; a < board.configured_axes(); ++a) board.start_at(a, start_m[size_t(a)]);
    link.connect();
  }
};

class BoardRig {
 public:
  // before: what the board has been through before the server starts;
  // start_m: where the tables stand at power-up (the plant's frame).
  explicit BoardRig(machine::MachineConfig m = machine::default_machine(),
                    const std::function<void(host::BoardLink&)>& before = {},
                    const std::array<double, 3>& start_m = {})
      : ib_(std::move(m), start_m) {
    if (before) before(link_);
    backend_ = std::make_unique<BoardBackend>(link_, m_);
    EngineOptions o;
    o.stored.settings = default_settings(m_);
    o.defaults = o.stored;
    engine_ = std::make_unique<Engine>(*backend_, o);
    out_ = engine_->take_output();
  }

  double now() const { return board_.board_seconds(); }
  BoardBackend& backend() { return *backend_; }
  host::BoardLink& link() { return link_; }
  sim::VirtualBoard& board() { return board_; }
  const std::string& out() const { return out_; }
  const machine::MachineConfig& machine() const { return m_; }

  // One round of the server loop, then 1 ms of board time.
  void step() {
    backend_->tick();
    engine_->poll();
    out_ += engine_->take_output();
    link_.poll(std::chrono::milliseconds(1));
  }
  void send(const std::string& bytes) {
    engine_->receive(bytes);
    engine_->poll();
    out_ += engine_->take_output();
  }
  Report status() {
    const size_t n = out_.size();
    send("?");
    const size_t lt = out_.find('<', n);
    EXPECT_NE(lt, std::string::npos) << out_.substr(n);
    return lt == std::string::npos ? Report{} : parse(out_.substr(lt, out_.find('\n', lt) - lt));
  }
  // Steps until pred() or max_s of board time; returns whether pred() held.
  bool run_until(const std::function<bool()>& pred, double max_s) {
    const double end = now() + max_s;
    while (!pred()) {
      if (now() > end) return false;
      step();
    }
    return true;
  }
  bool run_until_state(const std::string& state, double max_s) {
    return run_until([&] { return status().state == state; }, max_s);
  }
  void run_for(double s) {
    const double end = now() + s;
    while (now() < end) step();
  }
  // Streams lines as a sender counting characters against Grbl's 128-byte
  // buffer; returns after the last line's answer.
  void stream(const std::vector<std::string>& lines, double max_s) {
    size_t sent = 0, answered = 0, from = out_.size();
    std::vector<size_t> lens;
    size_t in_buffer = 0;
    const double end = now() + max_s;
    while (answered < lines.size() && now() < end) {
      while (sent < lines.size() && in_buffer + lines[sent].size() + 1 <= kRxBufferSize) {
        send(lines[sent] + "\n");
        in_buffer += lines[sent].size() + 1;
        lens.push_back(lines[sent].size() + 1);
        ++sent;
      }
      step();
      for (size_t p; (p = out_.find("\r\n", from)) != std::string::npos; from = p + 2) {
        const std::string reply = out_.substr(from, p - from);
        if (reply == "ok" || reply.rfind("error:", 0) == 0) in_buffer -= lens[answered++];
      }
    }
    ASSERT_EQ(answered, lines.size()) << "not every line was answered within " << max_s << " s";
  }

 private:
  InProcessBoard ib_;
  const machine::MachineConfig& m_ = ib_.m;
  sim::VirtualBoard& board_ = ib_.board;
  host::BoardLink& link_ = ib_.link;
  std::unique_ptr<BoardBackend> backend_;
  std::unique_ptr<Engine> engine_;
  std::string out_;
};

constexpr double kCount = 1.0 / 400;  // mm per count on the default machine

void expect_at(const Report& r, double x, double y, double z, double tol = 2 * kCount) {
  EXPECT_NEAR(r.mpos[0], x, tol);
  EXPECT_NEAR(r.mpos[1], y, tol);
  EXPECT_NEAR(r.mpos[2], z, tol);
}

TEST(GrblBoard, StreamedJobRunsOnTimeAndEndsAtItsEndPoint) {
  BoardRig rig;
  ASSERT_NE(rig.out().find("Grbl 1.1h"), std::string::npos);
  EXPECT_EQ(rig.status().state, "Idle");  // at power-up, whatever the servo does within its band
  std::vector<std::string> lines = {"G21 G90 G17 G94", "G1 Z-0.5 F600"};
  // 100 short lines of a zig-zag: a stop at each would take far longer than the plan.
  for (int i = 1; i <= 100; ++i)
    lines.push_back("G1 X" + std::to_string(0.2 * i) + " Y" + (i % 2 ? "0.3" : "0") + " F3000");
  lines.insert(lines.end(), {"G2 X30 Y0 I5 J0", "G0 X5 Y5", "G4 P0.1", "N77 G1 Z-0.2 F600"});
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  const machine::MachineConfig m = rig.machine();
  const double planned = machine::plan_program(text, "job", m, {}).summary.time_s;

  const double t0 = rig.now();
  rig.stream(lines, 30);
  EXPECT_EQ(rig.out().find("error"), std::string::npos) << rig.out();
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
  ASSERT_TRUE(rig.run_until_state("Idle", 10));
  const double took = rig.now() - t0;
  // Lines planned as they came, with look-ahead over the queue: close to
  // the whole program's plan, never a stop per line.
  EXPECT_LT(took, 1.25 * planned + 0.3) << "planned " << planned << " s";
  EXPECT_GT(took, 0.95 * planned);
  rig.run_for(0.2);  // the servo settles
  expect_at(rig.status(), 5, 5, -0.2);
}

// A board homed before the server started: MPos and the program are
// machine coordinates, from its origin (ORIGIN), as `motionctl run` plans.
TEST(GrblBoard, PositionsAreMachineCoordinatesFromTheBoardsOrigin) {
  // X's zero 10 mm behind where the board started, Y's 5 mm ahead.
  BoardRig rig(machine::default_machine(), [](host::BoardLink& l) {
    host::write_origin(l, 0, 4000);
    host::write_origin(l, 1, -2000);
  });
  rig.run_for(0.1);
  expect_at(rig.status(), -10, 5, 0);
  rig.stream({"G21 G90 G1 X1 Y-1 F3000"}, 10);
  ASSERT_TRUE(rig.run_until_state("Idle", 10));
  rig.run_for(0.2);  // the servo settles
  expect_at(rig.status(), 1, -1, 0);
  EXPECT_EQ(int32_t(rig.link().read(br::axis(0, br::AX_CMD))), 4400) << "board counts: origin + 1 mm";
  EXPECT_EQ(int32_t(rig.link().read(br::axis(1, br::AX_CMD))), -2400);
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
}

// The stepper router (configs/stepper_router.toml) runs a job from a
// sender as the servo router does: STEP_CFG set from the machine file, no
// PID enabled, every count of the command sent as one STEP pulse, none lost
// within the motors' torque, and the job ends at its end point exactly.
TEST(GrblBoard, StepperRouterRunsAJobWithEveryStepSent) {
  BoardRig rig(machine::load_machine(std::string(MC_SOURCE_DIR) + "/configs/stepper_router.toml"));
  const std::vector<std::string> lines = {"G21 G90 G17 G94",     "G1 Z-0.5 F600",   "G1 X4 Y2 F1500",
                                          "G2 X8 Y2 I2 J0",      "G1 X8 Y-1 F2000", "G0 X1 Y1 Z0.5",
                                          "G1 X1 Y2 Z-0.25 F900"};
  rig.stream(lines, 30);
  EXPECT_EQ(rig.out().find("error"), std::string::npos) << rig.out();
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
  ASSERT_TRUE(rig.run_until_state("Idle", 20));
  EXPECT_EQ(rig.link().read(br::STEP_CFG), machine::step_cfg_word(rig.machine()));
  // No gains were loaded, but the sample period is the machine's ts_s
  // (1e-4 s: 1200 clocks), not the power-up sweep time.
  EXPECT_EQ(rig.link().read(mc::pid_reg::addr(mc::pid_reg::GLOBAL_AXIS, mc::pid_reg::G_TS)), 1200u);
  constexpr int64_t kEnd[3] = {400, 800, -100};
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(rig.link().read(mc::pid_reg::addr(uint8_t(a), mc::pid_reg::CTRL)) & 1, 0u) << "axis " << a;
    // Every count of the way was a pulse: the driver's count is the
    // command's (400 counts/mm: X1 Y2 Z-0.25 from where the board started).
    EXPECT_EQ(int32_t(rig.link().read(br::axis(a, br::AX_CMD))), kEnd[a]) << "axis " << a;
    EXPECT_EQ(rig.board().driver_steps(a), kEnd[a]) << "axis " << a;
    EXPECT_EQ(rig.board().lost_full_steps(a), 0) << "axis " << a;
  }
  EXPECT_GT(rig.link().read(br::axis(0, br::AX_FERR)) & 0xFFFF, 0u) << "FERR is armed on a stepper axis";
  const Report r = rig.status();
  EXPECT_EQ(r.state, "Idle");
  expect_at(r, 1, 2, -0.25, 1.0 / 400);
}

TEST(GrblBoard, HoldStopsAlongThePathAndResumeFinishesTheJob) {
  BoardRig rig;
  rig.send("G1 X40 F3000\nG1 Y10\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().mpos[0] > 5; }, 2));
  EXPECT_EQ(rig.status().state, "Run");
  const double at_hold = rig.status().mpos[0];
  rig.send("!");
  EXPECT_EQ(rig.status().state, "Hold:1");
  ASSERT_TRUE(rig.run_until_state("Hold:0", 2));
  const Report held = rig.status();
  // Within the queued time (0.25 s and the piece running, at most 0.05 s, at
  // 50 mm/s), the deceleration (50^2 / 2 / 2000 mm) and the servo's lag
  // (under its 1 mm following-error limit): on the line, short of its end.
  EXPECT_GT(held.mpos[0], at_hold);
  EXPECT_LT(held.mpos[0], at_hold + 50 * (0.25 + 0.05) + 0.625 + 1);
  EXPECT_LT(held.mpos[0], 39);
  rig.run_for(0.5);
  EXPECT_NEAR(rig.status().mpos[0], held.mpos[0], 2 * kCount) << "moved while held";
  EXPECT_EQ(rig.status().state, "Hold:0");
  rig.send("~");
  ASSERT_TRUE(rig.run_until_state("Idle", 5));
  rig.run_for(0.2);
  expect_at(rig.status(), 40, 10, 0);
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
}

// The senders' job (tests/test_grbl_cncjs.js, --sim): arcs, a zig-zag of
// short lines and long lines. A hold every `every` s of board time, wherever
// it falls (a ramp, an arc, a corner), must stop and resume without a fault.
class GrblBoardHolds : public ::testing::TestWithParam<double> {};

TEST_P(GrblBoardHolds, AnywhereInAJobStopAndResumeWithoutAFault) {
  const double every = GetParam();
  BoardRig rig;
  std::vector<std::string> lines = {"G21 G90 G94",       "G0 X0 Y0 Z0", "G1 X20 F2400",
                                    "G2 X30 Y10 I0 J10", "G1 Y30",      "G3 X20 Y40 I-10 J0"};
  for (int i = 0; i < 20; ++i)
    lines.push_back("G1 X" + std::to_string(20 - 0.1 * (i + 1)) + " Y" + (i % 2 ? "40" : "39.5") + " F3000");
  lines.insert(lines.end(), {"G1 X0 Y40 F4800", "G1 Y0", "G0 X12.5 Y7.5"});
  size_t sent = 0;
  int holds = 0;
  double next_hold = rig.now() + every;
  const double end = rig.now() + 30;
  while (rig.now() < end) {
    if (sent < lines.size() && rig.backend().ready()) rig.send(lines[sent++] + "\n");
    rig.step();
    if (rig.now() >= next_hold && rig.status().state == "Run") {
      rig.send("!");
      ASSERT_TRUE(rig.run_until_state("Hold:0", 2)) << "hold " << holds << "\n" << rig.out();
      rig.send("~");
      ++holds;
      next_hold = rig.now() + every;
    }
    if (sent == lines.size() && rig.status().state == "Idle") break;
  }
  EXPECT_GE(holds, 6);
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
  EXPECT_EQ(rig.status().state, "Idle");
  rig.run_for(0.2);
  expect_at(rig.status(), 12.5, 7.5, 0);
}

INSTANTIATE_TEST_SUITE_P(Phases, GrblBoardHolds, ::testing::Values(0.25, 0.33));

TEST(GrblBoard, FeedOverridesChangeTheSpeedPartWay) {
  BoardRig rig;
  rig.send("G1 X100 F1200\n");  // 20 mm/s: 5 s
  ASSERT_TRUE(rig.run_until([&] { return rig.status().mpos[0] > 2; }, 2));
  EXPECT_NEAR(rig.status().feed, 1200, 12);
  for (int i = 0; i < 5; ++i) rig.send("\x92");  // -50 %
  EXPECT_TRUE(rig.run_until([&] { return std::fabs(rig.status().feed - 600) < 6; }, 0.6));
  const double x = rig.status().mpos[0];
  EXPECT_LT(x, 20);
  rig.send("\x90");                              // back to 100 %
  for (int i = 0; i < 5; ++i) rig.send("\x91");  // +50 %
  EXPECT_TRUE(rig.run_until([&] { return std::fabs(rig.status().feed - 1800) < 18; }, 0.6));
  ASSERT_TRUE(rig.run_until_state("Idle", 6));
  rig.run_for(0.2);
  expect_at(rig.status(), 100, 0, 0);
}

TEST(GrblBoard, DwellAnswersAfterItRan) {
  BoardRig rig;
  rig.send("G1 X2 F600\n");  // 0.2 s and the ramps
  const size_t from = rig.out().size();
  const double t0 = rig.now();
  rig.send("G4 P0.5\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.out().find("ok", from) != std::string::npos; }, 3));
  EXPECT_GE(rig.now() - t0, 0.2 + 0.5);
  EXPECT_LT(rig.now() - t0, 0.2 + 0.5 + 0.3);
  EXPECT_TRUE(rig.backend().drained());
  EXPECT_EQ(rig.status().state, "Idle");
}

TEST(GrblBoard, SpindleAndCoolantAreRecordedInOrder) {
  BoardRig rig;
  rig.send("G1 X5 F600\nM3 S1200\nM8\n");
  EXPECT_EQ(rig.status().rpm, 0);  // not before the move before it has run
  ASSERT_TRUE(rig.run_until([&] { return rig.status().rpm == 1200; }, 3));
  EXPECT_GT(rig.status().mpos[0], 5 - 3 * kCount);
  // Grbl shows A: with the override values, every few reports.
  EXPECT_TRUE(rig.run_until(
      [&] { return rig.status().state == "Idle" && rig.out().rfind("A:SF") != std::string::npos; }, 0.5))
      << rig.out();
  rig.send("M30\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.out().find("[MSG:Pgm End]") != std::string::npos; }, 2));
  EXPECT_EQ(rig.status().rpm, 0);
}

// The program's spindle and coolant reach the board's pins: SP_EN, SP_DIR,
// FLOOD, and SP_PWM at the duty of the S word (the default machine's
// max_rpm 24000: S12000 is duty 512, high 512 clocks in every 1024), after
// the move before them; the override scales the duty; M5 M9
// and a soft reset turn them off, and the next line's rearm does not bring
// them back.
TEST(GrblBoard, SpindleAndCoolantDriveTheBoardsPins) {
  BoardRig rig;
  using S = sim::VirtualBoard::SpindleState;
  rig.send("G1 X2 F600\nM4 S12000\nM8\n");
  EXPECT_EQ(rig.board().spindle_state(), S{});
  ASSERT_TRUE(rig.run_until([&] { return rig.board().spindle_state().flood; }, 3));
  EXPECT_GT(rig.status().mpos[0], 2 - 3 * kCount) << "not before the move before it";
  EXPECT_EQ(rig.board().spindle_state(), (S{true, true, true}));
  // The duty over 0.1 s of whole PWM periods (1024 clocks), give or take
  // the period the window cuts.
  const auto duty_over = [&](double s) {
    const uint64_t h0 = rig.board().spindle_high_clocks(), c0 = rig.board().cycles();
    rig.run_for(s);
    return double(rig.board().spindle_high_clocks() - h0) / double(rig.board().cycles() - c0);
  };
  EXPECT_NEAR(duty_over(0.1), 512.0 / 1024, 1024.0 / 1.2e6);
  rig.send("\x9B");  // spindle override -10 %: S10800, 0.45 of 1024 clocks: duty 461
  ASSERT_TRUE(rig.run_until([&] { return rig.status().rpm == 10800; }, 1));
  rig.run_for(0.01);
  EXPECT_NEAR(duty_over(0.1), 461.0 / 1024, 1024.0 / 1.2e6);
  rig.send("M5 M9\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.board().spindle_state() == S{}; }, 1));
  rig.send("M3 S6000 M7\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.board().spindle_state().on; }, 1));
  EXPECT_FALSE(rig.board().spindle_state().reverse);
  rig.send("\x18");  // soft reset
  ASSERT_TRUE(rig.run_until([&] { return rig.board().spindle_state() == S{}; }, 1));
  rig.send("G1 X3 F600\n");
  ASSERT_TRUE(rig.run_until_state("Idle", 3));
  EXPECT_EQ(rig.board().spindle_state(), S{}) << "the rearm must not restart the spindle";
  EXPECT_EQ(rig.link().read(br::IO_CTRL), 0u);
}

TEST(GrblBoard, BoardFaultIsAnAlarmNamingItAndTheNextLineRearms) {
  BoardRig rig;
  using S = sim::VirtualBoard::SpindleState;
  rig.send("G1 X1 F600\nM3 S6000 M8\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.board().spindle_state() == S{true, false, true}; }, 2));
  ASSERT_TRUE(rig.run_until_state("Idle", 2));
  // Nobody talks to the board for 300 ms: its watchdog turns the drives off.
  rig.link().poll(std::chrono::milliseconds(300));
  EXPECT_EQ(rig.board().spindle_state(), S{}) << "the board drops the spindle while disarmed";
  ASSERT_TRUE(rig.run_until([&] { return rig.out().find("ALARM:3") != std::string::npos; }, 1)) << rig.out();
  EXPECT_NE(rig.out().find("[MSG:Board fault: watchdog]"), std::string::npos) << rig.out();
  EXPECT_EQ(rig.status().state, "Alarm");
  rig.send("$X\n");
  rig.send("G1 X3 F600\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().state == "Idle" && rig.status().mpos[0] > 2.9; }, 3))
      << rig.out();
  rig.run_for(0.2);
  expect_at(rig.status(), 3, 0, 0);
  // Rearmed for the next line, the spindle and coolant stay off: the alarm
  // ended the program's spindle, which must ask for it again.
  EXPECT_EQ(rig.board().spindle_state(), S{});
  EXPECT_EQ(rig.link().read(br::IO_CTRL), 0u);
  EXPECT_EQ(rig.status().rpm, 0);
}

// $H on the board: the homing cycle of the machine file's [home] tables
// ($25 changed by the sender speeds up every axis's seek), reported as
// Home, then Idle with MPos in the new machine frame, and a move to machine
// zero takes the tables to where the plant's switches put it.
TEST(GrblBoard, HomingSetsMachineZeroFromTheSwitches) {
  const std::array<double, 3> start = {0.12, -0.05, -0.01};  // m, the plant's frame
  BoardRig rig(machine::default_machine(), {}, start);
  const size_t from = rig.out().size();
  rig.send("$H\n");
  EXPECT_NE(rig.out().find("error:5", from), std::string::npos) << "$22=0: " << rig.out().substr(from);
  rig.send("$22=1\n$25=9000\n");
  const size_t homing = rig.out().size();
  const double t0 = rig.now();
  rig.send("$H\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().state == "Home"; }, 1));
  ASSERT_TRUE(rig.run_until(
      [&] {
        return rig.out().find("ok", homing) != std::string::npos ||
               rig.out().find("ALARM") != std::string::npos;
      },
      60))
      << "homing did not end within 60 s of board time";
  ASSERT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
  // Y alone seeks 340 mm: 17 s at the file's 20 mm/s, 2.3 s at $25's 150
  // (the locates, at the file's 1 mm/s, take about 2 s per pass).
  EXPECT_LT(rig.now() - t0, 10) << "$25 did not speed up the seek";
  std::printf("$H from (120, -50, -10) mm with $25=9000: %.2f s of board time\n", rig.now() - t0);
  EXPECT_EQ(rig.status().state, "Idle");
  // Parked pull_off off each switch: X and Y at 290 - 2 mm, Z at 15 - 2.
  expect_at(rig.status(), 288, 288, 13, 3 * kCount);
  const host::MachineOrigin o = host::read_origin(rig.link());
  EXPECT_EQ(o.homed, 7u);
  for (int a = 0; a < 3; ++a) {
    const double cpm = machine::counts_per_m(rig.machine().axes[size_t(a)]);
    EXPECT_LE(std::fabs(double(o.counts[size_t(a)]) + start[size_t(a)] * cpm), 1.0)
        << "axis " << a << ": machine zero at the plant's zero within a count";
  }
  EXPECT_EQ(rig.link().read(br::SAFETY), board::bits::SAFETY_DEFAULT) << "limits back on";
  rig.stream({"G90 G0 X0 Y0 Z0"}, 10);
  ASSERT_TRUE(rig.run_until_state("Idle", 10));
  rig.run_for(0.2);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(rig.board().position_m(a), 0, 3e-6) << "axis " << a;
  EXPECT_EQ(rig.out().find("error", homing), std::string::npos) << rig.out().substr(homing);
}

// A reset while homing stops it: ALARM:6 as Grbl, the limits back on, and
// nothing left half homed.
TEST(GrblBoard, ResetDuringHomingIsAlarmSixAndRestoresTheLimits) {
  BoardRig rig(machine::default_machine(), {}, {0.1, 0.1, 0});
  rig.send("$22=1\n$H\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().state == "Home"; }, 1));
  rig.run_for(0.3);
  rig.send("\x18");
  EXPECT_NE(rig.out().find("ALARM:6"), std::string::npos) << rig.out();
  EXPECT_EQ(rig.link().read(br::SAFETY), board::bits::SAFETY_DEFAULT);
  EXPECT_EQ(rig.link().read(br::LATCH), 0u);
  EXPECT_EQ(host::read_origin(rig.link()).homed, 0u);
  rig.run_for(0.1);
  EXPECT_EQ(rig.status().state, "Alarm");
}

// G38.x on the board: the probe latches every axis on the board, [PRB:]
// reports it in machine coordinates, and Grbl's alarms 4 and 5 come where
// Grbl raises them.
TEST(GrblBoard, ProbingReportsWhereTheProbeChanged) {
  // The tool 2 mm above the plate at (50, 50) mm: MPos 0 there (not homed).
  BoardRig rig(machine::default_machine(), {}, {0.05, 0.05, 0.002});
  const machine::WorkpieceConfig& w = *rig.machine().workpiece;
  const double face = machine::surface_z_mm(w, 50, 50) - 2.0;  // MPos Z of the face
  const auto prb = [&](size_t from) {
    std::smatch m;
    const std::string tail = rig.out().substr(from);
    EXPECT_TRUE(std::regex_search(tail, m, std::regex(R"(\[PRB:([-0-9.]+),([-0-9.]+),([-0-9.]+):([01])\])")))
        << tail;
    return m.empty()
               ? std::array<double, 4>{}
               : std::array<double, 4>{std::stod(m[1]), std::stod(m[2]), std::stod(m[3]), std::stod(m[4])};
  };
  const auto answered = [&](size_t from) {
    return [&rig, from] {
      return rig.out().find("ok", from) != std::string::npos ||
             rig.out().find("ALARM", from) != std::string::npos;
    };
  };
  // Not far enough: G38.2 is ALARM:5, G38.3 only reports no contact.
  size_t from = rig.out().size();
  rig.send("G21 G90 G38.2 Z-1 F300\n");
  ASSERT_TRUE(rig.run_until(answered(from), 5));
  EXPECT_EQ(rig.status().state, "Alarm");
  EXPECT_NE(rig.out().find("ALARM:5", from), std::string::npos) << rig.out().substr(from);
  EXPECT_NEAR(prb(from)[2], -1, kCount);
  EXPECT_EQ(prb(from)[3], 0);
  rig.send("$X\n");
  from = rig.out().size();
  rig.send("G38.3 Z-1.5 F300\n");
  ASSERT_TRUE(rig.run_until(answered(from), 5));
  EXPECT_EQ(rig.out().find("ALARM", from), std::string::npos) << rig.out().substr(from);
  EXPECT_EQ(prb(from)[3], 0);
  // Down to the face: the latched Z is the face's count.
  from = rig.out().size();
  rig.send("G38.2 Z-5 F300\n");
  ASSERT_TRUE(rig.run_until(answered(from), 5));
  const std::array<double, 4> hit = prb(from);
  EXPECT_EQ(hit[3], 1) << rig.out().substr(from);
  EXPECT_NEAR(hit[0], 0, 3 * kCount);
  EXPECT_NEAR(hit[1], 0, 3 * kCount);
  EXPECT_LE(std::fabs(hit[2] - std::floor(face / kCount) * kCount), kCount + 1e-9)
      << "latched " << hit[2] << " mm, face at " << face << " mm";
  EXPECT_EQ(rig.out().find("ALARM", from), std::string::npos) << rig.out().substr(from);
  // Touching already: another G38.2 is ALARM:4 and does not move.
  rig.run_for(0.1);
  const double z = rig.status().mpos[2];
  from = rig.out().size();
  rig.send("G38.2 Z-5 F300\n");
  ASSERT_TRUE(rig.run_until(answered(from), 5));
  EXPECT_NE(rig.out().find("ALARM:4", from), std::string::npos) << rig.out().substr(from);
  EXPECT_NEAR(rig.status().mpos[2], z, 2 * kCount);
  // Away from the face (G38.4): the probe opens at it.
  rig.send("$X\n");
  from = rig.out().size();
  rig.send("G38.4 Z0 F60\n");
  ASSERT_TRUE(rig.run_until(answered(from), 5));
  EXPECT_EQ(prb(from)[3], 1) << rig.out().substr(from);
  EXPECT_NEAR(prb(from)[2], face, 2 * kCount);
  // The parser continues from where the probe stopped: G91 moves are from there.
  rig.send("G91 G0 Z1\n");
  ASSERT_TRUE(rig.run_until_state("Idle", 5));
  rig.run_for(0.2);
  EXPECT_NEAR(rig.status().mpos[2], prb(from)[2] + 1, 2 * kCount);
}

// $LEV on the board: lines are levelled with the height map the server was
// given (motionctl serve --level), split per cell; $LEV=0 stops it, a jog
// ends on the bed's height at its target, and a cut that leaves the map is
// an alarm naming it.
TEST(GrblBoard, LevellingFollowsTheMapAndSwitchesOffAndOn) {
  BoardRig rig;
  const size_t from = rig.out().size();
  rig.send("$LEV\n$LEV=1\n");
  EXPECT_NE(rig.out().find("[LEV:OFF]\r\nok\r\nerror:5", from), std::string::npos) << rig.out().substr(from);
  // A bed rising 0.2 mm over X 0..20 and 0.1 mm over Y 0..10.
  machine::HeightMap map = machine::parse_height_map(
      "[map]\nx0_mm = 0.0\ny0_mm = 0.0\ndx_mm = 10.0\ndy_mm = 10.0\n"
      "heights_mm = [[0.0, 0.1, 0.2], [0.1, 0.2, 0.3]]\n",
      "test map");
  rig.backend().set_height_map(map, "bed.toml");
  rig.send("$LEV\n");
  EXPECT_NE(rig.out().find("[LEV:ON,3x2,X0..20,Y0..10,bed.toml]"), std::string::npos) << rig.out();
  rig.stream({"G21 G90 G1 X20 Y0 Z-1 F1200", "G1 X15 Y5"}, 10);
  ASSERT_TRUE(rig.run_until_state("Idle", 10));
  rig.run_for(0.2);
  expect_at(rig.status(), 15, 5, -1 + 0.2, 3 * kCount);  // bilinear at (15, 5): 0.2
  // A jog from the parser's position (15, 5, -1) ends levelled too.
  rig.send("$J=G91 X-5 F600\n");
  ASSERT_TRUE(rig.run_until_state("Idle", 5));
  rig.run_for(0.2);
  expect_at(rig.status(), 10, 5, -1 + 0.15, 3 * kCount);
  rig.send("$LEV=0\n");
  rig.stream({"G1 X5 Y5 Z-1"}, 10);
  ASSERT_TRUE(rig.run_until_state("Idle", 10));
  rig.run_for(0.2);
  expect_at(rig.status(), 5, 5, -1, 3 * kCount);
  EXPECT_EQ(rig.out().find("error", from + 30), std::string::npos) << rig.out().substr(from);
  // A cut off the map: an alarm naming the line, nothing moves.
  rig.send("$LEV=1\n");
  rig.stream({"G1 X30 Y5"}, 5);
  rig.run_for(0.1);
  EXPECT_NE(rig.out().find("outside the height map"), std::string::npos) << rig.out();
  expect_at(rig.status(), 5, 5, -1, 3 * kCount);
}

// $MPG on the board: the wheel jogs the axis the sender selected by its
// step a detent while nothing else runs (HW: in the status report), a line
// takes the wheel off and starts where it left the axis, and the parser
// knows where that is.
TEST(GrblBoard, TheHandwheelJogsTheAxisASenderSelected) {
  BoardRig rig;
  const size_t from = rig.out().size();
  rig.send("$MPG\n$MPG=Q5\n$MPG=X1000\n$MPG=X10\n$MPG\n");
  EXPECT_NE(rig.out().find("[MPG:OFF]\r\nok\r\nerror:3\r\nerror:3\r\nok\r\n[MPG:X10]\r\nok", from),
            std::string::npos)
      << rig.out().substr(from);
  rig.step();
  const size_t n = rig.out().size();
  rig.send("?");
  EXPECT_NE(rig.out().find("|HW:X,10", n), std::string::npos) << rig.out().substr(n);
  // Five detents: 50 counts on X.
  rig.board().turn_handwheel(5, 0.05);
  rig.run_for(0.3);
  EXPECT_EQ(int32_t(rig.link().read(br::axis(0, br::AX_CMD))), 50);
  expect_at(rig.status(), 50 * kCount, 0, 0);
  // An incremental line runs from there; the wheel is off while it runs.
  rig.send("G91 G1 X1 F600\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().state == "Run"; }, 1));
  const size_t m = rig.out().size();
  rig.send("?");
  EXPECT_EQ(rig.out().find("|HW:", m), std::string::npos) << rig.out().substr(m);
  rig.board().turn_handwheel(3, 0.01);  // turned while the line runs: dropped
  ASSERT_TRUE(rig.run_until_state("Idle", 5));
  rig.run_for(0.3);
  EXPECT_EQ(int32_t(rig.link().read(br::axis(0, br::AX_CMD))), 450);
  // Back on once idle: Y now, one count a detent.
  rig.send("$MPG=Y1\n");
  rig.run_for(0.05);
  rig.board().turn_handwheel(-4, 0.02);
  rig.run_for(0.3);
  EXPECT_EQ(int32_t(rig.link().read(br::axis(1, br::AX_CMD))), -4);
  rig.send("$MPG=0\n");
  rig.board().turn_handwheel(4, 0.02);
  rig.run_for(0.3);
  EXPECT_EQ(int32_t(rig.link().read(br::axis(1, br::AX_CMD))), -4) << "off: the wheel moves nothing";
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos) << rig.out();
}

TEST(GrblBoard, JogCancelAndSoftResetStopShortAndTheNextMoveStartsThere) {
  BoardRig rig;
  rig.send("$J=G91 X30 F1800\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().mpos[0] > 3; }, 2));
  EXPECT_EQ(rig.status().state, "Jog");
  rig.send("\x85");
  ASSERT_TRUE(rig.run_until_state("Idle", 2));
  const double x = rig.status().mpos[0];
  EXPECT_LT(x, 20);
  // Soft reset while moving: the interpolator stops at once (ALARM:3, as
  // Grbl), and after $X the next move runs from where the axes are.
  rig.send("G1 X60 F3000\n");
  ASSERT_TRUE(rig.run_until([&] { return rig.status().mpos[0] > x + 5; }, 2));
  const double before = rig.status().mpos[0];
  rig.send("\x18");
  EXPECT_NE(rig.out().find("ALARM:3"), std::string::npos);
  rig.run_for(0.2);
  const double stopped = rig.status().mpos[0];
  EXPECT_LT(stopped, before + 1);  // the servo's overshoot, not the 12 mm queued
  rig.send("$X\nG1 X10 Y2 F3000\n");
  ASSERT_TRUE(rig.run_until_state("Idle", 3));
  rig.run_for(0.2);
  expect_at(rig.status(), 10, 2, 0);
  EXPECT_EQ(rig.out().find("error"), std::string::npos) << rig.out();
}

// The stress test of the line protocol on the board: 10,000 incremental
// lines (G91, distinct steps, so that a line lost or doubled moves the end
// point) streamed as fast as character counting allows, a status query
// every 10 ms of board time answered at once, Ln never going back (nothing
// reordered), and the machine ending where the sum of the steps puts it.
TEST(GrblBoard, TenThousandLinesStreamWithNoneLostDoubledOrReordered) {
  BoardRig rig;
  constexpr int kLines = 10000;
  std::vector<std::string> lines;
  int64_t sum_x = 0, sum_y = 0;  // counts
  for (int n = 1; n <= kLines; ++n) {
    // Counts: 1..7 forward, and a count across every 50th line (a straight
    // path runs at the look-ahead's speed, not a stop per corner).
    const int dx = 1 + n % 7, dy = n % 50 == 0 ? (n % 100 == 0 ? 1 : -1) : 0;
    sum_x += dx;
    sum_y += dy;
    char buf[64];
    std::snprintf(buf, sizeof buf, "N%d G91 G1 X%.4f Y%.4f F3000", n, dx * kCount, dy * kCount);
    lines.emplace_back(buf);
  }
  size_t sent = 0, answered = 0, from = rig.out().size(), in_buffer = 0;
  std::deque<size_t> lens;
  int last_ln = 0, reports = 0;
  const double t0 = rig.now();
  double next_query = t0;
  const double end = rig.now() + 600;
  while (answered < lines.size() && rig.now() < end) {
    while (sent < lines.size() && in_buffer + lines[sent].size() + 1 <= kRxBufferSize) {
      rig.send(lines[sent] + "\n");
      in_buffer += lines[sent].size() + 1;
      lens.push_back(lines[sent].size() + 1);
      ++sent;
    }
    if (rig.now() >= next_query) {
      const Report r = rig.status();  // answered in the same call: no board time passes
      ASSERT_FALSE(r.state.empty());
      ASSERT_GE(r.ln, last_ln) << "Ln went back: a line ran out of order";
      last_ln = r.ln;
      ++reports;
      next_query += 0.01;
    }
    rig.step();
    for (size_t p; (p = rig.out().find("\r\n", from)) != std::string::npos; from = p + 2) {
      const std::string reply = rig.out().substr(from, p - from);
      if (reply.empty() || reply[0] == '<') continue;
      ASSERT_EQ(reply, "ok") << "line " << answered + 1;
      in_buffer -= lens.front();
      lens.pop_front();
      ++answered;
    }
  }
  ASSERT_EQ(answered, lines.size());
  ASSERT_TRUE(rig.run_until_state("Idle", 30));
  rig.run_for(0.2);
  expect_at(rig.status(), double(sum_x) * kCount, double(sum_y) * kCount, 0);
  EXPECT_EQ(rig.out().find("ALARM"), std::string::npos);
  EXPECT_GT(reports, 100);
  std::printf("streamed %d lines in %.2f s of board time, %d status reports\n", kLines, rig.now() - t0,
              reports);
}

TEST(GrblBoard, WatchdogPeriodIsSetWithinWhatTheRegisterHolds) {
  InProcessBoard ib;
  const machine::MachineConfig& m = ib.m;
  host::BoardLink& link = ib.link;
  BoardBackend b(link, m, 16, {}, 0.5);
  EXPECT_EQ(link.read(br::WDOG), uint32_t(0.5 * m.clock_hz));
  EXPECT_THROW(watchdog_cycles(5, m.clock_hz), host::InputError);
  EXPECT_THROW(watchdog_cycles(1e-9, m.clock_hz), host::InputError);
}

// The streamer keeps queue_ahead_s of planned time queued, of which the
// piece the board runs counts at most as the longest motion piece: a long
// dwell must not count, or when it ends the board finds one short ramp
// piece behind it and runs dry while the host looks away.
TEST(JobStreamerQueue, KeepsItsTimeQueuedBehindADwell) {
  InProcessBoard ib;
  const machine::MachineConfig& m = ib.m;
  host::BoardLink& link = ib.link;
  const machine::JobBoard jb = machine::ready_board(link, m, [](const std::string&) {});
  const host::PlannerConfig cfg = machine::planner_config(m);
  const machine::Job j =
      machine::plan_program("G1 X1 F600\nG4 P0.5\nG1 X30 F3000\n", "dwell.nc", m, host::to_mm(jb.at, cfg));
  host::JobStreamer s(link, cfg, jb.at, 0.25);
  s.load(j.moves, j.pieces);
  int polls = 0;
  while (!(s.current() && s.current()->line == 2) && polls < 100000) {
    s.poll();
    ++polls;
  }
  ASSERT_TRUE(s.current() && s.current()->line == 2) << "the dwell never ran";
  for (int k = 0; k < 20; ++k) s.poll();
  ASSERT_EQ(s.current()->line, 2);
  EXPECT_GE(s.planned_s() - s.current()->t_end, 0.25 - cfg.max_piece_s - 1e-9);
  while (!s.drained() && polls < 200000) {
    s.poll();
    ++polls;
  }
  EXPECT_TRUE(s.drained());
  EXPECT_EQ(s.underruns(), 0);
}

}  // namespace
}  // namespace mc::grbl::test
