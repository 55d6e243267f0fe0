// uart_tx: 8N1 transmitter. Present a byte on data_i with valid_i in a clock
// where ready_o is high; it is sent at once, LSB first. tx_o idles high and
// comes straight from a flip-flop. The bit period is the one uart_rx uses for
// the same CLK_HZ and BAUD.
`default_nettype none

module uart_tx #(
    parameter integer CLK_HZ = 12_000_000,  // clock, Hz
    parameter integer BAUD   = 1_000_000    // bit rate, bit/s
) (
    // clock and reset
    input  wire       clk,
    input  wire       rst,
    // bytes to send
    input  wire [7:0] data_i,
    input  wire       valid_i,
    output wire       ready_o,
    // line
    output reg        tx_o
);

  localparam integer DIV = (CLK_HZ + BAUD / 2) / BAUD;  // clocks per bit
  localparam integer CW = $clog2(DIV);

  initial begin
    if (DIV < 4) $error("uart_tx: CLK_HZ/BAUD must be at least 4");
  end

  /* verilator lint_off WIDTH */
  localparam [CW-1:0] FULL = DIV - 1;
  /* verilator lint_on WIDTH */

  reg [CW-1:0] cnt;
  reg [   3:0] left;  // bits still to send after the one on the line
  reg [   8:0] sh;  // data then the stop bit
  reg          busy;

  assign ready_o = ~busy;

  always @(posedge clk) begin
    if (rst) begin
      busy <= 1'b0;
      tx_o <= 1'b1;
    end else if (!busy) begin
      if (valid_i) begin
        busy <= 1'b1;
        tx_o <= 1'b0;
        sh   <= {1'b1, data_i};
        cnt  <= FULL;
        left <= 4'd9;
      end
    end else if (cnt != {CW{1'b0}}) begin
      cnt <= cnt - 1'b1;
    end else if (left == 4'd0) begin
      busy <= 1'b0;
    end else begin
      cnt  <= FULL;
      left <= left - 4'd1;
      tx_o <= sh[0];
      sh   <= {1'b1, sh[8:1]};
    end
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh uart_tx; docs/formal.md). As the top of a
  // proof the input contract is assumed; inside a harness it is asserted.
`ifdef FORMAL_TOP_uart_tx
`define UTX_ASSUME assume
`else
`define UTX_ASSUME assert
`endif

  localparam integer F_FRAME = 10 * DIV;  // clocks per frame: start, 8 data, stop
  localparam integer F_W = $clog2(F_FRAME + 1);
  localparam [F_W-1:0] F_END = F_FRAME[F_W-1:0];
  localparam [F_W-1:0] F_DIV = DIV[F_W-1:0];

  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) `UTX_ASSUME (rst);  // start from reset

  // The byte last taken and the clocks since (F_FRAME: the frame is over).
  reg  [    7:0] f_data;
  reg  [F_W-1:0] f_t;
  wire [    9:0] f_frame = {1'b1, f_data, 1'b0};  // line bits, first one at [0]
  always @(posedge clk) begin
    if (!rst && valid_i && ready_o) begin
      f_data <= data_i;
      f_t    <= {F_W{1'b0}};
    end else if (rst) begin
      f_t <= F_END;
    end else if (f_t != F_END) begin
      f_t <= f_t + 1'b1;
    end
  end

  always @(*)
    if (f_past_valid) begin
      // Busy exactly the F_FRAME clocks after a byte is taken; the line
      // shows bit f_t / DIV of the frame in each, and idles high after.
      assert (busy == (f_t != F_END));
      assert (tx_o == (busy ? ((f_frame >> (f_t / F_DIV)) & 10'd1) != 10'd0 : 1'b1));
      // How the counters make that (the induction needs it spelled out).
      if (busy) begin
        assert (left <= 4'd9 && cnt <= FULL);
        assert (f_t == {{(F_W - 4) {1'b0}}, 4'd9 - left} * F_DIV + {{(F_W - CW) {1'b0}}, FULL - cnt});
        assert (sh == (({1'b1, f_data} >> (4'd9 - left)) | (9'h1FF << left)));
      end
    end

`ifdef FORMAL_TOP_uart_tx
  // Not vacuous (covers only when this module is the top): a whole byte goes
  // out and the next is taken at once.
  reg [1:0] f_sent;
  always @(posedge clk)
    if (rst) f_sent <= 2'd0;
    else if (valid_i && ready_o && f_sent != 2'd3) f_sent <= f_sent + 2'd1;
  always @(*) cover (f_past_valid && f_sent == 2'd2 && f_t == {F_W{1'b0}} && f_data == 8'hA5);
`endif

`undef UTX_ASSUME
`endif

endmodule

`default_nettype wire
