// motion_core: the portable motion datapath of the board, without pins or
// link. NAXES position loops: each axis's quadrature decoder gives the
// feedback, the interpolator's position the command, the shared pid_core
// closes the loops, and a PWM + direction generator drives an H-bridge.
// Twin: hls/motion_core.hpp (cycle for cycle).
//
// How to drive it:
// - Configure the PID through pid_* (pid_core's port, rtl/pid_regs.vh), the
//   decoders through enc_* (quad_decoder's ports, one slice per axis: no
//   position load, the host keeps offsets; errors counted to 255), and
//   queue segments through seg_wr/seg_wdata (interp_core's port; set the
//   position with ip_set, a strobe per axis, while the interpolator is idle).
// - The PID samples cmd/pos at tick, for all axes at once, and the decoders
//   take their velocity sample at the same tick. Each axis's new output
//   reaches drv_cmd as the sweep makes it (the sample RAM's OUT word; axis a
//   at the edge that ends clock 29 + 18a after the tick, DRV_CLOCK in
//   hls/motion_core.hpp) and the pins a clock later: a drive never waits for
//   the other axes, and the axes change 18 clocks apart (1.5 us at 12 MHz;
//   X to Z 3 us). smp_sat is latched at done.
// - The sample's words per axis are kept in a block RAM of two banks: the
//   sweep writes one while smp_raddr reads the other, and done swaps them,
//   so a read always sees one whole sample, the last completed, from the
//   clock after done until the next done. smp_raddr = {axis, field}, fields
//   (SMP_* in hls/motion_core.hpp) 0 command, 1 feedback, 2 error, 3 output
//   {[17] PID enabled, [16] saturated, [15:0] u}, 4 following error
//   command - feedback (saturated to 32 bits); 5-7 and absent axes read 0.
//   smp_rdata follows one clock later.
// - drv_allow (from the safety logic) low forces the drive value to 0 and the
//   pins low in the next clock, whatever the PID does. drv_ovr hands an axis's
//   drive to the host instead of the PID (the host-loop mode): done then
//   leaves its drv_cmd alone, and drv_ovr_we loads it with drv_ovr_val. When
//   drv_ovr falls, the host's last value holds until the PID's next output
//   for the axis (at most a sample period and drv_clock later).
// - PWM: a free-running PWM_BITS counter; the duty is the magnitude of
//   drv_u in steps of 2^(15-PWM_BITS) drive units, so full scale is always
//   on; dir_o gives the sign. drv_en_o enables the bridge for an axis whose
//   PID is enabled or that is overridden, and is allowed.
// - drv_sel is the drive value selected in this clock, drv_u the one the
//   pins show (drv_sel of the clock before). A user that registers its read
//   of drv_sel anyway (the board's register file) sees drv_u's value and
//   leaves drv_u's flip-flops to be trimmed.
`default_nettype none

module motion_core #(
    parameter integer NAXES    = 3,  // axes, 1..3 (the interpolator moves three)
    parameter integer FIFO_AW  = 9,  // log2 of the segment queue depth in words
    parameter integer PWM_BITS = 9,  // PWM period 2^PWM_BITS clocks, duty resolution
    parameter integer FILT_W   = 8,  // encoder glitch filter length width, bits
    parameter integer IDX_RAM  = 0,  // the decoders' index latches in block RAM (quad_decoder)
    parameter integer SERVO    = 1   // 0: pid_core without its loops (every axis disabled)
) (
    // clock and reset
    input  wire                  clk,
    input  wire                  rst,
    // PID configuration write (pid_core)
    input  wire                  pid_we,
    input  wire [           7:0] pid_waddr,
    input  wire [          31:0] pid_wdata,
    output wire                  pid_wready,
    // PID configuration read (pid_core)
    input  wire                  pid_re,
    input  wire [           7:0] pid_raddr,
    output wire                  pid_rready,
    output wire                  pid_rvalid,
    output wire [          31:0] pid_rdata,
    // segment queue and interpolator control (interp_core)
    input  wire                  seg_wr,
    input  wire [          31:0] seg_wdata,
    output wire [     FIFO_AW:0] seg_count,
    input  wire                  ip_abort,
    input  wire                  ip_hold,
    input  wire                  ip_clr,
    input  wire [           2:0] ip_set,
    input  wire [      3*32-1:0] ip_set_pos,
    input  wire [           2:0] ip_jog,      // handwheel jog: one count, while idle
    input  wire                  ip_jog_neg,
    output wire                  ip_busy,
    output wire                  ip_underrun,
    output wire                  ip_ovf,
    output wire [          15:0] ip_seg_cnt,
    // encoder pins (asynchronous; the decoders synchronize them)
    input  wire [     NAXES-1:0] enc_a,
    input  wire [     NAXES-1:0] enc_b,
    input  wire [     NAXES-1:0] enc_z,
    input  wire [     NAXES-1:0] enc_latch,  // synchronous latch strobes (home switch, probe)
    // encoder configuration and strobes, one slice per axis (quad_decoder)
    input  wire [NAXES*FILT_W-1:0] enc_filt,
    input  wire [     NAXES-1:0] enc_dir_inv,
    input  wire [     NAXES-1:0] enc_idx_clr_en,
    input  wire [     NAXES-1:0] enc_idx_arm,
    input  wire [     NAXES-1:0] enc_idx_disarm,
    input  wire [     NAXES-1:0] enc_err_clr,
    // encoder status
    output wire [     NAXES-1:0] enc_err,
    output wire [   NAXES*8-1:0] enc_err_cnt,
    output wire [  NAXES*32-1:0] enc_idx_pos,
    output wire [     NAXES-1:0] enc_idx_armed,
    output wire [     NAXES-1:0] enc_idx_seen,
    output wire [  NAXES*32-1:0] enc_vel,
    // drive control
    input  wire [     NAXES-1:0] drv_allow,
    input  wire [     NAXES-1:0] drv_ovr,     // level: the host drives the axis
    input  wire [     NAXES-1:0] drv_ovr_we,  // strobe: drv_cmd of the axis <- drv_ovr_val
    input  wire [          15:0] drv_ovr_val,
    // H-bridge pins
    output reg  [     NAXES-1:0] pwm_o,
    output reg  [     NAXES-1:0] dir_o,
    output reg  [     NAXES-1:0] drv_en_o,
    output reg  [  NAXES*16-1:0] drv_u,    // the drive value behind pwm_o/dir_o
    output wire [  NAXES*16-1:0] drv_sel,  // drv_u's next value (this clock's selection)
    // per-sample telemetry
    output wire                  tick,
    output wire                  done,
    input  wire [           4:0] smp_raddr,
    output reg  [          31:0] smp_rdata,
    output reg  [  NAXES*16-1:0] drv_cmd,  // the drive value before the safety gate
    output reg  [     NAXES-1:0] smp_sat,
    output wire [     NAXES-1:0] pid_en,
    // live positions
    output wire [  NAXES*32-1:0] pos,
    output wire [  NAXES*32-1:0] cmd
);

  initial begin
    if (NAXES < 1 || NAXES > 3) $error("motion_core: NAXES must be 1..3");
    if (PWM_BITS < 1 || PWM_BITS > 15) $error("motion_core: PWM_BITS must be 1..15");
  end

  // ---------------------------------------------------------------------
  // Command: the interpolator's position, first NAXES axes (the others are
  // unused in a one- or two-axis build).
  /* verilator lint_off UNUSEDSIGNAL */
  wire [3*32-1:0] ip_pos;
  /* verilator lint_on UNUSEDSIGNAL */
  assign cmd = ip_pos[NAXES*32-1:0];

  interp_core #(
      .FIFO_AW(FIFO_AW)
  ) u_interp (
      .clk       (clk),
      .rst       (rst),
      .wr_i      (seg_wr),
      .wdata_i   (seg_wdata),
      .count_o   (seg_count),
      .abort_i   (ip_abort),
      .hold_i    (ip_hold),
      .clr_i     (ip_clr),
      .set_i     (ip_set),
      .set_pos_i (ip_set_pos),
      .jog_i     (ip_jog),
      .jog_neg_i (ip_jog_neg),
      .pos_o     (ip_pos),
      .busy_o    (ip_busy),
      .underrun_o(ip_underrun),
      .ovf_o     (ip_ovf),
      .seg_cnt_o (ip_seg_cnt)
  );

  // ---------------------------------------------------------------------
  // Feedback: one decoder per axis, velocity sampled at the PID tick.
  wire pid_tick;
  genvar g;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_enc
      /* verilator lint_off PINCONNECTEMPTY */
      quad_decoder #(
          .FILT_W  (FILT_W),
          .ERR_W   (8),
          .VEL_W   (32),
          .IDX_RAM (IDX_RAM),
          .POS_LOAD(0)
      ) u_dec (
          .clk           (clk),
          .rst           (rst),
          .filt_len_i    (enc_filt[g*FILT_W+:FILT_W]),
          .dir_inv_i     (enc_dir_inv[g]),
          .idx_clr_en_i  (enc_idx_clr_en[g]),
          .pos_load_i    (1'b0),
          .pos_load_val_i(32'd0),
          .idx_arm_i     (enc_idx_arm[g]),
          .idx_disarm_i  (enc_idx_disarm[g]),
          .err_clr_i     (enc_err_clr[g]),
          .sample_i      (pid_tick),
          .enc_a_i       (enc_a[g]),
          .enc_b_i       (enc_b[g]),
          .enc_z_i       (enc_z[g]),
          .latch_i       (enc_latch[g]),
          .pos_o         (pos[g*32+:32]),
          .idx_pos_o     (enc_idx_pos[g*32+:32]),
          .idx_armed_o   (enc_idx_armed[g]),
          .idx_seen_o    (enc_idx_seen[g]),
          .err_o         (enc_err[g]),
          .err_cnt_o     (enc_err_cnt[g*8+:8]),
          .vel_o         (enc_vel[g*32+:32]),
          .age_o         (),
          .a_o           (),
          .b_o           (),
          .z_o           ()
      );
      /* verilator lint_on PINCONNECTEMPTY */
    end
  endgenerate

  // ---------------------------------------------------------------------
  // The loops. pid_core's u_o is unused: the drive takes u from the sample
  // stream, and synthesis trims u_o's flip-flops.
  /* verilator lint_off UNUSEDSIGNAL */
  wire [NAXES*16-1:0] pid_u;
  /* verilator lint_on UNUSEDSIGNAL */
  wire [   NAXES-1:0] pid_sat;
  wire                pid_smp_we;
  /* verilator lint_off UNUSEDSIGNAL */
  wire [         3:0] pid_smp_ax;
  /* verilator lint_on UNUSEDSIGNAL */
  wire [         2:0] pid_smp_fld;
  wire [        31:0] pid_smp_wd;
  /* verilator lint_off PINCONNECTEMPTY */
  pid_core #(
      .NAXES(NAXES),
      .SERVO(SERVO)
  ) u_pid (
      .clk       (clk),
      .rst       (rst),
      .cfg_we    (pid_we),
      .cfg_waddr (pid_waddr),
      .cfg_wdata (pid_wdata),
      .cfg_wready(pid_wready),
      .cfg_re    (pid_re),
      .cfg_raddr (pid_raddr),
      .cfg_rready(pid_rready),
      .cfg_rvalid(pid_rvalid),
      .cfg_rdata (pid_rdata),
      .cmd_i     (cmd),
      .fb_i      (pos),
      .u_o       (pid_u),
      .err_o     (),
      .sat_o     (pid_sat),
      .en_o      (pid_en),
      .smp_we_o  (pid_smp_we),
      .smp_ax_o  (pid_smp_ax),
      .smp_fld_o (pid_smp_fld),
      .smp_wd_o  (pid_smp_wd),
      .tick_o    (pid_tick),
      .done_o    (done),
      .busy_o    ()
  );
  /* verilator lint_on PINCONNECTEMPTY */
  assign tick = pid_tick;

  // The sample RAM: bank ~pb is written by the sweep, bank pb is read. pb is
  // not reset: a reset in the middle of a sweep must not publish the bank it
  // was writing (the next sweep rewrites all of it before done).
  (* no_rw_check *)
  reg [31:0] smp_ram[0:63];
  reg pb;
  integer si, a;
  initial begin
    for (si = 0; si < 64; si = si + 1) smp_ram[si] = 32'd0;
    pb = 1'b0;
  end
  always @(posedge clk) begin
    if (pid_smp_we) smp_ram[{~pb, pid_smp_ax[1:0], pid_smp_fld}] <= pid_smp_wd;
    smp_rdata <= smp_ram[{pb, smp_raddr}];
  end
  always @(posedge clk) begin
    if (done && !rst) pb <= ~pb;
  end

  // The drive takes each axis's u from the stream into the sample RAM (the
  // OUT word), so it needs no copy of pid_core's outputs. An overridden
  // axis's drv_cmd is the host's instead: one register either way.
  always @(posedge clk) begin
    if (rst) begin
      drv_cmd <= {NAXES * 16{1'b0}};
      smp_sat <= {NAXES{1'b0}};
    end else begin
      for (a = 0; a < NAXES; a = a + 1) begin
        if (drv_ovr_we[a]) drv_cmd[a*16+:16] <= drv_ovr_val;
        else if (pid_smp_we && pid_smp_fld == 3'd3 && pid_smp_ax == a[3:0] && !drv_ovr[a])
          drv_cmd[a*16+:16] <= pid_smp_wd[15:0];
      end
      if (done) smp_sat <= pid_sat;
    end
  end

  // ---------------------------------------------------------------------
  // Drive: value select, then PWM. Registered so the pins are glitch-free
  // and a safety drop takes effect in one clock.
  reg [PWM_BITS-1:0] pcnt;
  always @(posedge clk) begin
    if (rst) pcnt <= {PWM_BITS{1'b0}};
    else pcnt <= pcnt + 1'b1;
  end

  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_drv
      // The safety gate acts on the pins, after the magnitude: the same
      // result as gating the value, without a LUT per value bit.
      wire        [15:0] u_cmd = drv_cmd[g*16+:16];
      wire signed [15:0] u_sel = ~drv_allow[g] ? 16'sd0 : u_cmd;
      // |u| fits 16 bits unsigned even for -32768, which is full scale.
      wire        [15:0] u_mag = u_cmd[15] ? 16'd0 - u_cmd : u_cmd;
      wire        [15:0] duty = u_mag >> (15 - PWM_BITS);
      wire        [15:0] pcnt_w = {{(16 - PWM_BITS) {1'b0}}, pcnt};
      assign drv_sel[g*16+:16] = u_sel;
      always @(posedge clk) begin
        if (rst) begin
          drv_u[g*16+:16] <= 16'd0;
          pwm_o[g]        <= 1'b0;
          dir_o[g]        <= 1'b0;
          drv_en_o[g]     <= 1'b0;
        end else begin
          drv_u[g*16+:16] <= u_sel;
          pwm_o[g]        <= drv_allow[g] & (duty > pcnt_w);
          dir_o[g]        <= drv_allow[g] & u_cmd[15];
          drv_en_o[g]     <= drv_allow[g] & (pid_en[g] | drv_ovr[g]);
        end
      end
    end
  endgenerate

endmodule

`default_nettype wire
