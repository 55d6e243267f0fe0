// crc16_ccitt: CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, MSB first, no
// final xor), one bit per clock. Strobe init_i to start a frame; present each
// byte with en_i while busy_o is low; crc_o holds the CRC of all bytes given
// once busy_o falls, 8 clocks after the last one. A UART byte takes ten bit
// periods, so the serial form always keeps up, for a fraction of the logic of
// a byte-wide XOR network. Check: "123456789" gives 0x29B1.
`default_nettype none

module crc16_ccitt (
    // clock
    input  wire        clk,
    // control
    input  wire        init_i,
    input  wire        en_i,
    input  wire [ 7:0] data_i,
    // result
    output reg  [15:0] crc_o,
    output wire        busy_o
);

  reg [7:0] sh;
  reg [3:0] n;  // bits left to shift in

  assign busy_o = n != 4'd0;

  always @(posedge clk) begin
    if (init_i) begin
      crc_o <= 16'hFFFF;
      n     <= 4'd0;
    end else if (en_i && !busy_o) begin
      sh <= data_i;
      n  <= 4'd8;
    end else if (busy_o) begin
      crc_o <= {crc_o[14:0], 1'b0} ^ ((crc_o[15] ^ sh[7]) ? 16'h1021 : 16'h0000);
      sh    <= {sh[6:0], 1'b0};
      n     <= n - 4'd1;
    end
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh crc16_ccitt; docs/formal.md). As the top
  // of a proof the input contract is assumed; inside link_rx or link_tx it
  // is asserted, so their proofs check that they keep it.
`ifdef FORMAL_TOP_crc16_ccitt
`define CRC_ASSUME assume
`else
`define CRC_ASSUME assert
`endif

  // The reference, f_crc16_byte: the byte-wise form of the CRC.
`include "crc16_ref.vh"

  // The first k bits of d (MSB first) shifted into c, one by one.
  function [15:0] f_crc_bits(input [15:0] c, input [7:0] d, input [3:0] k);
    integer i;
    reg [15:0] r;
    begin
      r = c;
      for (i = 0; i < 8; i = i + 1)
        if (i < k) r = {r[14:0], 1'b0} ^ ((r[15] ^ d[7-i]) ? 16'h1021 : 16'h0000);
      f_crc_bits = r;
    end
  endfunction

  // The reference is the standard's CRC: "123456789" gives 0x29B1.
  always @(*)
    assert (f_crc16_byte(f_crc16_byte(f_crc16_byte(f_crc16_byte(f_crc16_byte(f_crc16_byte(f_crc16_byte(
        f_crc16_byte(f_crc16_byte(16'hFFFF, "1"), "2"), "3"), "4"), "5"), "6"), "7"), "8"), "9")
        == 16'h29B1);

  // f_known: an init has been seen, so crc_o means something. f_ref: the
  // reference CRC of every byte taken since it. f_age: clocks since the last
  // byte was taken (15: none pending).
  wire       f_take = en_i && !busy_o && !init_i;
  reg        f_known = 1'b0;
  reg [15:0] f_ref;
  reg [ 3:0] f_age;
  always @(posedge clk) begin
    if (init_i) begin
      f_known <= 1'b1;
      f_ref   <= 16'hFFFF;
      f_age   <= 4'd15;
    end else if (f_take) begin
      f_ref <= f_crc16_byte(f_ref, data_i);
      f_age <= 4'd0;
    end else if (f_age != 4'd15) begin
      f_age <= f_age + 4'd1;
    end
  end

  // Contract: init_i comes in one of the first two clocks after power-up
  // (link_rx and link_tx give it in the clock after their reset), and a byte
  // is offered only while busy_o is low (else it is lost).
  reg [1:0] f_clk = 2'd0;  // clocks since power-up, up to 2
  always @(posedge clk) if (f_clk != 2'd2) f_clk <= f_clk + 2'd1;
  always @(*) begin
    if (f_clk == 2'd2) `CRC_ASSUME (f_known);
    if (f_known && en_i && !init_i) `CRC_ASSUME (!busy_o);
  end

  always @(*)
    if (f_known) begin
      // busy_o lasts exactly the 8 clocks after a byte is taken.
      assert (busy_o == (f_age < 4'd8));
      // Once it falls crc_o is the CRC of every byte since init_i ...
      if (!busy_o) assert (crc_o == f_ref);
      // ... and until then the bits still to shift in complete it.
      if (busy_o) assert (n == 4'd8 - f_age && f_crc_bits(crc_o, sh, n) == f_ref);
    end

`ifdef FORMAL_TOP_crc16_ccitt
  // Not vacuous (covers only when this module is the top): the register itself
  // computes the check value.
  reg [3:0] f_msg;  // how many bytes of "123456789" were given, in order
  always @(posedge clk) begin
    if (init_i) f_msg <= 4'd0;
    else if (f_take) f_msg <= (f_msg < 4'd9 && data_i == 8'h31 + {4'd0, f_msg}) ? f_msg + 4'd1 : 4'd15;
  end
  always @(*) cover (f_known && f_msg == 4'd9 && !busy_o && crc_o == 16'h29B1);
`endif

`undef CRC_ASSUME
`endif

endmodule

`default_nettype wire
