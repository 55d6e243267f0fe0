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

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh mc_safety; docs/formal.md). All inputs are
  // free: any host command, any pin, in any clock. As the top of a proof the
  // reset at the start is assumed; inside a harness it is asserted.
`ifdef FORMAL_TOP_mc_safety
`define SAFE_ASSUME assume
`else
`define SAFE_ASSUME assert
`endif

  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) `SAFE_ASSUME (rst);  // start from reset

  // f_quiet: clocks armed without a valid frame. f_enc: last clock's
  // encoder flags (for their rise).
  reg [23:0] f_quiet;
  reg [NAXES-1:0] f_enc;
  always @(posedge clk) begin
    f_quiet <= (rst || kick_i || !armed_o) ? 24'd0 : f_quiet + 24'd1;
    f_enc   <= rst ? {NAXES{1'b0}} : enc_err_i;
  end

  // The causes of each FAULT bit, as docs/protocol.md (Safety) states them,
  // and the bits that have a cause at all.
  reg [15:0] f_cause, f_used;
  always @(*) begin
    f_cause = 16'd0;
    f_cause[B_F_WDOG] = armed_o && f_quiet >= wdog_i;  // the watchdog expired
    f_cause[B_F_ESTOP] = estop_act_o;
    f_cause[B_F_LIMIT_LSB+:NAXES] = lim_act_o;
    f_cause[B_F_FERR_LSB+:NAXES] = ferr_i;
    f_cause[B_F_ENC_LSB+:NAXES] = enc_err_i & ~f_enc;
    f_used = 16'd0;
    f_used[B_F_WDOG] = 1'b1;
    f_used[B_F_ESTOP] = 1'b1;
    f_used[B_F_LIMIT_LSB+:NAXES] = {NAXES{1'b1}};
    f_used[B_F_FERR_LSB+:NAXES] = {NAXES{1'b1}};
    f_used[B_F_ENC_LSB+:NAXES] = {NAXES{1'b1}};
  end

  reg [15:0] f_cause_q, f_kept_q;  // last clock's causes, and its faults not cleared
  reg f_rst_q, f_arm_ok_q, f_clr_arm_q, f_armed_q;
  reg [23:0] f_quiet_q;
  always @(posedge clk) begin
    f_quiet_q   <= f_quiet;
    f_armed_q   <= armed_o;
    f_cause_q   <= f_cause;
    f_kept_q    <= fault_o & ~clr_i;
    f_rst_q     <= rst;
    f_arm_ok_q  <= arm_set_i && !arm_clr_i && fault_o == 16'd0 && f_cause == 16'd0;
    f_clr_arm_q <= arm_clr_i;
  end

  always @(*)
    if (f_past_valid) begin
      // The drives run only while armed, and never with a fault latched.
      assert (allow_o == {NAXES{armed_o}});
      if (fault_o != 16'd0) assert (!armed_o);
      // Reset: disarmed, nothing latched.
      if (f_rst_q) begin
        assert (!armed_o && fault_o == 16'd0);
      end else begin
        // A cause latches its bit and disarms in the next clock; in
        // particular an expired watchdog (armed, no valid frame for
        // WDOG clocks) turns the drives off.
        assert ((fault_o & f_cause_q) == f_cause_q);
        if (f_cause_q != 16'd0) assert (!armed_o);
        // A bit stays latched until the host clears it ...
        assert ((fault_o & f_kept_q) == f_kept_q);
        // ... and is set only by its cause.
        assert ((fault_o & ~f_kept_q & ~f_cause_q) == 16'd0);
        // Arming needs the arm command, no disarm command, no fault
        // latched and no cause present; a disarm command always disarms.
        if (armed_o && !f_armed_q) assert (f_arm_ok_q);
        if (f_clr_arm_q) assert (!armed_o);
      end
      // Bits without a cause never set.
      assert ((fault_o & ~f_used) == 16'd0);
      // How the registers make that (the induction needs it spelled out).
      if (armed_o) assert (wd == f_quiet);
      assert (enc_err_d == f_enc);
    end

`ifdef FORMAL_TOP_mc_safety
  // Not vacuous (covers only when this module is the top): the watchdog trips;
  // a fault latches, holds until cleared, and the axis is armed again after.
  reg [1:0] f_story;  // 1 armed, 2 then a fault latched, 3 then cleared and armed again
  always @(posedge clk)
    if (rst) f_story <= 2'd0;
    else if (f_story == 2'd0 && armed_o) f_story <= 2'd1;
    else if (f_story == 2'd1 && fault_o[B_F_LIMIT_LSB] && !armed_o) f_story <= 2'd2;
    else if (f_story == 2'd2 && armed_o) f_story <= 2'd3;
  always @(*)
    if (f_past_valid) begin
      cover (!f_rst_q && f_kept_q == 16'd0 && fault_o == 16'd1 << B_F_WDOG && f_quiet_q == 24'd5);
      cover (f_story == 2'd3);
    end
`endif

`undef SAFE_ASSUME
`endif

endmodule

`default_nettype wire
