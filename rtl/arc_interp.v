// arc_interp: the stairs-approximation circle. Twin: hls/arc_interp.hpp
// (which explains the decision rule, the quadrant assignment and the end).
//
// How to drive it: stream the segment words through ld_i/ld_idx_i/ld_data_i
// (header for the direction and nq, then x0, y0, xe, ye, D0). The decision
// for the next iteration is registered: it is valid while rdy_o is high, which
// is two clocks after a load word or an iteration. Then, while fin_o is low,
// an iteration moves one coordinate one count: x if movex_o else y, towards
// minus if neg_o; outward_o says |x|+|y| grew (for the feed generator); it_i
// commits. No multiplier: D = x^2 + y^2 - R^2 follows by adding 2*m*c + 1 for
// a move of coordinate c by m.
`default_nettype none

module arc_interp (
    // clock
    input  wire        clk,
    // segment words
    input  wire        ld_i,
    input  wire [ 3:0] ld_idx_i,
    input  wire [31:0] ld_data_i,
    // iteration
    input  wire        it_i,
    output reg         rdy_o,      // the outputs below belong to the current state
    output reg         movex_o,    // move x (else y)
    output reg         neg_o,      // towards minus
    output reg         outward_o,  // away from the centre
    output reg         fin_o       // end point reached in the final quadrant
);

  /* verilator lint_off UNUSEDPARAM */
`include "interp_seg.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer A = SEG_ARC_W;
  localparam integer DW = SEG_D_W;
  /* verilator lint_off WIDTH */
  localparam [3:0] I_HDR = SEG_W_HDR;
  localparam [3:0] I_X0 = SEG_W_A;
  localparam [3:0] I_Y0 = SEG_W_B;
  localparam [3:0] I_XE = SEG_W_C;
  localparam [3:0] I_YE = SEG_W_D;
  localparam [3:0] I_D0 = SEG_W_E;
  /* verilator lint_on WIDTH */

  // Segment datapath: loaded before every run, needs no reset.
  reg signed [ A-1:0] x, y, xe, ye;
  reg signed [DW-1:0] d;
  reg        [   2:0] ncross;  // quadrant crossings so far
  reg        [   2:0] nq;     // crossings before the final quadrant
  reg                 ccw;

  // Quadrant, with axis points assigned so that the walk leaves a quadrant
  // exactly when an inward move zeroes a coordinate.
  wire xz = ~|x, yz = ~|y;
  wire xn = x[A-1], yn = y[A-1];
  wire xp = !xn && !xz, yp = !yn && !yz;
  wire q1 = ccw ? (xp && !yn) : (!xn && yp);
  wire q2 = ccw ? (!xp && yp) : (xn && !yn);
  wire q4 = ccw ? (!xn && yn) : (xp && !yp);
  wire upper = q1 || q2;
  wire right = q1 || q4;
  // Allowed moves (towards minus when set), and which of them is outward.
  // Registered: the zero tests behind them are deep, and the carry chains
  // below should start from flip-flops. They belong to the current state
  // one clock after it last changed (rdy_a).
  reg mxn, myn, xo, rdy_a;
  always @(posedge clk) begin
    mxn   <= upper == ccw;
    myn   <= right != ccw;
    xo    <= xz || (xn == (upper == ccw));
    rdy_a <= !(ld_i || it_i);
  end

  // S = D + mx*x + my*y is D at the corner of the cell both moves border,
  // less 1/2: outward when S < 0. DW+1 bits hold it for any loaded D.
  // Two carry chains, the negations folded in: -v = ~v + 1.
  wire signed [DW:0] xs = {{(DW + 1 - A) {x[A-1]}}, x} ^ {(DW + 1) {mxn}};
  wire signed [DW:0] ys = {{(DW + 1 - A) {y[A-1]}}, y} ^ {(DW + 1) {myn}};
  wire signed [DW:0] sx = {d[DW-1], d} + xs + {{DW{1'b0}}, mxn};
  wire signed [DW:0] s = sx + ys + {{DW{1'b0}}, myn};

  wire final_q = ncross == nq;
  wire xlock = final_q && x == xe;
  wire ylock = final_q && y == ye;
  wire movex_c = xlock ? 1'b0 : (ylock ? 1'b1 : (s[DW] == xo));

  // The decision is a register too: S's two carry chains and the update's two
  // would otherwise sit in one path. It belongs to the current state two
  // clocks after that last changed, so an arc step comes at most every third
  // clock (4 MHz at 12 MHz), far above any feed a machine uses.
  always @(posedge clk) begin
    rdy_o     <= rdy_a && !(ld_i || it_i);
    movex_o   <= movex_c;
    neg_o     <= movex_c ? mxn : myn;
    outward_o <= movex_c == xo;
    fin_o     <= xlock && ylock;
  end

  // The moving coordinate, its new value, and the change of D:
  // (c + m)^2 - c^2 = 2*m*c + 1.
  wire signed [ A-1:0] c = movex_o ? x : y;
  wire signed [ A-1:0] c_n = c + {{(A - 1) {neg_o}}, 1'b1};
  // D + 2*c + 1 = D + {c, 1}; moving down, c_n = c - 1 and
  // D - 2*c + 1 = D - 2*c_n - 1 = D + {~c_n, 1}: one chain either way.
  wire signed [ A-1:0] c_op = neg_o ? ~c_n : c;
  wire signed [DW-1:0] d_n = d + {{(DW - A - 1) {c_op[A-1]}}, c_op, 1'b1};
  // Leaving the quadrant: an inward move that makes the coordinate zero.
  wire ncross_n = !outward_o && ~|c_n;

  always @(posedge clk) begin
    if (ld_i) begin
      if (ld_idx_i == I_HDR) begin
        ccw   <= ld_data_i[SEG_H_CCW];
        nq    <= ld_data_i[SEG_H_NQ_LSB+:3];
        ncross <= 3'd0;
      end
      if (ld_idx_i == I_X0) x <= ld_data_i[A-1:0];
      if (ld_idx_i == I_Y0) y <= ld_data_i[A-1:0];
      if (ld_idx_i == I_XE) xe <= ld_data_i[A-1:0];
      if (ld_idx_i == I_YE) ye <= ld_data_i[A-1:0];
      if (ld_idx_i == I_D0) d <= ld_data_i[DW-1:0];
    end else if (it_i) begin
      if (movex_o) x <= c_n;
      else y <= c_n;
      d <= d_n;
      if (ncross_n) ncross <= ncross + 3'd1;
    end
  end

endmodule
