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

endmodule

`default_nettype wire
