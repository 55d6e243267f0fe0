// mc_step: the stepper axes of the board. It owns STEP_CFG (from the
// register file's write bus) and, for each axis STEP_CFG makes a stepper, a
// step_gen on the interpolator's command whose step and direction replace
// the H-bridge's PWM and DIR on the axis's pins. Twin: hls/mc_step.hpp.
//
// How it behaves:
// - Servo axis (the default): the pins carry motion_core's PWM and DIR and
//   the decoder the encoder pins, as before.
// - Stepper axis: one step per count of the command (step_gen: pulse width
//   and direction setup from STEP_CFG, polarity per axis). Open loop, the
//   decoder counts the steps sent (a quadrature copy of them), so POS, the
//   following error and the latches work as on a servo axis: FOLLOW is the
//   steps still owed. Closed loop (STEP_CFG.closed), the decoder counts the
//   encoder, which must give one count per step: lost steps show as
//   following error and trip FERR.
// - A step generator that cannot follow (err) raises ferr_o for one clock:
//   the board latches it as the axis's following-error fault; clearing that
//   fault (clr_i) clears the generator's error.
// - The generators run while the drives are allowed (allow_i); disarmed,
//   they drop what they owe (the host re-syncs the axis before arming).
// - Only the axes in STEPPERS get a generator (a board build option: the
//   iCEBreaker has no room for three next to three servo loops); on the
//   others STEP_CFG's bits are ignored and the pins stay the H-bridge's.
`default_nettype none

module mc_step #(
    parameter integer NAXES    = 3,  // axes (1..3)
    parameter integer STEPPERS = 7   // axes built with a step generator, bit a for axis a
) (
    // clock and reset
    input  wire               clk,
    input  wire               rst,
    // register write bus (mc_regs)
    input  wire               bus_we_i,
    input  wire [        4:0] bus_addr_i,
    /* verilator lint_off UNUSEDSIGNAL */
    input  wire [       31:0] bus_wdata_i,  // STEP_CFG's fields
    /* verilator lint_on UNUSEDSIGNAL */
    // command (interp_core): two low bits per axis, loads
    input  wire [NAXES*2-1:0] cmd_i,
    input  wire [NAXES-1:0]   sync_i,
    input  wire               allow_i,
    input  wire [NAXES-1:0]   clr_i,
    // H-bridge side (motion_core) and encoder pins
    input  wire [NAXES-1:0]   pwm_i,
    input  wire [NAXES-1:0]   dir_i,
    input  wire [NAXES-1:0]   enc_a_i,
    input  wire [NAXES-1:0]   enc_b_i,
    // pins and decoder inputs
    output wire [NAXES-1:0]   pwm_o,      // PWM, or STEP
    output wire [NAXES-1:0]   dir_o,
    output wire [NAXES-1:0]   enc_a_o,
    output wire [NAXES-1:0]   enc_b_o,
    // status
    output wire [NAXES-1:0]   stepper_o,
    output wire [NAXES-1:0]   err_o,      // sticky, per generator
    output wire [NAXES-1:0]   ferr_o      // one clock as err rises
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  initial begin
    if (NAXES < 1 || NAXES > 3) $error("mc_step: NAXES must be 1..3");
  end

  /* verilator lint_off WIDTH */
  localparam [NAXES-1:0] BUILT = STEPPERS;
  /* verilator lint_on WIDTH */
  reg [NAXES-1:0] stepper, closed, step_inv, dir_rev;
  reg [5:0] pw, setup;
  always @(posedge clk) begin
    if (rst) begin
      stepper  <= {NAXES{1'b0}};
      closed   <= {NAXES{1'b0}};
      step_inv <= {NAXES{1'b0}};
      dir_rev  <= {NAXES{1'b0}};
      pw       <= 6'd0;
      setup    <= 6'd0;
    end else if (bus_we_i && bus_addr_i == R_STEP_CFG[4:0]) begin
      stepper  <= bus_wdata_i[B_SC_STEPPER_LSB+:NAXES] & BUILT;
      closed   <= bus_wdata_i[B_SC_CLOSED_LSB+:NAXES];
      pw       <= bus_wdata_i[B_SC_PW_LSB+:6];
      setup    <= bus_wdata_i[B_SC_SETUP_LSB+:6];
      step_inv <= bus_wdata_i[B_SC_STEP_INV_LSB+:NAXES];
      dir_rev  <= bus_wdata_i[B_SC_DIR_INV_LSB+:NAXES];
    end
  end
  assign stepper_o = stepper;

  genvar g;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_ax
      if (BUILT[g]) begin : g_gen
        wire step, sdir, err;
        /* verilator lint_off PINCONNECTEMPTY */
        step_gen #(
            .PW_W(6),
            .BL_W(4)
        ) u_gen (
            .clk      (clk),
            .rst      (rst),
            .cmd_i    (cmd_i[g*2+:2]),
            .sync_i   (sync_i[g]),
            .en_i     (allow_i & stepper[g]),
            .pw_i     (pw),
            .setup_i  (setup),
            .clr_i    (clr_i[g]),
            .step_o   (step),
            .dir_o    (sdir),
            .err_o    (err),
            .backlog_o()
        );
        /* verilator lint_on PINCONNECTEMPTY */

        // The steps sent, as quadrature (A leads B forward): the open-loop
        // axis's decoder counts them.
        reg [1:0] q;
        reg step_q, err_q, fe;
        always @(posedge clk) begin
          if (rst) begin
            q      <= 2'd0;
            step_q <= 1'b0;
            err_q  <= 1'b0;
            fe     <= 1'b0;
          end else begin
            step_q <= step;
            err_q  <= err;
            fe     <= err & ~err_q;
            if (step && !step_q) q <= sdir ? q + 2'd1 : q - 2'd1;
          end
        end
        wire loop = stepper[g] & ~closed[g];
        assign enc_a_o[g] = loop ? q[1] ^ q[0] : enc_a_i[g];
        assign enc_b_o[g] = loop ? q[1] : enc_b_i[g];
        assign pwm_o[g]   = stepper[g] ? step ^ step_inv[g] : pwm_i[g];
        assign dir_o[g]   = stepper[g] ? sdir ^ dir_rev[g] : dir_i[g];
        assign err_o[g]   = err;
        assign ferr_o[g]  = fe;
      end else begin : g_servo
        /* verilator lint_off UNUSEDSIGNAL */
        wire unused = &{1'b0, cmd_i[g*2+:2], sync_i[g], clr_i[g], closed[g], step_inv[g], dir_rev[g], pw, setup, allow_i};
        /* verilator lint_on UNUSEDSIGNAL */
        assign enc_a_o[g] = enc_a_i[g];
        assign enc_b_o[g] = enc_b_i[g];
        assign pwm_o[g]   = pwm_i[g];
        assign dir_o[g]   = dir_i[g];
        assign err_o[g]   = 1'b0;
        assign ferr_o[g]  = 1'b0;
      end
    end
  endgenerate

endmodule

`default_nettype wire
