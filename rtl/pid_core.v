// pid_core: NAXES Tustin PID position loops sharing one multiply datapath.
// Twin: hls/pid_core.hpp (the golden model; the arithmetic is identical bit
// for bit, see that file for the realization and docs/numerics.md for why).
//
// How to drive it:
// - Configuration: present cfg_we/cfg_waddr/cfg_wdata; the write is taken on a
//   cycle where cfg_wready is high (the core is between sweeps), so a write
//   always lands between two samples, never inside one. Reads likewise:
//   cfg_re/cfg_raddr taken when cfg_rready, data on cfg_rdata one cycle later
//   with cfg_rvalid. Addresses: rtl/pid_regs.vh, {axis, reg}.
// - Every TS cycles (global register, clamped to at least LATENCY) tick_o
//   pulses; cmd_i and fb_i are sampled in that cycle, for all axes at once so
//   coordinated axes see the same instant. LATENCY cycles after tick_o,
//   done_o pulses and u_o/err_o/sat_o hold the new sample's values.
//
// Schedule per axis (14 cycles, c0..c13; one coefficient RAM read per cycle
// c0..c9, one multiply issued per cycle c3..c8, mul_align latency 2):
//   c0 rd DBAND   e_raw = sat(cmd - fb); operands vel, acc, D(k-1) as Q17.15
//   c1 rd ELIM    deadband
//   c2 rd KP      error clamp -> e
//   c3 rd KI      mul KP*e;          e+e1, e-e1
//   c4 rd KD_A    mul KI*(e+e1)
//   c5 rd KD_B    mul KD_A*D(k-1)    P
//   c6 rd KF1     mul KD_B*(e-e1)    I candidate = I + dI
//   c7 rd KF2     mul KF1*vel        alpha*D
//   c8 rd ILIM    mul KF2*acc        D(k)
//   c9 rd OLIM                       F1; integrator limit word
//   c10                              F; P+D; output limit; integrator bound
//   c11                              rest = P+D+F; clamp I candidate
//   c12                              anti-windup -> I(k); saturation flag
//   c13                              u = sat(rest + I(k)); state write-back
`default_nettype none

module pid_core #(
    parameter integer NAXES = 3  // axes sharing the datapath (1..15)
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
    output reg                    tick_o,  // sample instant
    output reg                    done_o,  // sweep finished, outputs valid
    output wire                   busy_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "mc_fixed.vh"
`include "pid_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer AXIS_CYCLES = 14;
  localparam integer LATENCY = 1 + NAXES * AXIS_CYCLES;
  localparam integer AXW = (NAXES > 1) ? $clog2(NAXES) : 1;
  localparam integer RAM_DEPTH = NAXES * 16;
  localparam integer RAM_AW = $clog2(RAM_DEPTH);
  localparam integer W = MC_ACC_W;
  localparam integer F = MC_ACC_FRAC;

  initial begin
    if (NAXES < 1 || NAXES > 15) begin
      $error("pid_core: NAXES must be 1..15");
    end
  end

  // Sized copies of integer parameters, for comparisons without width games.
  /* verilator lint_off WIDTH */
  localparam [3:0] NAXES4 = NAXES;
  localparam [AXW-1:0] LAST_AX = NAXES - 1;
  localparam [3:0] LAST_CYC = AXIS_CYCLES - 1;
  localparam [31:0] LATENCY32 = LATENCY;
  /* verilator lint_on WIDTH */

  localparam signed [W-1:0] ACC_MAX = {1'b0, {(W - 1) {1'b1}}};
  localparam signed [W-1:0] ACC_MIN = {1'b1, {(W - 1) {1'b0}}};

  // Saturating helpers. Every addition in the datapath goes through these:
  // the twin's sat_acc/sat32 calls correspond one to one.
  function automatic signed [W-1:0] sat_add;
    input signed [W-1:0] a;
    input signed [W-1:0] b;
    reg signed [W:0] t;
    begin
      t = {a[W-1], a} + {b[W-1], b};
      sat_add = (t[W] != t[W-1]) ? (t[W] ? ACC_MIN : ACC_MAX) : t[W-1:0];
    end
  endfunction

  function automatic signed [W-1:0] sat_sub;
    input signed [W-1:0] a;
    input signed [W-1:0] b;
    reg signed [W:0] t;
    begin
      t = {a[W-1], a} - {b[W-1], b};
      sat_sub = (t[W] != t[W-1]) ? (t[W] ? ACC_MIN : ACC_MAX) : t[W-1:0];
    end
  endfunction

  function automatic signed [31:0] sat32_33;
    input signed [32:0] t;
    begin
      sat32_33 = (t[32] != t[31]) ? (t[32] ? 32'sh80000000 : 32'sh7fffffff) : t[31:0];
    end
  endfunction

  function automatic signed [31:0] sat32_34;
    input signed [33:0] t;
    begin
      if (t > 34'sd2147483647) sat32_34 = 32'sh7fffffff;
      else if (t < -34'sd2147483648) sat32_34 = 32'sh80000000;
      else sat32_34 = t[31:0];
    end
  endfunction

  // ---------------------------------------------------------------------
  // Sequencer state
  reg              run;
  reg [AXW-1:0]    ax;
  reg [3:0]        cyc;  // 0..AXIS_CYCLES-1
  wire             last_axis = (ax == LAST_AX);
  wire             idle = ~run;

  assign busy_o     = run;
  assign cfg_wready = idle;
  assign cfg_rready = idle;

  // ---------------------------------------------------------------------
  // Configuration: coefficient RAM (block RAM, synchronous read) and flops.
  reg  [31:0]        ram [0:RAM_DEPTH-1];
  reg  [31:0]        ram_q;
  reg  [NAXES-1:0]   en;
  reg  [31:0]        ts;

  integer k;
  initial begin
    // Block RAM powers up as configured: all coefficients zero.
    for (k = 0; k < RAM_DEPTH; k = k + 1) ram[k] = 32'd0;
  end

  wire [3:0] w_ax = cfg_waddr[7:4];
  wire [3:0] w_rg = cfg_waddr[3:0];
  wire       w_ok = cfg_we & cfg_wready;
  wire       w_ram = w_ok & (w_ax < NAXES4) & (w_rg < PID_NREGS_RAM);

  // The RAM's single read port serves the sequencer during a sweep and the
  // configuration read port between sweeps.
  reg  [3:0] rd_reg;  // register the sequencer reads in this cycle
  // Word address {axis, reg}: the axis field is only as wide as NAXES needs.
  /* verilator lint_off UNUSEDSIGNAL */
  wire [7:0] seq_raddr8 = {{(4 - AXW) {1'b0}}, ax, rd_reg};
  wire [7:0] ram_raddr8 = run ? seq_raddr8 : cfg_raddr;
  wire [RAM_AW-1:0] ram_raddr = ram_raddr8[RAM_AW-1:0];
  wire [7:0] ram_waddr8 = cfg_waddr;
  /* verilator lint_on UNUSEDSIGNAL */

  always @(posedge clk) begin
    if (w_ram) ram[ram_waddr8[RAM_AW-1:0]] <= cfg_wdata;
    ram_q <= ram[ram_raddr];
  end

  // Enables and the sample period: control state, reset.
  always @(posedge clk) begin
    if (rst) begin
      en <= {NAXES{1'b0}};
      ts <= LATENCY32;
    end else if (w_ok) begin
      if (w_ax == PID_GLOBAL_AXIS && w_rg == PID_G_TS) begin
        ts <= (cfg_wdata < LATENCY32) ? LATENCY32 : cfg_wdata;
      end
      if (w_ax < NAXES4 && w_rg == PID_REG_CTRL) en[w_ax[AXW-1:0]] <= cfg_wdata[0];
    end
  end

  // Read-back: RAM words come from ram_q one cycle later; the rest from flops.
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

  always @(*) begin
    cfg_rvalid = r_pend;
    cfg_rdata  = 32'd0;
    if (r_ax == PID_GLOBAL_AXIS) begin
      if (r_rg == PID_G_TS) cfg_rdata = ts;
      else if (r_rg == PID_G_LATENCY) cfg_rdata = LATENCY32;
      else if (r_rg == PID_G_NAXES) cfg_rdata = {28'd0, NAXES4};
    end else if (r_ax < NAXES4) begin
      if (r_rg < PID_NREGS_RAM) cfg_rdata = ram_q;
      else if (r_rg == PID_REG_CTRL) cfg_rdata = {31'd0, en[r_ax[AXW-1:0]]};
    end
  end

  // ---------------------------------------------------------------------
  // Sample timer: tick every ts cycles. A new ts takes effect at the next
  // reload, so a running period is never cut short.
  reg [31:0] tcnt;
  always @(posedge clk) begin
    if (rst) begin
      tcnt   <= 32'd0;
      tick_o <= 1'b0;
    end else begin
      tick_o <= (tcnt == 32'd0);
      tcnt   <= (tcnt == 32'd0) ? ts - 32'd1 : tcnt - 32'd1;
    end
  end

  // Inputs of all axes latched at the same instant.
  reg [NAXES*32-1:0] cmd_s, fb_s;
  always @(posedge clk) begin
    if (tick_o) begin
      cmd_s <= cmd_i;
      fb_s  <= fb_i;
    end
  end

  always @(posedge clk) begin
    if (rst) begin
      run <= 1'b0;
      ax  <= {AXW{1'b0}};
      cyc <= 4'd0;
    end else if (idle) begin
      run <= tick_o;
      ax  <= {AXW{1'b0}};
      cyc <= 4'd0;
    end else if (cyc == LAST_CYC) begin
      cyc <= 4'd0;
      ax  <= ax + 1'b1;
      run <= ~last_axis;
    end else begin
      cyc <= cyc + 4'd1;
    end
  end

  always @(posedge clk) begin
    if (rst) done_o <= 1'b0;
    else done_o <= run & last_axis & (cyc == LAST_CYC);
  end

  // RAM read schedule.
  always @(*) begin
    case (cyc)
      4'd0:    rd_reg = PID_REG_DBAND;
      4'd1:    rd_reg = PID_REG_ELIM;
      4'd2:    rd_reg = PID_REG_KP;
      4'd3:    rd_reg = PID_REG_KI;
      4'd4:    rd_reg = PID_REG_KD_A;
      4'd5:    rd_reg = PID_REG_KD_B;
      4'd6:    rd_reg = PID_REG_KF1;
      4'd7:    rd_reg = PID_REG_KF2;
      4'd8:    rd_reg = PID_REG_ILIM;
      4'd9:    rd_reg = PID_REG_OLIM;
      default: rd_reg = PID_REG_KP;
    endcase
  end

  // ---------------------------------------------------------------------
  // Per-axis state (flops; NAXES entries, read at c0..c12, written at c13).
  // The testbench reads the dynamic state to compare it with the twin's.
  reg signed [W-1:0]  st_i  [0:NAXES-1]  /* verilator public_flat_rd */;  // integrator, Q17.32
  reg signed [W-1:0]  st_d  [0:NAXES-1]  /* verilator public_flat_rd */;  // derivative, Q17.32
  reg signed [31:0]   st_e1 [0:NAXES-1];
  reg signed [31:0]   st_c1 [0:NAXES-1];
  reg signed [31:0]   st_c2 [0:NAXES-1];
  reg signed [15:0]   out_u [0:NAXES-1];
  reg signed [31:0]   out_e [0:NAXES-1];
  reg [NAXES-1:0]     out_s;

  wire signed [31:0] cmd_a = cmd_s[ax*32+:32];
  wire signed [31:0] fb_a = fb_s[ax*32+:32];

  // ---------------------------------------------------------------------
  // Datapath registers.
  reg signed [31:0]  e_raw, e_db, e_r, sum_e, dif_e, vel, acc, doper;
  reg signed [W-1:0] p_r, ic_r, da_r, dn_r, f1_r, ff_r, pd_r, rest_r, icc_r, in_r;
  reg signed [W-1:0] ulim_r, ibnd_r;
  reg [15:0]         il_r;
  reg                sat_r;

  // Operand select for the shared multiply, by schedule slot.
  reg signed [31:0] mx;
  always @(*) begin
    case (cyc)
      4'd3:    mx = e_r;
      4'd4:    mx = sum_e;
      4'd5:    mx = doper;
      4'd6:    mx = dif_e;
      4'd7:    mx = vel;
      default: mx = acc;
    endcase
  end

  wire signed [W-1:0] y;
  mul_align #(
      .M_W     (MC_COEF_M_W),
      .X_W     (MC_MUL_X_W),
      .S_W     (MC_COEF_S_W),
      .ACC_W   (W),
      .ACC_FRAC(F)
  ) u_mul (
      .clk(clk),
      .m  (ram_q[MC_COEF_M_W-1:0]),
      .x  (mx),
      .s  (ram_q[MC_COEF_M_W+:MC_COEF_S_W]),
      .y  (y)
  );

  // c0: error and command differences, derivative state as operand.
  wire signed [32:0] e_dif = {cmd_a[31], cmd_a} - {fb_a[31], fb_a};
  wire signed [33:0] c_vel = {{2{cmd_a[31]}}, cmd_a} - {{2{st_c1[ax][31]}}, st_c1[ax]};
  wire signed [33:0] c_acc = {{2{cmd_a[31]}}, cmd_a} - {st_c1[ax][31], st_c1[ax], 1'b0} +
                             {{2{st_c2[ax][31]}}, st_c2[ax]};
  // D(k-1) in Q17.15: round half up, then saturate to the 32-bit operand.
  localparam integer DSH = F - MC_D_OPER_FRAC;
  /* verilator lint_off UNUSEDSIGNAL */
  wire signed [W:0] d_rnd = {st_d[ax][W-1], st_d[ax]} + $signed({{(W + 1 - DSH) {1'b0}}, 1'b1, {(DSH - 1) {1'b0}}});
  /* verilator lint_on UNUSEDSIGNAL */
  wire signed [W-DSH:0] d_q = d_rnd[W:DSH];
  wire d_fits = (&d_q[W-DSH:31]) | ~(|d_q[W-DSH:31]);
  wire signed [31:0] d_oper = d_fits ? d_q[31:0] : (d_q[W-DSH] ? 32'sh80000000 : 32'sh7fffffff);

  // c1, c2: deadband and clamp; limits are 31-bit unsigned words.
  wire signed [32:0] limw = {2'b00, ram_q[30:0]};  // DBAND at c1, ELIM at c2
  wire signed [32:0] e_raw33 = {e_raw[31], e_raw};
  // Both results fit 32 bits (|e| only shrinks), so bit 32 is dropped.
  /* verilator lint_off UNUSEDSIGNAL */
  wire signed [32:0] e_db33 = (e_raw33 > limw) ? e_raw33 - limw :
                              (e_raw33 < -limw) ? e_raw33 + limw : 33'sd0;
  wire signed [32:0] e_db_x = {e_db[31], e_db};
  wire signed [32:0] e_cl33 = (limw == 33'sd0) ? e_db_x :
                              (e_db_x > limw) ? limw : (e_db_x < -limw) ? -limw : e_db_x;
  /* verilator lint_on UNUSEDSIGNAL */

  // c10: effective output limit and integrator bound, in Q17.32.
  wire [15:0]       ol_w = ram_q[15:0];
  wire [15:0]       ol = (ol_w == 16'd0 || ol_w > 16'd32767) ? 16'd32767 : ol_w;
  wire [15:0]       ib = (il_r != 16'd0 && il_r < ol) ? il_r : ol;

  // c12: anti-windup against the headroom the output limit leaves.
  wire signed [W-1:0] v = sat_add(rest_r, icc_r);
  wire signed [W-1:0] head_hi = sat_sub(ulim_r, rest_r);
  wire signed [W-1:0] head_lo = sat_sub(-ulim_r, rest_r);
  wire signed [W-1:0] cap_hi = (head_hi > st_i[ax]) ? head_hi : st_i[ax];
  wire signed [W-1:0] cap_lo = (head_lo < st_i[ax]) ? head_lo : st_i[ax];
  wire                over = v > ulim_r;
  wire                under = v < -ulim_r;
  wire signed [W-1:0] i_new = over ? ((icc_r < cap_hi) ? icc_r : cap_hi) :
                              under ? ((icc_r > cap_lo) ? icc_r : cap_lo) : icc_r;

  // c13: output in drive units, round half up, clamp to the limit.
  wire signed [W-1:0]   yo = sat_add(rest_r, in_r);
  /* verilator lint_off UNUSEDSIGNAL */
  wire signed [W:0]     yo_h = {yo[W-1], yo} + $signed({{(W + 1 - F) {1'b0}}, 1'b1, {(F - 1) {1'b0}}});
  /* verilator lint_on UNUSEDSIGNAL */
  wire signed [W-F:0]   yo_r = yo_h[W:F];
  wire signed [W-F:0]   ul = {1'b0, ulim_r[W-1:F]};
  wire signed [15:0]    u_new = (yo_r > ul) ? ul[15:0] : (yo_r < -ul) ? -ul[15:0] : yo_r[15:0];

  always @(posedge clk) begin
    if (run) begin
      case (cyc)
        4'd0: begin
          e_raw <= sat32_33(e_dif);
          vel   <= sat32_34(c_vel);
          acc   <= sat32_34(c_acc);
          doper <= d_oper;
        end
        4'd1: e_db <= e_db33[31:0];
        4'd2: e_r <= e_cl33[31:0];
        4'd3: begin
          sum_e <= sat32_33({e_r[31], e_r} + {st_e1[ax][31], st_e1[ax]});
          dif_e <= sat32_33({e_r[31], e_r} - {st_e1[ax][31], st_e1[ax]});
        end
        4'd5: p_r <= y;
        4'd6: ic_r <= sat_add(st_i[ax], y);
        4'd7: da_r <= y;
        4'd8: dn_r <= sat_add(da_r, y);
        4'd9: begin
          f1_r <= y;
          il_r <= ram_q[15:0];
        end
        4'd10: begin
          ff_r   <= sat_add(f1_r, y);
          pd_r   <= sat_add(p_r, dn_r);
          ulim_r <= $signed({{(W - F - 16) {1'b0}}, ol, {F{1'b0}}});
          ibnd_r <= $signed({{(W - F - 16) {1'b0}}, ib, {F{1'b0}}});
        end
        4'd11: begin
          rest_r <= sat_add(pd_r, ff_r);
          icc_r  <= (ic_r > ibnd_r) ? ibnd_r : (ic_r < -ibnd_r) ? -ibnd_r : ic_r;
        end
        4'd12: begin
          in_r  <= i_new;
          sat_r <= over | under;
        end
        default: ;
      endcase
    end
  end

  // c13: state write-back. A disabled axis outputs 0 and clears its dynamic
  // state, but keeps tracking error and command so enabling is bumpless.
  always @(posedge clk) begin
    if (rst) begin
      for (k = 0; k < NAXES; k = k + 1) begin
        st_i[k]  <= {W{1'b0}};
        st_d[k]  <= {W{1'b0}};
        st_e1[k] <= 32'd0;
        st_c1[k] <= 32'd0;
        st_c2[k] <= 32'd0;
        out_u[k] <= 16'd0;
        out_e[k] <= 32'd0;
      end
      out_s <= {NAXES{1'b0}};
    end else if (run && cyc == LAST_CYC) begin
      st_i[ax]  <= en[ax] ? in_r : {W{1'b0}};
      st_d[ax]  <= en[ax] ? dn_r : {W{1'b0}};
      st_e1[ax] <= e_r;
      st_c2[ax] <= st_c1[ax];
      st_c1[ax] <= cmd_a;
      out_u[ax] <= en[ax] ? u_new : 16'd0;
      out_e[ax] <= e_r;
      out_s[ax] <= en[ax] & sat_r;
    end
  end

  genvar g;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_out
      assign u_o[g*16+:16]   = out_u[g];
      assign err_o[g*32+:32] = out_e[g];
    end
  endgenerate
  assign sat_o = out_s;
  assign en_o  = en;

endmodule

`default_nettype wire
