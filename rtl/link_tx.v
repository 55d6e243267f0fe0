// link_tx: frame sender of the link protocol (docs/protocol.md) in front of
// uart_tx. Payload words wait in a block RAM of 16 words that the caller
// writes (we_i, waddr_i, wdata_i). Strobe start_i while busy_o is low with
// the header fields: the frame is SYNC, LEN, SEQ, CMD, then (status_en_i) the
// status byte, then nwords_i words from address wbase_i, little-endian, then
// the CRC-16. The words and the header fields (all inputs but start_i) must
// stay unchanged until busy_o falls: the frame reads them as it goes, which
// spares a copy of each.
`default_nettype none

module link_tx (
    // clock and reset
    input  wire        clk,
    input  wire        rst,
    // payload RAM
    input  wire        we_i,
    input  wire [ 3:0] waddr_i,
    input  wire [31:0] wdata_i,
    // frame
    input  wire        start_i,
    input  wire [ 7:0] seq_i,
    input  wire [ 7:0] cmd_i,
    input  wire        status_en_i,
    input  wire [ 7:0] status_i,
    input  wire [ 3:0] wbase_i,
    input  wire [ 3:0] nwords_i,
    output wire        busy_o,
    // to uart_tx
    output reg  [ 7:0] byte_o,
    output reg         valid_o,
    input  wire        ready_i
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam [2:0] S_IDLE = 3'd0, S_HDR = 3'd1, S_STAT = 3'd2, S_DATA = 3'd3, S_CRC0 = 3'd4;
  localparam [2:0] S_CRC1 = 3'd5, S_END = 3'd6;

  reg [31:0] ram[0:15];
  reg [31:0] q;
  reg [ 3:0] ra;
  always @(posedge clk) begin
    if (we_i) ram[waddr_i] <= wdata_i;
    q <= ram[ra];
  end

  reg  [2:0] st;
  reg  [1:0] hb;  // header byte, and byte within a word
  reg  [3:0] wleft;  // words left after the current one
  reg        hold;  // the byte just handed over has not left uart_tx's ready yet, or q is not fresh
  wire [7:0] len = {2'd0, nwords_i, 2'd0} + {7'd0, status_en_i};
  wire [15:0] crc;
  wire        crc_busy;

  assign busy_o = st != S_IDLE;

  // The next byte, by state; the CRC takes every byte but SYNC and itself.
  reg  [7:0] nb;
  always @(*) begin
    case (st)
      S_HDR:   nb = (hb == 2'd0) ? P_SYNC : (hb == 2'd1) ? len : (hb == 2'd2) ? seq_i : cmd_i;
      S_STAT:  nb = status_i;
      S_DATA:  nb = q[hb*8+:8];
      S_CRC0:  nb = crc[7:0];
      default: nb = crc[15:8];
    endcase
  end
  wire go = st != S_IDLE && st != S_END && ready_i && !valid_o && !hold && !crc_busy;

  crc16_ccitt u_crc (
      .clk   (clk),
      .init_i(st == S_IDLE),
      .en_i  (go && (st == S_STAT || st == S_DATA || (st == S_HDR && hb != 2'd0))),
      .data_i(nb),
      .crc_o (crc),
      .busy_o(crc_busy)
  );

  always @(posedge clk) begin
    valid_o <= 1'b0;
    hold    <= valid_o;  // uart_tx's ready falls the clock after it takes a byte
    if (rst) begin
      st <= S_IDLE;
    end else if (st == S_IDLE) begin
      if (start_i) begin
        st      <= S_HDR;
        hb      <= 2'd0;
        ra      <= wbase_i;
        wleft   <= nwords_i - 4'd1;
      end
    end else if (st == S_END) begin
      if (ready_i && !hold && !valid_o) st <= S_IDLE;
    end else if (go) begin
      byte_o  <= nb;
      valid_o <= 1'b1;
      hb      <= hb + 2'd1;
      case (st)
        S_HDR:
        if (hb == 2'd3) begin
          hb <= 2'd0;
          st <= status_en_i ? S_STAT : (len == 8'd0 ? S_CRC0 : S_DATA);
        end
        S_STAT: begin
          hb <= 2'd0;
          st <= (len == 8'd1) ? S_CRC0 : S_DATA;
        end
        S_DATA:
        if (hb == 2'd3) begin
          ra    <= ra + 4'd1;
          wleft <= wleft - 4'd1;
          if (wleft == 4'd0) st <= S_CRC0;
        end
        S_CRC0:  st <= S_CRC1;
        default: st <= S_END;
      endcase
    end
  end

endmodule

`default_nettype wire
