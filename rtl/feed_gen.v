// feed_gen: the feed-rate generator. A phase accumulator that fires one
// interpolation iteration each time it overflows. Twin: hls/feed_gen.hpp.
//
// How to drive it: stream the segment words through ld_i/ld_idx_i/ld_data_i
// (it keeps the rate words, hls/interp_seg.hpp); hold run_i high while the
// segment runs; fire_o pulses once per iteration due, inc/2^PH_W per clock on
// average, with no drift (exact integer phase). For arcs, strobe adj_i on
// every step taken, adj_up_i when |x|+|y| grew: the rate follows the tangent
// as inc = k*(|x|+|y|), kept exact by adding or subtracting k.
`default_nettype none

module feed_gen (
    // clock and reset
    input  wire        clk,
    input  wire        rst,
    // segment words
    input  wire        ld_i,
    input  wire [ 3:0] ld_idx_i,
    input  wire [31:0] ld_data_i,
    // rate control
    input  wire        run_i,
    input  wire        adj_i,
    input  wire        adj_up_i,
    // iteration strobe
    output reg         fire_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "interp_seg.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer W = SEG_PH_W;
  /* verilator lint_off WIDTH */
  localparam [3:0] I_INC_LO = SEG_W_INC_LO;
  localparam [3:0] I_INC_HI = SEG_W_INC_HI;
  localparam [3:0] I_K_LO = SEG_W_K_LO;
  /* verilator lint_on WIDTH */

  reg  [W-1:0] ph;
  reg  [W-1:0] inc;  // datapath: loaded before every run, needs no reset
  reg  [W-1:0] k;
  wire [  W:0] sum = {1'b0, ph} + {1'b0, inc};
  // inc +- k as one carry chain: inc + (k ^ ~up) + ~up.
  wire [W-1:0] inc_adj = inc + (k ^ {W{~adj_up_i}}) + {{(W - 1) {1'b0}}, ~adj_up_i};

  // Phase and fire: the carry out of the accumulator is the iteration.
  always @(posedge clk) begin
    if (rst) begin
      ph     <= {W{1'b0}};
      fire_o <= 1'b0;
    end else begin
      fire_o <= run_i & sum[W];
      if (run_i) ph <= sum[W-1:0];
    end
  end

  // Rate words from the segment; during a run, +-k per arc step.
  always @(posedge clk) begin
    if (ld_i) begin
      if (ld_idx_i == I_INC_LO) inc[31:0] <= ld_data_i;
      if (ld_idx_i == I_INC_HI) begin
        inc[W-1:32] <= ld_data_i[15:0];
        k[W-1:32]   <= ld_data_i[31:16];
      end
      if (ld_idx_i == I_K_LO) k[31:0] <= ld_data_i;
    end else if (adj_i) begin
      inc <= inc_adj;
    end
  end

endmodule
