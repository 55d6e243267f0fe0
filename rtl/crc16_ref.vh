// Formal-only reference of CRC-16/CCITT-FALSE, included under `ifdef FORMAL
// by crc16_ccitt.v, link_rx.v and link_tx.v: the byte-wise form (no loop
// over bits, a different derivation from crc16_ccitt's shift register).
// crc16_ccitt's proof checks it gives 0x29B1 for "123456789".
function [15:0] f_crc16_byte(input [15:0] c, input [7:0] d);
  reg [7:0] x;
  begin
    x = c[15:8] ^ d;
    x = x ^ (x >> 4);
    f_crc16_byte = {c[7:0], 8'h00} ^ {x[3:0], 12'h000} ^ {3'b000, x, 5'b00000} ^ {8'h00, x};
  end
endfunction
