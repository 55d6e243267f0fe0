// mc_board: the portable board core: motion_core plus the link (UART,
// framed protocol, register file), the safety logic, a handwheel decoder,
// the machine I/O (mc_io: probe and home latches, spindle, coolant,
// handwheel jog), the stepper axes (mc_step) and the status LEDs. The pins reach it through the board top
// (rtl/motioncore_icebreaker.v), which synchronizes every input but the
// encoders (the decoders synchronize those) and makes the reset.
//
// How to use it: connect the host's UART to rx_i/tx_o at BAUD and speak
// docs/protocol.md. The drives stay off (drv_en_o, pwm_o low) until the host
// arms them (CTRL.arm) and fall off at once on any fault (FAULT register);
// while disarmed the interpolator holds its feed. led_ok_o is on while
// armed and blinks while disarmed without a fault; led_fault_o is on while a
// fault is latched.
`default_nettype none

module mc_board #(
    parameter integer NAXES    = 3,           // axes (1..3)
    parameter integer FIFO_AW  = 9,           // segment queue, log2 words
    parameter integer PWM_BITS = 9,           // PWM period 2^PWM_BITS clocks
    parameter integer FILT_W   = 4,           // encoder filter length bits: up to 15 clocks (1.25 us)
    parameter integer CLK_HZ   = 12_000_000,  // clock, Hz
    parameter integer BAUD     = 1_000_000,   // UART rate, bit/s
    parameter integer HANDWHEEL = 1,          // 1: build the handwheel decoder, 0: HW_POS reads 0
    parameter integer STEPPERS  = 0,          // axes that can be steppers (bit a: axis a; mc_step)
    parameter integer SERVO     = 1           // 1: the PID loops (servo axes); 0: none, a stepper-only board
) (
    // clock and reset
    input  wire             clk,
    input  wire             rst,
    // host link (rx_i synchronized)
    input  wire             rx_i,
    output wire             tx_o,
    // encoders and handwheel (asynchronous)
    input  wire [NAXES-1:0] enc_a_i,
    input  wire [NAXES-1:0] enc_b_i,
    input  wire [NAXES-1:0] enc_z_i,
    input  wire             hw_a_i,
    input  wire             hw_b_i,
    // switches (synchronized)
    input  wire [NAXES-1:0] lim_i,
    input  wire             estop_i,
    input  wire             stop_i,
    input  wire             probe_i,
    // H-bridges, or step/dir for stepper axes
    output wire [NAXES-1:0] pwm_o,
    output wire [NAXES-1:0] dir_o,
    output wire [NAXES-1:0] drv_en_o,
    // spindle and coolant
    output wire             sp_pwm_o,
    output wire             sp_en_o,
    output wire             sp_dir_o,
    output wire             flood_o,
    output wire             mist_o,
    // LEDs, active high
    output wire             led_ok_o,
    output wire             led_fault_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  // ---------------------------------------------------------------------
  // Link: UART, frame parser, frame sender.
  wire [7:0] rx_byte, tx_byte;
  wire rx_valid, rx_ferr, tx_valid, tx_ready;
  uart_rx #(
      .CLK_HZ(CLK_HZ),
      .BAUD  (BAUD)
  ) u_urx (
      .clk    (clk),
      .rst    (rst),
      .rx_i   (rx_i),
      .data_o (rx_byte),
      .valid_o(rx_valid),
      .ferr_o (rx_ferr)
  );
  uart_tx #(
      .CLK_HZ(CLK_HZ),
      .BAUD  (BAUD)
  ) u_utx (
      .clk    (clk),
      .rst    (rst),
      .data_i (tx_byte),
      .valid_i(tx_valid),
      .ready_o(tx_ready),
      .tx_o   (tx_o)
  );

  wire       frame, crc_err, framing, junk;
  wire [7:0] f_seq, f_cmd, f_len, pay_raddr, pay_rdata;
  link_rx #(
      .CLK_HZ(CLK_HZ)
  ) u_lrx (
      .clk        (clk),
      .rst        (rst),
      .byte_i     (rx_byte),
      .valid_i    (rx_valid),
      .ferr_i     (rx_ferr),
      .frame_o    (frame),
      .seq_o      (f_seq),
      .cmd_o      (f_cmd),
      .len_o      (f_len),
      .pay_raddr_i(pay_raddr),
      .pay_rdata_o(pay_rdata),
      .crc_err_o  (crc_err),
      .framing_o  (framing),
      .junk_o     (junk)
  );

  wire        tx_we, tx_start, tx_status_en, tx_busy;
  wire [ 3:0] tx_waddr, tx_wbase, tx_nwords;
  wire [31:0] tx_wdata;
  wire [ 7:0] tx_seq, tx_cmd, tx_status;
  link_tx u_ltx (
      .clk        (clk),
      .rst        (rst),
      .we_i       (tx_we),
      .waddr_i    (tx_waddr),
      .wdata_i    (tx_wdata),
      .start_i    (tx_start),
      .seq_i      (tx_seq),
      .cmd_i      (tx_cmd),
      .status_en_i(tx_status_en),
      .status_i   (tx_status),
      .wbase_i    (tx_wbase),
      .nwords_i   (tx_nwords),
      .busy_o     (tx_busy),
      .byte_o     (tx_byte),
      .valid_o    (tx_valid),
      .ready_i    (tx_ready)
  );

  // ---------------------------------------------------------------------
  // Register file, safety, datapath.
  wire                    kick, arm_set, arm_clr, armed, estop_act;
  wire [            15:0] fclr, fault;
  wire [             7:0] safety;
  wire [            23:0] wdog;
  wire [       NAXES-1:0] ferr, lim_act, allow;
  wire                    pid_we, pid_wready, pid_re, pid_rready, pid_rvalid;
  wire [             7:0] pid_waddr, pid_raddr;
  wire [            31:0] pid_wdata, pid_rdata, seg_wdata;
  wire                    seg_wr, ip_abort, ip_hold, ip_clr, ip_busy, ip_underrun, ip_ovf;
  wire [             2:0] ip_set;
  wire [       FIFO_AW:0] seg_count;
  wire [            31:0] ip_set_val;
  wire [            15:0] ip_seg_cnt;
  wire [NAXES*FILT_W-1:0] enc_filt;
  wire [       NAXES-1:0] enc_dir_inv, enc_idx_clr_en, enc_idx_arm, enc_idx_disarm, enc_err_clr;
  wire [       NAXES-1:0] enc_err, enc_idx_armed, enc_idx_seen;
  wire [    NAXES*32-1:0] enc_idx_pos;
  wire [     NAXES*8-1:0] enc_err_cnt;
  wire [    NAXES*16-1:0] drv_sel;
  wire [            15:0] drv_ovr_val;
  wire [       NAXES-1:0] drv_ovr, drv_ovr_we, pid_en;
  wire [             4:0] smp_raddr;
  wire [            31:0] smp_rdata;
  wire                    done;
  wire [      FILT_W-1:0] hw_filt;
  wire                    hw_dir_inv;
  wire [            31:0] hw_pos;
  wire                    bus_we;
  wire [             4:0] bus_addr;
  wire [            31:0] bus_wdata, io_stat_io, io_stat;
  wire [       NAXES-1:0] step_ferr, step_err, stepper, io_latch;
  wire                    io_stop, ip_jog_neg;
  wire [             2:0] ip_jog;
  wire [       NAXES-1:0] core_pwm, core_dir, core_en, enc_a_c, enc_b_c;

  mc_regs #(
      .NAXES  (NAXES),
      .FIFO_AW(FIFO_AW),
      .FILT_W (FILT_W),
      .CLK_HZ (CLK_HZ),
      .BAUD   (BAUD),
      .STEPPERS (STEPPERS),
      .SERVO    (SERVO),
      .HANDWHEEL(HANDWHEEL)
  ) u_regs (
      .clk               (clk),
      .rst               (rst),
      .frame_i           (frame),
      .seq_i             (f_seq),
      .cmd_i             (f_cmd),
      .len_i             (f_len),
      .pay_raddr_o       (pay_raddr),
      .pay_rdata_i       (pay_rdata),
      .crc_err_i         (crc_err),
      .framing_i         (framing),
      .junk_i            (junk),
      .tx_we_o           (tx_we),
      .tx_waddr_o        (tx_waddr),
      .tx_wdata_o        (tx_wdata),
      .tx_start_o        (tx_start),
      .tx_seq_o          (tx_seq),
      .tx_cmd_o          (tx_cmd),
      .tx_status_en_o    (tx_status_en),
      .tx_status_o       (tx_status),
      .tx_wbase_o        (tx_wbase),
      .tx_nwords_o       (tx_nwords),
      .tx_busy_i         (tx_busy),
      .kick_o            (kick),
      .arm_set_o         (arm_set),
      .arm_clr_o         (arm_clr),
      .fclr_o            (fclr),
      .safety_o          (safety),
      .wdog_o            (wdog),
      .ferr_o            (ferr),
      .fault_i           (fault),
      .armed_i           (armed),
      .estop_act_i       (estop_act),
      .lim_act_i         (lim_act),
      .pid_we_o          (pid_we),
      .pid_waddr_o       (pid_waddr),
      .pid_wdata_o       (pid_wdata),
      .pid_wready_i      (pid_wready),
      .pid_re_o          (pid_re),
      .pid_raddr_o       (pid_raddr),
      .pid_rready_i      (pid_rready),
      .pid_rvalid_i      (pid_rvalid),
      .pid_rdata_i       (pid_rdata),
      .seg_wr_o          (seg_wr),
      .seg_wdata_o       (seg_wdata),
      .seg_count_i       (seg_count),
      .ip_abort_o        (ip_abort),
      .ip_hold_o         (ip_hold),
      .ip_clr_o          (ip_clr),
      .ip_set_o          (ip_set),
      .ip_set_val_o      (ip_set_val),
      .ip_busy_i         (ip_busy),
      .ip_underrun_i     (ip_underrun),
      .ip_ovf_i          (ip_ovf),
      .ip_seg_cnt_i      (ip_seg_cnt),
      .enc_filt_o        (enc_filt),
      .enc_dir_inv_o     (enc_dir_inv),
      .enc_idx_clr_en_o  (enc_idx_clr_en),
      .enc_idx_arm_o     (enc_idx_arm),
      .enc_idx_disarm_o  (enc_idx_disarm),
      .enc_err_clr_o     (enc_err_clr),
      .enc_err_i         (enc_err),
      .enc_err_cnt_i     (enc_err_cnt),
      .enc_idx_pos_i     (enc_idx_pos),
      .enc_idx_armed_i   (enc_idx_armed),
      .enc_idx_seen_i    (enc_idx_seen),
      .drv_ovr_o         (drv_ovr),
      .drv_ovr_we_o      (drv_ovr_we),
      .drv_ovr_val_o     (drv_ovr_val),
      .drv_en_i          (drv_en_o),
      .drv_sel_i         (drv_sel),
      .done_i            (done),
      .smp_raddr_o       (smp_raddr),
      .smp_rdata_i       (smp_rdata),
      .pid_en_i          (pid_en),
      .hw_filt_o         (hw_filt),
      .hw_dir_inv_o      (hw_dir_inv),
      .hw_pos_i          (hw_pos),
      .bus_we_o          (bus_we),
      .bus_addr_o        (bus_addr),
      .bus_wdata_o       (bus_wdata),
      .io_stat_i         (io_stat)
  );

  mc_safety #(
      .NAXES(NAXES)
  ) u_safety (
      .clk        (clk),
      .rst        (rst),
      .arm_set_i  (arm_set),
      .arm_clr_i  (arm_clr),
      .clr_i      (fclr),
      .cfg_i      (safety),
      .wdog_i     (wdog),
      .kick_i     (kick),
      .estop_i    (estop_i),
      .stop_i     (stop_i),
      .lim_i      (lim_i),
      .ferr_i     (ferr | step_ferr),
      .enc_err_i  (enc_err),
      .fault_o    (fault),
      .armed_o    (armed),
      .allow_o    (allow),
      .estop_act_o(estop_act),
      .lim_act_o  (lim_act)
  );

  // Unused datapath outputs: synthesis removes the logic behind them (the
  // decoders' velocity, the live positions; the link reads the sampled ones;
  // the registered drive value, as the register file registers drv_sel; the
  // sample's outputs, which the register file reads from the sample RAM).
  /* verilator lint_off UNUSEDSIGNAL */
  wire                tick;
  wire [NAXES*32-1:0] enc_vel, pos_live, cmd_live;
  wire [NAXES*16-1:0] drv_u, drv_cmd;
  wire [   NAXES-1:0] smp_sat;
  /* verilator lint_on UNUSEDSIGNAL */
  motion_core #(
      .NAXES   (NAXES),
      .FIFO_AW (FIFO_AW),
      .PWM_BITS(PWM_BITS),
      .FILT_W  (FILT_W),
      .IDX_RAM (1),  // 96 flip-flops fewer for three axes
      .SERVO   (SERVO)
  ) u_core (
      .clk             (clk),
      .rst             (rst),
      .pid_we          (pid_we),
      .pid_waddr       (pid_waddr),
      .pid_wdata       (pid_wdata),
      .pid_wready      (pid_wready),
      .pid_re          (pid_re),
      .pid_raddr       (pid_raddr),
      .pid_rready      (pid_rready),
      .pid_rvalid      (pid_rvalid),
      .pid_rdata       (pid_rdata),
      .seg_wr          (seg_wr),
      .seg_wdata       (seg_wdata),
      .seg_count       (seg_count),
      .ip_abort        (ip_abort | io_stop),
      .ip_hold         (ip_hold | ~armed),
      .ip_clr          (ip_clr),
      .ip_set          (ip_set),
      .ip_set_pos      ({3{ip_set_val}}),  // one value, an axis at a time
      .ip_jog          (ip_jog),
      .ip_jog_neg      (ip_jog_neg),
      .ip_busy         (ip_busy),
      .ip_underrun     (ip_underrun),
      .ip_ovf          (ip_ovf),
      .ip_seg_cnt      (ip_seg_cnt),
      .enc_a           (enc_a_c),
      .enc_b           (enc_b_c),
      .enc_z           (enc_z_i),
      .enc_latch       (io_latch),
      .enc_filt        (enc_filt),
      .enc_dir_inv     (enc_dir_inv),
      .enc_idx_clr_en  (enc_idx_clr_en),
      .enc_idx_arm     (enc_idx_arm),
      .enc_idx_disarm  (enc_idx_disarm),
      .enc_err_clr     (enc_err_clr),
      .enc_err         (enc_err),
      .enc_err_cnt     (enc_err_cnt),
      .enc_idx_pos     (enc_idx_pos),
      .enc_idx_armed   (enc_idx_armed),
      .enc_idx_seen    (enc_idx_seen),
      .enc_vel         (enc_vel),
      .drv_allow       (allow),
      .drv_ovr         (drv_ovr),
      .drv_ovr_we      (drv_ovr_we),
      .drv_ovr_val     (drv_ovr_val),
      .pwm_o           (core_pwm),
      .dir_o           (core_dir),
      .drv_en_o        (core_en),
      .drv_u           (drv_u),
      .drv_sel         (drv_sel),
      .tick            (tick),
      .done            (done),
      .smp_raddr       (smp_raddr),
      .smp_rdata       (smp_rdata),
      .drv_cmd         (drv_cmd),
      .smp_sat         (smp_sat),
      .pid_en          (pid_en),
      .pos             (pos_live),
      .cmd             (cmd_live)
  );

  // ---------------------------------------------------------------------
  // Machine I/O and stepper axes, on the register file's write bus.
  mc_io #(
      .NAXES(NAXES)
  ) u_io (
      .clk        (clk),
      .rst        (rst),
      .bus_we_i   (bus_we),
      .bus_addr_i (bus_addr),
      .bus_wdata_i(bus_wdata),
      .stat_o     (io_stat_io),
      .armed_i    (armed),
      .lim_inv_i  (safety[B_S_LIM_INV_LSB+:NAXES]),
      .lim_i      (lim_i),
      .probe_i    (probe_i),
      .idx_armed_i(enc_idx_armed),
      .latch_o    (io_latch),
      .stop_o     (io_stop),
      .ip_idle_i  (~ip_busy & (seg_count == {(FIFO_AW + 1) {1'b0}})),
      .jog_o      (ip_jog),
      .jog_neg_o  (ip_jog_neg),
      .hw_pos_i   (hw_pos[7:0]),
      .sp_pwm_o   (sp_pwm_o),
      .sp_en_o    (sp_en_o),
      .sp_dir_o   (sp_dir_o),
      .flood_o    (flood_o),
      .mist_o     (mist_o)
  );

  // The command's two low bits per axis, for the step generators.
  wire [NAXES*2-1:0] cmd_lo;
  genvar g;
  generate
    for (g = 0; g < NAXES; g = g + 1) begin : g_cmd
      assign cmd_lo[g*2+:2] = cmd_live[g*32+:2];
    end
  endgenerate
  mc_step #(
      .NAXES   (NAXES),
      .STEPPERS(STEPPERS)
  ) u_step (
      .clk        (clk),
      .rst        (rst),
      .bus_we_i   (bus_we),
      .bus_addr_i (bus_addr),
      .bus_wdata_i(bus_wdata),
      .cmd_i      (cmd_lo),
      .sync_i     (ip_set[NAXES-1:0]),
      .allow_i    (armed),
      .clr_i      (fclr[B_F_FERR_LSB+:NAXES]),
      .pwm_i      (core_pwm),
      .dir_i      (core_dir),
      .enc_a_i    (enc_a_i),
      .enc_b_i    (enc_b_i),
      .pwm_o      (pwm_o),
      .dir_o      (dir_o),
      .enc_a_o    (enc_a_c),
      .enc_b_o    (enc_b_c),
      .stepper_o  (stepper),
      .err_o      (step_err),
      .ferr_o     (step_ferr)
  );
  // A stepper axis's driver is enabled while the drives are armed.
  assign drv_en_o = core_en | ({NAXES{armed}} & stepper);
  reg [31:0] io_stat_w;
  always @(*) begin
    io_stat_w = io_stat_io;
    io_stat_w[B_IOS_STEP_ERR_LSB+:NAXES] = step_err;
  end
  assign io_stat = io_stat_w;

  // Handwheel: a decoder of its own, position only (the rest is trimmed).
  generate
    if (HANDWHEEL != 0) begin : g_hw
  /* verilator lint_off PINCONNECTEMPTY */
  quad_decoder #(
      .FILT_W  (FILT_W),
      .ERR_W   (2),
      .VEL_W   (2),
      .AGE_W   (2),
      .POS_LOAD(0)
  ) u_hw (
      .clk           (clk),
      .rst           (rst),
      .filt_len_i    (hw_filt),
      .dir_inv_i     (hw_dir_inv),
      .idx_clr_en_i  (1'b0),
      .pos_load_i    (1'b0),
      .pos_load_val_i(32'd0),
      .idx_arm_i     (1'b0),
      .idx_disarm_i  (1'b0),
      .err_clr_i     (1'b0),
      .sample_i      (1'b0),
      .enc_a_i       (hw_a_i),
      .enc_b_i       (hw_b_i),
      .enc_z_i       (1'b0),
      .latch_i       (1'b0),
      .pos_o         (hw_pos),
      .idx_pos_o     (),
      .idx_armed_o   (),
      .idx_seen_o    (),
      .err_o         (),
      .err_cnt_o     (),
      .vel_o         (),
      .age_o         (),
      .a_o           (),
      .b_o           (),
      .z_o           ()
  );
  /* verilator lint_on PINCONNECTEMPTY */
    end else begin : g_no_hw
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused_hw = &{hw_a_i, hw_b_i, hw_filt, hw_dir_inv};
      /* verilator lint_on UNUSEDSIGNAL */
      assign hw_pos = 32'd0;
    end
  endgenerate

  // LEDs: a heartbeat of about 1 Hz while disarmed shows the design runs.
  localparam integer HB_W = $clog2(CLK_HZ);
  reg [HB_W-1:0] hb;
  always @(posedge clk) begin
    if (rst) hb <= {HB_W{1'b0}};
    else hb <= hb + 1'b1;
  end
  assign led_fault_o = |fault;
  assign led_ok_o    = armed | (~led_fault_o & hb[HB_W-1]);

endmodule

`default_nettype wire
