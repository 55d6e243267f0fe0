// interp_core: the interpolator. A queue of segments (lines, stairs arcs,
// dwells), the feed-rate generator, and the position command it moves one
// count at a time. Twin: hls/interp_core.hpp; segment format:
// hls/interp_seg.hpp.
//
// How to drive it:
// - Queue segments a word at a time with wr_i/wdata_i. A segment is admitted
//   whole or not at all: if the FIFO lacks room for all SEG_WORDS words when
//   its first word arrives, the whole segment is dropped and ovf_o set, so the
//   queue never falls out of step. Check count_o before writing.
// - The core loads the oldest segment (SEG_WORDS + 1 clocks) and runs it,
//   then the next, with the feed generator's phase carried over, so queued
//   segments run without a stop; iterations that fall due during a load are
//   kept (up to three) and run after it.
// - A segment that ends with no whole segment queued behind it, and is not
//   marked last, sets underrun_o: the position holds, never jumps, and
//   motion resumes when segments arrive.
// - hold_i pauses the feed; abort_i stops at once and empties the queue;
//   set_i loads pos_o from set_pos_i and is taken only while idle (busy_o
//   low); clr_i clears the sticky flags (an event in the same cycle wins).
`default_nettype none

module interp_core #(
    parameter integer FIFO_AW = 9  // log2 of the queue depth in words
) (
    // clock and reset
    input  wire              clk,
    input  wire              rst,
    // segment queue
    input  wire              wr_i,
    input  wire [      31:0] wdata_i,
    output wire [ FIFO_AW:0] count_o,
    // control
    input  wire              abort_i,
    input  wire              hold_i,
    input  wire              clr_i,
    input  wire              set_i,
    input  wire [    3*32-1:0] set_pos_i,
    // position command, counts: x in [31:0], y, z
    output wire [    3*32-1:0] pos_o,
    // status
    output wire              busy_o,
    output reg               underrun_o,
    output reg               ovf_o,
    output reg  [      15:0] seg_cnt_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "interp_seg.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer NW = SEG_N_W;
  localparam integer DEPTH = 1 << FIFO_AW;
  localparam [1:0] ST_IDLE = 2'd0, ST_LOAD = 2'd1, ST_RUN = 2'd2;
  /* verilator lint_off WIDTH */
  localparam [3:0] I_HDR = SEG_W_HDR;
  localparam [3:0] I_N = SEG_W_N;
  localparam [3:0] NWORDS = SEG_WORDS;
  localparam [3:0] I_LAST = SEG_WORDS - 1;
  localparam [FIFO_AW:0] SEGW = SEG_WORDS;
  localparam [FIFO_AW:0] ROOM = DEPTH - SEG_WORDS;  // most words held with room for a segment
  localparam [1:0] T_LINE = SEG_T_LINE;
  localparam [1:0] T_ARC = SEG_T_ARC;
  /* verilator lint_on WIDTH */

  initial begin
    if (FIFO_AW < 4 || FIFO_AW > 12) begin
      $error("interp_core: FIFO_AW must be 4..12");
    end
  end

  reg  [   1:0] st;
  reg  [   3:0] widx;  // next word to read while loading
  reg  [   3:0] ridx;  // word arriving from the FIFO
  reg           rv;    // a word arrives this cycle
  reg  [   3:0] wi;    // writer: word index within the segment being queued
  reg           drop;  // writer: the segment being queued is dropped
  reg  [   1:0] pend;  // iterations due, not yet run
  reg  [   1:0] typ;
  reg           last;
  reg  [   1:0] plane;
  reg  [NW-1:0] n_left;

  wire [  31:0] rdata;
  wire          fire;
  wire [   2:0] l_mv, l_neg;
  wire a_rdy, a_movex, a_neg, a_out, a_fin;

  // --- Sequencing -----------------------------------------------------------
  wire running = st == ST_RUN;
  wire is_line = typ == T_LINE;
  wire is_arc = typ == T_ARC;
  // An arc's decision is registered (arc_interp): valid while a_rdy.
  wire fin = n_left == {NW{1'b0}} || (is_arc && a_rdy && a_fin);
  wire it = running && !fin && pend != 2'd0 && !hold_i && !abort_i && (!is_arc || a_rdy);
  wire rd = st == ST_LOAD && widx < NWORDS && !abort_i;
  wire ld = rv && !abort_i;
  // Writer: the first word decides for the whole segment.
  wire drop_n = wi == 4'd0 ? count_o > ROOM : drop;
  wire push = wr_i && !abort_i && !drop_n;

  seg_fifo #(
      .AW(FIFO_AW)
  ) u_fifo (
      .clk    (clk),
      .rst    (rst),
      .flush_i(abort_i),
      .wr_i   (push),
      .wdata_i(wdata_i),
      .rd_i   (rd),
      .rdata_o(rdata),
      .count_o(count_o)
  );

  feed_gen u_feed (
      .clk      (clk),
      .rst      (rst),
      .ld_i     (ld),
      .ld_idx_i (ridx),
      .ld_data_i(rdata),
      .run_i    (running && !hold_i && !abort_i),
      .adj_i    (it && is_arc),
      .adj_up_i (a_out),
      .fire_o   (fire)
  );

  line_interp u_line (
      .clk      (clk),
      .ld_i     (ld),
      .ld_idx_i (ridx),
      .ld_data_i(rdata),
      .it_i     (it && is_line),
      .mv_o     (l_mv),
      .neg_o    (l_neg)
  );

  arc_interp u_arc (
      .clk      (clk),
      .ld_i     (ld),
      .ld_idx_i (ridx),
      .ld_data_i(rdata),
      .it_i     (it && is_arc),
      .rdy_o    (a_rdy),
      .movex_o  (a_movex),
      .neg_o    (a_neg),
      .outward_o(a_out),
      .fin_o    (a_fin)
  );

  // The arc's x and y on the machine axes of its plane (G17/G18/G19).
  reg [2:0] a_mv;
  always @(*) begin
    case (plane)
      2'd1:    a_mv = a_movex ? 3'b100 : 3'b001;  // ZX
      2'd2:    a_mv = a_movex ? 3'b010 : 3'b100;  // YZ
      default: a_mv = a_movex ? 3'b001 : 3'b010;  // XY
    endcase
  end
  wire [2:0] mv = !it ? 3'b000 : (is_line ? l_mv : (is_arc ? a_mv : 3'b000));
  wire [2:0] neg = is_line ? l_neg : {3{a_neg}};

  // Writer state and the sticky flags; a flag raised in the cycle of clr_i
  // stays raised.
  always @(posedge clk) begin
    if (rst) begin
      wi    <= 4'd0;
      drop  <= 1'b0;
      ovf_o <= 1'b0;
    end else begin
      if (clr_i) ovf_o <= 1'b0;
      if (abort_i) begin
        wi   <= 4'd0;
        drop <= 1'b0;
      end else if (wr_i) begin
        drop <= drop_n;
        wi   <= wi == I_LAST ? 4'd0 : wi + 4'd1;
        if (drop_n) ovf_o <= 1'b1;
      end
    end
  end

  // Iterations due: the feed generator fires, the runner consumes.
  always @(posedge clk) begin
    if (rst || abort_i) pend <= 2'd0;
    else if (fire && !it) pend <= pend == 2'd3 ? 2'd3 : pend + 2'd1;
    else if (!fire && it) pend <= pend - 2'd1;
  end

  // Load, run, next.
  always @(posedge clk) begin
    rv   <= rd;
    ridx <= widx;
    if (rst) begin
      st         <= ST_IDLE;
      rv         <= 1'b0;
      seg_cnt_o  <= 16'd0;
      underrun_o <= 1'b0;
    end else begin
      if (clr_i) underrun_o <= 1'b0;
      case (st)
        ST_IDLE:
        if (!set_i && count_o >= SEGW) begin
          st   <= ST_LOAD;
          widx <= 4'd0;
        end
        ST_LOAD: begin
          if (rd) widx <= widx + 4'd1;
          if (ld && ridx == I_LAST) st <= ST_RUN;
        end
        default:
        if (fin) begin
          st        <= ST_IDLE;
          seg_cnt_o <= seg_cnt_o + 16'd1;
          if (!last && count_o < SEGW) underrun_o <= 1'b1;
        end
      endcase
      if (abort_i) begin
        st <= ST_IDLE;
        rv <= 1'b0;
      end
    end
  end

  // The segment's header fields and iteration count.
  always @(posedge clk) begin
    if (ld && ridx == I_HDR) begin
      typ   <= rdata[SEG_H_TYPE_LSB+:2];
      last  <= rdata[SEG_H_LAST];
      plane <= rdata[SEG_H_PLANE_LSB+:2];
    end
    if (ld && ridx == I_N) n_left <= rdata[NW-1:0];
    else if (it) n_left <= n_left - 1'b1;
  end

  // Position command: one count per axis per iteration, saturating (never
  // wraps), or loaded while idle.
  genvar a;
  generate
    for (a = 0; a < 3; a = a + 1) begin : g_pos
      reg  signed [31:0] p;
      wire               at_max = p == 32'sh7FFF_FFFF;
      wire               at_min = p == 32'sh8000_0000;
      // +-1 as one carry chain; a step into the limit is not taken.
      wire signed [31:0] p_n = p + {{31{neg[a]}}, 1'b1};
      wire               step = mv[a] && !(neg[a] ? at_min : at_max);
      always @(posedge clk) begin
        if (rst) p <= 32'sd0;
        else if (st == ST_IDLE && set_i) p <= set_pos_i[a*32+:32];
        else if (step) p <= p_n;
      end
      assign pos_o[a*32+:32] = p;
    end
  endgenerate

  assign busy_o = st != ST_IDLE;

endmodule
