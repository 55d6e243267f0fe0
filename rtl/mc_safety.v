// mc_safety: the fault latches, the arm state and the link watchdog.
//
// How it behaves:
// - The drives may run (allow_o) only while armed. arm_set_i arms, but only
//   with no fault latched; arm_clr_i disarms. Reset leaves it disarmed, so
//   the drives are off from configuration until the host arms them.
// - Each fault source sets its bit of fault_o (bit positions B_F_* of
//   rtl/board_regs.vh) and disarms at once: the watchdog (armed and no
//   kick_i for wdog_i clocks), the e-stop, a limit switch of an axis, a
//   following-error trip (ferr_i, a strobe) and an encoder error (the rise
//   of enc_err_i, the decoder's sticky flag: the host clears the flag along
//   with the FAULT bit, and the flag falls a clock after that). Enables and polarities of the switches come from cfg_i
//   (the SAFETY register).
// - clr_i clears the bits set in it (write 1 to clear). A condition still
//   present sets its bit again at once, so a fault is cleared only once its
//   cause is gone; after that the host arms again.
`default_nettype none

module mc_safety #(
    parameter integer NAXES = 3  // axes (1..3)
) (
    // clock and reset
    input  wire             clk,
    input  wire             rst,
    // host commands
    input  wire             arm_set_i,
    input  wire             arm_clr_i,
    input  wire [     15:0] clr_i,
    input  wire [      7:0] cfg_i,
    input  wire [     23:0] wdog_i,     // clock cycles
    input  wire             kick_i,     // a valid frame arrived
    // fault sources
    input  wire             estop_i,    // synchronized pin (polarity and enable: cfg_i)
    input  wire             stop_i,     // local stop button, active high, always enabled
    input  wire [NAXES-1:0] lim_i,      // synchronized pins
    input  wire [NAXES-1:0] ferr_i,     // following-error trips
    input  wire [NAXES-1:0] enc_err_i,  // decoder error flags
    // state
    output reg  [     15:0] fault_o,
    output reg              armed_o,
    output wire [NAXES-1:0] allow_o,
    output wire             estop_act_o,
    output wire [NAXES-1:0] lim_act_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  initial begin
    if (NAXES < 1 || NAXES > 3) $error("mc_safety: NAXES must be 1..3");
  end

  assign estop_act_o = stop_i | (cfg_i[B_S_ESTOP_EN] & (estop_i ^ cfg_i[B_S_ESTOP_INV]));
  assign lim_act_o = cfg_i[B_S_LIM_EN_LSB+:NAXES] & (lim_i ^ cfg_i[B_S_LIM_INV_LSB+:NAXES]);

  // Watchdog: counts while armed, restarts on every valid frame.
  reg  [23:0] wd;
  wire        wd_trip = armed_o && wd >= wdog_i;
  always @(posedge clk) begin
    if (rst || kick_i || !armed_o) wd <= 24'd0;
    else if (!wd_trip) wd <= wd + 24'd1;
  end

  reg [NAXES-1:0] enc_err_d;
  always @(posedge clk) enc_err_d <= rst ? {NAXES{1'b0}} : enc_err_i;

  reg [15:0] ev;
  always @(*) begin
    ev = 16'd0;
    ev[B_F_WDOG] = wd_trip;
    ev[B_F_ESTOP] = estop_act_o;
    ev[B_F_LIMIT_LSB+:NAXES] = lim_act_o;
    ev[B_F_FERR_LSB+:NAXES] = ferr_i;
    ev[B_F_ENC_LSB+:NAXES] = enc_err_i & ~enc_err_d;
  end

  always @(posedge clk) begin
    if (rst) fault_o <= 16'd0;
    else fault_o <= (fault_o & ~clr_i) | ev;
  end

  always @(posedge clk) begin
    if (rst || |ev || arm_clr_i) armed_o <= 1'b0;
    else if (arm_set_i && fault_o == 16'd0) armed_o <= 1'b1;
  end

  assign allow_o = {NAXES{armed_o}};

endmodule

`default_nettype wire
