// step_gen: step and direction for a stepper driver (A4988, DRV8825, TMC, or
// a servo drive with a step/dir input): one step per count of the
// interpolator's position command. Twin: hls/step_gen.hpp.
//
// How it behaves:
// - It watches the command's two low bits (cmd_i). The interpolator moves an
//   axis at most one count per iteration, so a change of +1 or -1 (mod 4) is
//   one step forward or back. A command loaded rather than moved (sync_i) and
//   any change while the axis is disabled are taken without a step.
// - Steps still owed are kept in a signed backlog of BL_W bits, so a pulse
//   longer than the iteration period delays steps instead of losing them.
//   A step that would take the backlog past +-(2^(BL_W-1) - 1), or a change
//   of 2 (mod 4: the command moved two counts at once), sets err_o, sticky
//   until clr_i: the step timing cannot follow the command and the motor
//   would lose position. The board counts it as a following-error fault.
// - A step whose direction differs from dir_o changes dir_o first and waits
//   max(setup_i, 1) clocks (the driver's dir-to-step setup time). Then step_o
//   is high for max(pw_i, 1) clocks and low for at least max(pw_i, 1) + 1
//   clocks, which also holds dir_o that long after the falling edge. The
//   highest step rate is f_clk / (2 pw_i + 1).
// - en_i low (drives off) drops the backlog and ends a pulse at once: a
//   disabled driver ignores its pins, and the host re-homes or re-syncs.
// - Pin polarity is applied at the top, not here.
`default_nettype none

module step_gen #(
    parameter integer PW_W = 8,  // width of the pulse and setup times, clocks
    parameter integer BL_W = 4   // width of the signed step backlog
) (
    // clock and reset
    input  wire            clk,
    input  wire            rst,
    // command
    input  wire [     1:0] cmd_i,    // the position command's two low bits
    input  wire            sync_i,   // cmd_i was loaded: take it without a step
    input  wire            en_i,     // the axis's drive is allowed
    // timing (STEP_CFG register)
    input  wire [PW_W-1:0] pw_i,     // step pulse width, clocks
    input  wire [PW_W-1:0] setup_i,  // direction-to-step setup, clocks
    input  wire            clr_i,    // clears err_o
    // driver pins, active high
    output reg             step_o,
    output reg             dir_o,    // 1: the count increases
    // status
    output reg             err_o,
    output reg  [BL_W-1:0] backlog_o
);

  initial begin
    if (PW_W < 2 || PW_W > 16) $error("step_gen: PW_W must be 2..16");
    if (BL_W < 2 || BL_W > 8) $error("step_gen: BL_W must be 2..8");
  end

  localparam [1:0] ST_IDLE = 2'd0, ST_SETUP = 2'd1, ST_HIGH = 2'd2, ST_LOW = 2'd3;
  localparam signed [BL_W-1:0] BL_MAX = {1'b0, {(BL_W - 1) {1'b1}}};

  reg  [     1:0] last;
  reg  [     1:0] st;
  reg  [PW_W-1:0] tmr;

  // The command's move in this clock: +1, -1, or an impossible 2.
  wire [     1:0] d = cmd_i - last;
  wire            moving = en_i && !sync_i;
  wire            inc = moving && d == 2'd1;
  wire            dec = moving && d == 2'd3;
  wire            jump = moving && d == 2'd2;
  wire            owed = backlog_o != {BL_W{1'b0}};
  wire            fwd = !backlog_o[BL_W-1];  // the owed steps' direction
  wire            tmr_end = tmr <= {{(PW_W - 1) {1'b0}}, 1'b1};
  // A pulse starts in this clock: a step is owed in dir_o's direction, and
  // the generator is idle or at the end of the setup time. A step owed the
  // other way turns dir_o first, and again if the command reverses while
  // the setup time runs; the setup time is waited out even if the command
  // comes back to where it was, so every pulse finds dir_o set up.
  wire            ready = owed && fwd == dir_o;
  wire            turn = en_i && owed && fwd != dir_o && (st == ST_IDLE || st == ST_SETUP);
  wire            rise = en_i && ready && (st == ST_IDLE || (st == ST_SETUP && tmr_end));
  // The backlog after this clock's step (taken at the rising edge) and move.
  wire [BL_W-1:0] taken = rise ? (dir_o ? backlog_o - 1'b1 : backlog_o + 1'b1) : backlog_o;
  wire            over = (inc && taken == BL_MAX) || (dec && taken == -BL_MAX);

  always @(posedge clk) begin
    if (rst) last <= 2'd0;
    else last <= cmd_i;
  end

  always @(posedge clk) begin
    if (rst || !en_i) backlog_o <= {BL_W{1'b0}};
    else if (over) backlog_o <= taken;
    else backlog_o <= taken + {{(BL_W - 1) {1'b0}}, inc} - {{(BL_W - 1) {1'b0}}, dec};
  end

  always @(posedge clk) begin
    if (rst) err_o <= 1'b0;
    else if (over || jump) err_o <= 1'b1;
    else if (clr_i) err_o <= 1'b0;
  end

  always @(posedge clk) begin
    if (rst) begin
      st <= ST_IDLE;
      tmr <= {PW_W{1'b0}};
      step_o <= 1'b0;
      dir_o <= 1'b1;
    end else if (rise) begin
      st <= ST_HIGH;
      tmr <= pw_i;
      step_o <= 1'b1;
    end else if (turn) begin
      st <= ST_SETUP;
      tmr <= setup_i;
      dir_o <= fwd;
    end else begin
      case (st)
        ST_IDLE: ;
        ST_SETUP: if (!tmr_end) tmr <= tmr - 1'b1;
        ST_HIGH:
        if (!en_i) begin  // a disabled driver: end the pulse now
          st <= ST_IDLE;
          step_o <= 1'b0;
        end else if (tmr_end) begin
          st <= ST_LOW;
          tmr <= pw_i;
          step_o <= 1'b0;
        end else tmr <= tmr - 1'b1;
        default:  // ST_LOW
        if (!en_i || tmr_end) st <= ST_IDLE;
        else tmr <= tmr - 1'b1;
      endcase
    end
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh step_gen; docs/formal.md). Every input is
  // free in every clock, the timing inputs too: a pulse keeps the width it
  // started with, the low time the pw_i of its fall, the setup the setup_i
  // of its turn. Values named f_*_q are last clock's.
  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) assume (rst);

  localparam [PW_W:0] F_SAT = {1'b1, {PW_W{1'b0}}};
  // f_hi: clocks step_o was high before this one, in this pulse; f_lo: clocks
  // it was low since it fell; f_dir: clocks dir_o was stable before the
  // last one (both saturate at F_SAT). f_dis: the axis was disabled or reset
  // since the pulse before the last one began.
  reg f_step_q, f_dir_q, f_rst_q, f_en_q, f_dis;
  reg [BL_W-1:0] f_bl_q;
  reg [PW_W:0] f_hi, f_lo, f_dir;
  reg [PW_W-1:0] f_pw, f_pwl, f_set;
  always @(posedge clk) begin
    f_step_q <= step_o;
    f_dir_q <= dir_o;
    f_rst_q <= rst;
    f_en_q <= en_i;
    f_bl_q <= backlog_o;
    if (rst) begin
      f_hi <= 0;
      f_lo <= F_SAT;
      f_dir <= F_SAT;
      f_dis <= 1'b1;
      f_pw <= 0;
      f_pwl <= 0;
      f_set <= 0;
    end else begin
      f_hi <= step_o ? f_hi + 1'b1 : {(PW_W + 1) {1'b0}};
      f_lo <= step_o ? {(PW_W + 1) {1'b0}} : (f_lo[PW_W] ? f_lo : f_lo + 1'b1);
      f_dir <= dir_o != f_dir_q ? {(PW_W + 1) {1'b0}} : (f_dir[PW_W] ? f_dir : f_dir + 1'b1);
      f_dis <= (step_o && !f_step_q ? 1'b0 : f_dis) | !en_i;  // cleared once a pulse has begun
      if (rise) f_pw <= pw_i;
      if (en_i && st == ST_HIGH && tmr_end) f_pwl <= pw_i;
      if (turn) f_set <= setup_i;
    end
  end
  wire [PW_W:0] f_pw1 = f_pw == 0 ? 1 : {1'b0, f_pw};
  wire [PW_W:0] f_pwl1 = f_pwl == 0 ? 1 : {1'b0, f_pwl};
  wire [PW_W:0] f_set1 = f_set == 0 ? 1 : {1'b0, f_set};

  always @(*)
    if (f_past_valid && !f_rst_q) begin
      // A pulse starts for a step owed in dir_o's direction, with dir_o set
      // up and the last one's low time kept.
      if (step_o && !f_step_q) begin
        assert (f_bl_q != 0 && f_bl_q[BL_W-1] != dir_o);
        assert (f_dir + 1'b1 >= f_set1 || f_dir[PW_W]);
        assert (f_dis || f_lo >= f_pwl1 + 1'b1 || f_lo[PW_W]);
      end
      // A pulse ends after exactly its width, unless the axis was disabled.
      if (!step_o && f_step_q && f_en_q) assert (f_hi == f_pw1);
      // dir_o moves only between pulses, never in a pulse's first low clock.
      if (dir_o != f_dir_q) assert (!step_o && !f_step_q && f_lo >= 1);
      // Disabled: no pulse, nothing owed.
      if (!f_en_q) assert (!step_o && backlog_o == 0);
    end

  // The state's invariants, spelled out for the induction.
  always @(*)
    if (f_past_valid && !f_rst_q) begin
      assert (step_o == (st == ST_HIGH));
      assert (f_dir <= F_SAT && f_lo <= F_SAT && f_hi < F_SAT);
      assert (backlog_o != {1'b1, {(BL_W - 1) {1'b0}}});  // never -2^(BL_W-1)
      if (st == ST_HIGH) assert (f_hi + (tmr == 0 ? 1 : tmr) == f_pw1 && (f_pw == 0 || tmr != 0));
      if (st == ST_LOW) assert (f_lo + (tmr == 0 ? 1 : tmr) == f_pwl1 && (f_pwl == 0 || tmr != 0));
      if (st == ST_IDLE || st == ST_SETUP) assert (f_dis || f_lo >= f_pwl1 || f_lo[PW_W]);
      if (st == ST_SETUP && dir_o != f_dir_q) assert (tmr == f_set);
      if (st == ST_SETUP && dir_o == f_dir_q)
        assert (f_dir[PW_W] || (tmr_end ? f_dir + 2'd2 >= f_set1 : f_dir + tmr + 1'b1 == f_set1));
      if (st != ST_SETUP) assert (f_dir + 1'b1 >= f_set1 || f_dir[PW_W]);
    end

  always @(posedge clk) begin
    cover (f_past_valid && !f_rst_q && step_o && !f_step_q && !dir_o && f_set == 3);
    cover (f_past_valid && !f_rst_q && err_o);
  end
`endif

endmodule

`default_nettype wire
