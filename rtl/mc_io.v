// mc_io: the machine I/O of the board: the probe and home-switch latches,
// the spindle and coolant outputs, and the handwheel jog. It sits on the
// register file's write bus and owns IO_CTRL, LATCH, MPG and MPG_INC (their
// read-back comes from the register file's shadow RAM) and IO_STAT's live
// value. Twin: hls/mc_io.hpp. docs/protocol.md has the registers,
// docs/board.md the pins.
//
// How it behaves:
// - The probe (probe_i, synchronized, LATCH.probe_inv applied) and each
//   home switch (the axis's limit input, SAFETY's polarity applied, whether
//   or not the limit is enabled) pass a glitch filter: a new level counts
//   once the input has shown it on 4 consecutive clocks.
// - latch_o[a] pulses in the clock the filtered input that LATCH selects for
//   axis a (its home switch, or the probe) becomes active. The decoders take
//   it as an index edge: every armed axis latches its position in that one
//   clock, exact whatever the link latency. With LATCH.stop, a pulse that
//   finds its axis armed also pulses stop_o in the same clock: the board
//   aborts the interpolator (queue flushed, command held).
// - Spindle: PWM over 1024 clocks (11.7 kHz at 12 MHz) with IO_CTRL's duty,
//   enable and direction; two coolant outputs. All of them are low while the
//   drives are disarmed (armed_i), so any fault or the watchdog stops them.
//   IO_CTRL.mist_on_dir puts the mist output on the direction pin (sp_dir_o)
//   for boards with one pin for both.
// - Handwheel jog (MPG.on): every detent of the handwheel (hw_pos_i: four
//   counts, or one with MPG.detent1) adds the selected increment to a
//   pending count (signed; a detent that would take it further beyond
//   16383 is dropped, so it never wraps). While the drives are armed and the
//   interpolator is idle with its queue empty, jog_o moves the selected
//   axis's command one count at a time towards nothing pending, the counts
//   16 * (MPG.rate - 1) + 1 to 16 * MPG.rate clocks apart (MPG.rate below 2
//   acts as 2), under the same following-error and limit checks as any
//   motion. Turning MPG off drops what is pending.
`default_nettype none

module mc_io #(
    parameter integer NAXES = 3  // axes (1..3)
) (
    // clock and reset
    input  wire             clk,
    input  wire             rst,
    // register write bus (mc_regs): global registers, by address bits [4:0]
    input  wire             bus_we_i,
    input  wire [      4:0] bus_addr_i,
    input  wire [     31:0] bus_wdata_i,
    output wire [     31:0] stat_o,       // IO_STAT but the step errors
    // machine state
    input  wire             armed_i,
    input  wire [NAXES-1:0] lim_inv_i,    // SAFETY's limit polarity
    // switches (synchronized)
    input  wire [NAXES-1:0] lim_i,
    input  wire             probe_i,
    // position latches and interpolator (motion_core)
    input  wire [NAXES-1:0] idx_armed_i,
    output reg  [NAXES-1:0] latch_o,
    output reg              stop_o,
    input  wire             ip_idle_i,    // not busy, queue empty
    output reg  [      2:0] jog_o,
    output reg              jog_neg_o,
    // handwheel position (its decoder): the low bits
    input  wire [      7:0] hw_pos_i,
    // spindle and coolant pins
    output reg              sp_pwm_o,
    output reg              sp_en_o,
    output reg              sp_dir_o,
    output reg              flood_o,
    output reg              mist_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  initial begin
    if (NAXES < 1 || NAXES > 3) $error("mc_io: NAXES must be 1..3");
  end

  // ---------------------------------------------------------------------
  // Registers from the bus.
  reg         sp_on, sp_rev, flood, mist, mist_on_dir;
  reg  [ 9:0] duty;
  reg  [ 5:0] lsrc;
  reg         probe_inv, lstop;
  reg         m_on, m_det1;
  reg  [ 1:0] m_axis, m_step;
  reg  [ 7:0] m_rate;
  reg  [11:0] m_inc;
  always @(posedge clk) begin
    if (rst) begin
      {sp_on, sp_rev, flood, mist, mist_on_dir} <= 5'd0;
      duty      <= 10'd0;
      lsrc      <= 6'd0;
      probe_inv <= 1'b0;
      lstop     <= 1'b0;
      m_on      <= 1'b0;
      m_det1    <= 1'b0;
      m_axis    <= 2'd0;
      m_step    <= 2'd0;
      m_rate    <= 8'd0;
      m_inc     <= 12'd0;
    end else if (bus_we_i) begin
      case (bus_addr_i)
        R_IO_CTRL[4:0]: begin
          sp_on       <= bus_wdata_i[B_IO_SPINDLE];
          sp_rev      <= bus_wdata_i[B_IO_SPINDLE_REV];
          flood       <= bus_wdata_i[B_IO_FLOOD];
          mist        <= bus_wdata_i[B_IO_MIST];
          mist_on_dir <= bus_wdata_i[B_IO_MIST_ON_DIR];
          duty        <= bus_wdata_i[B_IO_DUTY_LSB+:10];
        end
        R_LATCH[4:0]: begin
          lsrc      <= bus_wdata_i[B_L_SRC_LSB+:6];
          probe_inv <= bus_wdata_i[B_L_PROBE_INV];
          lstop     <= bus_wdata_i[B_L_STOP];
        end
        R_MPG[4:0]: begin
          m_on   <= bus_wdata_i[B_M_ON];
          m_axis <= bus_wdata_i[B_M_AXIS_LSB+:2];
          m_step <= bus_wdata_i[B_M_STEP_LSB+:2];
          m_det1 <= bus_wdata_i[B_M_DETENT1];
          m_rate <= bus_wdata_i[B_M_RATE_LSB+:8];
        end
        R_MPG_INC[4:0]: m_inc <= bus_wdata_i[11:0];
        default: ;
      endcase
    end
  end

  // ---------------------------------------------------------------------
  // Switch filters: the home switches, then the probe. sw_cnt: clocks the
  // input has differed from its level, minus one.
  localparam integer NS = NAXES + 1;
  wire [NS-1:0] sw_in = {probe_i ^ probe_inv, lim_i ^ lim_inv_i};
  wire [NS-1:0] sw_rst = {probe_i, lim_i ^ lim_inv_i};  // with probe_inv's reset value
  reg  [NS-1:0] sw;  // filtered levels
  reg  [NS*2-1:0] sw_cnt;
  reg  [NS-1:0] sw_rise;  // the filtered level becomes 1 at this clock's edge
  integer i;
  always @(*) begin
    for (i = 0; i < NS; i = i + 1) sw_rise[i] = sw_in[i] && !sw[i] && &sw_cnt[i*2+:2];
  end
  always @(posedge clk) begin
    for (i = 0; i < NS; i = i + 1) begin
      if (rst) begin
        sw[i] <= sw_rst[i];  // adopt the present levels: leaving reset latches nothing
        sw_cnt[i*2+:2] <= 2'd0;
      end else if (sw_in[i] == sw[i]) begin
        sw_cnt[i*2+:2] <= 2'd0;
      end else begin
        if (&sw_cnt[i*2+:2]) sw[i] <= sw_in[i];
        sw_cnt[i*2+:2] <= sw_cnt[i*2+:2] + 2'd1;  // 3 wraps to 0 as the level flips
      end
    end
  end

  // Latch strobes, and the stop they make.
  reg [NAXES-1:0] lat;
  always @(*) begin
    for (i = 0; i < NAXES; i = i + 1) begin
      case (lsrc[i*2+:2])
        2'd1: lat[i] = sw_rise[i];
        2'd2: lat[i] = sw_rise[NAXES];
        default: lat[i] = 1'b0;
      endcase
    end
  end
  always @(posedge clk) begin
    if (rst) begin
      latch_o <= {NAXES{1'b0}};
      stop_o  <= 1'b0;
    end else begin
      latch_o <= lat;
      stop_o  <= lstop && |(lat & idx_armed_i);
    end
  end

  // ---------------------------------------------------------------------
  // Spindle and coolant.
  reg [9:0] pcnt;
  always @(posedge clk) begin
    if (rst) begin
      pcnt     <= 10'd0;
      sp_pwm_o <= 1'b0;
      sp_en_o  <= 1'b0;
      sp_dir_o <= 1'b0;
      flood_o  <= 1'b0;
      mist_o   <= 1'b0;
    end else begin
      pcnt     <= pcnt + 10'd1;
      sp_pwm_o <= armed_i && sp_on && (&duty || pcnt < duty);
      sp_en_o  <= armed_i && sp_on;
      sp_dir_o <= armed_i && (mist_on_dir ? mist : sp_on && sp_rev);
      flood_o  <= armed_i && flood;
      mist_o   <= armed_i && mist;
    end
  end

  // ---------------------------------------------------------------------
  // Handwheel jog. ref: the handwheel count of the last detent (low bits).
  // One adder serves a detent (+-inc) and a count moved (towards zero).
  reg  [ 7:0] ref_pos;
  reg  [15:0] pend;  // signed
  reg  [ 7:0] tmr;  // in units of 16 clocks (pcnt's low bits)
  wire [ 7:0] hd = hw_pos_i - ref_pos;
  wire [ 7:0] det = m_det1 ? 8'd1 : 8'd4;
  // hd >= det and -hd >= det, for det 1 or 4, without the comparators.
  wire        det_up = !hd[7] && (m_det1 ? |hd[6:0] : |hd[6:2]);
  wire        det_dn = hd[7] && (m_det1 || !(&hd[6:2] && |hd[1:0]));  // hd <= -4: not FD..FF
  // A detent is taken while |pend| is below 16384, or when it lowers it.
  wire        room = pend[15] == pend[14] || (det_dn ^ pend[15]);
  reg  [11:0] inc;
  always @(*) begin
    case (m_step)
      2'd0: inc = 12'd1;
      2'd1: inc = 12'd10;
      2'd2: inc = 12'd100;
      default: inc = m_inc;
    endcase
  end
  wire        pend_nz = pend != 16'd0;
  wire        go = m_on && armed_i && ip_idle_i && pend_nz && tmr == 8'd0 && !(det_up || det_dn);
  wire [15:0] step = (det_up || det_dn) ? (det_dn ? -{4'd0, inc} : {4'd0, inc}) : (pend[15] ? 16'd1 : 16'hFFFF);
  wire [15:0] p_next = pend + step;
  always @(posedge clk) begin
    jog_o     <= 3'd0;
    jog_neg_o <= !rst && pend[15];
    if (rst || !m_on) begin
      ref_pos <= hw_pos_i;
      pend    <= 16'd0;
      tmr     <= 8'd0;
    end else begin
      if (det_up || det_dn) ref_pos <= det_dn ? ref_pos - det : ref_pos + det;
      if (((det_up || det_dn) && room) || go) pend <= p_next;
      if (go) tmr <= m_rate < 8'd2 ? 8'd2 : m_rate;
      else if (tmr != 8'd0 && &pcnt[3:0]) tmr <= tmr - 8'd1;
      if (go) jog_o <= 3'd1 << m_axis;
    end
  end

  reg [31:0] stat;
  always @(*) begin
    stat = 32'd0;
    stat[B_IOS_PROBE] = sw[NAXES];
    stat[B_IOS_HOME_LSB+:NAXES] = sw[NAXES-1:0];
    stat[B_IOS_MPG_PEND_LSB+:16] = pend;
  end
  assign stat_o = stat;

endmodule

`default_nettype wire
