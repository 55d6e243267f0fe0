// line_interp: Bresenham line in up to three axes. Twin: hls/line_interp.hpp
// (which explains the rounding rule that makes a line retrace itself when run
// backwards).
//
// How to drive it: stream the segment words through ld_i/ld_idx_i/ld_data_i
// (header for the directions, N, |dx|, |dy|, |dz|). Then, for each of the N
// iterations, mv_o says which axes move (neg_o gives their direction) and
// it_i commits the iteration. After N iterations every axis has moved exactly
// its |d|.
`default_nettype none

module line_interp (
    // clock
    input  wire        clk,
    // segment words
    input  wire        ld_i,
    input  wire [ 3:0] ld_idx_i,
    /* verilator lint_off UNUSEDSIGNAL */  // words carry N_W-bit fields
    input  wire [31:0] ld_data_i,
    /* verilator lint_on UNUSEDSIGNAL */
    // iteration
    input  wire        it_i,
    output wire [ 2:0] mv_o,   // axis a moves in this iteration
    output reg  [ 2:0] neg_o   // axis a moves towards minus
);

  /* verilator lint_off UNUSEDPARAM */
`include "interp_seg.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer NW = SEG_N_W;
  localparam integer EW = NW + 1;  // doubled error term, 0..2N
  /* verilator lint_off WIDTH */
  localparam [3:0] I_HDR = SEG_W_HDR;
  localparam [3:0] I_N = SEG_W_N;
  localparam [3:0] I_A = SEG_W_A;
  /* verilator lint_on WIDTH */

  // Segment datapath: loaded before every run, needs no reset.
  reg [NW-1:0] n;

  always @(posedge clk) begin
    if (ld_i && ld_idx_i == I_HDR) neg_o <= ld_data_i[SEG_H_NEG_LSB+:3];
    if (ld_i && ld_idx_i == I_N) n <= ld_data_i[NW-1:0];
  end

  genvar a;
  generate
    for (a = 0; a < 3; a = a + 1) begin : g_axis
      reg  [NW-1:0] d;
      reg  [EW-1:0] e;
      // s = E + 2d, t = s - 2N: an axis steps when t >= 0. E starts one
      // lower for an axis running towards plus, so ties round the same way
      // in absolute coordinates whichever way the line runs.
      wire [  EW:0] s = {1'b0, e} + {1'b0, d, 1'b0};
      wire [EW+1:0] t = {1'b0, s} - {2'b00, n, 1'b0};
      wire [EW-1:0] e0 = {1'b0, ld_data_i[NW-1:0]} - {{(EW - 1) {1'b0}}, !neg_o[a]};
      assign mv_o[a] = !t[EW+1];

      always @(posedge clk) begin
        if (ld_i && ld_idx_i == I_N) e <= e0;
        else if (it_i) e <= mv_o[a] ? t[EW-1:0] : s[EW-1:0];
        if (ld_i && ld_idx_i == I_A + a[3:0]) d <= ld_data_i[NW-1:0];
      end
    end
  endgenerate

endmodule
