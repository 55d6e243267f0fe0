// pid_core: NAXES Tustin PID position loops sharing one multiply datapath.
// Twin: hls/pid_core.hpp (the golden model; the arithmetic is identical bit
// for bit, see that file for the realization and docs/numerics.md for why).
//
// How to drive it:
// - After reset the core zeroes its per-axis state (SDEPTH cycles, busy_o
//   high, cfg_wready and cfg_rready low, no ticks); the coefficient RAM keeps
//   its contents.
// - Configuration: present cfg_we/cfg_waddr/cfg_wdata; the write is taken on a
//   cycle where cfg_wready is high (the core is between sweeps), so a write
//   always lands between two samples, never inside one. Reads likewise:
//   cfg_re/cfg_raddr taken when cfg_rready, data on cfg_rdata one cycle later
//   with cfg_rvalid. Addresses: rtl/pid_regs.vh, {axis, reg}.
// - Every TS cycles (global register, clamped to at least LATENCY) tick_o
//   pulses; cmd_i and fb_i are sampled in that cycle, for all axes at once so
//   coordinated axes see the same instant. LATENCY cycles after tick_o,
//   done_o pulses and u_o/err_o/sat_o hold the new sample's values.
// - smp_* stream each axis's words of the sample as the sweep makes them,
//   one word per clock, all before done_o: command, feedback, error, the
//   output word {en, sat, u} (as u_o/sat_o/en_o take them) and the
//   following error cmd - fb (saturated to 32 bits, before deadband and
//   clamp). A user that keeps them in block RAM needs none of err_o's
//   flip-flops and no copy of the outputs for reading (motion_core).
//
// Structure (docs/numerics.md section 8 gives the area and the reasons). Three
// shared units run a fixed microcoded schedule for every axis in turn:
// - the front ALU (FW bits, saturating to 32) forms the error, deadband and
//   clamp, and the multiplier operands c-2c1+c2, c-c1, e-e1, e, e+e1;
// - mul_align multiplies an operand by a coefficient word, one product per
//   cycle;
// - the back ALU (ACC_W bits, saturating) adds the products as they arrive
//   and does the integrator limit, output limit and anti-windup as
//   compare-and-select steps.
// Per-axis state and intermediates live in block RAM: the front RAM holds the
// command and error history (rings indexed by the sample count, so nothing
// is ever copied) and copies of DBAND/ELIM, the back RAM the integrator and
// derivative state and two intermediates. Limit words reach the back ALU
// as products too: mantissa = the limit, x = +-2^LIM_S, shift LIM_S.
//
// Schedule. Each axis owns a slot of AXIS_CYCLES cycles for its front end;
// its back end runs mostly in the next slot, over the front end of the
// following axis. A sweep is NAXES + 1 slots cut short:
// LATENCY = NAXES * AXIS_CYCLES + FILL_CYCLES. The product of an operand an
// ALU makes in cycle c is issued to mul_align in c+1 and added in c+4. Per
// slot cycle (a = this slot's axis, p = the previous one):
//  cy  front ALU (a)               back ALU                      issued
//   0  acc <- cmd                  p: pd = dn + p                +IL p
//   1  acc <- sat32(acc - fb)      p: rest = pd + ff             -IL p
//   2  deadband: e - db if >= 0    p: ic = I(k-1) + di           +UL p
//   3  deadband: e + db if < 0     p: ic min IL                  -UL p
//   4  clamp: el if e > el         p: ic max -IL
//   5  clamp: is e < -el?          p: ic min UL                  +UL p
//   6  clamp: -el                  p: ic max -UL                 -UL p
//   7  acc <- cmd (e to RAM, err)  p: v = rest + ic
//   8  acc -= c1                   p: v min UL -> over
//   9  acc -= c1                   p: v max -UL -> under
//  10  x: sat32(acc + c2) (acc)    p: head = +-UL - rest; u, sat out
//  11  x: sat32(acc + c1) (vel)    a: doper = round(D(k-1) / 2^DSH)  KF2*acc
//  12  acc <- e                    p: cap = max/min(head, I(k-1))  KF1*vel
//  13  x: sat32(e - e1)            p: I(k) = min/max(cap, ic)    KD_A*doper
//  14  x: e                        a: acc <- f2                  KD_B*dif
//  15                              a: acc += f1 -> ff            KP*e
//  16  x: sat32(e + e1)            a: acc <- da
//  17                              a: acc += db -> D(k)          KI*sum
// A disabled axis runs the same steps; ic, D(k), v and u are forced to zero.
//
// SERVO = 0 builds the core without its loops, for a board whose axes are
// all steppers: no axis can be enabled, so every output word is a disabled
// axis's (u = 0), and the back ALU, the back RAM and the multiplier, whose
// results nothing then reads, are trimmed. The timer, the input chain and
// the front ALU stay: the sample stream (command, feedback, error,
// following error) is the board's telemetry and FERR check.
`default_nettype none

module pid_core #(
    parameter integer NAXES = 3,  // axes sharing the datapath (1..15)
    parameter integer SERVO = 1   // 0: no loops (a stepper board): every axis stays disabled
) (
    // clock and reset
    input  wire                   clk,
    input  wire                   rst,
    // configuration write
    input  wire                   cfg_we,
    input  wire [            7:0] cfg_waddr,
    input  wire [           31:0] cfg_wdata,
    output wire                   cfg_wready,
    // configuration read
    input  wire                   cfg_re,
    input  wire [            7:0] cfg_raddr,
    output wire                   cfg_rready,
    output reg                    cfg_rvalid,
    output reg  [           31:0] cfg_rdata,
    // loop inputs (counts), sampled at tick_o
    input  wire [   NAXES*32-1:0] cmd_i,
    input  wire [   NAXES*32-1:0] fb_i,
    // loop outputs
    output wire [   NAXES*16-1:0] u_o,     // drive output, signed
    output wire [   NAXES*32-1:0] err_o,   // processed error, signed counts
    output wire [      NAXES-1:0] sat_o,   // output limit active
    output wire [      NAXES-1:0] en_o,    // axis enabled
    // the sample's words as the sweep makes them, for a sample RAM
    // (motion_core): field 0 command, 1 feedback, 2 error, 3 output word
    // ([15:0] u, [16] sat, [17] en), 4 following error
    output wire                   smp_we_o,
    output wire [            3:0] smp_ax_o,
    output wire [            2:0] smp_fld_o,
    output wire [           31:0] smp_wd_o,
    output reg                    tick_o,  // sample instant
    output reg                    done_o,  // sweep finished, outputs valid
    output wire                   busy_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "mc_fixed.vh"
`include "pid_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  // The microcode table below has a row per slot cycle: these two are its
  // shape, not free parameters. FILL_CYCLES: the tick, the back end of the
  // last axis up to its final write (in slot NAXES, cycle LAST_STEP), done_o.
  localparam integer AXIS_CYCLES = 18;  // one slot per axis, cycles
  localparam integer FILL_CYCLES = 16;
  localparam integer LATENCY = NAXES * AXIS_CYCLES + FILL_CYCLES;
  localparam integer SLW = $clog2(NAXES + 1);  // slot 0..NAXES
  localparam integer SAW = SLW + 3;  // state RAM word address {axis, word}
  localparam integer CAW = 8;  // coefficient RAM word address = register address
  localparam integer SDEPTH = 1 << SAW;
  localparam integer CDEPTH = 1 << CAW;
  localparam integer W = MC_ACC_W;  // back ALU and its RAM, bits
  localparam integer F = MC_ACC_FRAC;
  localparam integer DSH = F - MC_D_OPER_FRAC;  // D(k-1) enters the multiplier shifted right by this
  localparam integer FW = MC_POS_W + 2;  // front ALU: c - 2 c1 + c2 needs two bits more
  localparam integer LIM_S = 7;  // a limit L as mantissa, shift LIM_S, x = 2^LIM_S: L * 2^F

  initial begin
    if (NAXES < 1 || NAXES > 15) begin
      $error("pid_core: NAXES must be 1..15");
    end
    if (AXIS_CYCLES != 18) begin
      $error("pid_core: the cy_n table and the microcode are written for 18 cycles a slot");
    end
    if (DSH < 1 || DSH + 32 > W || MC_OUT_W != 16 || MC_MUL_X_W != 32) begin
      $error("pid_core: the datapath is laid out for the formats of mc_fixed.vh");
    end
  end

  // Sized copies of integer parameters, for comparisons without width games.
  /* verilator lint_off WIDTH */
  localparam [3:0] NAXES4 = NAXES;
  localparam [SLW-1:0] LAST_SL = NAXES;
  localparam [31:0] LATENCY32 = LATENCY;
  localparam [4:0] LAST_CY = AXIS_CYCLES - 1;
  localparam [4:0] LAST_STEP = FILL_CYCLES - 2;
  localparam integer LATW = $clog2(LATENCY + 1);  // bits LATENCY needs
  /* verilator lint_on WIDTH */

  // ---------------------------------------------------------------------
  // Sequencer: slot sl (front end of axis sl, back end of axis sl-1) and the
  // cycle cy within it. After reset, clr walks the state RAMs writing zeros.
  reg           run;
  reg           clr;
  reg [SAW-1:0] cc;  // address being cleared
  reg [SLW-1:0] sl;
  reg [    4:0] cy;
  wire          idle = ~run & ~clr;
  wire          last = (sl == LAST_SL) && (cy == LAST_STEP);  // the last axis's final write
  wire [SLW-1:0] slp = sl - 1'b1;  // the axis whose back end runs in slots' first part

  assign busy_o     = ~idle;
  assign cfg_wready = idle;
  assign cfg_rready = idle & ~cfg_we;

  always @(posedge clk) begin
    if (rst) begin
      clr <= 1'b1;
      cc  <= {SAW{1'b0}};
    end else if (clr) begin
      cc  <= cc + 1'b1;
      clr <= ~&cc;
    end
  end

  always @(posedge clk) begin
    if (rst) begin
      run <= 1'b0;
      sl  <= {SLW{1'b0}};
      cy  <= 5'd0;
    end else if (~run) begin
      run <= tick_o;
      sl  <= {SLW{1'b0}};
      cy  <= 5'd0;
    end else if (last) begin
      run <= 1'b0;
    end else if (cy == LAST_CY) begin
      cy <= 5'd0;
      sl <= sl + 1'b1;
    end else begin
      cy <= cy + 5'd1;
    end
  end

  always @(posedge clk) begin
    if (rst) done_o <= 1'b0;
    else done_o <= run & last;
  end

  // Sample count modulo 2 and 3: the rings of error, integrator and command
  // history rotate instead of being copied. It advances after done_o, so
  // during done_o it still names the sample just finished.
  reg       k2;
  reg [1:0] k3;
  always @(posedge clk) begin
    if (rst) begin
      k2 <= 1'b0;
      k3 <= 2'd0;
    end else if (done_o) begin
      k2 <= ~k2;
      k3 <= (k3 == 2'd2) ? 2'd0 : k3 + 2'd1;
    end
  end

  // ---------------------------------------------------------------------
  // Microcode: what each unit does in slot cycle cy (table in the header).
  localparam [3:0] F_NOP = 4'd0, F_LDIN = 4'd1, F_ERAW = 4'd2, F_DB1 = 4'd3, F_DB2 = 4'd4;
  localparam [3:0] F_ELHI = 4'd5, F_ELCMP = 4'd6, F_ELSET = 4'd7, F_LDQ = 4'd8, F_SUBQ = 4'd9;
  localparam [3:0] F_XADD = 4'd10, F_XSUB = 4'd11;
  // Front RAM words, ring-relative: DBAND, ELIM copies, command of this sample
  // and the two before, error of this sample and the one before, a zero.
  localparam [2:0] FR_DB = 3'd0, FR_EL = 3'd1, FR_C0 = 3'd2, FR_C1 = 3'd3, FR_C2 = 3'd4;
  localparam [2:0] FR_E0 = 3'd5, FR_E1 = 3'd6, FR_ZERO = 3'd7;
  localparam [3:0] B_DOPER = 4'd1, B_LDY = 4'd2, B_ADDY = 4'd3, B_ADDYZ = 4'd4;
  localparam [3:0] B_ADDQ = 4'd5, B_QADDYZ = 4'd6, B_MINY = 4'd7, B_MAXY = 4'd8, B_MINYO = 4'd9;
  localparam [3:0] B_MAXYU = 4'd10, B_SUBQ = 4'd11, B_CAP = 4'd12, B_INS = 4'd13;
  // Back RAM words: D, the integrator ring, two intermediates.
  // Writes name words with the read codes; two more: no write, and I(k)
  // again only if the output limit was active.
  localparam [2:0] BR_D = 3'd0, BR_IOLD = 3'd1, BR_INEW = 3'd2, BR_FF = 3'd3, BR_REST = 3'd4;
  localparam [2:0] BW_D = BR_D, BW_INEW = BR_INEW, BW_FF = BR_FF, BW_REST = BR_REST;
  localparam [2:0] BW_INSAT = 3'd5, BW_NONE = 3'd7;
  localparam [1:0] X_FA = 2'd0, X_BA = 2'd1, X_POS = 2'd2, X_NEG = 2'd3;
  localparam [1:0] M_COEF = 2'd0, M_IL = 2'd1, M_OL = 2'd2;

  // The table is looked up for the next cycle and registered, so the
  // datapath's selects come straight from flip-flops.
  // cy_n as a table of cy, not an adder: the microcode table below then
  // merges with it into two or three LUT levels, where a carry chain in
  // front of it made the board's longest path.
  reg  [4:0]     cy_n;
  always @(*) begin
    case (cy)
      5'd0: cy_n = 5'd1;
      5'd1: cy_n = 5'd2;
      5'd2: cy_n = 5'd3;
      5'd3: cy_n = 5'd4;
      5'd4: cy_n = 5'd5;
      5'd5: cy_n = 5'd6;
      5'd6: cy_n = 5'd7;
      5'd7: cy_n = 5'd8;
      5'd8: cy_n = 5'd9;
      5'd9: cy_n = 5'd10;
      5'd10: cy_n = 5'd11;
      5'd11: cy_n = 5'd12;
      5'd12: cy_n = 5'd13;
      5'd13: cy_n = 5'd14;
      5'd14: cy_n = 5'd15;
      5'd15: cy_n = 5'd16;
      5'd16: cy_n = 5'd17;
      default: cy_n = 5'd0;  // LAST_CY (17): the next slot
    endcase
    if (~run) cy_n = 5'd0;
  end
  wire           run_n = run ? ~last : tick_o;

  // One microword per slot cycle:
  // {front op, front RAM read, front RAM write cmd, write e (and err_o),
  //  chain shift, back op, back RAM read, back RAM write, drive output,
  //  x source, coefficient kind, coefficient RAM read}
  // RAM and coefficient reads name the word the next cycle's step uses.
  localparam integer UW = 29;
  localparam [0:0] N = 1'b0, Y = 1'b1;
  reg [UW-1:0] uc_n;
  always @(*) begin
    case (cy_n)
      //              front           RAM     cmd e  sh  back      RAM      write    u  x      coef    read
      5'd0:  uc_n = {F_LDIN,  FR_DB,   N, N, Y, B_ADDY,   BR_FF,   BW_D,    N, X_NEG, M_IL,   PID_REG_ILIM};
      5'd1:  uc_n = {F_ERAW,  FR_DB,   Y, N, Y, B_ADDQ,   BR_IOLD, BW_NONE, N, X_POS, M_IL,   PID_REG_OLIM};
      5'd2:  uc_n = {F_DB1,   FR_DB,   N, N, N, B_QADDYZ, BR_D,    BW_REST, N, X_NEG, M_OL,   PID_REG_OLIM};
      5'd3:  uc_n = {F_DB2,   FR_EL,   N, N, N, B_MINY,   BR_D,    BW_NONE, N, X_FA,  M_OL,   PID_REG_OLIM};
      5'd4:  uc_n = {F_ELHI,  FR_EL,   N, N, N, B_MAXY,   BR_D,    BW_NONE, N, X_POS, M_COEF, PID_REG_OLIM};
      5'd5:  uc_n = {F_ELCMP, FR_EL,   N, N, N, B_MINY,   BR_D,    BW_NONE, N, X_NEG, M_OL,   PID_REG_OLIM};
      5'd6:  uc_n = {F_ELSET, FR_C0,   N, N, N, B_MAXY,   BR_REST, BW_NONE, N, X_FA,  M_OL,   PID_REG_OLIM};
      5'd7:  uc_n = {F_LDQ,   FR_C1,   N, Y, N, B_ADDQ,   BR_D,    BW_INEW, N, X_FA,  M_COEF, PID_REG_OLIM};
      5'd8:  uc_n = {F_SUBQ,  FR_C1,   N, N, N, B_MINYO,  BR_D,    BW_NONE, N, X_FA,  M_COEF, PID_REG_OLIM};
      5'd9:  uc_n = {F_SUBQ,  FR_C2,   N, N, N, B_MAXYU,  BR_REST, BW_NONE, N, X_FA,  M_COEF, PID_REG_OLIM};
      5'd10: uc_n = {F_XADD,  FR_C1,   N, N, N, B_SUBQ,   BR_D,    BW_NONE, Y, X_FA,  M_COEF, PID_REG_KF2};
      5'd11: uc_n = {F_XADD,  FR_E0,   N, N, N, B_DOPER,  BR_IOLD, BW_NONE, N, X_FA,  M_COEF, PID_REG_KF1};
      5'd12: uc_n = {F_LDQ,   FR_E1,   N, N, N, B_CAP,    BR_INEW, BW_NONE, N, X_BA,  M_COEF, PID_REG_KD_A};
      5'd13: uc_n = {F_XSUB,  FR_ZERO, N, N, N, B_INS,    BR_D,    BW_NONE, N, X_FA,  M_COEF, PID_REG_KD_B};
      5'd14: uc_n = {F_XADD,  FR_DB,   N, N, N, B_LDY,    BR_D,    BW_INSAT, N, X_FA, M_COEF, PID_REG_KP};
      5'd15: uc_n = {F_NOP,   FR_E1,   N, N, N, B_ADDY,   BR_D,    BW_NONE, N, X_FA,  M_COEF, PID_REG_OLIM};
      5'd16: uc_n = {F_XADD,  FR_DB,   N, N, N, B_LDY,    BR_D,    BW_FF,   N, X_FA,  M_COEF, PID_REG_KI};
      default: uc_n = {F_NOP, FR_DB,   N, N, N, B_ADDYZ,  BR_D,    BW_NONE, N, X_POS, M_COEF, PID_REG_ILIM};
    endcase
  end
  wire [3:0] fa_op_n = uc_n[28:25];
  wire [3:0] ba_op_n = uc_n[18:15];

  reg [3:0] c_reg;
  reg [2:0] fa_rc, ba_rc, ba_wc;
  reg [1:0] xs, mp;
  reg       fa_wcmd, fa_we_e, ch_shift, ou_we;
  always @(posedge clk) begin
    {fa_rc, fa_wcmd, fa_we_e, ch_shift} <= uc_n[24:19];
    {ba_rc, ba_wc, ou_we, xs, mp, c_reg} <= uc_n[14:0];
  end

  // Which axis each unit works on in this cycle, and whether it exists.
  wire           fa_ok = run & (sl != LAST_SL);
  wire [SLW-1:0] br_ax = (cy == 5'd10 || cy >= 5'd13) ? sl : slp;  // back RAM read, one ahead
  wire           bw_hi = (cy >= 5'd15);  // back RAM write, one cycle behind
  wire [SLW-1:0] bw_ax = bw_hi ? sl : slp;
  wire           bw_ok = bw_hi ? (sl != LAST_SL) : (sl != {SLW{1'b0}});
  wire [SLW-1:0] cr_ax = (cy >= 5'd10) ? sl : slp;  // coefficient read for the next issue

  // ---------------------------------------------------------------------
  // Configuration: coefficient RAM (block RAM, synchronous read) and flops.
  // No word is ever read in the cycle it is written (the schedule keeps them
  // apart, and a configuration read waits while a write is presented), so
  // Yosys need not wrap the block RAMs in read-first emulation (no_rw_check).
  (* no_rw_check *)
  reg [31:0] cram[0:CDEPTH-1];
  reg [31:0] cq;  // coefficient RAM output
  reg [NAXES-1:0] en;
  reg [31:0] ts;

  // Every register address has a word, so read-back is the RAM output for
  // all but TS and CTRL: unmapped words are never written and read 0, and
  // the read-only globals are the RAM's initial contents.
  integer ci;
  initial begin
    // Block RAM powers up as configured: all coefficients zero.
    for (ci = 0; ci < CDEPTH; ci = ci + 1) cram[ci] = 32'd0;
    cram[{PID_GLOBAL_AXIS, PID_G_LATENCY}] = LATENCY32;
    cram[{PID_GLOBAL_AXIS, PID_G_NAXES}] = {28'd0, NAXES4};
  end

  wire [3:0] w_ax = cfg_waddr[7:4];
  wire [3:0] w_rg = cfg_waddr[3:0];
  wire       w_ok = cfg_we & cfg_wready;
  wire       w_axok = w_ok & (w_ax < NAXES4);
  wire       w_ram = w_axok & (w_rg < PID_NREGS_RAM);

  // The single read port serves the multiplier during a sweep and the
  // configuration read port between sweeps.
  wire [3:0] cr_ax4;  // the axis as a 4-bit register address field
  generate
    if (SLW < 4) begin : g_ax4
      assign cr_ax4 = {{(4 - SLW) {1'b0}}, cr_ax};
    end else begin : g_ax4
      assign cr_ax4 = cr_ax;
    end
  endgenerate
  wire [CAW-1:0] cr_addr = run ? {cr_ax4, c_reg} : cfg_raddr;

  always @(posedge clk) begin
    if (w_ram) cram[cfg_waddr] <= cfg_wdata;
    cq <= cram[cr_addr];
  end

  // Enables and the sample period: control state, reset. A period below
  // LATENCY loads LATENCY the same way reset does (flip-flop set/reset).
  // (The compare looks only at the bits LATENCY has: a carry-chain compare
  // of all 32 would cost a LUT per bit.)
  wire ts_w = w_ok & (w_ax == PID_GLOBAL_AXIS) & (w_rg == PID_G_TS);
  wire ts_lt = ~(|cfg_wdata[31:LATW]) & (cfg_wdata[LATW-1:0] < LATENCY32[LATW-1:0]);
  always @(posedge clk) begin
    if (rst | (ts_w & ts_lt)) ts <= LATENCY32;
    else if (ts_w) ts <= cfg_wdata;
  end

  integer ea;
  always @(posedge clk) begin
    if (rst) begin
      en <= {NAXES{1'b0}};
    end else if (w_ok) begin
      for (ea = 0; ea < NAXES; ea = ea + 1) begin
        if (w_ax == ea[3:0] && w_rg == PID_REG_CTRL) en[ea] <= cfg_wdata[0] & (SERVO != 0);
      end
    end
  end

  // Enable of an axis by slot number (slot NAXES and the wrap of 0-1 have none).
  wire [(1<<SLW)-1:0] en_pad = {{((1 << SLW) - NAXES) {1'b0}}, en};
  // The back ALU's axis next cycle (registered use: the zero force): slot
  // sl's own axis from cycle 14 of the slot to cycle 0 of the next, i.e. when
  // this cycle is 13 to 17, the previous slot's before; none between sweeps.
  // Decided from this cycle's registers, not from cy_n and sl_n: that chain
  // was the board's longest path.
  wire                ba_en_n = run & ((cy >= 5'd13) ? en_pad[sl] : en_pad[slp]);

  // Read-back: RAM words come from cq one cycle later; the rest from flops.
  reg [3:0] r_ax, r_rg;
  reg       r_pend;
  always @(posedge clk) begin
    if (rst) begin
      r_pend <= 1'b0;
    end else begin
      r_pend <= cfg_re & cfg_rready;
    end
    if (cfg_re & cfg_rready) begin
      r_ax <= cfg_raddr[7:4];
      r_rg <= cfg_raddr[3:0];
    end
  end

  wire [15:0] en16 = {{(16 - NAXES) {1'b0}}, en};
  wire        r_ts = (r_ax == PID_GLOBAL_AXIS) && (r_rg == PID_G_TS);
  wire        r_ctrl = (r_ax != PID_GLOBAL_AXIS) && (r_rg == PID_REG_CTRL);
  always @(*) begin
    cfg_rvalid = r_pend;
    if (r_ts) cfg_rdata = ts;
    else if (r_ctrl) cfg_rdata = {31'd0, en16[r_ax]};
    else cfg_rdata = cq;
  end


  // ---------------------------------------------------------------------
  // Sample timer: tick every ts cycles (counts ts down to 1, then reloads).
  // A new ts takes effect at the next reload, so a running period is never
  // cut short. Held while clearing; the first tick follows at once.
  reg [31:0] tcnt;
  wire       tlast = (tcnt == 32'd1);
  always @(posedge clk) begin
    if (rst | clr) begin
      tcnt   <= 32'd1;
      tick_o <= 1'b0;
    end else begin
      tick_o <= tlast;
      tcnt   <= tlast ? ts : tcnt - 32'd1;
    end
  end

  // Inputs of all axes latched at the same instant into a chain that the
  // front ALU reads from its head: cmd0, fb0, cmd1, fb1, ...; it shifts one
  // word after each use, so no axis multiplexer is needed.
  reg  [NAXES*64-1:0] chain;
  wire [NAXES*64-1:0] chain_load;
  genvar g;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_load
      assign chain_load[g*64+:32]    = cmd_i[g*32+:32];
      assign chain_load[g*64+32+:32] = fb_i[g*32+:32];
    end
  endgenerate
  always @(posedge clk) begin
    if (tick_o) chain <= chain_load;
    else if (fa_ok & ch_shift) chain <= {chain[NAXES*64-1-:32], chain[NAXES*64-1:32]};
  end
  wire [31:0] in_w = chain[31:0];

  // ---------------------------------------------------------------------
  // State RAMs (block RAM, synchronous read). Front: {axis, word} words of 32
  // bits; back: ACC_W bits. Word maps: front 0-2 command ring, 3-4 error
  // ring, 5 DBAND, 6 ELIM (both written by configuration, bit 31 cleared),
  // 7 zero; back 0 D, 1-2 integrator ring, 3 F1+F2, 4 rest.
  (* no_rw_check *)
  reg [31:0] fram[0:SDEPTH-1]  /* verilator public_flat_rd */;
  (* no_rw_check *)
  reg [W-1:0] bram[0:SDEPTH-1]  /* verilator public_flat_rd */;
  reg [31:0] qf;  // front RAM output
  reg [W-1:0] qb;  // back RAM output
  integer si;
  initial begin
    for (si = 0; si < SDEPTH; si = si + 1) begin
      fram[si] = 32'd0;
      bram[si] = {W{1'b0}};
    end
  end

  // Ring words for this sample k: command k, k-1, k-2 (words 0-2); error k,
  // k-1 (3-4); integrator k, k-1 (back RAM 1-2).
  wire [1:0] k3m1 = (k3 == 2'd0) ? 2'd2 : k3 - 2'd1;
  wire [1:0] k3m2 = (k3 == 2'd2) ? 2'd0 : k3 + 2'd1;
  wire [2:0] w_e0 = k2 ? 3'd4 : 3'd3;
  wire [2:0] w_e1 = k2 ? 3'd3 : 3'd4;
  wire [2:0] w_i0 = k2 ? 3'd2 : 3'd1;
  wire [2:0] w_i1 = k2 ? 3'd1 : 3'd2;
  reg  [2:0] fr_word;
  always @(*) begin
    case (fa_rc)
      FR_DB:   fr_word = 3'd5;
      FR_EL:   fr_word = 3'd6;
      FR_C0:   fr_word = {1'b0, k3};
      FR_C1:   fr_word = {1'b0, k3m1};
      FR_C2:   fr_word = {1'b0, k3m2};
      FR_E0:   fr_word = w_e0;
      FR_E1:   fr_word = w_e1;
      default: fr_word = 3'd7;
    endcase
  end
  // Back RAM word of a read or write code (writes of I(k) under BW_INSAT).
  function [2:0] bword;
    input [2:0] code;
    begin
      case (code)
        BR_IOLD: bword = w_i1;
        BR_FF:   bword = 3'd3;
        BR_REST: bword = 3'd4;
        BR_D:    bword = 3'd0;
        default: bword = w_i0;
      endcase
    end
  endfunction
  wire [2:0] br_word = bword(ba_rc);
  wire [2:0] bw_word = bword(ba_wc);

  reg  [FW-1:0] fa_acc;
  reg  [ W-1:0] ba_acc;
  reg           over, under;

  // Front RAM write port: the front ALU during a sweep, zeros while
  // clearing (fa_acc is reset), DBAND/ELIM copies between sweeps.
  wire          fw_cfg = w_axok & (w_rg == PID_REG_DBAND || w_rg == PID_REG_ELIM);
  wire [SAW-1:0] fw_addr = run ? {sl, fa_wcmd ? {1'b0, k3} : w_e0} :
                           clr ? cc : {w_ax[SLW-1:0], (w_rg == PID_REG_ELIM) ? 3'd6 : 3'd5};
  wire          fw_we = run ? fa_ok & (fa_wcmd | fa_we_e) :
                        clr ? ~(cc[2:0] == 3'd5 || cc[2:0] == 3'd6) : fw_cfg;
  wire [31:0]   fw_data = (run | clr) ? fa_acc[31:0] : {1'b0, cfg_wdata[30:0]};
  always @(posedge clk) begin
    if (fw_we) fram[fw_addr] <= fw_data;
    qf <= fram[{sl, fr_word}];
  end

  // Back RAM write port: the back ALU's accumulator (zero while clearing).
  wire [SAW-1:0] bw_addr = clr ? cc : {bw_ax, bw_word};
  wire           bw_we = clr | (run & bw_ok & (ba_wc != BW_NONE) & (ba_wc != BW_INSAT | over | under));
  always @(posedge clk) begin
    if (bw_we) bram[bw_addr] <= ba_acc;
    qb <= bram[{br_ax, br_word}];
  end

  // ---------------------------------------------------------------------
  // Result select shared by both ALUs: per bit, one LUT chooses the sum, a
  // forced 0 or 1 (saturation, clearing) or the B operand (compare-and-select).
  // Codes {k1, k0}: 00 the sum, 01 zero, 10 one, 11 the B operand.

  // Front ALU: t = acc + (B ^ inv) + cin, FW bits plus a sign bit. Loads
  // pass B through the result select, and -el is formed from an accumulator
  // cleared the cycle before, so the A operand needs no multiplexer.
  reg fa_bin, fa_inv, fa_cin, fa_setp, fa_setn;
  reg fa_sm, fa_pm, fa_db;
  reg [2:0] fa_wec;
  // Front ALU steps: operand B from the input chain (else the front RAM),
  // invert B, carry-in, set p (deadband kept), set n (e < -el), result mode
  // (0 sum, 1 saturate cmd - fb to 32 bits, 2 select B, 3 deadband: zero
  // unless negative), accumulator write (0 no, 1 yes, 2 if t >= 0, 3 if not p,
  // 4 if el != 0 and t >= 0, 5 if n).
  reg fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n;
  reg [1:0] fa_mode_n;
  reg [2:0] fa_wec_n;
  always @(*) begin
    case (fa_op_n)
      //                   bin   inv   cin   p     n     mode   write
      F_LDIN:  {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {Y, Y, N, N, N, 2'd2, 3'd1};  // acc <- cmd
      F_ERAW:  {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {Y, Y, Y, N, N, 2'd1, 3'd1};  // sat32(cmd - fb)
      F_DB1:   {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, Y, Y, Y, N, 2'd0, 3'd2};  // e - db if >= 0
      F_DB2:   {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, N, N, N, N, 2'd3, 3'd3};  // else e + db if < 0, or 0
      F_ELHI:  {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, Y, N, N, N, 2'd2, 3'd4};  // e > el: e <- el
      F_ELCMP: {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, N, N, N, Y, 2'd0, 3'd0};  // e + el < 0 (clears acc)
      F_ELSET: {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, Y, Y, N, N, 2'd0, 3'd5};  // then e <- 0 - el
      F_LDQ:   {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, Y, N, N, N, 2'd2, 3'd1};  // acc <- RAM word
      F_SUBQ:  {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, Y, Y, N, N, 2'd0, 3'd1};  // acc -= RAM word
      F_XADD:  {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, N, N, N, N, 2'd0, 3'd0};  // x <- sat32(acc + word)
      F_XSUB:  {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, Y, Y, N, N, 2'd0, 3'd0};  // x <- sat32(acc - word)
      default: {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_mode_n, fa_wec_n} = {N, N, N, N, N, 2'd0, 3'd0};
    endcase
  end

  always @(posedge clk) begin
    {fa_bin, fa_inv, fa_cin, fa_setp, fa_setn, fa_wec} <=
        {fa_bin_n, fa_inv_n, fa_cin_n, fa_setp_n, fa_setn_n, fa_wec_n};
    fa_sm <= (fa_mode_n == 2'd1);  // saturate to 32 bits
    fa_pm <= (fa_mode_n == 2'd2);  // select B
    fa_db <= (fa_mode_n == 2'd3);  // deadband: zero unless negative
  end

  wire [    31:0] fa_b32 = fa_bin ? in_w : qf;
  wire [  FW-1:0] fa_bp = {{(FW - 32) {fa_b32[31]}}, fa_b32} ^ {FW{fa_inv}};
  wire [    FW:0] fa_t = {fa_acc[FW-1], fa_acc} + {fa_bp[FW-1], fa_bp} + {{FW{1'b0}}, fa_cin};
  wire            fa_neg = fa_t[FW];
  wire            el_nz = |qf[30:0];  // ELIM = 0 means no clamp

  // Result select codes, one LUT level behind the adder (the same scheme as
  // the back ALU's): saturation forces bits FW-1..31 to the sign and the
  // rest to its complement. Only cmd - fb saturates here, and its 33-bit
  // sum overflows 32 bits exactly when bits 32 and 31 differ; the operands
  // for the multiplier saturate at the operand multiplexer, like the doper.
  // The deadband's "0 if not negative" is the accumulator's synchronous
  // reset instead.
  wire fa_pos = fa_sm & ~fa_t[32] & fa_t[31];  // above 2^31 - 1
  wire fa_ng = fa_sm & fa_t[32] & ~fa_t[31];  // below -2^31
  wire [1:0] fk_hi = {fa_pm | fa_ng, fa_pm | fa_pos};  // bits FW-1..31
  wire [1:0] fk_lo = {fa_pm | fa_pos, fa_pm | fa_ng};  // bits 30..0

  wire [FW-1:0] fa_r;
  generate
    for (g = 0; g < FW; g = g + 1) begin : g_far
      wire [1:0] kk = (g >= 31) ? fk_hi : fk_lo;
      assign fa_r[g] = kk[1] ? (kk[0] ? ~fa_bp[g] : 1'b1) : (kk[0] ? 1'b0 : fa_t[g]);
    end
  endgenerate

  reg fp, fn;  // deadband kept e_raw - db; e < -el
  // Accumulator write, likewise one LUT behind the sign bit.
  wire fa_wa = run & ((fa_wec == 3'd1) | (fa_wec == 3'd3 & ~fp) | (fa_wec == 3'd5 & fn));
  wire fa_wp = run & ((fa_wec == 3'd2) | (fa_wec == 3'd4 & el_nz));  // if t >= 0
  wire fa_we = fa_wa | (fa_wp & ~fa_neg);

  // acc <- 0: ahead of -el, and the deadband's zero
  wire fa_clr = run & ((fa_setn & el_nz & fa_neg) | (fa_db & ~fp & ~fa_neg));
  always @(posedge clk) begin
    if (rst | fa_clr) fa_acc <= {FW{1'b0}};
    else if (fa_we) fa_acc <= fa_r;
    if (fa_setp) fp <= ~fa_neg;
    if (fa_setn) fn <= el_nz & fa_neg;
  end

  // ---------------------------------------------------------------------
  // Multiplier: operand x from either ALU or +-2^LIM_S for limit words;
  // coefficient from the coefficient RAM, or a limit word made a mantissa.
  wire [   W-2:0] yw;
  wire            ys_next, yc_next;
  /* verilator lint_off UNUSEDSIGNAL */
  wire            ys, yc;  // used a cycle early, as ys_next and yc_next
  /* verilator lint_on UNUSEDSIGNAL */
  wire [    31:0] ba_xd;  // doper field of the back ALU result
  // The operand. Both ALUs' results are registered before the multiplexer
  // (the front ALU's in fxr, the doper in dreg), so neither ALU's
  // saturation logic shares a clock cycle with the route to the DSP tiles,
  // and each x bit is one LUT of flip-flops: a product is consumed four
  // cycles after the ALU step that made its operand. Region codes of x,
  // bits 6..0, 7, 30..8, 31: 0 front ALU, 1 doper, 2 zero, 3 one (limits
  // enter as x = +-2^LIM_S). Both ALUs' operands saturate here: body to
  // ~sign, bit 31 to the sign.
  reg [31:0] fxr;
  reg        fovf, fneg;  // the front ALU's sum is beyond 32 bits; its sign
  reg [ 1:0] xs_d;  // the x source, one cycle on
  always @(posedge clk) begin
    fxr  <= fa_t[31:0];
    fovf <= ~((&fa_t[FW:31]) | ~(|fa_t[FW:31]));
    fneg <= fa_t[FW];
    xs_d <= xs;
  end
  reg [1:0] xk_lo, xk_7, xk_hi, xk_s;
  always @(*) begin
    case (xs_d)
      X_FA: begin
        if (fovf) {xk_lo, xk_7, xk_hi, xk_s} = {1'b1, ~fneg, 1'b1, ~fneg, 1'b1, ~fneg, 1'b1, fneg};
        else {xk_lo, xk_7, xk_hi, xk_s} = {2'd0, 2'd0, 2'd0, 2'd0};
      end
      X_BA: begin
        if (dovf) {xk_lo, xk_7, xk_hi, xk_s} = {1'b1, ~dneg, 1'b1, ~dneg, 1'b1, ~dneg, 1'b1, dneg};
        else {xk_lo, xk_7, xk_hi, xk_s} = {2'd1, 2'd1, 2'd1, 2'd1};
      end
      X_POS:   {xk_lo, xk_7, xk_hi, xk_s} = {2'd2, 2'd3, 2'd2, 2'd2};
      default: {xk_lo, xk_7, xk_hi, xk_s} = {2'd2, 2'd3, 2'd3, 2'd3};
    endcase
  end
  wire [31:0] mx;
  generate
    for (g = 0; g < 32; g = g + 1) begin : g_mx
      wire [1:0] kk = (g < LIM_S) ? xk_lo : (g == LIM_S) ? xk_7 : (g == 31) ? xk_s : xk_hi;
      assign mx[g] = kk[1] ? kk[0] : (kk[0] ? ba_xd[g] : fxr[g]);
    end
  endgenerate

  // Limits as the twin reads them: ILIM 0 means none (the output limit then
  // bounds the integrator alone), OLIM 0 or above full scale means full scale.
  wire        c16z = (cq[15:0] == 16'd0);
  wire [15:0] il_eff = c16z ? 16'hFFFF : cq[15:0];
  wire [15:0] ol_eff = (c16z | cq[15]) ? 16'h7FFF : cq[15:0];
  wire [MC_COEF_M_W-1:0] mm = (mp == M_IL) ? {{(MC_COEF_M_W - 16) {1'b0}}, il_eff} :
                              (mp == M_OL) ? {{(MC_COEF_M_W - 16) {1'b0}}, ol_eff} :
                              cq[MC_COEF_M_W-1:0];
  /* verilator lint_off WIDTH */
  wire [MC_COEF_S_W-1:0] ms = (mp == M_COEF) ? cq[MC_COEF_M_W+:MC_COEF_S_W] : LIM_S;
  /* verilator lint_on WIDTH */

  mul_align #(
      .M_W     (MC_COEF_M_W),
      .X_W     (MC_MUL_X_W),
      .S_W     (MC_COEF_S_W),
      .ACC_W   (W),
      .ACC_FRAC(F)
  ) u_mul (
      .clk(clk),
      .m  (mm),
      .x  (mx),
      .s  (ms),
      .yw (yw),
      .ys (ys),
      .yc (yc),
      .ys_next(ys_next),
      .yc_next(yc_next)
  );

  // ---------------------------------------------------------------------
  // Back ALU: t = A + (B ^ inv) + cin, ACC_W bits plus a sign bit. B is a
  // back RAM word or the product; the product's sign fold and rounding
  // increment ride on the inverter and the carry-in.
  reg [1:0] ba_asel;
  reg ba_by, ba_seto, ba_setu, ba_dop, ba_inv2, ba_cin;
  reg ba_wa, ba_wp, ba_wn, ba_z;
  reg ba_sm, ba_pm, ba_pz;  // saturating sum; select B; select B or zero
  // Back ALU steps: A (0 zero, 1 acc, 2 RAM word, 3 doper rounding
  // constant), B is the product (else the back RAM), invert B, carry-in
  // (before the product's rounding increment), zero for a disabled axis, set
  // over, set under, result mode (0 saturate, 1 raw sum for the doper, 2
  // select B), accumulator write (0 no, 1 yes, 2 if t >= 0: min, 3 if t < 0:
  // max). The anti-windup selects turn with the limit that was active.
  reg [1:0] ba_asel_n, ba_mode_n, ba_wec_n;
  reg ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n;
  wire [1:0] cap_w = over ? 2'd3 : 2'd2;  // over: cap = max(head, I(k-1))
  wire [1:0] ins_w = over ? 2'd2 : 2'd3;  // over: I(k) = min(cap, ic)
  always @(*) begin
    case (ba_op_n)
      //                   A     B=y  inv  cin   zd   over under mode   write
      B_DOPER:  {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd3, N, N, N,     N, N, N, 2'd1, 2'd0};
      B_LDY:    {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd0, Y, N, N,     N, N, N, 2'd0, 2'd1};
      B_ADDY:   {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, Y, N, N,     N, N, N, 2'd0, 2'd1};
      B_ADDYZ:  {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, Y, N, N,     Y, N, N, 2'd0, 2'd1};
      B_ADDQ:   {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, N, N, N,     N, N, N, 2'd0, 2'd1};
      B_QADDYZ: {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd2, Y, N, N,     Y, N, N, 2'd0, 2'd1};
      B_MINY:   {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, Y, Y, N,     N, N, N, 2'd2, 2'd2};
      B_MAXY:   {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, Y, Y, Y,     N, N, N, 2'd2, 2'd3};
      B_MINYO:  {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, Y, Y, N,     Y, Y, N, 2'd2, 2'd2};
      B_MAXYU:  {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, Y, Y, Y,     Y, N, Y, 2'd2, 2'd3};
      B_SUBQ:   {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, N, Y, Y,     N, N, N, 2'd0, 2'd1};
      B_CAP:    {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, N, Y, over,  N, N, N, 2'd2, cap_w};
      B_INS:    {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, N, Y, ~over, N, N, N, 2'd2, ins_w};
      default:  {ba_asel_n, ba_by_n, ba_inv_n, ba_cb_n, ba_zd_n, ba_seto_n, ba_setu_n, ba_mode_n, ba_wec_n} = {2'd1, N, N, N,     N, N, N, 2'd0, 2'd0};
    endcase
  end


  always @(posedge clk) begin
    {ba_asel, ba_by, ba_seto, ba_setu} <= {ba_asel_n, ba_by_n, ba_seto_n, ba_setu_n};
    // Write enables: always, if t >= 0, if t < 0; a disabled axis's zd step
    // always writes (zero).
    ba_z  <= ba_zd_n & ~ba_en_n;
    ba_sm <= (ba_mode_n == 2'd0) & ~(ba_zd_n & ~ba_en_n);
    ba_pm <= (ba_mode_n == 2'd2) & ~(ba_zd_n & ~ba_en_n);
    ba_pz <= (ba_mode_n == 2'd2) | (ba_zd_n & ~ba_en_n);
    ba_wa <= run_n & ((ba_wec_n == 2'd1) | (ba_zd_n & ~ba_en_n));
    ba_wp <= run_n & (ba_wec_n == 2'd2) & ~(ba_zd_n & ~ba_en_n);
    ba_wn <= run_n & (ba_wec_n == 2'd3) & ~(ba_zd_n & ~ba_en_n);
    // The carry-in adds the product's rounding increment.
    ba_cin <= ba_cb_n ^ (ba_by_n & yc_next);
    ba_dop <= (ba_op_n == B_DOPER);
    // The operand inverter also undoes the product's sign fold; the sign is
    // known a cycle ahead, so the combined flag comes from a flip-flop.
    ba_inv2 <= ba_inv_n ^ (ba_by_n & ys_next);
  end

  reg [W-1:0] ba_a;
  always @(*) begin
    case (ba_asel)
      2'd0:    ba_a = {W{1'b0}};
      2'd1:    ba_a = ba_acc;
      2'd2:    ba_a = qb;
      default: ba_a = {{(W - DSH) {1'b0}}, 1'b1, {(DSH - 1) {1'b0}}};
    endcase
  end
  wire [ W-1:0] ba_bp = (ba_by ? {1'b0, yw} : qb) ^ {W{ba_inv2}};
  wire [   W:0] ba_t = {ba_a[W-1], ba_a} + {ba_bp[W-1], ba_bp} + {{W{1'b0}}, ba_cin};
  wire          ba_neg = ba_t[W];
  wire          ba_ovd = ~((&ba_t[W:DSH+31]) | ~(|ba_t[W:DSH+31]));

  // Result select codes, one LUT level behind the adder: the mode is
  // registered and pre-combined with the zero force, so each code bit is a
  // function of two mode signals and the two top sum bits. Saturation forces
  // the sign bit to t[W] and the rest to ~t[W]; the doper step (mode 1)
  // keeps the raw sum and is saturated at the operand multiplexer.
  wire          ba_pos = ba_sm & ~ba_t[W] & ba_t[W-1];  // overflow upwards
  wire          ba_ng = ba_sm & ba_t[W] & ~ba_t[W-1];  // overflow downwards
  wire [1:0] bk_s = {ba_pm | ba_ng, ba_pz | ba_pos};
  wire [1:0] bk_o = {ba_pm | ba_pos, ba_pz | ba_ng};

  wire [W-1:0] ba_r;
  generate
    for (g = 0; g < W; g = g + 1) begin : g_bar
      wire [1:0] kk = (g == W - 1) ? bk_s : bk_o;
      assign ba_r[g] = kk[1] ? (kk[0] ? ~ba_bp[g] : 1'b1) : (kk[0] ? 1'b0 : ba_t[g]);
    end
  endgenerate
  // The doper operand waits in a register for its multiplier slot, raw, with
  // its overflow and sign: the saturation happens at the operand multiplexer.
  reg [31:0] dreg;
  reg        dovf, dneg;
  always @(posedge clk) begin
    if (ba_dop) begin
      dreg <= ba_t[DSH+31:DSH];
      dovf <= ba_ovd;
      dneg <= ba_t[W];
    end
  end
  assign ba_xd = dreg;

  // Accumulator write: one LUT behind the sign bit (the compare-and-select
  // steps decide on it), from flip-flops otherwise.
  wire ba_we = ba_wa | (ba_wp & ~ba_neg) | (ba_wn & ba_neg);

  // SERVO = 0: the accumulator and the limit flags stay zero, as a
  // disabled axis's outputs are, and synthesis trims the back ALU, the back
  // RAM and the multiplier, which then drive nothing.
  localparam [0:0] LOOPS = (SERVO != 0);
  always @(posedge clk) begin
    if (rst || !LOOPS) ba_acc <= {W{1'b0}};
    else if (ba_we) ba_acc <= ba_r;
    // The selects that clamp v record whether the limit was active.
    if (ba_seto) over <= LOOPS & ~ba_z & ~ba_neg;
    if (ba_setu) under <= LOOPS & ~ba_z & ba_neg;
  end

  // ---------------------------------------------------------------------
  // Outputs: the error when the front ALU has it, the drive output and
  // saturation flag when the back ALU has clamped v (u = round(v clamped)).
  wire [15:0] u_rnd = ba_acc[F+15:F] + {15'd0, ba_acc[F-1]};
  reg  [NAXES*16-1:0] u_r;
  reg  [NAXES*32-1:0] e_r;
  reg  [   NAXES-1:0] s_r;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_out
      /* verilator lint_off WIDTH */
      localparam [SLW-1:0] GA = g;
      localparam [SLW-1:0] GB = g + 1;
      /* verilator lint_on WIDTH */
      always @(posedge clk) begin
        if (rst) begin
          u_r[g*16+:16] <= 16'd0;
          e_r[g*32+:32] <= 32'd0;
          s_r[g]        <= 1'b0;
        end else begin
          if (run & fa_we_e & (sl == GA)) e_r[g*32+:32] <= fa_acc[31:0];
          if (run & ou_we & (sl == GB)) begin
            u_r[g*16+:16] <= u_rnd;
            s_r[g]        <= over | under;
          end
        end
      end
    end
  endgenerate
  assign u_o   = u_r;
  assign err_o = e_r;
  // Command and feedback leave the chain's head in slot cycles 0 and 1, the
  // raw error cmd - fb is in the front ALU's accumulator in cycle 2, the
  // error in cycle 7 (the microcode's chain-shift and write-e columns), and
  // the back ALU has the previous axis's output in cycle 10 (the drive
  // column): never two in one clock.
  wire smp_raw = fa_ok & (cy == 5'd2);
  wire smp_out = run & ou_we & (sl != {SLW{1'b0}});
  /* verilator lint_off WIDTH */
  assign smp_we_o  = (fa_ok & (ch_shift | fa_we_e)) | smp_raw | smp_out;
  assign smp_ax_o  = smp_out ? slp : sl;
  /* verilator lint_on WIDTH */
  assign smp_fld_o = smp_out ? 3'd3 : smp_raw ? 3'd4 : fa_we_e ? 3'd2 : {2'b00, cy[0]};
  assign smp_wd_o  = smp_out ? {14'd0, en_pad[slp], over | under, u_rnd} :
                     (smp_raw | fa_we_e) ? fa_acc[31:0] : in_w;
  assign sat_o = s_r;
  assign en_o  = en;

`ifdef VERILATOR
  // Simulation-only view of the per-axis state, as the twin's PidState holds
  // it after the sample that done_o ends: the testbench compares it.
  wire [W-1:0] st_i[0:NAXES-1]  /* verilator public_flat_rd */;
  wire [W-1:0] st_d[0:NAXES-1]  /* verilator public_flat_rd */;
  wire [31:0] st_e1[0:NAXES-1]  /* verilator public_flat_rd */;
  wire [31:0] st_c1[0:NAXES-1]  /* verilator public_flat_rd */;
  wire [31:0] st_c2[0:NAXES-1]  /* verilator public_flat_rd */;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_st
      /* verilator lint_off WIDTH */
      localparam [SLW-1:0] GA = g;
      /* verilator lint_on WIDTH */
      assign st_i[g]  = bram[{GA, w_i0}];
      assign st_d[g]  = bram[{GA, 3'd0}];
      assign st_e1[g] = fram[{GA, w_e0}];
      assign st_c1[g] = fram[{GA, 1'b0, k3}];
      assign st_c2[g] = fram[{GA, 1'b0, k3m1}];
    end
  endgenerate
`endif

endmodule

`default_nettype wire
