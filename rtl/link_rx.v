// link_rx: frame parser of the link protocol (docs/protocol.md). Feed it the
// bytes uart_rx delivers. It hunts for SYNC, takes LEN, SEQ and CMD, stores
// the payload in a block RAM and checks the CRC-16; then it pulses frame_o
// for one clock with seq_o, cmd_o and len_o, and the payload can be read from
// the RAM (pay_raddr_i, data one clock later) until the payload of the next
// frame starts arriving, at least HDR_BYTES byte times later.
//
// Nothing else is ever signalled for a bad frame: it is dropped and one of
// the counting strobes pulses: crc_err_o (CRC mismatch), framing_o (LEN above
// MAX_LEN, a stop bit missing inside a frame, or a frame stalled for
// BYTE_TIMEOUT_US), junk_o (a byte skipped while hunting for SYNC). After a
// bad frame the hunt resumes with the next byte.
`default_nettype none

module link_rx #(
    parameter integer CLK_HZ = 12_000_000  // clock, Hz (for the byte timeout)
) (
    // clock and reset
    input  wire       clk,
    input  wire       rst,
    // bytes from uart_rx
    input  wire [7:0] byte_i,
    input  wire       valid_i,
    input  wire       ferr_i,
    // good frames
    output reg        frame_o,
    output reg  [7:0] seq_o,
    output reg  [7:0] cmd_o,
    output reg  [7:0] len_o,
    input  wire [7:0] pay_raddr_i,
    output reg  [7:0] pay_rdata_o,
    // drop counting strobes
    output reg        crc_err_o,
    output reg        framing_o,
    output reg        junk_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer TIMEOUT = CLK_HZ / 1_000_000 * P_BYTE_TIMEOUT_US;  // clocks
  localparam integer TW = $clog2(TIMEOUT + 1);
  /* verilator lint_off WIDTH */
  localparam [TW-1:0] TIMEOUT_T = TIMEOUT;
  localparam [7:0] MAXLEN8 = P_MAX_LEN;
  /* verilator lint_on WIDTH */

  initial begin
    if (CLK_HZ < 1_000_000) $error("link_rx: CLK_HZ below 1 MHz");
  end

  localparam [2:0] S_HUNT = 3'd0, S_LEN = 3'd1, S_SEQ = 3'd2, S_CMD = 3'd3;
  localparam [2:0] S_PAY = 3'd4, S_CRC0 = 3'd5, S_CRC1 = 3'd6;

  reg  [   2:0] st;
  reg  [   7:0] idx;  // payload bytes received
  reg  [   7:0] crc_lo;
  reg  [TW-1:0] idle;  // clocks since the last byte, within a frame
  wire [  15:0] crc;
  wire          crc_busy;

  // The CRC covers LEN, SEQ, CMD and the payload.
  wire crc_en = valid_i && (st == S_LEN || st == S_SEQ || st == S_CMD || st == S_PAY);
  crc16_ccitt u_crc (
      .clk   (clk),
      .init_i(st == S_HUNT),
      .en_i  (crc_en),
      .data_i(byte_i),
      .crc_o (crc),
      .busy_o(crc_busy)
  );

  // Payload RAM: one block RAM, written as bytes arrive.
  reg [7:0] pay[0:255];
  always @(posedge clk) begin
    if (valid_i && st == S_PAY) pay[idx] <= byte_i;
    pay_rdata_o <= pay[pay_raddr_i];
  end

  wire stalled = st != S_HUNT && idle == TIMEOUT_T;

  always @(posedge clk) begin
    frame_o   <= 1'b0;
    crc_err_o <= 1'b0;
    framing_o <= 1'b0;
    junk_o    <= 1'b0;
    if (valid_i || st == S_HUNT) idle <= {TW{1'b0}};
    else if (!stalled) idle <= idle + 1'b1;
    if (rst) begin
      st <= S_HUNT;
    end else if (stalled || (ferr_i && st != S_HUNT)) begin
      st        <= S_HUNT;
      framing_o <= 1'b1;
    end else if (ferr_i) begin
      junk_o <= 1'b1;
    end else if (valid_i) begin
      case (st)
        S_HUNT: begin
          if (byte_i == P_SYNC) st <= S_LEN;
          else junk_o <= 1'b1;
        end
        S_LEN: begin
          len_o <= byte_i;
          idx   <= 8'd0;
          if (byte_i > MAXLEN8) begin
            st        <= S_HUNT;
            framing_o <= 1'b1;
          end else begin
            st <= S_SEQ;
          end
        end
        S_SEQ: begin
          seq_o <= byte_i;
          st    <= S_CMD;
        end
        S_CMD: begin
          cmd_o <= byte_i;
          st    <= (len_o == 8'd0) ? S_CRC0 : S_PAY;
        end
        S_PAY: begin
          idx <= idx + 8'd1;
          if (idx + 8'd1 == len_o) st <= S_CRC0;
        end
        S_CRC0: begin
          crc_lo <= byte_i;
          st     <= S_CRC1;
        end
        default: begin  // S_CRC1; the CRC finished long ago (crc16_ccitt)
          st <= S_HUNT;
          if ({byte_i, crc_lo} == crc && !crc_busy) frame_o <= 1'b1;
          else crc_err_o <= 1'b1;
        end
      endcase
    end
  end

endmodule

`default_nettype wire
