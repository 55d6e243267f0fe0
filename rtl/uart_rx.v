// uart_rx: 8N1 receiver. rx_i must already be synchronized to clk (the board
// top's pin synchronizer does it). Each received byte pulses valid_o for one
// clock with the byte on data_o; a byte whose stop bit is low pulses ferr_o
// instead (a break or a baud mismatch), so the caller can count it.
//
// The bit period is CLK_HZ / BAUD clocks rounded to the nearest whole clock;
// elaboration fails if that rounding is off by more than 2 %, or if a bit is
// shorter than 4 clocks. The start bit is checked again at its middle, so a
// glitch shorter than half a bit starts nothing.
`default_nettype none

module uart_rx #(
    parameter integer CLK_HZ = 12_000_000,  // clock, Hz
    parameter integer BAUD   = 1_000_000    // bit rate, bit/s
) (
    // clock and reset
    input  wire       clk,
    input  wire       rst,
    // line (synchronized)
    input  wire       rx_i,
    // received bytes
    output reg  [7:0] data_o,
    output reg        valid_o,
    output reg        ferr_o
);

  localparam integer DIV = (CLK_HZ + BAUD / 2) / BAUD;  // clocks per bit
  localparam integer CW = $clog2(DIV);

  initial begin
    if (DIV < 4) $error("uart_rx: CLK_HZ/BAUD must be at least 4");
    if ((DIV * BAUD - CLK_HZ) * 50 > CLK_HZ || (CLK_HZ - DIV * BAUD) * 50 > CLK_HZ)
      $error("uart_rx: BAUD is more than 2 %% off any whole divisor of CLK_HZ");
  end

  /* verilator lint_off WIDTH */
  localparam [CW-1:0] FULL = DIV - 1;
  localparam [CW-1:0] HALF = DIV / 2 - 1;
  /* verilator lint_on WIDTH */

  reg          busy;
  reg [CW-1:0] cnt;  // clocks to the middle of the next bit, minus one
  reg [   3:0] bitn;  // 0 start, 1..8 data, 9 stop
  reg [   7:0] sh;

  always @(posedge clk) begin
    valid_o <= 1'b0;
    ferr_o  <= 1'b0;
    if (rst) begin
      busy <= 1'b0;
    end else if (!busy) begin
      if (!rx_i) begin
        busy <= 1'b1;
        cnt  <= HALF;
        bitn <= 4'd0;
      end
    end else if (cnt != {CW{1'b0}}) begin
      cnt <= cnt - 1'b1;
    end else begin
      cnt  <= FULL;
      bitn <= bitn + 4'd1;
      if (bitn == 4'd0) begin
        if (rx_i) busy <= 1'b0;  // the start bit did not last: a glitch
      end else if (bitn == 4'd9) begin
        busy    <= 1'b0;
        data_o  <= sh;
        valid_o <= rx_i;
        ferr_o  <= ~rx_i;
      end else begin
        sh <= {rx_i, sh[7:1]};
      end
    end
  end

endmodule

`default_nettype wire
