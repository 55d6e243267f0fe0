// mul_align: the shared multiply of the PID datapath, twin of mc::mul_align
// (hls/mc_fixed.hpp).
//
// Present a coefficient (mantissa m, shift s) and an operand x in one cycle;
// two cycles later y holds round(m * x * 2^ACC_FRAC / 2^s), rounded half up and
// saturated to ACC_W bits. A new operand pair may be presented every cycle.
// The product is exact (M_W + X_W bits); only the final alignment rounds, so a
// coefficient's precision is set by its 24-bit mantissa alone, whatever its
// magnitude (Ki*Ts/2 at Ts = 10 us is as precise as Kp).
`default_nettype none

module mul_align #(
    parameter integer M_W      = 24,  // coefficient mantissa width, bits
    parameter integer X_W      = 32,  // operand width, bits
    parameter integer S_W      = 6,   // shift width, bits
    parameter integer ACC_W    = 50,  // result width, bits
    parameter integer ACC_FRAC = 32   // fraction bits appended before the shift
) (
    // clock
    input  wire                    clk,
    // operands
    input  wire signed [  M_W-1:0] m,
    input  wire signed [  X_W-1:0] x,
    input  wire        [  S_W-1:0] s,
    // aligned product, two cycles later
    output reg signed  [ACC_W-1:0] y
);

  localparam integer P_W = M_W + X_W;
  // {p, ACC_FRAC zeros} plus one guard bit so adding the rounding constant
  // can never overflow.
  localparam integer T_W = P_W + ACC_FRAC + 1;

  initial begin
    if (ACC_W > P_W + ACC_FRAC) begin
      $error("mul_align: ACC_W wider than the aligned product");
    end
  end

  // Stage 1: exact product (maps onto SB_MAC16 tiles).
  reg signed [P_W-1:0] p;
  reg        [S_W-1:0] s1;
  always @(posedge clk) begin
    p  <= m * x;
    s1 <= s;
  end

  // Stage 2: align, round, saturate.
  wire signed [T_W-1:0] t = {p[P_W-1], p, {ACC_FRAC{1'b0}}};
  wire        [T_W-1:0] one = {{(T_W - 1) {1'b0}}, 1'b1};
  wire signed [T_W-1:0] rnd = (s1 == {S_W{1'b0}}) ? {T_W{1'b0}} : $signed(one << (s1 - 1'b1));
  wire signed [T_W-1:0] sh = (t + rnd) >>> s1;
  // Out of range when the bits above the result are not all copies of its sign.
  wire                  hi = ~sh[T_W-1] & (|sh[T_W-2:ACC_W-1]);
  wire                  lo = sh[T_W-1] & ~(&sh[T_W-2:ACC_W-1]);

  localparam signed [ACC_W-1:0] YMAX = {1'b0, {(ACC_W - 1) {1'b1}}};
  localparam signed [ACC_W-1:0] YMIN = {1'b1, {(ACC_W - 1) {1'b0}}};

  always @(posedge clk) begin
    y <= hi ? YMAX : (lo ? YMIN : sh[ACC_W-1:0]);
  end

endmodule

`default_nettype wire
