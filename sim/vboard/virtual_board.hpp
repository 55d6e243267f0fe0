// The virtual board: the Verilated iCEBreaker top (rtl/motioncore_icebreaker.v,
// three axes and the handwheel) clocked at the machine's clock, one DC-motor
// plant per configured axis on its encoder and H-bridge pins, and the UART
// pins bridged bit by bit (sim/uart_model.hpp) to a byte stream. serve()
// carries that stream over a pseudo-terminal, so the unchanged host tools
// speak the board's own protocol to it (`motionctl sim serve`).
//
//   VirtualBoard b(default_machine());
//   b.send(bytes);                  // the host's bytes, onto the RX pin
//   b.run(clocks, out);             // whole plant steps; the board's TX bytes appended to out
//
// Pins: each plant step (MachineConfig::plant_dt_s, a whole number of clocks)
// the plant sees the mean of its PWM/DIR pins and the shared DRV_EN over
// the step as terminal volts (+-supply while DRV_EN and PWM are high), and
// its encoder count is shown on the A/B pins one edge every other clock, as
// the co-simulation does. A stepper axis ([axis.N.stepper]) has a driver
// on its STEP/DIR pins instead: each rising STEP edge is a step in DIR's
// direction, and the shaft's encoder shows the rotor in step units.
// An axis the config does not describe keeps its encoder still.
//
// Switches (sim/vboard/contact.hpp): an axis with [axis.N.home] shows its
// home switch on its limit pin, high while the table is at or beyond
// switch_m in the switch's direction; the probe pin is high while the Z
// axis's tool tip is at or below the [workpiece] face (surface_z_mm) under
// it. Both change at plant-step boundaries and bounce for their bounce_s
// after each change. The e-stop input stays inactive.
//
// Handwheel (turn_handwheel): a 100-PPR manual pulse generator on HW_A/HW_B,
// four quadrature counts a detent, each edge at its own clock (not at a
// plant-step boundary: a hand is not synchronous with anything), on both
// engines alike; the twin's fast-forward stops before every edge.
// Outputs: every change of SP_EN, SP_DIR or FLOOD is logged at its clock,
// with SP_PWM's high clocks since the change before (spindle_log()).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "host/machine/machine_config.hpp"

namespace mc::sim {

using mc::machine::MachineConfig;
class WheelSocket;

constexpr int kBoardAxes = 3;
// The longest watchdog period the board can hold (WDOG is 24 bits): after
// this long without a frame the drives are off for sure.
constexpr uint64_t kMaxWatchdogClocks = uint64_t(1) << 24;
// The board's power-on reset (rtl/motioncore_icebreaker.v's por: 15 clocks)
// and a clock for the synchronizer: a host's first byte comes after it.
constexpr uint64_t kPowerOnClocks = 16;
// The handwheel: quadrature counts a detent (a 100-PPR wheel has 100 detents
// and 400 counts a turn), and the fewest clocks between two of its edges:
// above the decoder's longest filter (HW_CFG, 15 clocks) and its
// synchronizer, so that no edge is lost to them.
constexpr int kHandwheelCountsPerDetent = 4;
constexpr uint64_t kHandwheelEdgeClocks = 32;
constexpr int kMaxHandwheelDetents = 100'000;

// What clocks the board: the twin of the board top (hls/), which skips the
// clocks in which only counters move, or the Verilated top, every clock.
enum class BoardEngine { Twin, Rtl };
const char* board_engine_name(BoardEngine e);
// "twin" or "rtl"; throws InputError naming `what` otherwise.
BoardEngine parse_board_engine(const std::string& name, const std::string& what);

class VirtualBoard {
 public:
  // Powers up as the FPGA does, every register and RAM zero; seed != 0 (RTL
  // engine): Verilator's random power-up state instead (seeded), to flush
  // out reset bugs.
  explicit VirtualBoard(const MachineConfig& m, uint32_t seed = 0, BoardEngine e = BoardEngine::Twin);
  ~VirtualBoard();
  VirtualBoard(const VirtualBoard&) = delete;
  VirtualBoard& operator=(const VirtualBoard&) = delete;

  // Queues host bytes on the board's RX line (1 Mbaud 8N1 at the board's BAUD).
  void send(const uint8_t* p, size_t n);
  // Bytes queued on RX that have not left the host's line yet.
  size_t rx_backlog() const;
  // Runs at least `clocks` clocks, in whole plant steps; appends the bytes the
  // board sent on TX to out. until_output: stop after the plant step in
  // which the first of them came.
  void run(uint64_t clocks, std::vector<uint8_t>& out, bool until_output = false);

  uint64_t cycles() const;
  // Of cycles(), the clocks the engine stepped one by one (the RTL: all).
  uint64_t stepped_clocks() const;
  // Plant steps taken by runs of equal drive rather than one by one
  // (AxisPlant::hold; the twin engine, where no switch can change).
  uint64_t held_steps() const;
  BoardEngine engine() const;
  double clock_hz() const;
  double board_seconds() const { return double(cycles()) / clock_hz(); }
  uint32_t clocks_per_step() const;
  // Clocks since the last UART activity on either line.
  uint64_t link_quiet_clocks() const;
  // Nothing observable can change by itself: the link has been quiet for
  // longer than any watchdog period (so the drives are off), every drive
  // pin is off, every plant stands still and no switch is bouncing.
  bool dormant() const;

  // For status lines: the plants' table positions, m (the plant's frame:
  // start_at() plus the distance moved), and whether each drive is on.
  double position_m(int axis) const;
  bool drive_enabled(int axis) const;
  int configured_axes() const;
  // A stepper axis: the STEP pulses its driver counted (DIR high: +1), and
  // the full steps the rotor has slipped behind them (0 when it kept up;
  // StepperPlant::lost_full_steps). 0 on a servo axis.
  int64_t driver_steps(int axis) const;
  int64_t lost_full_steps(int axis) const;
  // Before the first run(): the table of `axis` stands at table_m (the
  // plant's frame, that of travel_min_m/travel_max_m and switch_m) instead
  // of 0. The encoder still counts from 0 there: POS counts from power-up,
  // wherever the table is (the host keeps the offset). Throws
  // std::logic_error once the board has run.
  void start_at(int axis, double table_m);
  // The switch pins as the board sees them now, and how often each has
  // changed (bounces included). An axis without [home], or a machine
  // without a probe ([workpiece] and a Z axis), keeps its pin low.
  bool limit_pin(int axis) const;
  bool probe_pin() const;
  uint64_t limit_edges(int axis) const;
  uint64_t probe_edges() const;

  // The spindle and coolant outputs.
  struct SpindleState {
    bool on = false;       // SP_EN
    bool reverse = false;  // SP_DIR (or mist with IO_CTRL.mist_on_dir)
    bool flood = false;    // FLOOD
    bool operator==(const SpindleState&) const = default;
  };
  struct SpindleEvent {
    uint64_t clock = 0;  // the board clock after whose edge the pins show `state`
    SpindleState state;
    // SP_PWM over the clocks since the event before (or power-up): the
    // clocks after whose edge it was high, of all of them.
    uint64_t pwm_high = 0, pwm_clocks = 0;
    double duty() const { return pwm_clocks ? double(pwm_high) / double(pwm_clocks) : 0; }
    bool operator==(const SpindleEvent&) const = default;
  };
  SpindleState spindle_state() const;
  const std::vector<SpindleEvent>& spindle_log() const;
  // SP_PWM's high clocks since power-up (both engines count every clock,
  // the twin's skipped ones included).
  uint64_t spindle_high_clocks() const;

  // Turns the handwheel by `detents` (negative: backwards), its 4 * |detents|
  // quadrature edges on HW_A/HW_B spread evenly over the next `seconds` of
  // board time (the last one at the end), as a hand turning it steadily
  // would. A turn asked while one is still going follows it (one hand, one
  // wheel). Edges closer than kHandwheelEdgeClocks are spread to that: the
  // board's decoder, whatever its HW_CFG filter, sees every one. Throws
  // InputError for seconds outside 0..3600 or more than
  // kMaxHandwheelDetents detents.
  void turn_handwheel(int detents, double seconds);
  // The count HW_A/HW_B show now (0 at power-up: the wheel's own count, not
  // the board's HW_POS, which counts what its decoder saw), and the board
  // time at which the turns asked so far are done (in the past: at rest).
  int64_t handwheel_count() const;
  double handwheel_done_s() const;

  // For link checks: appends to *words every 32-bit word the board writes
  // into its segment queue, in order, as it writes it (10 per segment,
  // hls/interp_seg.hpp); nullptr stops. Both engines.
  void tap_segments(std::vector<uint32_t>* words);
  // For engine comparisons: appends to *log every encoder edge the board's
  // pins show, the clock from which they show it and the count (the twin's
  // jumps hand the board edges inside its stretches; the clocks are the
  // same on both engines); nullptr stops.
  struct EncoderEdge {
    uint64_t clock;
    int axis;
    int64_t count;
    bool operator==(const EncoderEdge&) const = default;
  };
  void log_encoder_edges(std::vector<EncoderEdge>* log);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A pseudo-terminal whose slave side the host tools open as a serial port.
// The master stays with the virtual board; the board keeps a slave
// descriptor open itself, so that a host closing its side is not a hang-up
// for the board (bytes sent while no host listens wait in the terminal's
// buffer, and a host discards them when it opens the port).
class Pty {
 public:
  Pty();  // throws std::runtime_error with the failing call
  ~Pty();
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  const std::string& path() const { return path_; }
  int master_fd() const { return master_; }

 private:
  int master_ = -1, slave_ = -1;
  std::string path_;
};

struct ServeStatus {
  double board_s = 0;        // the board's time
  double wall_s = 0;         // since serve() started
  double rt_factor = 0;      // board seconds per wall second over the last report interval
  bool model_bound = false;  // slower than real time (running flat out)
  bool dormant = false;      // waiting for the host with the clock stopped
  uint64_t bytes_in = 0, bytes_out = 0, bytes_dropped = 0;
  // Paced: the 100 us periods of board time run, and those finished more
  // than a period after the wall clock reached their end.
  uint64_t periods = 0, late_periods = 0;
  double run_wall_s = 0;   // wall time not spent dormant
  double host_wait_s = 0;  // of it, free-running: waiting for the host's next request
  double speed() const { return run_wall_s > 0 ? board_s / run_wall_s : 0; }
};
// "N periods of 100 us, M late (x %)" when paced, else "x real time".
std::string describe_speed(const ServeStatus& s, bool paced);

struct ServeOptions {
  bool paced =
      true;  // at most 4 ms ahead of the wall clock (1 ms after host bytes); false: flat out (--speed max)
  double idle_exit_s = 0;     // return after this long without a host byte (0: never)
  double status_every_s = 5;  // wall seconds between status reports
  // Free-running: after answering a host request, wait this long (wall) for
  // the next one before running on, so that the host's reaction time does
  // not turn into board time (0: never wait, the fastest).
  double host_wait_s = 0;
  std::function<void(const ServeStatus&)> status;
  // Turns of the handwheel from other processes (sim/vboard/wheel_socket.hpp),
  // taken between runs; a request counts as host activity. nullptr: none.
  WheelSocket* wheel = nullptr;
};

// Runs the board on the pseudo-terminal until `stop` becomes true or the
// idle limit passes. Host bytes go onto RX as they come; TX bytes go out as
// the board sends them (dropped, and counted, when no host reads and the
// terminal's buffer is full). A dormant board (VirtualBoard::dormant) waits
// for the next host byte or wheel request with its clock stopped instead of
// burning a core.
ServeStatus serve(VirtualBoard& board, Pty& pty, const ServeOptions& opt, const std::atomic<bool>& stop);

}  // namespace mc::sim
