// motioncore_icebreaker: the iCEBreaker board top. It holds only what faces
// the pins: the power-on reset, a two-flop synchronizer on every input that
// is not an encoder (the decoders synchronize those themselves), and the
// LEDs' active-low drive. The 24 PMOD pins carry three axes (encoder A/B,
// limit = home switch, PWM/DIR or STEP/DIR), one enable for every driver,
// the probe, the spindle (PWM, enable, direction or mist), flood coolant,
// the handwheel and the e-stop; no encoder index (no pin is left for it). Everything else is mc_board. Pin names are those
// of constraints/icebreaker.pcf; docs/board.md maps them to PMOD pins.
//
// The UART runs at BAUD over the FTDI FT2232H's second channel (the board's
// RX/TX pins); 12 MHz / BAUD must be a whole number of clocks (uart_rx).
//
// Two builds fit the UP5K (docs/board.md): the servo board (STEPPERS = 0,
// SERVO = 1, `make synth`) and the stepper board (STEPPERS = 7, SERVO = 0,
// `make synth-stepper`); INFO tells the host which it is.
`default_nettype none

module motioncore_icebreaker #(
    parameter integer NAXES  = 3,           // axes built (1..3): X, then Y, then Z
    parameter integer CLK_HZ = 12_000_000,  // the board oscillator, Hz
    parameter integer BAUD   = 1_000_000,   // host link, bit/s
    parameter integer HANDWHEEL = 1,        // build the handwheel decoder
    parameter integer STEPPERS  = 0,        // axes built with a step generator (bit a: axis a)
    parameter integer SERVO     = 1         // the PID loops; 0: a stepper board without them
) (
    // clock: 12 MHz oscillator
    input  wire CLK,
    // FTDI UART and the board's button and LEDs
    input  wire RX,
    output wire TX,
    input  wire BTN_N,
    output wire LEDR_N,
    output wire LEDG_N,
    // PMOD 1A: axis X, probe, the drivers' shared enable, handwheel A
    input  wire X_ENC_A,
    input  wire X_ENC_B,
    input  wire PROBE,
    input  wire X_LIM,
    output wire X_PWM,    // STEP on a stepper axis
    output wire X_DIR,
    output wire DRV_EN,
    input  wire HW_A,
    // PMOD 1B: axis Y, flood coolant, spindle PWM, handwheel B
    input  wire Y_ENC_A,
    input  wire Y_ENC_B,
    output wire FLOOD,
    input  wire Y_LIM,
    output wire Y_PWM,
    output wire Y_DIR,
    output wire SP_PWM,
    input  wire HW_B,
    // PMOD 2: axis Z, spindle direction (or mist) and enable, e-stop
    input  wire Z_ENC_A,
    input  wire Z_ENC_B,
    output wire SP_DIR,
    input  wire Z_LIM,
    output wire Z_PWM,
    output wire Z_DIR,
    output wire SP_EN,
    input  wire ESTOP
);

  initial begin
    if (NAXES < 1 || NAXES > 3) $error("motioncore_icebreaker: NAXES must be 1..3");
  end

  // Power-on reset: the flip-flops start at zero after configuration, so the
  // counter holds rst for 15 clocks, long enough to fill every synchronizer.
  reg  [3:0] por = 4'd0;
  wire       rst = ~&por;
  always @(posedge clk_w) if (rst) por <= por + 4'd1;
  wire clk_w = CLK;

  // Pins of the three axis slots; an axis not built leaves its inputs
  // unused and its outputs low.
  /* verilator lint_off UNUSEDSIGNAL */
  wire [2:0] lim_p = {Z_LIM, Y_LIM, X_LIM};
  wire [2:0] enc_a_p = {Z_ENC_A, Y_ENC_A, X_ENC_A};
  wire [2:0] enc_b_p = {Z_ENC_B, Y_ENC_B, X_ENC_B};
  /* verilator lint_on UNUSEDSIGNAL */

  // Two-flop synchronizers: {RX, probe, button, e-stop, limits}. RX idles high.
  localparam integer NS = 4 + NAXES;
  reg [NS-1:0] s1, s2;
  always @(posedge clk_w) begin
    s1 <= {RX, PROBE, ~BTN_N, ESTOP, lim_p[NAXES-1:0]};
    s2 <= s1;
  end

  wire [NAXES-1:0] pwm, dir, en;
  wire led_ok, led_fault;
  /* verilator lint_off UNUSEDSIGNAL */
  wire mist;
  /* verilator lint_on UNUSEDSIGNAL */
  mc_board #(
      .NAXES (NAXES),
      .CLK_HZ(CLK_HZ),
      .BAUD  (BAUD),
      .HANDWHEEL(HANDWHEEL),
      .STEPPERS (STEPPERS),
      .SERVO    (SERVO)
  ) u_board (
      .clk        (clk_w),
      .rst        (rst),
      .rx_i       (s2[NS-1]),
      .tx_o       (TX),
      .enc_a_i    (enc_a_p[NAXES-1:0]),
      .enc_b_i    (enc_b_p[NAXES-1:0]),
      .enc_z_i    ({NAXES{1'b0}}),
      .hw_a_i     (HW_A),
      .hw_b_i     (HW_B),
      .lim_i      (s2[NAXES-1:0]),
      .estop_i    (s2[NAXES]),
      .stop_i     (s2[NAXES+1]),
      .probe_i    (s2[NAXES+2]),
      .pwm_o      (pwm),
      .dir_o      (dir),
      .drv_en_o   (en),
      .sp_pwm_o   (SP_PWM),
      .sp_en_o    (SP_EN),
      .sp_dir_o   (SP_DIR),
      .flood_o    (FLOOD),
      .mist_o     (mist),  // no pin: IO_CTRL.mist_on_dir puts it on SP_DIR
      .led_ok_o   (led_ok),
      .led_fault_o(led_fault)
  );

  /* verilator lint_off UNUSEDSIGNAL */
  wire [NAXES+2:0] pwm_p = {3'b000, pwm};
  wire [NAXES+2:0] dir_p = {3'b000, dir};
  /* verilator lint_on UNUSEDSIGNAL */
  assign {Z_PWM, Y_PWM, X_PWM} = pwm_p[2:0];
  assign {Z_DIR, Y_DIR, X_DIR} = dir_p[2:0];
  assign DRV_EN = |en;
  assign LEDG_N = ~led_ok;
  assign LEDR_N = ~led_fault;

endmodule

`default_nettype wire
