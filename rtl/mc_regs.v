// mc_regs: the board's register file and command executor, between the link
// (link_rx, link_tx) and the datapath (motion_core). Register map and
// protocol: rtl/board_regs.vh, generated from hls/board_regs.hpp;
// docs/protocol.md is the spec.
//
// How it works:
// - link_rx pulses frame_i for a frame with a good CRC. If the previous
//   command or its reply is still in progress the frame is dropped and
//   counted as a framing error (the host waits for each reply). Otherwise the
//   command is checked (length, register, sequence number, queue room) and
//   either refused with a status, or applied once; the reply (status, value)
//   then goes out through link_tx.
// - A frame with the SEQ of the last applied one is not applied again; it is
//   answered with ST_DUP (a read is answered with the value as it is now).
//   A segment frame refused FULL counts as the last one too, and its copies
//   are refused FULL without a second look at the queue: every copy of a
//   frame gets the answer the first copy got, so a late reply to any copy
//   tells the host the truth. PING forgets the last SEQ.
// - After every PID sample (done_i) a walker reads TLM_HDR and each axis's
//   POS, CMD, ERR, OUT and FOLLOW through the read path. It checks each
//   axis's following error |FOLLOW| against FERR (strobing ferr_o), and every
//   TLM.decim-th sample it also copies the words of the axes in TLM.axes into
//   link_tx's RAM and sends them as a telemetry frame, unless the previous
//   one is still being sent (the sample count in TLM_HDR then shows the gap).
// - Registers that read back what was written (RW in the table) are read
//   from a shadow block RAM written with every register write, so their
//   read-back costs no multiplexer, and so are the constants (ID, INFO,
//   CLK_HZ, BAUD); live values go through the multiplexer.
//   The shadow RAM holds the reset values from configuration on.
// - The link counters (LINK_CRC, LINK_CMD, LINK_JUNK) live in the shadow RAM
//   too: an event marks its counter pending, and a read-modify-write of the
//   word adds it when the RAM's ports are free (within about 40 clocks: the
//   walker's reads, the other counters, one retry; events of one counter are
//   a byte time, 120 clocks, apart or more). Being block
//   RAM, they count from configuration: reset does not clear them.
`default_nettype none

module mc_regs #(
    parameter integer NAXES   = 3,           // axes (1..3)
    parameter integer FIFO_AW = 9,           // interpolator queue, log2 words
    parameter integer FILT_W  = 8,           // encoder filter length bits (the field is 8; longer values clamp)
    parameter integer CLK_HZ  = 12_000_000,  // clock, Hz
    parameter integer BAUD    = 1_000_000,   // UART rate, bit/s
    // What the board was built with, for INFO only
    parameter integer STEPPERS  = 0,  // axes with a step generator, bit a for axis a
    parameter integer SERVO     = 1,  // the PID loops are built
    parameter integer HANDWHEEL = 1   // the handwheel decoder is built
) (
    // clock and reset
    input  wire                    clk,
    input  wire                    rst,
    // frames from link_rx
    input  wire                    frame_i,
    input  wire [             7:0] seq_i,
    input  wire [             7:0] cmd_i,
    input  wire [             7:0] len_i,
    output wire [             7:0] pay_raddr_o,
    input  wire [             7:0] pay_rdata_i,
    input  wire                    crc_err_i,
    input  wire                    framing_i,
    input  wire                    junk_i,
    // frames to link_tx
    output wire                    tx_we_o,
    output wire [             3:0] tx_waddr_o,
    output wire [            31:0] tx_wdata_o,
    output reg                     tx_start_o,
    output reg  [             7:0] tx_seq_o,
    output reg  [             7:0] tx_cmd_o,
    output reg                     tx_status_en_o,
    output reg  [             7:0] tx_status_o,
    output reg  [             3:0] tx_wbase_o,
    output reg  [             3:0] tx_nwords_o,
    input  wire                    tx_busy_i,
    // safety (mc_safety)
    output wire                    kick_o,
    output reg                     arm_set_o,
    output reg                     arm_clr_o,
    output reg  [            15:0] fclr_o,
    output reg  [             7:0] safety_o,
    output reg  [            23:0] wdog_o,
    output reg  [       NAXES-1:0] ferr_o,
    input  wire [            15:0] fault_i,
    input  wire                    armed_i,
    input  wire                    estop_act_i,
    input  wire [       NAXES-1:0] lim_act_i,
    // motion_core: PID configuration port
    output wire                    pid_we_o,
    output wire [             7:0] pid_waddr_o,
    output wire [            31:0] pid_wdata_o,
    input  wire                    pid_wready_i,
    output wire                    pid_re_o,
    output wire [             7:0] pid_raddr_o,
    input  wire                    pid_rready_i,
    input  wire                    pid_rvalid_i,
    input  wire [            31:0] pid_rdata_i,
    // motion_core: interpolator
    output reg                     seg_wr_o,
    output wire [            31:0] seg_wdata_o,
    input  wire [       FIFO_AW:0] seg_count_i,
    output reg                     ip_abort_o,
    output reg                     ip_hold_o,
    output reg                     ip_clr_o,
    output wire [             2:0] ip_set_o,      // per axis, one clock each, x then y then z
    output wire [            31:0] ip_set_val_o,  // the position for the axis ip_set_o names
    input  wire                    ip_busy_i,
    input  wire                    ip_underrun_i,
    input  wire                    ip_ovf_i,
    input  wire [            15:0] ip_seg_cnt_i,
    // motion_core: encoders
    output reg  [NAXES*FILT_W-1:0] enc_filt_o,
    output reg  [       NAXES-1:0] enc_dir_inv_o,
    output reg  [       NAXES-1:0] enc_idx_clr_en_o,
    output reg  [       NAXES-1:0] enc_idx_arm_o,
    output reg  [       NAXES-1:0] enc_idx_disarm_o,
    output reg  [       NAXES-1:0] enc_err_clr_o,
    input  wire [       NAXES-1:0] enc_err_i,
    input  wire [     NAXES*8-1:0] enc_err_cnt_i,
    input  wire [    NAXES*32-1:0] enc_idx_pos_i,
    input  wire [       NAXES-1:0] enc_idx_armed_i,
    input  wire [       NAXES-1:0] enc_idx_seen_i,
    // motion_core: drives
    output reg  [       NAXES-1:0] drv_ovr_o,
    output reg  [       NAXES-1:0] drv_ovr_we_o,   // a DRV write with the override bit: load the value
    output wire [            15:0] drv_ovr_val_o,
    input  wire [       NAXES-1:0] drv_en_i,
    input  wire [    NAXES*16-1:0] drv_sel_i,  // registered here (q): the value the pins show
    // motion_core: per-sample values
    input  wire                    done_i,
    output wire [             4:0] smp_raddr_o,  // motion_core's sample RAM: {axis, field}
    input  wire [            31:0] smp_rdata_i,
    input  wire [       NAXES-1:0] pid_en_i,
    // handwheel decoder
    output reg  [      FILT_W-1:0] hw_filt_o,
    output reg                     hw_dir_inv_o,
    input  wire [            31:0] hw_pos_i,
    // register write bus of the I/O blocks (mc_io, mc_step): global
    // registers they decode themselves, written in the executor's apply clock
    output wire                    bus_we_o,
    output wire [             4:0] bus_addr_o,
    output wire [            31:0] bus_wdata_o,
    input  wire [            31:0] io_stat_i
);

  /* verilator lint_off UNUSEDPARAM */
`include "board_regs.vh"
  /* verilator lint_on UNUSEDPARAM */

  initial begin
    if (NAXES < 1 || NAXES > 3) $error("mc_regs: NAXES must be 1..3");
    if (FIFO_AW < 6 || FIFO_AW > 12) $error("mc_regs: FIFO_AW must be 6..12 (a frame of segments fits)");
    if (FILT_W < 1 || FILT_W > 8) $error("mc_regs: FILT_W must be 1..8");
  end

  /* verilator lint_off WIDTH */
  localparam [3:0] NAXES4 = NAXES;
  localparam [3:0] FIFO_AW4 = FIFO_AW;
  localparam [2:0] STEPPERS3 = STEPPERS & ((1 << NAXES) - 1);
  localparam [0:0] SERVO1 = (SERVO != 0);
  localparam [0:0] HANDWHEEL1 = (HANDWHEEL != 0);
  localparam [31:0] CLK32 = CLK_HZ;
  localparam [31:0] BAUD32 = BAUD;
  localparam [23:0] WDOG_RESET = CLK_HZ / 10;  // wdog_default() of hls/board_regs.hpp
  localparam [FIFO_AW+1:0] DEPTH = 1 << FIFO_AW;
  /* verilator lint_on WIDTH */

  // ---------------------------------------------------------------------
  // Link drop counters (16 bits, saturating), in the shadow RAM: which
  // counters have an event not yet added. Counter c is the half c[0] of
  // the word LINK_CRC + c/2: crc, framing, NAK, duplicate, junk.
  reg drop_busy, cnt_nak_inc, cnt_dup_inc;
  wire [4:0] cnt_ev = {junk_i, cnt_dup_inc, cnt_nak_inc, framing_i | drop_busy, crc_err_i};
  assign kick_o = frame_i;

  // ---------------------------------------------------------------------
  // Read path: a registered multiplexer of live values (ra -> q, two clocks)
  // and the shadow RAM (sa -> sq, two clocks), shared by the command
  // executor and the walker; the walker has priority.
  // Only the bits that tell registers apart reach the multiplexer.
  /* verilator lint_off UNUSEDSIGNAL */
  reg  [15:0] ra;
  /* verilator lint_on UNUSEDSIGNAL */
  reg  [ 7:0] sa;
  reg  [31:0] q, sq;
  reg  [15:0] sample_cnt;
  wire [ 1:0] ra_ax = ra[5:4];
  wire [ 3:0] ra_off = ra[3:0];

  // Shadow RAM index of a register address: {per-axis, low seven bits}.
  /* verilator lint_off UNUSEDSIGNAL */
  function [7:0] sidx(input [15:0] a);
    sidx = {a[9], a[6:0]};
  endfunction
  /* verilator lint_on UNUSEDSIGNAL */

  (* no_rw_check *)
  reg [31:0] shadow[0:255];
  integer si;
  initial begin
    for (si = 0; si < 256; si = si + 1) shadow[si] = 32'd0;
    shadow[R_WDOG[7:0]]   = {8'd0, WDOG_RESET};
    shadow[R_SAFETY[7:0]] = B_SAFETY_DEFAULT;
    // The constants are read from here too (never written: not writable).
    shadow[R_ID[7:0]]     = B_ID_MAGIC | {24'd0, P_VERSION};
    shadow[R_INFO[7:0]]   = {11'd0, HANDWHEEL1, SERVO1, STEPPERS3, P_VERSION, FIFO_AW4, NAXES4};
    shadow[R_CLK_HZ[7:0]] = CLK32;
    shadow[R_BAUD[7:0]]   = BAUD32;
  end

  // Per-axis inputs padded to four axes, so the multiplexer indexes them
  // with the address's two axis bits (absent axes read 0; they are refused
  // before a read anyway).
  localparam integer PADN = 4 - NAXES;
  wire [127:0] p_idx = {{(PADN * 32) {1'b0}}, enc_idx_pos_i};
  wire [31:0] p_ecnt = {{(PADN * 8) {1'b0}}, enc_err_cnt_i};
  wire [63:0] p_du = {{(PADN * 16) {1'b0}}, drv_sel_i};
  wire [3:0] p_seen = {{PADN{1'b0}}, enc_idx_seen_i};
  wire [3:0] p_armd = {{PADN{1'b0}}, enc_idx_armed_i};
  wire [3:0] p_eerr = {{PADN{1'b0}}, enc_err_i};
  wire [3:0] p_den = {{PADN{1'b0}}, drv_en_i};
  wire [3:0] p_ovr = {{PADN{1'b0}}, drv_ovr_o};

  reg [31:0] live;
  always @(*) begin
    live  = 32'd0;
    if (ra[9]) begin
      case (ra_off)
        R_AX_IDX: live = p_idx[ra_ax*32+:32];
        R_AX_ENC_STAT: live = {13'd0, p_seen[ra_ax], p_armd[ra_ax], p_eerr[ra_ax], 8'd0, p_ecnt[ra_ax*8+:8]};
        // the sample RAM's OUT word has the rest (ORed in below)
        R_AX_OUT: live = {13'd0, p_den[ra_ax], 18'd0};
        R_AX_DRV: live = {15'd0, p_ovr[ra_ax], p_du[ra_ax*16+:16]};
        default:  live = 32'd0;
      endcase
    end else begin
      case (ra[4:0])
        R_STATUS[4:0]: begin
          live[B_ST_ARMED] = armed_i;
          live[B_ST_ESTOP_IN] = estop_act_i;
          live[B_ST_IP_BUSY] = ip_busy_i;
          live[B_ST_IP_UNDERRUN] = ip_underrun_i;
          live[B_ST_IP_OVF] = ip_ovf_i;
          live[B_ST_LIMIT_IN_LSB+:NAXES] = lim_act_i;
          live[B_ST_DRV_EN_LSB+:NAXES] = drv_en_i;
          live[B_ST_PID_EN_LSB+:NAXES] = pid_en_i;
        end
        R_FAULT[4:0]: live = {16'd0, fault_i};
        R_IP_STAT[4:0]: begin
          live[B_IS_COUNT_LSB+:FIFO_AW+1] = seg_count_i;
          live[B_IS_BUSY] = ip_busy_i;
          live[B_IS_UNDERRUN] = ip_underrun_i;
          live[B_IS_OVF] = ip_ovf_i;
        end
        R_IP_SEGS[4:0]: live = {16'd0, ip_seg_cnt_i};
        R_HW_POS[4:0]: live = hw_pos_i;
        R_TLM_HDR[4:0]: live = {fault_i, sample_cnt};
        R_IO_STAT[4:0]: live = io_stat_i;
        default: live = 32'd0;
      endcase
    end
  end
  always @(posedge clk) q <= live;

  // A sample's POS, CMD, ERR, OUT and FOLLOW come from motion_core's sample
  // RAM, which answers in the same two clocks as the multiplexer; the
  // multiplexer gives 0 for them but OUT's live drive-enable bit.
  reg  [2:0] ra_fld;
  reg        ra_smp, q_smp;
  always @(*) begin
    ra_smp = ra[9];
    case (ra_off)
      R_AX_CMD: ra_fld = 3'd0;
      R_AX_POS: ra_fld = 3'd1;
      R_AX_ERR: ra_fld = 3'd2;
      R_AX_OUT: ra_fld = 3'd3;
      R_AX_FOLLOW: ra_fld = 3'd4;
      default: begin
        ra_fld = 3'd7;
        ra_smp = 1'b0;
      end
    endcase
  end
  assign smp_raddr_o = {ra_ax, ra_fld};
  always @(posedge clk) q_smp <= ra_smp;
  wire [31:0] qv = q_smp ? (smp_rdata_i | q) : q;

  // ---------------------------------------------------------------------
  // Register decoding: does an address exist, take writes, read back from
  // the shadow RAM.
  reg [15:0] addr;
  reg [31:0] data;
  wire [3:0] p_ax = addr[7:4], p_rg = addr[3:0];
  wire       is_pid = addr[15:8] == 8'h00;
  wire       is_glb = addr[15:8] == R_ID[15:8] && addr[7:0] < R_GLOBAL_END[7:0];
  wire       is_ax = addr[15:8] == R_AXIS_BASE[15:8] && addr[7:6] == 2'b00 && {2'b00, addr[5:4]} < NAXES4 &&
                     addr[3:0] < R_AX_END;
  wire       pid_ok_r = (p_ax < NAXES4 && (p_rg < 4'd10 || p_rg == 4'hF)) || (p_ax == 4'hF && p_rg <= 4'd2);
  wire       pid_ok_w = (p_ax < NAXES4 && (p_rg < 4'd10 || p_rg == 4'hF)) || (p_ax == 4'hF && p_rg == 4'd0);
  wire       rd_ok = is_pid ? pid_ok_r : (is_glb | is_ax);
  wire       wr_ok = is_pid ? pid_ok_w : (is_glb ? R_GLOBAL_WMASK[addr[4:0]] : is_ax & R_AX_WMASK[addr[3:0]]);
  /* verilator lint_off WIDTH */
  localparam [31:0] CNT_SHADOW = (32'd1 << R_LINK_CRC[4:0]) | (32'd1 << R_LINK_CMD[4:0]) |
                                 (32'd1 << R_LINK_JUNK[4:0]) | (32'd1 << R_ID[4:0]) |
                                 (32'd1 << R_INFO[4:0]) | (32'd1 << R_CLK_HZ[4:0]) | (32'd1 << R_BAUD[4:0]);
  /* verilator lint_on WIDTH */
  localparam [31:0] GLB_SHADOW = R_GLOBAL_SHADOW | CNT_SHADOW;
  wire       rd_shadow = is_glb ? GLB_SHADOW[addr[4:0]] : R_AX_SHADOW[addr[3:0]];
  wire [1:0] a_ax = addr[5:4];

  // ---------------------------------------------------------------------
  // Command executor.
  localparam [3:0] X_IDLE = 4'd0, X_CHECK = 4'd1, X_FETCH = 4'd2, X_DECIDE = 4'd3, X_APPLY = 4'd4;
  localparam [3:0] X_PIDW = 4'd5, X_PIDR = 4'd6, X_PIDRW = 4'd7, X_RD = 4'd8, X_RD1 = 4'd9, X_RD2 = 4'd10;
  localparam [3:0] X_REPLY = 4'd11, X_SET = 4'd12;
  reg  [3:0] xs;
  reg  [7:0] f_seq, f_cmd, f_len, status;
  reg  [7:0] bi, rbi;  // payload byte read, byte arriving
  reg        rv;
  reg  [7:0] last_seq;
  reg        last_valid;
  reg        last_full;  // the frame of last_seq was refused FULL: so are its copies
  reg        rep_pend, rep_sending, tlm_pend, tlm_sending;
  reg        w_act;  // the walker is issuing reads
  wire       w_wr;  // the walker writes a telemetry word this clock
  reg        val_shadow;  // the reply value comes from sq, not q
  // val_direct: the reply value is data, the frame's own value (a write's
  // echo), or what replaced it: a PID register read, or 0 for a refusal.
  reg        val_direct;
  reg  [1:0] set_n;  // X_SET: the axis whose position is read next
  wire       rep_busy = rep_pend | rep_sending;
  wire       dup = last_valid && f_seq == last_seq;
  // A segment frame's room check is decided as the frame is taken (from the
  // link's length and the queue's count in that clock), not in X_CHECK: the
  // adder and compare in front of the executor's decisions were the board's
  // longest path. The queue only drains in between, so a frame refused FULL
  // here would at most have fitted by the segment finished in that clock.
  wire [FIFO_AW+1:0] room_need = {{(FIFO_AW - 4) {1'b0}}, len_i[7:2]} + {1'b0, seg_count_i};
  reg                seg_full;
  wire       seg_len_ok = f_len == 8'd40 || f_len == 8'd80 || f_len == 8'd120 || f_len == 8'd160 ||
                          f_len == 8'd200 || f_len == 8'd240;

  assign pay_raddr_o = bi;
  assign seg_wdata_o = data;
  assign pid_we_o    = xs == X_PIDW && !rst;  // no write from a powered-up state
  assign pid_waddr_o = addr[7:0];
  assign pid_wdata_o = data;
  assign pid_re_o    = xs == X_PIDR;
  assign pid_raddr_o = addr[7:0];

  // The filter-length field is 8 bits in the register map whatever the
  // decoders are built with: a longer value than FILT_W bits hold becomes
  // the longest filter, never a short one by truncation.
  wire [7:0] filt_field = data[B_E_FILT_LSB+:8];
  /* verilator lint_off WIDTH */
  wire [FILT_W-1:0] filt_len = (filt_field >> FILT_W) != 8'd0 ? {FILT_W{1'b1}} : filt_field[FILT_W-1:0];
  /* verilator lint_on WIDTH */
  assign drv_ovr_val_o = data[B_D_VAL_LSB+:16];

  // The same checks a clock early, for X_DECIDE: addr is complete in the
  // clock X_FETCH ends, and the decode chain into the executor's state was
  // the board's longest path.
  reg        d_ok, d_pid, d_shadow;
  always @(posedge clk) begin
    d_ok     <= f_cmd == P_CMD_READ ? rd_ok : wr_ok;
    d_pid    <= is_pid;
    d_shadow <= rd_shadow;
  end

  // The checks of a frame that need no payload.
  reg [7:0] chk;
  always @(*) begin
    chk = P_ST_OK;
    case (f_cmd)
      P_CMD_PING:  if (f_len != 8'd0) chk = P_ST_BAD_LEN;
      P_CMD_READ:  if (f_len != 8'd2) chk = P_ST_BAD_LEN;
      P_CMD_WRITE: if (f_len != 8'd6) chk = P_ST_BAD_LEN;
      P_CMD_SEG:
      if (!seg_len_ok) chk = P_ST_BAD_LEN;
      else if (dup) chk = last_full ? P_ST_FULL : P_ST_DUP;
      else if (seg_full) chk = P_ST_FULL;
      default:     chk = P_ST_BAD_CMD;
    endcase
  end

  // Register writes: the strobes pulse for one clock, in X_APPLY.
  wire apply = xs == X_APPLY;
  // The shadow RAM takes every applied write, never one during reset,
  // whatever state the executor powers up in.
  always @(posedge clk) begin
    if (!rst) begin
      if (apply) shadow[sidx(addr)] <= data;
      else if (cu2) shadow[cu_word(cu_c2[2:1])] <= cu_new;
    end
    sq <= shadow[sa];
  end

  // The counters' read-modify-write: a pending counter's word is read when
  // neither the walker nor the executor needs the read port (cu1 issued,
  // cu2 the word in sq), one at a time, and written back unless a register
  // write has the write port in that clock (then it is pending again).
  reg  [4:0] cnt_pend;
  reg        cu1, cu2;
  reg  [2:0] cu_c1, cu_c2;
  wire       cu_free = ~w_act & (xs != X_RD) & (xs != X_SET) & ~cu1 & ~cu2;
  reg  [2:0] cu_pick;
  always @(*) begin
    casez (cnt_pend)
      5'b????1: cu_pick = 3'd0;
      5'b???10: cu_pick = 3'd1;
      5'b??100: cu_pick = 3'd2;
      5'b?1000: cu_pick = 3'd3;
      default:  cu_pick = 3'd4;
    endcase
  end
  wire cu_go = cu_free & (|cnt_pend);
  function [7:0] cu_word(input [1:0] w);  // the counter's word: LINK_CRC + w
    /* verilator lint_off WIDTH */
    cu_word = sidx(R_LINK_CRC + w);
    /* verilator lint_on WIDTH */
  endfunction
  wire [15:0] cu_half = cu_c2[0] ? sq[31:16] : sq[15:0];
  wire [15:0] cu_inc = cu_half + {15'd0, ~&cu_half};
  wire [31:0] cu_new = cu_c2[0] ? {cu_inc, sq[15:0]} : {sq[31:16], cu_inc};
  always @(posedge clk) begin
    if (rst) begin
      cnt_pend <= 5'd0;
      cu1      <= 1'b0;
      cu2      <= 1'b0;
    end else begin
      cnt_pend <= (cnt_pend & ~({4'd0, cu_go} << cu_pick)) | cnt_ev | ({4'd0, cu2 & apply} << cu_c2);
      cu1      <= cu_go;
      cu2      <= cu1;
    end
    cu_c1 <= cu_pick;
    cu_c2 <= cu_c1;
  end
  wire w_glb = apply & is_glb;
  wire w_ax = apply & is_ax & ~is_pid;
  assign bus_we_o    = w_glb;
  assign bus_addr_o  = addr[4:0];
  assign bus_wdata_o = data;
  integer ax;
  always @(posedge clk) begin
    arm_set_o        <= 1'b0;
    arm_clr_o        <= 1'b0;
    fclr_o           <= 16'd0;
    ip_abort_o       <= 1'b0;
    ip_clr_o         <= 1'b0;
    enc_idx_arm_o    <= {NAXES{1'b0}};
    enc_idx_disarm_o <= {NAXES{1'b0}};
    enc_err_clr_o    <= {NAXES{1'b0}};
    drv_ovr_we_o     <= {NAXES{1'b0}};
    if (rst) begin
      ip_hold_o     <= 1'b0;
      wdog_o        <= WDOG_RESET;
      safety_o      <= B_SAFETY_DEFAULT[7:0];
      hw_filt_o     <= {FILT_W{1'b0}};
      hw_dir_inv_o  <= 1'b0;
      enc_filt_o    <= {NAXES * FILT_W{1'b0}};
      enc_dir_inv_o <= {NAXES{1'b0}};
      enc_idx_clr_en_o <= {NAXES{1'b0}};
      drv_ovr_o     <= {NAXES{1'b0}};
    end else begin
      if (w_glb) begin
        case (addr[4:0])
          R_FAULT[4:0]: begin
            fclr_o        <= data[15:0];
            enc_err_clr_o <= data[B_F_ENC_LSB+:NAXES];
          end
          R_CTRL[4:0]: begin
            arm_set_o <= data[B_C_ARM];
            arm_clr_o <= ~data[B_C_ARM];
            ip_hold_o <= data[B_C_IP_HOLD];
          end
          R_WDOG[4:0]: wdog_o <= data[23:0];
          R_SAFETY[4:0]: safety_o <= data[7:0];
          R_IP_CTRL[4:0]: begin
            ip_abort_o <= data[B_I_ABORT];
            ip_clr_o   <= data[B_I_CLR];
          end
          R_HW_CFG[4:0]: begin
            hw_filt_o    <= filt_len;
            hw_dir_inv_o <= data[B_E_DIR_INV];
          end
          default: ;
        endcase
      end
      for (ax = 0; ax < NAXES; ax = ax + 1) begin
        if (w_ax && a_ax == ax[1:0]) begin
          case (addr[3:0])
            R_AX_ENC_CFG: begin
              enc_filt_o[ax*FILT_W+:FILT_W] <= filt_len;
              enc_dir_inv_o[ax]    <= data[B_E_DIR_INV];
              enc_idx_clr_en_o[ax] <= data[B_E_IDX_CLR_EN];
            end
            R_AX_IDX: begin
              enc_idx_arm_o[ax]    <= data[B_X_ARM];
              enc_idx_disarm_o[ax] <= data[B_X_DISARM];
            end
            R_AX_ENC_STAT: enc_err_clr_o[ax] <= data[B_ES_W_ERR_CLR];
            R_AX_DRV: begin
              drv_ovr_we_o[ax] <= data[B_D_OVR];
              drv_ovr_o[ax]    <= data[B_D_OVR];
            end
            default: ;
          endcase
        end
      end
    end
  end

  // The executor's own state. Payload bytes are read one per clock; a byte
  // arrives from the RAM a clock after its address (rv, rbi).
  wire rd_free = ~w_act & ~w_start;  // the read path is free for the executor this clock
  always @(posedge clk) begin
    drop_busy   <= 1'b0;
    cnt_nak_inc <= 1'b0;
    cnt_dup_inc <= 1'b0;
    seg_wr_o    <= 1'b0;
    rv          <= 1'b0;
    if (rst) begin
      xs         <= X_IDLE;
      last_valid <= 1'b0;
      last_full  <= 1'b0;
      rep_pend   <= 1'b0;
    end else begin
      if (frame_i && (xs != X_IDLE || rep_busy)) drop_busy <= 1'b1;
      if (rv) begin
        if (f_cmd != P_CMD_SEG && rbi < 8'd2) addr <= {pay_rdata_i, addr[15:8]};
        else data <= {pay_rdata_i, data[31:8]};
        seg_wr_o <= f_cmd == P_CMD_SEG && rbi[1:0] == 2'd3;
      end
      if (tx_start_o && tx_status_en_o) rep_pend <= 1'b0;
      case (xs)
        X_IDLE:
        if (frame_i && !rep_busy) begin
          f_seq <= seq_i;
          f_cmd <= cmd_i;
          f_len    <= len_i;
          seg_full <= room_need > DEPTH;
          xs       <= X_CHECK;
        end
        X_CHECK: begin
          status     <= chk;
          bi         <= 8'd0;
          val_direct <= 1'b0;
          val_shadow <= 1'b0;
          if (f_cmd == P_CMD_PING) begin  // answered with ID, from the shadow RAM
            last_valid <= 1'b0;
            addr       <= R_ID;
            val_shadow <= 1'b1;
          end else if (f_cmd == P_CMD_SEG) begin
            addr <= R_IP_STAT;
          end
          if (chk == P_ST_BAD_LEN || chk == P_ST_BAD_CMD || chk == P_ST_FULL) begin
            if (chk == P_ST_FULL) begin  // its copies get FULL too, never a later evaluation
              last_seq   <= f_seq;
              last_valid <= 1'b1;
              last_full  <= 1'b1;
            end
            cnt_nak_inc <= 1'b1;
            val_direct  <= 1'b1;
            data        <= 32'd0;
            xs          <= X_REPLY;
          end else if (chk == P_ST_DUP) begin  // a repeated segment frame
            cnt_dup_inc <= 1'b1;
            xs          <= X_RD;
          end else if (f_len == 8'd0) begin
            xs <= X_RD;
          end else begin
            xs <= X_FETCH;
          end
        end
        X_FETCH: begin
          if (bi != f_len) begin
            bi  <= bi + 8'd1;
            rv  <= 1'b1;
            rbi <= bi;
          end else if (!rv && !seg_wr_o) begin
            xs <= X_DECIDE;
          end
        end
        X_DECIDE: begin
          if (f_cmd == P_CMD_SEG) begin
            last_seq   <= f_seq;
            last_valid <= 1'b1;
            last_full  <= 1'b0;
            xs         <= X_RD;
          end else if (!d_ok) begin
            status      <= P_ST_BAD_REG;
            cnt_nak_inc <= 1'b1;
            val_direct  <= 1'b1;
            data        <= 32'd0;
            xs          <= X_REPLY;
          end else begin
            if (dup) begin
              status      <= P_ST_DUP;
              cnt_dup_inc <= 1'b1;
            end else begin
              last_seq   <= f_seq;
              last_valid <= 1'b1;
              last_full  <= 1'b0;
            end
            if (f_cmd == P_CMD_WRITE) begin
              val_direct <= 1'b1;
              xs         <= dup ? X_REPLY : (d_pid ? X_PIDW : X_APPLY);
            end else begin
              val_shadow <= ~d_pid & d_shadow;
              xs         <= d_pid ? X_PIDR : X_RD;
            end
          end
        end
        // IP_CTRL.set: the positions wait in the shadow RAM (IP_SET_X..Z);
        // X_SET reads them in turn and each strobes its axis as it arrives.
        X_APPLY: begin
          if (w_glb && addr[4:0] == R_IP_CTRL[4:0] && data[B_I_SET]) begin
            addr  <= R_IP_SET_X;
            set_n <= 2'd0;
            xs    <= X_SET;
          end else begin
            xs <= X_REPLY;
          end
        end
        X_SET:
        if (rd_free) begin
          addr  <= addr + 16'd1;
          set_n <= set_n + 2'd1;
          if (set_n == 2'd2) xs <= X_REPLY;
        end
        X_PIDW: if (pid_wready_i) xs <= X_REPLY;
        X_PIDR: if (pid_rready_i) xs <= X_PIDRW;
        X_PIDRW:
        if (pid_rvalid_i) begin
          val_direct <= 1'b1;
          data       <= pid_rdata_i;
          xs         <= X_REPLY;
        end
        X_RD: if (rd_free) xs <= X_RD1;
        X_RD1: xs <= X_RD2;
        default:  // X_RD2, X_REPLY: the value goes into word 0 of link_tx's RAM
        if (x_wr) begin
          rep_pend <= 1'b1;
          xs       <= X_IDLE;
        end
      endcase
    end
  end

  // The IP_SET reads follow the shadow RAM's two clocks: {valid, axis}.
  reg [2:0] set_t1, set_t2;
  always @(posedge clk) begin
    if (rst) begin
      set_t1 <= 3'd0;
      set_t2 <= 3'd0;
    end else begin
      set_t1 <= {xs == X_SET && rd_free, set_n};
      set_t2 <= set_t1;
    end
  end
  assign ip_set_o     = {3{set_t2[2]}} & (3'd1 << set_t2[1:0]);
  assign ip_set_val_o = sq;

  // link_tx's RAM: the walker's telemetry words, or the reply's value. In
  // X_RD2 the walker cannot be writing (it was idle when X_RD issued, and
  // starts three clocks before its first write); X_REPLY waits for a free clock.
  wire x_wr = xs == X_RD2 || (xs == X_REPLY && !w_wr);
  assign tx_we_o    = w_wr | x_wr;
  assign tx_waddr_o = w_wr ? w_ptr : 4'd0;
  assign tx_wdata_o = (w_wr || !(val_direct || val_shadow)) ? qv : (val_direct ? data : sq);

  // ---------------------------------------------------------------------
  // Walker: after each sample, TLM_HDR then each axis's POS, CMD, ERR, OUT
  // (the TLM_WORD order) and FOLLOW (checked, not sent), one read issued per
  // clock. (w_hdr, w_a, w_k) is the next word to issue.
  reg  [1:0] w_a;
  reg  [2:0] w_k;
  reg        w_hdr;
  reg        w_tlm;  // this walk sends telemetry
  reg        w_tlm_busy;  // from its start until the frame is handed over
  reg  [3:0] w_ptr;  // next telemetry word in link_tx's RAM
  reg  [1:0] done_d;
  reg  [15:0] tlm_left, tlm_decim;  // samples until the next frame is due, counting this one
  reg  [2:0] tlm_axes;
  reg        tlm_due_l;
  // A down-count to 1 needs no comparator: the long path a count up to the
  // decimation had (docs/board.md, Fmax).
  wire       tlm_due = tlm_decim != 16'd0 && tlm_left[15:1] == 15'd0;
  wire       w_start = done_d[1];  // the sample RAM swaps the clock after done
  wire       w_last = !w_hdr && w_k == 3'd4 && {2'd0, w_a} == NAXES4 - 4'd1;
  wire       tlm_free = !(tlm_pend || tlm_sending || w_tlm_busy);

  // TLM register (also in the shadow RAM for read-back). Writing it restarts
  // the decimation: the first frame follows DECIM samples later.
  always @(posedge clk) begin
    if (rst) begin
      tlm_decim <= 16'd0;
      tlm_axes  <= 3'd0;
      tlm_left  <= 16'd0;
    end else if (w_glb && addr[4:0] == R_TLM[4:0]) begin
      tlm_decim <= data[B_T_DECIM_LSB+:16];
      tlm_axes  <= data[B_T_AXES_LSB+:3];
      tlm_left  <= data[B_T_DECIM_LSB+:16];
    end else if (done_i) begin
      tlm_left <= (tlm_decim == 16'd0 || tlm_due) ? tlm_decim : tlm_left - 16'd1;
    end
  end

  // Sample count and decimation.
  always @(posedge clk) begin
    done_d <= {done_d[0], done_i};
    if (done_i) tlm_due_l <= tlm_due;
    if (rst) begin
      done_d     <= 2'd0;
      sample_cnt <= 16'd0;
    end else if (done_i) begin
      sample_cnt <= sample_cnt + 16'd1;
    end
  end

  always @(posedge clk) begin
    if (rst) begin
      w_act <= 1'b0;
    end else if (w_start) begin
      w_act <= 1'b1;
      w_hdr <= 1'b1;
      w_a   <= 2'd0;
      w_k   <= 3'd0;
      w_tlm <= tlm_due_l && tlm_free;
    end else if (w_act) begin
      w_hdr <= 1'b0;
      if (w_last) w_act <= 1'b0;
      if (!w_hdr) begin
        w_k <= (w_k == 3'd4) ? 3'd0 : w_k + 3'd1;
        if (w_k == 3'd4) w_a <= w_a + 2'd1;
      end
    end
  end

  // Read addresses: the walker's while it runs, else the executor's.
  reg [3:0] w_off;
  always @(*) begin
    case (w_k)
      3'd0:    w_off = TLM_WORD0;
      3'd1:    w_off = TLM_WORD1;
      3'd2:    w_off = TLM_WORD2;
      3'd3:    w_off = TLM_WORD3;
      default: w_off = R_AX_FOLLOW;
    endcase
  end
  always @(posedge clk) begin
    if (w_act) begin
      ra <= w_hdr ? R_TLM_HDR : (R_AXIS_BASE | {8'd0, 2'd0, w_a, w_off});
      sa <= sidx(R_AXIS_BASE | {8'd0, 2'd0, w_a, R_AX_FERR});
    end else begin
      ra <= addr;
      sa <= cu_go ? cu_word(cu_pick[2:1]) : sidx(addr);
    end
  end

  // Tags {valid, last, hdr, k} and the axis follow the reads through the
  // two-clock pipeline.
  reg [5:0] t1, t2;
  reg [1:0] ta1, ta2;
  always @(posedge clk) begin
    if (rst) begin
      t1 <= 6'd0;
      t2 <= 6'd0;
    end else begin
      t1 <= {w_act, w_last, w_hdr, w_k};
      t2 <= t1;
    end
    ta1 <= w_a;
    ta2 <= ta1;
  end
  wire       t_v = t2[5];
  wire       t_last = t2[4];
  wire       t_hdr = t2[3];
  wire [2:0] t_k = t2[2:0];
  wire       t_follow = !t_hdr && t_k == 3'd4;  // checked, not sent
  assign w_wr = t_v && w_tlm && (t_hdr || (tlm_axes[ta2] && !t_follow));

  // Telemetry words and the following-error check, as the values arrive:
  // trip when FERR != 0 and |FOLLOW| > FERR, one adder for both signs
  // (FERR - d when d >= 0, d + FERR when d < 0: negative means a trip).
  wire [15:0] flim = sq[15:0];
  wire [31:0] dif = qv;
  wire        dneg = dif[31];
  /* verilator lint_off UNUSEDSIGNAL */
  wire [32:0] fsum = ({dif[31], dif} ^ {33{~dneg}}) + {17'd0, flim} + {32'd0, ~dneg};
  /* verilator lint_on UNUSEDSIGNAL */
  reg         w_end;
  reg  [ 3:0] tlm_n;
  /* verilator lint_off UNUSEDSIGNAL */
  wire [ 3:0] ferr_hit = {3'd0, flim != 16'd0 && fsum[32]} << ta2;
  /* verilator lint_on UNUSEDSIGNAL */
  always @(posedge clk) begin
    ferr_o <= {NAXES{1'b0}};
    w_end  <= t_v & t_last;
    if (rst) begin
      w_tlm_busy <= 1'b0;
    end else begin
      if (w_start) begin
        w_ptr      <= 4'd1;
        w_tlm_busy <= tlm_due_l && tlm_free;
      end
      if (w_wr) w_ptr <= w_ptr + 4'd1;
      if (w_end) begin
        w_tlm_busy <= 1'b0;
        // Only a walk that wrote telemetry: its frame may still wait behind
        // a reply when the next sample's walk ends (Ts under a reply's time).
        if (w_tlm_busy) tlm_n <= w_ptr - 4'd1;
      end
      if (t_v && t_follow) ferr_o <= ferr_hit[NAXES-1:0];
    end
  end

  // ---------------------------------------------------------------------
  // Sender arbitration: the reply first, then telemetry.
  reg [7:0] tlm_seq;
  always @(posedge clk) begin
    tx_start_o <= 1'b0;
    if (rst) begin
      tlm_pend    <= 1'b0;
      tlm_sending <= 1'b0;
      rep_sending <= 1'b0;
      tlm_seq     <= 8'd0;
    end else begin
      // The walk that wrote telemetry has ended: the frame is ready.
      if (w_end && w_tlm_busy) tlm_pend <= 1'b1;
      if (!tx_busy_i && !tx_start_o) begin
        rep_sending <= 1'b0;
        tlm_sending <= 1'b0;
        if (rep_pend) begin
          tx_start_o     <= 1'b1;
          tx_seq_o       <= f_seq;
          tx_cmd_o       <= f_cmd | P_REPLY;
          tx_status_en_o <= 1'b1;
          tx_status_o    <= status;
          tx_wbase_o     <= 4'd0;
          tx_nwords_o    <= 4'd1;
          rep_sending    <= 1'b1;
        end else if (tlm_pend) begin
          tx_start_o     <= 1'b1;
          tx_seq_o       <= tlm_seq;
          tx_cmd_o       <= P_CMD_TLM;
          tx_status_en_o <= 1'b0;
          tx_wbase_o     <= 4'd1;
          tx_nwords_o    <= tlm_n;
          tlm_seq        <= tlm_seq + 8'd1;
          tlm_pend       <= 1'b0;
          tlm_sending    <= 1'b1;
        end
      end
    end
  end

endmodule

`default_nettype wire
