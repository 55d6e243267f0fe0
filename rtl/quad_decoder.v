// quad_decoder: one quadrature encoder (A, B, index Z) to a 32-bit position,
// with glitch filters, error detection, an index latch and a velocity figure.
// Twin: hls/quad_decoder.hpp (cycle for cycle; the testbench compares every
// output every clock). User guide: docs/encoder.md.
//
// How to drive it:
// - Wire the encoder straight to enc_a_i/enc_b_i/enc_z_i: they may change at
//   any time; each goes through two synchronizer flops here. During rst the
//   filters adopt the pins' present levels, so leaving reset counts nothing
//   (right after power-up hold it 3 clocks, for the synchronizers to fill).
// - filt_len_i (clocks) sets the glitch filter of all three inputs: a new
//   level passes once the synchronized input has shown it on filt_len_i
//   consecutive clocks; 0 and 1 both mean one clock (no filtering beyond the
//   synchronizer). A pin change reaches pos_o and a_o/b_o/z_o
//   max(filt_len_i, 1) + 1 clock edges after the edge that first samples it.
// - pos_o counts every A and B edge (4x), up when A leads B (dir_inv_i
//   reverses that), and wraps modulo 2^32: take differences in 32-bit
//   arithmetic. Strobe pos_load_i to set it to pos_load_val_i (0 to clear);
//   an edge counted in that clock is dropped from pos_o, not from vel_o.
//   With POS_LOAD = 0 there is no load (the board keeps offsets in the host
//   instead: 32 multiplexer LUTs fewer per decoder) and pos_load_i is ignored.
// - Index, LinuxCNC index-enable style: strobe idx_arm_i; idx_armed_o stays
//   high until the next rising edge of the filtered Z, which latches the
//   position (this clock's edge included) into idx_pos_o, sets idx_seen_o and
//   drops idx_armed_o. With idx_clr_en_i high, that same position becomes 0.
//   idx_disarm_i cancels an armed latch; arming clears idx_seen_o.
//   latch_i, a synchronous strobe from outside (a home switch, the probe),
//   latches the same way as a Z edge, in the clock it is high: the board
//   latches every armed axis in one clock from one probe edge.
//   With IDX_RAM = 1 the latched position lives in block RAM instead of 32
//   flip-flops: idx_pos_o then follows a clock later (the RAM's output
//   register) and reset leaves it as it was; idx_seen_o says whether it is
//   valid. (The board, short of logic cells, builds it so.)
// - err_o (sticky) and err_cnt_o (saturating) report quadrature errors: the
//   filtered A and B changed in the same clock (not counted), or a filter
//   discarded a pulse on one channel during which the other channel moved
//   (edges closer than the filter lets through). Either means pos_o may be
//   off. err_clr_i clears both; an error in that very clock still counts.
// - Strobe sample_i once per sample period (the PID tick) and read pos_o in
//   that clock. At its end vel_o becomes the edges counted since the previous
//   strobe, i.e. the difference of the two pos_o samples when nothing was
//   loaded (signed, saturating), and age_o the clocks pos_o had held its
//   count at the strobe (saturating): with it, software can time the last
//   edge and estimate low speeds better than one count per sample.
`default_nettype none

module quad_decoder #(
    parameter integer FILT_W = 8,   // filter length input width, bits (clocks up to 2^FILT_W-1)
    parameter integer ERR_W  = 16,  // error counter width, bits (saturates)
    parameter integer VEL_W  = 32,  // velocity width, bits (counts per sample, saturates)
    parameter integer AGE_W  = 16,  // edge age width, bits (clocks, saturates)
    parameter integer IDX_RAM = 0,  // 1: the index latch in block RAM (see above)
    parameter integer POS_LOAD = 1  // 0: no position load (see above)
) (
    // clock and reset
    input  wire              clk,
    input  wire              rst,
    // configuration (levels, may change at any time)
    input  wire [FILT_W-1:0] filt_len_i,      // glitch filter length, clocks
    input  wire              dir_inv_i,       // count down when A leads B
    input  wire              idx_clr_en_i,    // the index edge also zeroes pos_o
    // control strobes (one clock each)
    input  wire              pos_load_i,
    input  wire [      31:0] pos_load_val_i,  // signed counts
    input  wire              idx_arm_i,
    input  wire              idx_disarm_i,
    input  wire              err_clr_i,
    input  wire              sample_i,
    // encoder pins (asynchronous)
    input  wire              enc_a_i,
    input  wire              enc_b_i,
    input  wire              enc_z_i,
    input  wire              latch_i,         // synchronous: latch as a Z edge would
    // position and index
    output reg  [      31:0] pos_o,           // signed counts, wraps
    output reg  [      31:0] idx_pos_o,       // signed counts
    output reg               idx_armed_o,
    output reg               idx_seen_o,
    // errors
    output reg               err_o,
    output reg  [ ERR_W-1:0] err_cnt_o,
    // per sample
    output reg  [ VEL_W-1:0] vel_o,           // signed counts per sample
    output reg  [ AGE_W-1:0] age_o,           // clocks
    // filtered pin levels
    output wire              a_o,
    output wire              b_o,
    output wire              z_o
);

  initial begin
    if (FILT_W < 1 || FILT_W > 16) $error("quad_decoder: FILT_W must be 1..16");
    if (ERR_W < 2 || ERR_W > 32) $error("quad_decoder: ERR_W must be 2..32");
    if (VEL_W < 2 || VEL_W > 32) $error("quad_decoder: VEL_W must be 2..32");
    if (AGE_W < 2 || AGE_W > 32) $error("quad_decoder: AGE_W must be 2..32");
  end

  // Channels everywhere below: bit 0 = A, 1 = B, 2 = Z.
  integer c;
  genvar g;

  // ---------------------------------------------------------------------
  // Synchronizers. No reset: they hold nothing but pin samples.
  reg [2:0] meta, sync;
  always @(posedge clk) begin
    meta <= {enc_z_i, enc_b_i, enc_a_i};
    sync <= meta;
  end

  // ---------------------------------------------------------------------
  // Glitch filters. cnt counts the clocks the synchronized level has
  // differed from the filtered one, minus one; any clock where they agree
  // restarts it, so only an unbroken run of filt_len_i clocks passes.
  reg  [3*FILT_W-1:0] cnt;
  reg  [         2:0] filt;
  wire [         2:0] differ = sync ^ filt;
  wire [         2:0] pass;  // the filtered level takes the new one at this edge
  wire [         1:0] drop;  // A, B: a pending change was discarded (a glitch)
  generate
    for (g = 0; g < 3; g = g + 1) begin : g_filt
      wire [FILT_W-1:0] n = cnt[g*FILT_W+:FILT_W];
      wire [  FILT_W:0] seen = {1'b0, n} + 1'b1;  // this clock included
      assign pass[g] = differ[g] & (seen >= {1'b0, filt_len_i});
      if (g < 2) begin : g_drop
        assign drop[g] = ~differ[g] & (n != {FILT_W{1'b0}});
      end
    end
  endgenerate

  always @(posedge clk) begin
    for (c = 0; c < 3; c = c + 1) begin
      if (rst || !differ[c] || pass[c]) cnt[c*FILT_W+:FILT_W] <= {FILT_W{1'b0}};
      else cnt[c*FILT_W+:FILT_W] <= cnt[c*FILT_W+:FILT_W] + 1'b1;
    end
  end

  // Reset adopts the present levels, so nothing counts when it ends.
  always @(posedge clk) begin
    if (rst) filt <= sync;
    else filt <= filt ^ pass;
  end

  assign a_o = filt[0];
  assign b_o = filt[1];
  assign z_o = filt[2];

  // A discarded pulse on A is noise only if B ended where it started (and
  // vice versa): if B moved an odd number of times meanwhile, the pins went
  // through a sequence that real motion faster than the filter also makes,
  // and the count cannot be trusted. oth holds the other channel's level
  // from the clock before this channel's pending change began.
  reg  [1:0] oth;
  wire [1:0] sync_other = {sync[0], sync[1]};
  always @(posedge clk) begin
    for (c = 0; c < 2; c = c + 1) begin
      if (rst || !differ[c] || pass[c]) oth[c] <= sync_other[c];
    end
  end
  wire straddle = |(drop[1:0] & (sync_other ^ oth));

  // ---------------------------------------------------------------------
  // 4x decode from the filter's pass events, registered once before the
  // counters: the filter's compare and the 32-bit count would otherwise be
  // one path, the board's longest.
  // Forward (A leads B) runs AB = 00, 10, 11, 01: an A edge goes forward
  // when A's new level differs from B, a B edge when B's new level equals A.
  wire a_mv = pass[0];
  wire b_mv = pass[1];
  wire fwd = a_mv ? (sync[0] ^ filt[1]) : ~(sync[1] ^ filt[0]);
  reg  step, fwd_r, qerr, z_rise;
  always @(posedge clk) begin
    if (rst) begin
      step   <= 1'b0;
      fwd_r  <= 1'b0;
      qerr   <= 1'b0;
      z_rise <= 1'b0;
    end else begin
      step   <= a_mv ^ b_mv;
      fwd_r  <= fwd;
      qerr   <= (a_mv & b_mv) | straddle;
      z_rise <= pass[2] & sync[2];
    end
  end
  wire up = fwd_r ^ dir_inv_i;

  // One adder for both directions: +1, -1 (all ones) or 0.
  wire        dn = step & ~up;
  wire [31:0] pos_cnt = pos_o + {{31{dn}}, step};
  wire        idx_hit = idx_armed_o & (z_rise | latch_i);

  // Load beats the index clear, which beats counting: software's explicit
  // value is the one it expects to read back.
  always @(posedge clk) begin
    if (rst) pos_o <= 32'd0;
    else if (POS_LOAD != 0 && pos_load_i) pos_o <= pos_load_val_i;
    else if (idx_hit && idx_clr_en_i) pos_o <= 32'd0;
    else pos_o <= pos_cnt;
  end

  generate
    if (POS_LOAD == 0) begin : g_no_load
      /* verilator lint_off UNUSEDSIGNAL */
      wire unused = &{1'b0, pos_load_i, pos_load_val_i};
      /* verilator lint_on UNUSEDSIGNAL */
    end
  endgenerate

  // The latched position is the one that becomes 0 with idx_clr_en_i, so
  // idx_pos_o is exactly the offset between the old and the new count.
  generate
    if (IDX_RAM != 0) begin : g_idx_ram
      // Two words written in turn, the output reading the newer: a memory
      // of one word at a constant address would be folded into flip-flops.
      reg idx_w;
      (* ram_style = "block" *)
      reg [31:0] idx_mem[0:1];
      initial begin
        idx_mem[0] = 32'd0;
        idx_mem[1] = 32'd0;
        idx_w      = 1'b0;
        idx_pos_o  = 32'd0;
      end
      always @(posedge clk) begin
        if (idx_hit && !rst) begin
          idx_mem[~idx_w] <= pos_cnt;
          idx_w           <= ~idx_w;
        end
        idx_pos_o <= idx_mem[idx_w];
      end
    end else begin : g_idx_ff
      always @(posedge clk) begin
        if (rst) idx_pos_o <= 32'd0;
        else if (idx_hit) idx_pos_o <= pos_cnt;
      end
    end
  endgenerate

  // An index edge uses the arm it finds: arming in the same clock neither
  // helps nor hurts, and a disarm arrives too late to stop it.
  always @(posedge clk) begin
    if (rst) begin
      idx_armed_o <= 1'b0;
      idx_seen_o  <= 1'b0;
    end else begin
      if (idx_disarm_i || idx_hit) idx_armed_o <= 1'b0;
      else if (idx_arm_i) idx_armed_o <= 1'b1;
      if (idx_hit) idx_seen_o <= 1'b1;
      else if (idx_arm_i) idx_seen_o <= 1'b0;
    end
  end

  // A clear never hides an error that happens in the same clock.
  always @(posedge clk) begin
    if (rst) begin
      err_o     <= 1'b0;
      err_cnt_o <= {ERR_W{1'b0}};
    end else begin
      err_o <= (err_o & ~err_clr_i) | qerr;
      if (err_clr_i) err_cnt_o <= {{(ERR_W - 1) {1'b0}}, qerr};
      else err_cnt_o <= err_cnt_o + {{(ERR_W - 1) {1'b0}}, qerr & ~&err_cnt_o};
    end
  end

  // ---------------------------------------------------------------------
  // Per sample. vel_acc counts apart from pos_o so that loads and index
  // clears do not show up as motion. The strobe's own clock belongs to the
  // next period: pos_o as sampled in that clock (the PID's feedback) does not
  // include it yet, so vel_o is exactly the difference of two such samples.
  // A step can only overflow away from zero: the sign bits tell, and the
  // accumulator then holds.
  reg  [VEL_W-1:0] vel_acc;
  wire [VEL_W-1:0] vel_d = {{(VEL_W - 1) {dn}}, step};
  wire [VEL_W-1:0] vel_sum = vel_acc + vel_d;
  wire             vel_ovf = step & (vel_acc[VEL_W-1] == dn) & (vel_sum[VEL_W-1] != dn);
  always @(posedge clk) begin
    if (rst) begin
      vel_acc <= {VEL_W{1'b0}};
      vel_o   <= {VEL_W{1'b0}};
    end else if (sample_i) begin
      vel_acc <= vel_d;
      vel_o   <= vel_acc;
    end else if (!vel_ovf) begin
      vel_acc <= vel_sum;
    end
  end

  // age: clocks pos_o has held its value (in counting; loads aside). It
  // starts saturated: after reset no edge has been seen.
  reg [AGE_W-1:0] age;
  always @(posedge clk) begin
    if (rst) begin
      age   <= {AGE_W{1'b1}};
      age_o <= {AGE_W{1'b1}};
    end else begin
      age <= step ? {AGE_W{1'b0}} : age + {{(AGE_W - 1) {1'b0}}, ~&age};
      if (sample_i) age_o <= age;
    end
  end

`ifdef FORMAL
  // ---------------------------------------------------------------------
  // Properties (scripts/formal.sh quad_decoder, quad_rate; docs/formal.md).
  // Pins, strobes and configuration are free and may change in any clock.
  // As the top of a proof the reset at the start is assumed; inside a
  // harness it is asserted.
`ifdef FORMAL_TOP_quad_decoder
`define QD_ASSUME assume
`else
`define QD_ASSUME assert
`endif

  reg f_past_valid = 1'b0;
  reg [1:0] f_age2 = 2'd0;  // clocks since power-up, up to 2
  always @(posedge clk) begin
    f_past_valid <= 1'b1;
    if (f_age2 != 2'd2) f_age2 <= f_age2 + 2'd1;
  end
  always @(*) if (!f_past_valid) `QD_ASSUME (rst);  // start from reset

  // The pins through two flip-flops of our own: the synchronized levels.
  reg [2:0] f_p1, f_p2;
  always @(posedge clk) begin
    f_p1 <= {enc_z_i, enc_b_i, enc_a_i};
    f_p2 <= f_p1;
  end

  // f_hold: clocks each synchronized level had held before this one
  // (saturating); f_len: the filter length in force, max(filt_len_i, 1).
  localparam [FILT_W:0] F_SAT = {(FILT_W + 1) {1'b1}};
  reg  [               2:0] f_sync_q;
  reg  [3*(FILT_W+1)-1:0] f_run;  // f_hold + 1 of the last clock
  reg  [3*(FILT_W+1)-1:0] f_hold;
  wire [          FILT_W:0] f_len = (filt_len_i == {FILT_W{1'b0}}) ? {{FILT_W{1'b0}}, 1'b1} : {1'b0, filt_len_i};
  reg  [               2:0] f_filt;  // the filtered levels due next clock
  always @(*)
    for (c = 0; c < 3; c = c + 1)
      f_hold[c*(FILT_W+1)+:FILT_W+1] = (sync[c] != f_sync_q[c]) ? {(FILT_W + 1) {1'b0}} : f_run[c*(FILT_W+1)+:FILT_W+1];
  always @(posedge clk) begin
    f_sync_q <= sync;
    for (c = 0; c < 3; c = c + 1) begin
      // (In reset the filter adopts the level: from there on it counts as
      // held for long.)
      f_run[c*(FILT_W+1)+:FILT_W+1] <= (rst || f_hold[c*(FILT_W+1)+:FILT_W+1] == F_SAT) ? F_SAT
          : f_hold[c*(FILT_W+1)+:FILT_W+1] + 1'b1;
      // The filter's rule: a new level passes once it has been there for
      // f_len clocks in a row, this one included; reset adopts it at once.
      f_filt[c] <= (rst || (sync[c] != filt[c] && f_hold[c*(FILT_W+1)+:FILT_W+1] + 1'b1 >= f_len))
          ? sync[c] : filt[c];
    end
  end

  // Quadrature position (0..3 along AB = 00, 10, 11, 01) of a level pair.
  function [1:0] f_qpos(input a, input b);
    f_qpos = {b, a ^ b};
  endfunction

  // The filtered levels of the last clock, and what moving from them to
  // this clock's should count: +1 or -1 (2'b01, 2'b11 as a 2-bit delta:
  // forward or back a quarter), nothing, or an error (both changed).
  reg [1:0] f_ab_q;
  reg f_rst_q, f_z_q;
  always @(posedge clk) begin
    f_ab_q  <= {b_o, a_o};
    f_z_q   <= z_o;
    f_rst_q <= rst;
  end
  wire [1:0] f_d = f_qpos(a_o, b_o) - f_qpos(f_ab_q[0], f_ab_q[1]);
  wire f_fwd = !f_rst_q && f_d == 2'd1;
  wire f_back = !f_rst_q && f_d == 2'd3;
  wire f_both = !f_rst_q && f_d == 2'd2;
  wire f_hit = idx_armed_o && !f_rst_q && ((z_o && !f_z_q) || latch_i);  // armed, and a rising filtered Z or a latch strobe
  wire [31:0] f_delta = (f_fwd != f_back) ? ((f_fwd ^ dir_inv_i) ? 32'd1 : 32'hFFFF_FFFF) : 32'd0;

  reg [31:0] f_pos_q, f_delta_q, f_load_val_q;
  reg [31:0] f_idx_q;
  reg f_load_q, f_clr_q, f_both_q, f_err_q, f_errclr_q, f_hit_q, f_arm_q, f_disarm_q, f_armed_q, f_seen_idx_q;
  reg [ERR_W-1:0] f_err_cnt_q;
  always @(posedge clk) begin
    f_pos_q      <= pos_o;
    f_delta_q    <= f_delta;
    f_load_q     <= pos_load_i;
    f_load_val_q <= pos_load_val_i;
    f_clr_q      <= f_hit && idx_clr_en_i;
    f_both_q     <= f_both;
    f_err_q      <= err_o;
    f_err_cnt_q  <= err_cnt_o;
    f_errclr_q   <= err_clr_i;
    f_hit_q      <= f_hit;
    f_arm_q      <= idx_arm_i;
    f_disarm_q   <= idx_disarm_i;
    f_armed_q    <= idx_armed_o;
    f_seen_idx_q <= idx_seen_o;
    f_idx_q      <= idx_pos_o;
  end

  always @(*)
    if (f_past_valid) begin
      // The filter passes a level exactly as its rule says.
      if (!f_rst_q) assert (filt == f_filt);
      // pos_o counts each step of the filtered A and B by one, up when A
      // leads (down with dir_inv_i), nothing when both changed; a load
      // sets it, an index clear zeroes it, reset clears it. So it never
      // moves by more than one count in a clock but through those.
      if (f_rst_q) assert (pos_o == 32'd0);
      else if (f_load_q) assert (pos_o == f_load_val_q);
      else if (f_clr_q) assert (pos_o == 32'd0);
      else assert (pos_o == f_pos_q + f_delta_q);
      // A and B changing in one clock sets err_o (sticky until err_clr_i)
      // and counts in err_cnt_o, which saturates.
      if (!f_rst_q && f_both_q) assert (err_o && err_cnt_o != {ERR_W{1'b0}});
      if (!f_rst_q && f_err_q && !f_errclr_q) assert (err_o);
      if (!f_rst_q && !f_errclr_q) assert (err_cnt_o >= f_err_cnt_q);
      // Index: an armed latch takes the position at the first rising
      // edge of the filtered Z (this clock's count included), sets
      // idx_seen_o and disarms; arming and disarming act otherwise.
      if (!f_rst_q && f_hit_q) begin
        assert (!idx_armed_o && idx_seen_o);
        assert (f_load_q || pos_o == (f_clr_q ? 32'd0 : f_pos_q + f_delta_q));
      end
      if (!f_rst_q && !f_hit_q) assert (idx_armed_o == (!f_disarm_q && (f_arm_q || f_armed_q)));
      if (!f_rst_q && !f_hit_q) assert (idx_seen_o == (!f_arm_q && f_seen_idx_q));
      if (f_rst_q) assert (!idx_armed_o && !idx_seen_o);
      // The latched position is the count the clock of the edge made, the
      // one an index clear zeroes; it holds otherwise. (With IDX_RAM it
      // follows a clock later and survives reset: not proven here.)
      if (IDX_RAM == 0) begin
        if (f_rst_q) assert (idx_pos_o == 32'd0);
        else if (f_hit_q) assert (idx_pos_o == f_pos_q + f_delta_q);
        else assert (idx_pos_o == f_idx_q);
      end
      // How the registers make that (the induction needs it spelled out).
      if (f_age2 == 2'd2) assert (sync == f_p2);
      for (c = 0; c < 3; c = c + 1)
        if (sync[c] != filt[c]) assert (cnt[c*FILT_W+:FILT_W] == f_hold[c*(FILT_W+1)+:FILT_W]
                                        && !f_hold[c*(FILT_W+1)+FILT_W]);
      if (!f_rst_q) begin
        assert (step == (f_fwd || f_back) && z_rise == (z_o && !f_z_q));
        if (step) assert (fwd_r == f_fwd);
        if (f_both) assert (qerr);
      end
    end

`ifdef FORMAL_QUAD_RATE
  // ---------------------------------------------------------------------
  // At or below the rated edge rate (docs/encoder.md: every level of A and
  // of B lasts max(filt_len_i, 1) clocks or more, and A and B never change
  // in the same clock), with the filter length and direction fixed, no
  // loads and no index clears, after a reset of 3 clocks: pos_o counts
  // every pin edge exactly and err_o never rises. (scripts/formal.sh
  // quad_rate defines FORMAL_QUAD_RATE.)
  reg [1:0] f_clk3 = 2'd0;  // clocks since power-up, up to 3
  always @(posedge clk) if (f_clk3 != 2'd3) f_clk3 <= f_clk3 + 2'd1;
  reg [FILT_W-1:0] f_filt_len_q;
  reg f_dir_inv_q;
  always @(posedge clk) begin
    f_filt_len_q <= filt_len_i;
    f_dir_inv_q  <= dir_inv_i;
  end

  // The pins' levels: f_phold, clocks each had held before this one, as
  // f_hold above; and two clocks later (what sync shows then).
  reg  [                 1:0] f_pin_q;
  reg  [2*(FILT_W+1)-1:0] f_prun = {2 * (FILT_W + 1) {1'b1}};  // as if held for long before power-up
  reg  [2*(FILT_W+1)-1:0] f_phold;
  reg  [2*(FILT_W+1)-1:0] f_phold_d1, f_phold_d2, f_prun_d1, f_prun_d2;
  wire [                 1:0] f_pin = {enc_b_i, enc_a_i};
  always @(*)
    for (c = 0; c < 2; c = c + 1)
      f_phold[c*(FILT_W+1)+:FILT_W+1] = (f_pin[c] != f_pin_q[c]) ? {(FILT_W + 1) {1'b0}} : f_prun[c*(FILT_W+1)+:FILT_W+1];
  always @(posedge clk) begin
    f_pin_q <= f_pin;
    for (c = 0; c < 2; c = c + 1)
      f_prun[c*(FILT_W+1)+:FILT_W+1] <= (f_phold[c*(FILT_W+1)+:FILT_W+1] == F_SAT) ? F_SAT
          : f_phold[c*(FILT_W+1)+:FILT_W+1] + 1'b1;
    f_phold_d1 <= f_phold;
    f_phold_d2 <= f_phold_d1;
    f_prun_d1  <= f_prun;
    f_prun_d2  <= f_prun_d1;
  end

  always @(*) begin
    `QD_ASSUME (rst == (f_clk3 != 2'd3));
    if (f_clk3 == 2'd0) `QD_ASSUME (f_pin == f_pin_q);
    if (f_clk3 != 2'd0) `QD_ASSUME (filt_len_i == f_filt_len_q && dir_inv_i == f_dir_inv_q);
    `QD_ASSUME (!pos_load_i && !idx_clr_en_i);
    `QD_ASSUME (!(f_pin[0] != f_pin_q[0] && f_pin[1] != f_pin_q[1]));
    for (c = 0; c < 2; c = c + 1)
      if (f_pin[c] != f_pin_q[c]) `QD_ASSUME (f_prun[c*(FILT_W+1)+:FILT_W+1] >= f_len);
  end

  // f_seen: the count the synchronized pins have made (every A and B edge,
  // signed as pos_o counts), and what is still on its way to pos_o: an
  // edge waiting in a filter counts in the direction the other channel's
  // level will give it when it passes (the other channel's new level if
  // its own edge is older and passes first), a step waiting in the
  // register between the filters and the counter.
  reg  [31:0] f_seen_q;
  wire [ 1:0] f_sd = f_qpos(sync[0], sync[1]) - f_qpos(f_sync_q[0], f_sync_q[1]);
  wire [31:0] f_sstep = (f_sd == 2'd1) ? 32'd1 : (f_sd == 2'd3) ? 32'hFFFF_FFFF : 32'd0;
  wire [31:0] f_seen = f_seen_q + (dir_inv_i ? 32'd0 - f_sstep : f_sstep);
  always @(posedge clk) f_seen_q <= rst ? 32'd0 : f_seen;
  wire [FILT_W:0] f_ha = f_hold[0+:FILT_W+1], f_hb = f_hold[FILT_W+1+:FILT_W+1];
  wire f_b_at_a = (differ[1] && f_hb < f_ha) ? filt[1] : sync[1];  // B when A's edge passes
  wire f_a_at_b = (differ[0] && f_ha < f_hb) ? filt[0] : sync[0];  // A when B's edge passes
  wire f_up_a = (sync[0] ^ f_b_at_a) ^ dir_inv_i;
  wire f_up_b = ~(sync[1] ^ f_a_at_b) ^ dir_inv_i;
  wire [31:0] f_wait = (differ[0] ? (f_up_a ? 32'd1 : 32'hFFFF_FFFF) : 32'd0)
                     + (differ[1] ? (f_up_b ? 32'd1 : 32'hFFFF_FFFF) : 32'd0)
                     + (step ? (up ? 32'd1 : 32'hFFFF_FFFF) : 32'd0);

  // The saturating increment of f_phold, as f_prun takes it.
  function [2*(FILT_W+1)-1:0] f_inc2(input [2*(FILT_W+1)-1:0] h);
    integer k;
    begin
      for (k = 0; k < 2; k = k + 1)
        f_inc2[k*(FILT_W+1)+:FILT_W+1] = (h[k*(FILT_W+1)+:FILT_W+1] == F_SAT) ? F_SAT
            : h[k*(FILT_W+1)+:FILT_W+1] + 1'b1;
    end
  endfunction
  reg [1:0] f_pin_d1, f_pin_d2;
  always @(posedge clk) begin
    f_pin_d1 <= f_pin_q;
    f_pin_d2 <= f_pin_d1;
  end

  always @(*)
    if (f_clk3 == 2'd3) begin
      // Every edge counted exactly once, in its direction; no error.
      assert (pos_o + f_wait == f_seen);
      assert (!err_o && err_cnt_o == {ERR_W{1'b0}} && !qerr);
      // How the registers make that (the induction needs it spelled out).
      assert (f_p2 == sync && f_p1 == meta);
      assert (f_hold[0+:2*(FILT_W+1)] == f_phold_d2 && f_run[0+:2*(FILT_W+1)] == f_prun_d2);
      assert (f_p1[1:0] == f_pin_q && f_sync_q[1:0] == f_pin_d2 && f_p2[1:0] == f_pin_d1);
      assert (f_prun == f_inc2(f_phold_d1) && f_prun_d1 == f_inc2(f_phold_d2));
      assert (!(differ[0] && differ[1] && f_ha == f_hb));
      for (c = 0; c < 2; c = c + 1) begin
        if (differ[c]) assert (f_hold[c*(FILT_W+1)+:FILT_W+1] < f_len);
        if (!differ[c]) assert (cnt[c*FILT_W+:FILT_W] == {FILT_W{1'b0}});
        if (sync[c] != f_sync_q[c]) assert (f_run[c*(FILT_W+1)+:FILT_W+1] >= f_len);
      end
    end

`ifdef FORMAL_TOP_quad_decoder
  // Not vacuous: counts at the rated rate for filt_len_i = 3.
  always @(*) cover (f_clk3 == 2'd3 && filt_len_i == 4'd3 && pos_o == 32'd3 && !dir_inv_i);
`endif
`else
`ifdef FORMAL_TOP_quad_decoder
  // Not vacuous (covers only when this module is the top): counts both ways
  // without a load, an error, an index latch that clears the position.
  reg f_loaded = 1'b0;
  always @(posedge clk) if (pos_load_i) f_loaded <= 1'b1;
  always @(*)
    if (f_past_valid && !f_loaded) begin
      cover (pos_o == 32'd2 && !dir_inv_i && filt_len_i == 4'd3);
      cover (pos_o == 32'hFFFF_FFFE);
      cover (err_o);
      cover (idx_seen_o && pos_o == 32'd0 && idx_pos_o == 32'd1);
    end
`endif
`endif

`undef QD_ASSUME
`endif

endmodule

`default_nettype wire
