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

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh uart_rx; docs/formal.md). rx_i is free:
  // any waveform, glitches included. As the top of a proof the reset at the
  // start is assumed; inside a harness it is asserted.
`ifdef FORMAL_TOP_uart_rx
`define URX_ASSUME assume
`else
`define URX_ASSUME assert
`endif

  localparam integer F_STOP = DIV / 2 - 1 + 9 * DIV;  // clocks from the start edge to the stop bit's middle
  localparam integer F_W = $clog2(F_STOP + 4);
  localparam [F_W-1:0] F_END = F_STOP[F_W-1:0];
  localparam integer F_GAPI = F_STOP + 2;  // fewest clocks from one output pulse to the next
  localparam integer F_SATI = F_STOP + 3;  // f_gap's ceiling: no pulse since reset, or longer ago
  localparam [F_W-1:0] F_GAP = F_GAPI[F_W-1:0];
  localparam [F_W-1:0] F_SAT = F_SATI[F_W-1:0];
  localparam [F_W-1:0] F_DIV = DIV[F_W-1:0];
  localparam [F_W-1:0] F_HALF = {{(F_W - CW) {1'b0}}, HALF};

  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) `URX_ASSUME (rst);  // start from reset

  // f_t: clocks since the line's falling edge started a byte (its first low
  // clock is the one before f_t = 0). f_smp: the line at each bit's middle,
  // f_t = HALF + k * DIV for bit k (0 start, 1..8 data, 9 stop), shifted in
  // from the top.
  // f_gap: clocks since the last output pulse, up to F_SAT.
  reg  [F_W-1:0] f_t;
  reg  [    9:0] f_smp;
  reg  [F_W-1:0] f_gap;
  wire           f_mid = f_t >= F_HALF && (f_t - F_HALF) % F_DIV == {F_W{1'b0}};
  always @(posedge clk) begin
    f_t <= busy ? f_t + 1'b1 : {F_W{1'b0}};
    if (busy && f_mid) f_smp <= {rx_i, f_smp[9:1]};
    if (rst) f_gap <= F_SAT;
    else if (valid_o || ferr_o) f_gap <= {{(F_W - 1) {1'b0}}, 1'b1};
    else if (f_gap != F_SAT) f_gap <= f_gap + 1'b1;
  end

  always @(*)
    if (f_past_valid) begin
      // A byte ends at the stop bit's middle at the latest (so the receiver
      // is idle in time for a start edge right after the stop bit) ...
      if (busy) assert (f_t <= F_END);
      // ... and past the start bit's middle only if the line was low there.
      if (busy && bitn != 4'd0) assert ((f_smp >> (4'd10 - bitn)) == 10'd0 || !f_smp[4'd10-bitn]);
      // One pulse per byte, in the clock after its stop bit was sampled:
      // valid_o with the eight middles as data if the stop bit is high,
      // else ferr_o; and never both.
      assert (!(valid_o && ferr_o));
      if (valid_o || ferr_o) begin
        assert (f_smp[0] == 1'b0 && ferr_o == !f_smp[9]);
        if (valid_o) assert (data_o == f_smp[8:1]);
      end
      // Pulses are at least F_GAP clocks apart (link_rx and crc16_ccitt
      // rely on bytes that are at least 9 clocks apart).
      if (valid_o || ferr_o) assert (f_gap >= F_GAP);
      // How the counters make that (the induction needs it spelled out).
      if (busy) begin
        assert (bitn <= 4'd9 && cnt <= (bitn == 4'd0 ? HALF : FULL));
        assert (f_t == F_HALF + {{(F_W - 4) {1'b0}}, bitn} * F_DIV - {{(F_W - CW) {1'b0}}, cnt});
        assert (({2'b00, sh} >> (4'd9 - bitn)) == (f_smp >> (4'd11 - bitn)));
      end
      assert (f_gap <= F_SAT && (!busy || f_gap > f_t));
    end

`ifdef FORMAL_TOP_uart_rx
  // Not vacuous (covers only when this module is the top): a good byte, a bad
  // stop bit, a glitch that starts nothing, and two bytes as close as the line
  // allows.
  always @(*)
    if (f_past_valid) begin
      cover (valid_o && data_o == 8'hA5);
      cover (ferr_o);
      cover (busy && bitn == 4'd0 && cnt == {CW{1'b0}} && rx_i);
      cover (valid_o && f_gap == F_GAP);
    end
`endif

`undef URX_ASSUME
`endif

endmodule

`default_nettype wire
