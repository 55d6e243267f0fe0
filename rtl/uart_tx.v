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

endmodule

`default_nettype wire
