// seg_fifo: the interpolator's command FIFO, 32-bit words in block RAM.
// Twin: hls/seg_fifo.hpp.
//
// How to drive it: wr_i with wdata_i appends a word; rd_i takes the oldest,
// which appears on rdata_o after the clock edge, as block RAM reads do.
// count_o is the number of words held. flush_i empties it. The user never
// writes when full nor reads when empty (interp_core admits a segment only
// when all of it fits and loads one only when all of it is queued), so the
// FIFO spends no logic checking; keeping segments whole is the user's job too.
`default_nettype none

module seg_fifo #(
    parameter integer AW = 9  // log2 of the depth in words (512 words = 4 EBR)
) (
    // clock and reset
    input  wire        clk,
    input  wire        rst,
    // control
    input  wire        flush_i,
    // write
    input  wire        wr_i,
    input  wire [31:0] wdata_i,
    // read
    input  wire        rd_i,
    output reg  [31:0] rdata_o,
    // status
    output reg  [AW:0] count_o
);

  localparam integer DEPTH = 1 << AW;

  // A read and a write never meet at one address (equal pointers mean empty,
  // when the user reads nothing, or full, when it writes nothing), so Yosys
  // needs no collision logic around the block RAM.
  (* no_rw_check *)
  reg [31:0] mem[0:DEPTH-1];
  reg [AW-1:0] wp, rp;
  wire do_wr = wr_i && !flush_i;
  wire do_rd = rd_i && !flush_i;

  // Storage and read port: plain synchronous RAM so Yosys maps it to EBR.
  always @(posedge clk) begin
    if (do_wr) mem[wp] <= wdata_i;
    if (do_rd) rdata_o <= mem[rp];
  end

  always @(posedge clk) begin
    if (rst || flush_i) begin
      wp      <= {AW{1'b0}};
      rp      <= {AW{1'b0}};
      count_o <= {(AW + 1) {1'b0}};
    end else begin
      if (do_wr) wp <= wp + 1'b1;
      if (do_rd) rp <= rp + 1'b1;
      // +1 or -1 as one carry chain; a write and a read together cancel.
      if (do_wr != do_rd) count_o <= count_o + {{AW{do_rd}}, 1'b1};
    end
  end

endmodule
