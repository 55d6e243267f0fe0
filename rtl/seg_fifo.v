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

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh seg_fifo; docs/formal.md). As the top of
  // a proof the user's side of the contract is assumed; inside interp_core
  // it would be asserted.
`ifdef FORMAL_TOP_seg_fifo
`define FIFO_ASSUME assume
`else
`define FIFO_ASSUME assert
`endif

  localparam [AW:0] F_DEPTH = {1'b1, {AW{1'b0}}};

  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) `FIFO_ASSUME (rst);  // start from reset

  // The user never writes when full nor reads when empty (a read and a
  // write in one clock included).
  always @(*)
    if (f_past_valid && !rst) begin
      if (do_wr) `FIFO_ASSUME (count_o != F_DEPTH);
      if (do_rd) `FIFO_ASSUME (count_o != {(AW + 1) {1'b0}});
    end

  // Follow one word, of the solver's choice: the one written when f_pick is
  // high. f_ahead counts the words in front of it; it must come out after
  // exactly that many reads, so no word is lost, doubled or reordered.
  /* verilator lint_off UNDRIVEN */
  (* anyseq *) wire f_pick;
  /* verilator lint_on UNDRIVEN */
  reg        f_tr = 1'b0;  // following a word
  reg [31:0] f_val;  // its value
  reg [  AW:0] f_ahead;  // words in front of it
  reg        f_out = 1'b0;  // it was read in the last clock
  reg [  AW:0] f_count_q;
  reg        f_clear_q, f_wr_q, f_rd_q;
  always @(posedge clk) begin
    f_out <= 1'b0;
    if (rst || flush_i) begin
      f_tr <= 1'b0;
    end else if (!f_tr && do_wr && f_pick) begin
      f_tr    <= 1'b1;
      f_val   <= wdata_i;
      f_ahead <= count_o - {{AW{1'b0}}, do_rd};
    end else if (f_tr && do_rd) begin
      if (f_ahead == {(AW + 1) {1'b0}}) begin
        f_tr  <= 1'b0;
        f_out <= 1'b1;
      end else begin
        f_ahead <= f_ahead - 1'b1;
      end
    end
    f_count_q <= count_o;
    f_clear_q <= rst || flush_i;
    f_wr_q    <= do_wr;
    f_rd_q    <= do_rd;
  end

  wire [AW-1:0] f_addr = rp + f_ahead[AW-1:0];
  always @(*)
    if (f_past_valid) begin
      // count_o stays within the depth and moves by one per write or read.
      assert (count_o <= F_DEPTH);
      assert (count_o == (f_clear_q ? {(AW + 1) {1'b0}}
                          : f_count_q + {{AW{1'b0}}, f_wr_q} - {{AW{1'b0}}, f_rd_q}));
      // A read and a write never meet at one address (no_rw_check above).
      if (!rst && do_wr && do_rd) assert (wp != rp);
      // The followed word comes out in its turn, unchanged.
      if (f_out) assert (rdata_o == f_val);
      if (f_tr) assert (f_ahead < count_o && mem[f_addr] == f_val);
      // How the pointers make that (the induction needs it spelled out).
      assert (wp - rp == count_o[AW-1:0]);
    end

`ifdef FORMAL_TOP_seg_fifo
  // Not vacuous (covers only when this module is the top): a followed word
  // comes out after another one was read in front of it; and, for a depth a
  // cover can reach (the proof's AW 4), the FIFO fills up and a followed word
  // is read across the pointers' wrap.
  always @(*) if (f_past_valid) cover (f_out && f_count_q == {{(AW - 1) {1'b0}}, 2'd2});
  generate
    if (AW <= 4) begin : g_cover_full
      reg [AW+1:0] f_nrd;  // reads since reset, saturating
      always @(posedge clk)
        if (rst) f_nrd <= {(AW + 2) {1'b0}};
        else if (do_rd && !f_nrd[AW+1]) f_nrd <= f_nrd + 1'b1;
      always @(*)
        if (f_past_valid) begin
          cover (count_o == F_DEPTH);
          cover (f_out && f_nrd > {1'b0, F_DEPTH});
        end
    end
  endgenerate
`endif

`undef FIFO_ASSUME
`endif

endmodule
