// mul_align: the shared multiply of the PID datapath, twin of
// mc::mul_align_parts (hls/mc_fixed.hpp).
//
// Present a coefficient (mantissa m, shift s) and an operand x on a clock
// edge; three edges later the outputs hold the aligned product
//   y = round(m * x * 2^ACC_FRAC / 2^s), rounded half up, saturated to ACC_W
// bits, in three parts:
//   y = {ys, yw ^ {(ACC_W-1){ys}}} + yc
// ys is the sign, yw the remaining bits with the sign folded out, and yc the
// rounding increment not yet added. A new operand pair may be presented every
// cycle. The product is exact (M_W + X_W bits); only the final alignment
// rounds, so a coefficient's precision is set by its 24-bit mantissa alone,
// whatever its magnitude (Ki*Ts/2 at Ts = 10 us is as precise as Kp).
//
// Why the output is split: the only consumer is pid_core's back-end adder. It
// takes yc as its carry-in and undoes the sign fold with the inverter it has
// for subtraction anyway, so the rounding increment and the sign fold cost no
// logic here. In the folded form a saturated result is all ones in yw for
// either sign, so saturation is the flip-flops' synchronous set.
//
// Why it is small: s = 8q + r. The fine part r is applied to the mantissa
// before the multiply (m * 2^(7 - r) still fits the 32-bit DSP operand the
// 24-bit mantissa occupies anyway), so the product needs only a three-stage
// shifter in steps of 8, and only over the ACC_W + 1 bits that survive.
`default_nettype none

module mul_align #(
    parameter integer M_W      = 24,  // coefficient mantissa width, bits
    parameter integer X_W      = 32,  // operand width, bits
    parameter integer S_W      = 6,   // shift width, bits
    parameter integer ACC_W    = 50,  // result width, bits
    parameter integer ACC_FRAC = 32   // fraction bits of the result
) (
    // clock
    input  wire                    clk,
    // operands, sampled on the clock edge
    input  wire signed [  M_W-1:0] m,
    input  wire signed [  X_W-1:0] x,
    input  wire        [  S_W-1:0] s,
    // aligned product, three edges later: {ys, yw ^ {ys}} + yc
    output reg         [ACC_W-2:0] yw,
    output reg                     ys,
    output reg                     yc,
    // the values ys and yc take at the next edge, for a consumer that
    // registers its use of them
    output wire                    ys_next,
    output wire                    yc_next
);

  localparam integer FINE = 3;                    // s mod 8 goes into the mantissa
  localparam integer MP_W = M_W + (1 << FINE) - 1;  // mantissa shifted by up to 7
  localparam integer P_W = MP_W + X_W;            // exact product of the two
  localparam integer QMAX = (1 << (S_W - FINE)) - 1;
  // z = floor(p * 2^(8 v) / 2^G), v = QMAX - s div 8, is the product aligned
  // with one extra fraction bit; y = floor((z + 1) / 2) = (z >> 1) + z[0].
  localparam integer G = 8 * QMAX + 6 - ACC_FRAC;
  localparam integer LW = G + ACC_W;  // bits of the shifted product below the overflow line

  initial begin
    if (S_W != 6 || G < 1 || LW < P_W) begin
      $error("mul_align: the shifter is built for S_W = 6 and ACC_FRAC < 56");
    end
  end

  // Stage A: fine shift of the mantissa; operands registered (they map onto
  // the DSP tiles' input registers).
  reg signed [MP_W-1:0] mr;
  reg signed [ X_W-1:0] xr;
  reg        [     2:0] va;
  always @(posedge clk) begin
    mr <= {{((1 << FINE) - 1) {m[M_W-1]}}, m} << (~s[FINE-1:0]);
    xr <= x;
    va <= ~s[S_W-1:FINE];
  end

  // Stage B: exact product (SB_MAC16 tiles).
  reg signed [P_W-1:0] p;
  reg        [    2:0] vb;
  always @(posedge clk) begin
    p  <= mr * xr;
    vb <= va;
  end

  // Stage C: fold the sign out (p ^ sign is non-negative, and a floor shift
  // commutes with the fold), shift left by 8 v largest step first with the
  // sign as fill, keep the window, and flag any set bit pushed past it.
  wire          sg = p[P_W-1];
  assign ys_next = sg;
  wire [  LW-1:0] pt = {{(LW - P_W) {1'b0}}, p ^ {P_W{sg}}};
  wire [  LW-1:0] b1 = vb[2] ? {pt[LW-33:0], {32{sg}}} : pt;
  wire [  LW-1:0] b2 = vb[1] ? {b1[LW-17:0], {16{sg}}} : b1;
  wire [  LW-1:0] b3 = vb[0] ? {b2[LW-9:0], {8{sg}}} : b2;
  wire          ovf = (vb[2] & (|pt[LW-1:LW-32])) | (vb[1] & (|b1[LW-1:LW-16])) |
                      (vb[0] & (|b2[LW-1:LW-8]));
  // z = 2^(ACC_W) - 1 exactly: y would be 2^(ACC_W-1), one past the maximum;
  // the body is already the maximum, so only the increment is dropped.
  wire          top = ~sg & (&b3[LW-1:G]);

  assign yc_next = (b3[G] ^ sg) & ~ovf & ~top;
  always @(posedge clk) begin
    yw <= ovf ? {(ACC_W - 1) {1'b1}} : b3[LW-1:G+1];
    ys <= sg;
    yc <= yc_next;
  end

endmodule

`default_nettype wire
