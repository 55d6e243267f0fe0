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

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh link_rx; docs/formal.md). Bytes are free
  // but come as uart_rx delivers them. As the top of a proof that is
  // assumed; inside a harness it is asserted.
`ifdef FORMAL_TOP_link_rx
`define LRX_ASSUME assume
`else
`define LRX_ASSUME assert
`endif
`include "crc16_ref.vh"

  reg f_past_valid = 1'b0;
  always @(posedge clk) f_past_valid <= 1'b1;
  always @(*) if (!f_past_valid) `LRX_ASSUME (rst);  // start from reset

  // A byte or a framing error, never both, at least 9 clocks apart (the CRC
  // takes 8 per byte; uart_rx's proof gives HALF + 9 * DIV + 2).
  reg [3:0] f_gap = 4'd9;  // clocks since the last one, up to 9
  always @(posedge clk)
    f_gap <= (valid_i || ferr_i) ? 4'd1 : (f_gap >= 4'd9) ? 4'd9 : f_gap + 4'd1;
  always @(*) begin
    `LRX_ASSUME (!(valid_i && ferr_i));
    if (valid_i || ferr_i) `LRX_ASSUME (f_gap == 4'd9);
  end

  // The frame as a reader of docs/protocol.md sees it, by byte position
  // after SYNC: 0 LEN, 1 SEQ, 2 CMD, 3 .. 2+LEN payload, then the CRC, low
  // byte first. f_crc: the reference CRC of LEN, SEQ, CMD and the payload
  // so far. f_quiet: clocks since the last byte of the frame.
  wire        f_in = st != S_HUNT;  // in a frame: SYNC seen, not dropped yet
  reg  [ 7:0] f_nb;  // bytes of the frame so far, after SYNC
  reg  [ 7:0] f_len, f_seq, f_cmd, f_lo;
  reg  [15:0] f_crc;
  reg  [TW-1:0] f_quiet;
  wire        f_stall = f_in && f_quiet == TIMEOUT_T;
  always @(posedge clk) begin
    if (!f_in) begin
      f_nb  <= 8'd0;
      f_crc <= 16'hFFFF;
    end else if (valid_i) begin
      f_nb <= f_nb + 8'd1;
      if (f_nb == 8'd0) f_len <= byte_i;
      if (f_nb == 8'd1) f_seq <= byte_i;
      if (f_nb == 8'd2) f_cmd <= byte_i;
      if (f_nb >= 8'd3 && f_nb == f_len + 8'd3) f_lo <= byte_i;
      if (f_nb == 8'd0 || f_nb < f_len + 8'd3) f_crc <= f_crc16_byte(f_crc, byte_i);
    end
    f_quiet <= (!f_in || valid_i) ? {TW{1'b0}} : f_stall ? f_quiet : f_quiet + 1'b1;
  end

  // What each clock's byte or error should lead to, for the next clock.
  wire f_crc1 = f_in && !f_stall && valid_i && f_nb >= 8'd4 && f_nb == f_len + 8'd4;
  wire f_good = f_crc1 && {byte_i, f_lo} == f_crc;
  wire f_bad = f_crc1 && {byte_i, f_lo} != f_crc;
  wire f_frm = f_in && (f_stall || ferr_i || (valid_i && f_nb == 8'd0 && byte_i > MAXLEN8));
  wire f_junk = !f_in && (ferr_i || (valid_i && byte_i != P_SYNC));
  wire [3:0] f_str = {frame_o, crc_err_o, framing_o, junk_o};
  reg f_good_q, f_bad_q, f_frm_q, f_junk_q, f_rst_q;
  always @(posedge clk) begin
    f_good_q <= !rst && f_good;
    f_bad_q  <= !rst && f_bad;
    f_frm_q  <= !rst && f_frm;
    f_junk_q <= !rst && f_junk;
    f_rst_q  <= rst;
  end

  always @(*)
    if (f_past_valid) begin
      // A frame is accepted exactly when its CRC is good, with the fields
      // it carried; a bad CRC is counted instead.
      assert (frame_o == f_good_q);
      assert (crc_err_o == f_bad_q);
      if (frame_o) assert (len_o == f_len && seq_o == f_seq && cmd_o == f_cmd && len_o <= MAXLEN8);
      // LEN above MAX_LEN, a framing error in a frame, or a stall drop the
      // frame and count; a framing error or a byte other than SYNC while
      // hunting counts as junk. At most one strobe per clock.
      assert (framing_o == f_frm_q);
      assert (junk_o == f_junk_q);
      assert ((f_str & (f_str - 4'd1)) == 4'd0);
      // The parser always returns to hunt: a frame never stalls longer
      // than the byte timeout, nor runs past LEN + 5 bytes; after its last
      // byte, or a reset, it hunts.
      if (f_in) assert (f_quiet <= TIMEOUT_T);
      if (f_in && f_nb != 8'd0) assert (f_nb <= f_len + 8'd4 && f_len <= MAXLEN8);
      if (frame_o || crc_err_o || framing_o || f_rst_q) assert (st == S_HUNT);
      // How the registers make that (the induction needs it spelled out).
      assert (st <= S_CRC1);
      assert (f_gap <= 4'd9);
      if (f_in) begin
        assert (idle == f_quiet);
        assert ((st == S_LEN) == (f_nb == 8'd0));
        assert ((st == S_SEQ) == (f_nb == 8'd1));
        assert ((st == S_CMD) == (f_nb == 8'd2));
        assert ((st == S_PAY) == (f_nb >= 8'd3 && f_nb < f_len + 8'd3));
        assert ((st == S_CRC0) == (f_nb >= 8'd3 && f_nb == f_len + 8'd3));
        if (f_nb >= 8'd1) assert (len_o == f_len);
        if (f_nb >= 8'd2) assert (seq_o == f_seq);
        if (f_nb >= 8'd3) assert (cmd_o == f_cmd);
        if (f_nb >= 8'd1 && f_nb <= 8'd3) assert (idx == 8'd0);
        if (st == S_PAY) assert (idx == f_nb - 8'd3);
        if (st == S_CRC1) assert (crc_lo == f_lo);
        if (f_nb == 8'd0) assert (crc == 16'hFFFF && !crc_busy && f_crc == 16'hFFFF);
        if (f_nb != 8'd0 && !crc_busy) assert (crc == f_crc);
      end
      if (crc_busy && !f_rst_q) assert (f_gap <= 4'd8);
    end

  // Payload byte f_k, of the solver's choice, reads back after the frame.
  // (The RAM is left out of the proof of everything else, scripts/formal.sh
  // link_rx, which is faster without it; link_rx_pay proves these.)
  /* verilator lint_off UNDRIVEN */
  (* anyconst *) wire [7:0] f_k;
  /* verilator lint_on UNDRIVEN */
  reg [7:0] f_pv;  // its value in this frame
  reg f_cur = 1'b0;  // it was written in this frame
  reg f_chk;  // it is on pay_rdata_o now
  always @(posedge clk) begin
    if (st == S_LEN) f_cur <= 1'b0;
    else if (valid_i && st == S_PAY && idx == f_k) f_cur <= 1'b1;
    if (valid_i && st == S_PAY && idx == f_k) f_pv <= byte_i;
    f_chk <= f_past_valid && frame_o && pay_raddr_i == f_k && f_k < len_o;
  end
  always @(*)
    if (f_past_valid) begin
`ifndef FORMAL_NO_PAY_RAM
      if (f_chk) assert (pay_rdata_o == f_pv);
      if (f_cur) assert (pay[f_k] == f_pv);
`endif
      if (st == S_SEQ || st == S_CMD) assert (!f_cur);
      if (st == S_PAY) assert (f_cur == (f_k < idx));
      if (st == S_CRC0 || st == S_CRC1 || frame_o) assert (f_cur == (f_k < len_o));
    end

`ifdef FORMAL_TOP_link_rx
`ifdef FORMAL_NO_PAY_RAM
  // Not vacuous (covers only when this module is the top, and once: with
  // the RAM out): frames accepted (without payload, and with a payload byte
  // f_k = 1 read back), a bad CRC, LEN too long, junk.
  always @(*)
    if (f_past_valid) begin
      cover (frame_o && len_o == 8'd0);
      cover (f_chk && f_k == 8'd1 && f_pv == 8'h5A && cmd_o == 8'h02);
      cover (crc_err_o);
      cover (framing_o);
      cover (junk_o);
    end
`endif
`endif

`undef LRX_ASSUME
`endif

endmodule

`default_nettype wire
