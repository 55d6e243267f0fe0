// interp_core: the interpolator. A queue of segments (lines, stairs arcs,
// dwells), the feed-rate generator, and the position command it moves one
// count at a time. Twin: hls/interp_core.hpp (the schedule in full, and the
// state RAM's map); segment format: hls/interp_seg.hpp.
//
// How to drive it:
// - Queue segments a word at a time with wr_i/wdata_i. A segment is admitted
//   whole or not at all: if the FIFO lacks room for all SEG_WORDS words when
//   its first word arrives, the whole segment is dropped and ovf_o set, so the
//   queue never falls out of step. Check count_o before writing.
// - The core loads the oldest segment (SEG_WORDS + 1 clocks), prepares it
//   (PREP_STEPS clocks) and runs it, then the next, with the feed
//   generator's phase carried over, so queued segments run without a stop.
// - At most one iteration runs per tick of 2^SEG_TICK_LOG2 clocks: the
//   highest iteration rate is f_clk / 2^SEG_TICK_LOG2. Iterations that fall
//   due and cannot run yet are kept, up to three.
// - A segment that ends with no whole segment queued behind it, and is not
//   marked last, sets underrun_o: the position holds, never jumps, and
//   motion resumes when segments arrive.
// - hold_i pauses the feed; abort_i stops at once and empties the queue;
//   set_i[a] loads axis a of pos_o from its slice of set_pos_i and is taken
//   only while idle (busy_o low): a loader may set the axes one at a time
//   from one 32-bit value (the board does); clr_i clears the sticky flags
//   (an event in the same cycle wins).
// - jog_i[a] moves axis a's command one count (down with jog_neg_i) while
//   idle, as an iteration would: the board's handwheel jog. set_i wins.
//
// Structure: a serial engine, like pid_core. One 32-bit ALU,
// out = A + (B ^ inv) + cin with A from read port a and B from read port b
// or the FIFO word, runs a fixed schedule over a 16-word state RAM (block
// RAM: two copies for two read ports, written together).
// Loading a segment, preparing it, the feed phase accumulator, the three
// Bresenham axes and the stairs arc all go through it; the schedule is
// listed step by step in hls/interp_core.hpp. Only the position counters,
// the segment header and a few flags are flip-flops.
`default_nettype none

module interp_core #(
    parameter integer FIFO_AW = 9  // log2 of the queue depth in words
) (
    // clock and reset
    input  wire                clk,
    input  wire                rst,
    // segment queue
    input  wire                wr_i,
    input  wire [        31:0] wdata_i,
    output wire [   FIFO_AW:0] count_o,
    // control
    input  wire                abort_i,
    input  wire                hold_i,
    input  wire                clr_i,
    input  wire [         2:0] set_i,      // one strobe per axis: x, y, z
    input  wire [    3*32-1:0] set_pos_i,
    input  wire [         2:0] jog_i,      // one strobe per axis, while idle
    input  wire                jog_neg_i,
    // position command, counts: x in [31:0], y, z
    output wire [    3*32-1:0] pos_o,
    // status
    output wire                busy_o,
    output reg                 underrun_o,
    output reg                 ovf_o,
    output reg  [        15:0] seg_cnt_o
);

  /* verilator lint_off UNUSEDPARAM */
`include "interp_seg.vh"
  /* verilator lint_on UNUSEDPARAM */

  localparam integer DEPTH = 1 << FIFO_AW;
  localparam integer PHB = 16 - SEG_TICK_LOG2;  // phase bits in the upper phase word
  localparam [1:0] ST_IDLE = 2'd0, ST_LOAD = 2'd1, ST_PREP = 2'd2, ST_RUN = 2'd3;
  localparam [2:0] INIT_STEPS = 3'd5;  // after reset: equalize, read, clear three words
  localparam [3:0] PREP_LAST = 4'd7;  // PREP_STEPS - 1
  // write modes
  localparam [2:0] W_NONE = 3'd0, W_BOTH = 3'd1, W_LO = 3'd2, W_MASK = 3'd3, W_SWAP = 3'd4;
  /* verilator lint_off WIDTH */
  localparam [3:0] I_HDR = SEG_W_HDR;
  localparam [3:0] I_N = SEG_W_N;
  localparam [3:0] I_A = SEG_W_A;
  localparam [3:0] I_B = SEG_W_B;
  localparam [3:0] NWORDS = SEG_WORDS;
  localparam [3:0] I_LAST = SEG_WORDS - 1;
  localparam [FIFO_AW:0] SEGW = SEG_WORDS;
  localparam [FIFO_AW:0] ROOM = DEPTH - SEG_WORDS;  // most words held with room for a segment
  localparam [1:0] T_LINE = SEG_T_LINE;
  localparam [1:0] T_ARC = SEG_T_ARC;
  /* verilator lint_on WIDTH */

  initial begin
    if (FIFO_AW < 4 || FIFO_AW > 12) begin
      $error("interp_core: FIFO_AW must be 4..12");
    end
    if (SEG_TICK_LOG2 != 4) begin
      $error("interp_core: the schedule is written for a tick of 16 clocks");
    end
  end

  reg  [ 1:0] st;
  reg  [ 3:0] sq;    // PREP step or RUN tick step
  reg  [ 2:0] ic;    // init steps done after reset
  reg  [ 3:0] widx;  // next word to read while loading
  reg  [ 3:0] ridx;  // word arriving from the FIFO
  reg         rv;    // a word arrives this cycle
  reg  [ 3:0] wi;    // writer: word index within the segment being queued
  reg         drop;  // writer: the segment being queued is dropped
  reg  [ 1:0] pend;  // iterations due, not yet run
  reg         go;    // this tick iterates
  reg         fen;   // this tick advances the feed
  reg         carry;
  // segment header
  reg  [ 1:0] typ;
  reg         last;
  reg         ccw;
  reg  [ 1:0] plane;
  reg  [ 2:0] nq;
  reg  [ 2:0] neg_h;
  // flags of the running segment
  reg nz, xz, xn, yz, yn, xeq, yeq;
  reg  [ 2:0] ncross;
  reg  [ 2:0] lmv;  // line: axes that step this iteration
  reg movex, negm, outw;
  // the state RAM's read ports
  reg  [31:0] ra_q, rb_q;

  wire [31:0] fd;
  wire is_line = typ == T_LINE;
  wire is_arc = typ == T_ARC;
  wire running = st == ST_RUN;
  wire rd = st == ST_LOAD && widx < NWORDS && !abort_i;
  wire ld = rv && !abort_i;
  // Writer: the first word decides for the whole segment.
  wire drop_n = wi == 4'd0 ? count_o > ROOM : drop;
  wire push = wr_i && !abort_i && !drop_n;

  seg_fifo #(
      .AW(FIFO_AW)
  ) u_fifo (
      .clk    (clk),
      .rst    (rst),
      .flush_i(abort_i),
      .wr_i   (push),
      .wdata_i(wdata_i),
      .rd_i   (rd),
      .rdata_o(fd),
      .count_o(count_o)
  );

  // --- The arc's quadrant ----------------------------------------------------
  // Axis points assigned so that the walk leaves a quadrant exactly when an
  // inward move zeroes a coordinate (hls/arc_interp.hpp).
  wire xp = !xn && !xz, yp = !yn && !yz;
  wire q1 = ccw ? (xp && !yn) : (!xn && yp);
  wire q2 = ccw ? (!xp && yp) : (xn && !yn);
  wire q4 = ccw ? (!xn && yn) : (xp && !yp);
  wire upper = q1 || q2;
  wire right = q1 || q4;
  wire mxn = upper == ccw;  // the allowed x move is towards minus
  wire myn = right != ccw;
  wire xo = xz || (xn == mxn);  // the x move is outward
  wire final_q = ncross == nq;
  wire xlock = final_q && xeq;
  wire ylock = final_q && yeq;
  wire [3:0] c_addr = movex ? 4'd4 : 4'd5;  // the coordinate that moves
  wire fin = running && sq == 4'd5 && (!nz || (is_arc && xlock && ylock));
  // line steps 7..9 and 10..12: the axis
  reg [1:0] lax;
  always @(*) begin
    case (sq)
      4'd8, 4'd11: lax = 2'd1;
      4'd9, 4'd12: lax = 2'd2;
      default:     lax = 2'd0;
    endcase
  end
  wire [1:0] psq = sq[1:0];  // PREP steps 4..6 decode steps 5..7: the axis whose g starts

  // --- The operation of this clock --------------------------------------------
  // A is read port a; B is read port b or the FIFO word, inverted by binv.
  // The operand controls (bfd, binv, cin) are registered, decoded a clock
  // ahead for the step that follows, so that no decoding sits in front of
  // the carry chain; the flags they depend on are settled a clock before
  // their steps. A step the prediction gets wrong never writes: the first
  // LOAD clock (no word yet) and IDLE after a segment (init is over); only
  // the LOAD -> PREP edge is decoded exactly. cin takes the carry register
  // itself at the steps that chain words.
  reg bfd_q, binv_q, cin_q, csel_q;
  always @(posedge clk) begin
    bfd_q  <= 1'b0;
    binv_q <= 1'b0;
    cin_q  <= 1'b0;
    csel_q <= 1'b0;
    case (st)
      ST_IDLE: begin
        binv_q <= 1'b1;
        cin_q  <= 1'b1;
      end
      ST_LOAD: bfd_q <= !(ld && ridx == I_LAST);
      ST_PREP: cin_q <= sq >= 4'd4 && sq != PREP_LAST && !neg_h[psq];
      default:
      case (sq)
        4'd0: csel_q <= 1'b1;
        4'd1: begin
          binv_q <= mxn;
          cin_q  <= mxn;
        end
        4'd2, 4'd3: begin
          binv_q <= 1'b1;
          cin_q  <= 1'b1;
        end
        4'd4: begin
          binv_q <= myn;
          cin_q  <= myn;
        end
        4'd5: binv_q <= 1'b1;
        default: begin
          if (is_line && sq >= 4'd6 && sq <= 4'd8) begin
            binv_q <= 1'b1;
            cin_q  <= 1'b1;
          end
          if (is_arc) begin
            case (sq)
              4'd6, 4'd9: begin
                binv_q <= negm;
                cin_q  <= negm;
              end
              4'd7: begin
                binv_q <= negm;
                cin_q  <= !negm;
              end
              4'd8: begin
                binv_q <= !outw;
                cin_q  <= !outw;
              end
              4'd10: begin
                binv_q <= !outw;
                csel_q <= 1'b1;
              end
              default: ;
            endcase
          end
        end
      endcase
    endcase
  end
  wire bfd = bfd_q;
  wire binv = binv_q;
  wire cin = csel_q ? carry : cin_q;

  // The write of this clock: address and mode.
  reg [3:0] wa;
  reg [2:0] wm;
  always @(*) begin
    wa = sq;
    wm = W_NONE;
    case (st)
      ST_IDLE: begin
        // After reset: the two copies of V1 made equal (whatever the value),
        // then V1 - V1 = 0 into the zero word and the phase.
        wa = ic == 3'd0 ? 4'd1 : (ic == 3'd2 ? 4'd0 : (ic == 3'd3 ? 4'd11 : 4'd12));
        wm = (ic != 3'd1 && ic != INIT_STEPS) ? W_BOTH : W_NONE;
      end
      ST_LOAD: begin
        // V0 + word
        wa = ridx;
        wm = (ld && ridx != I_HDR) ? W_BOTH : W_NONE;
      end
      ST_PREP: begin
        wa = sq + 4'd2;
        if (sq == 4'd0) begin
          wa = 4'd13;
          wm = W_SWAP;
        end else if (sq == 4'd1) begin
          wa = 4'd14;
          wm = W_BOTH;
        end else begin
          wm = is_line ? W_BOTH : W_NONE;
        end
      end
      default: begin
        case (sq)
          4'd0: begin
            wa = 4'd11;
            wm = (!hold_i && !abort_i) ? W_BOTH : W_NONE;
          end
          4'd1: begin
            wa = 4'd12;
            wm = fen ? W_MASK : W_NONE;
          end
          4'd2: begin
            wa = 4'd15;
            wm = W_BOTH;
          end
          4'd6: begin
            wa = 4'd1;
            wm = go ? W_BOTH : W_NONE;
          end
          default: begin
            if (is_line) begin
              if (sq >= 4'd7 && sq <= 4'd9) wm = go ? W_BOTH : W_NONE;
              if (sq >= 4'd10 && sq <= 4'd12) begin
                wa = sq - 4'd3;
                wm = (go && lmv[lax]) ? W_BOTH : W_NONE;
              end
            end
            if (is_arc) begin
              case (sq)
                4'd7, 4'd10: begin
                  wa = 4'd8;
                  wm = go ? W_BOTH : W_NONE;
                end
                4'd8: begin
                  wa = c_addr;
                  wm = go ? W_BOTH : W_NONE;
                end
                4'd9: begin
                  wa = 4'd2;
                  wm = go ? W_BOTH : W_NONE;
                end
                4'd11: begin
                  wa = 4'd3;
                  wm = go ? W_LO : W_NONE;
                end
                default: ;
              endcase
            end
          end
        endcase
      end
    endcase
  end

  // --- The ALU -----------------------------------------------------------------
  wire [31:0] a_op = ra_q;
  wire [31:0] b_op = (bfd ? fd : rb_q) ^ {32{binv}};
  wire [32:0] sum = {1'b0, a_op} + {1'b0, b_op} + {32'd0, cin};
  wire [31:0] out = sum[31:0];
  wire zero = ~|out;
  wire sign = out[31];
  // The arc's move, from S = D + mx*x + my*y at tick step 5: outward when S < 0.
  wire movex_c = xlock ? 1'b0 : (ylock ? 1'b1 : (sign == xo));
  wire c16 = out[16] ^ a_op[16] ^ b_op[16];  // carry into bit 16
  // The phase accumulator's carries: out of its top bit (PHB - 1 of the upper
  // word), or further for a rate word above the tick rate.
  wire fire = running && sq == 4'd1 && fen && (c16 || |out[15:PHB]);
  wire [15:0] wd_lo = wm == W_SWAP ? out[31:16] :
      {wm == W_MASK ? {(16 - PHB) {1'b0}} : out[15:PHB], out[PHB-1:0]};
  wire we_lo = wm != W_NONE;
  wire we_hi = wm == W_BOTH;

  // --- The state RAM -----------------------------------------------------------
  // The read addresses of the next clock's operation (the RAM registers them),
  // by the current state and step.
  reg [3:0] ra_n, rb_n;
  always @(*) begin
    {ra_n, rb_n} = {4'd1, 4'd0};
    case (st)
      ST_IDLE: {ra_n, rb_n} = {4'd1, 4'd1};  // init: a - a = 0
      ST_LOAD: {ra_n, rb_n} = {4'd0, 4'd3};
      ST_PREP:
      case (sq)
        4'd0: {ra_n, rb_n} = {4'd1, 4'd1};
        4'd1: {ra_n, rb_n} = {4'd4, 4'd4};
        4'd2: {ra_n, rb_n} = {4'd5, 4'd5};
        4'd3: {ra_n, rb_n} = {4'd6, 4'd6};
        4'd7: {ra_n, rb_n} = {4'd11, 4'd2};
        default: ;
      endcase
      default:
      case (sq)
        4'd15: {ra_n, rb_n} = {4'd11, 4'd2};
        4'd0: {ra_n, rb_n} = {4'd12, 4'd3};
        4'd1: {ra_n, rb_n} = {4'd8, 4'd4};
        4'd2: {ra_n, rb_n} = {4'd4, 4'd6};
        4'd3: {ra_n, rb_n} = {4'd5, 4'd7};
        4'd4: {ra_n, rb_n} = {4'd15, 4'd5};
        4'd6: {ra_n, rb_n} = is_line ? {4'd7, 4'd4} : {4'd8, c_addr};
        4'd7: {ra_n, rb_n} = is_line ? {4'd8, 4'd5} : {c_addr, 4'd0};
        4'd8: {ra_n, rb_n} = is_line ? {4'd9, 4'd6} : {4'd2, 4'd9};
        4'd9: {ra_n, rb_n} = is_line ? {4'd7, 4'd14} : {4'd8, c_addr};
        4'd10: {ra_n, rb_n} = is_line ? {4'd8, 4'd14} : {4'd3, 4'd13};
        4'd11: {ra_n, rb_n} = {4'd9, 4'd14};
        default: ;
      endcase
    endcase
  end

  // Two copies, one per read port. The schedule never uses a word read in
  // the clock it is written (the twin's table shows it), so the collision
  // logic Yosys would add for the read-old-data rule is not needed.
  (* no_rw_check *)
  reg [31:0] mem_a[0:15];
  (* no_rw_check *)
  reg [31:0] mem_b[0:15];
  always @(posedge clk) begin
    if (we_lo) begin
      mem_a[wa][15:0] <= wd_lo;
      mem_b[wa][15:0] <= wd_lo;
    end
    if (we_hi) begin
      mem_a[wa][31:16] <= out[31:16];
      mem_b[wa][31:16] <= out[31:16];
    end
    ra_q <= mem_a[ra_n];
    rb_q <= mem_b[rb_n];
  end

  // --- Flags ------------------------------------------------------------------
  always @(posedge clk) begin
    if (ld) begin
      if (ridx == I_HDR) begin
        typ    <= fd[SEG_H_TYPE_LSB+:2];
        last   <= fd[SEG_H_LAST];
        ccw    <= fd[SEG_H_CCW];
        plane  <= fd[SEG_H_PLANE_LSB+:2];
        nq     <= fd[SEG_H_NQ_LSB+:3];
        neg_h  <= fd[SEG_H_NEG_LSB+:3];
        ncross <= 3'd0;
      end
      if (ridx == I_N) nz <= !zero;
      if (ridx == I_A) begin
        xz <= zero;
        xn <= sign;
      end
      if (ridx == I_B) begin
        yz <= zero;
        yn <= sign;
      end
    end
    if (running) begin
      if (sq == 4'd0) fen <= !hold_i && !abort_i;
      if (sq == 4'd0 || sq == 4'd9) carry <= sum[32];
      if (sq == 4'd3) xeq <= zero;
      if (sq == 4'd4) yeq <= zero;
      if (is_line && sq >= 4'd7 && sq <= 4'd9) lmv[lax] <= sign || zero;
      if (sq == 4'd6 && go) nz <= !zero;
      if (is_arc && sq == 4'd8 && go) begin
        if (movex) begin
          xz <= zero;
          xn <= sign;
        end else begin
          yz <= zero;
          yn <= sign;
        end
        if (!outw && zero) ncross <= ncross + 3'd1;
      end
      if (sq == 4'd5) begin
        movex <= movex_c;
        negm  <= movex_c ? mxn : myn;
        outw  <= movex_c == xo;
      end
    end
  end

  // Iterations due and the tick's decision: the feed fires at step 1, the
  // tick iterates from step 5 and moves at step 13.
  wire commit = running && sq == 4'd13 && go;
  always @(posedge clk) begin
    if (rst || abort_i) begin
      pend <= 2'd0;
      go   <= 1'b0;
    end else begin
      if (fire) pend <= pend == 2'd3 ? 2'd3 : pend + 2'd1;
      if (running && sq == 4'd5 && !fin) begin
        go <= pend != 2'd0 && !hold_i;
        if (pend != 2'd0 && !hold_i) pend <= pend - 2'd1;
      end
      if (commit) go <= 1'b0;
    end
  end

  // Writer state and the sticky flags; a flag raised in the cycle of clr_i
  // stays raised.
  always @(posedge clk) begin
    if (rst) begin
      wi    <= 4'd0;
      drop  <= 1'b0;
      ovf_o <= 1'b0;
    end else begin
      if (clr_i) ovf_o <= 1'b0;
      if (abort_i) begin
        wi   <= 4'd0;
        drop <= 1'b0;
      end else if (wr_i) begin
        drop <= drop_n;
        wi   <= wi == I_LAST ? 4'd0 : wi + 4'd1;
        if (drop_n) ovf_o <= 1'b1;
      end
    end
  end

  // Init, load, prepare, run, next.
  always @(posedge clk) begin
    rv   <= rd;
    ridx <= widx;
    if (rst) begin
      st         <= ST_IDLE;
      ic         <= 3'd0;
      rv         <= 1'b0;
      seg_cnt_o  <= 16'd0;
      underrun_o <= 1'b0;
    end else begin
      if (clr_i) underrun_o <= 1'b0;
      case (st)
        ST_IDLE: begin
          if (set_i == 3'b000 && ic == INIT_STEPS && count_o >= SEGW) begin
            st   <= ST_LOAD;
            widx <= 4'd0;
          end
          if (ic != INIT_STEPS) ic <= ic + 3'd1;
        end
        ST_LOAD: begin
          if (rd) widx <= widx + 4'd1;
          if (ld && ridx == I_LAST) begin
            st <= ST_PREP;
            sq <= 4'd0;
          end
        end
        ST_PREP: begin
          if (sq == PREP_LAST) st <= ST_RUN;
          sq <= sq == PREP_LAST ? 4'd0 : sq + 4'd1;
        end
        default: begin
          sq <= sq + 4'd1;
          if (fin) begin
            st        <= ST_IDLE;
            seg_cnt_o <= seg_cnt_o + 16'd1;
            if (!last && count_o < SEGW) underrun_o <= 1'b1;
          end
        end
      endcase
      if (abort_i) begin
        st <= ST_IDLE;
        rv <= 1'b0;
      end
    end
  end

  // Position command: one count per axis per iteration, saturating (never
  // wraps), or loaded while idle.
  reg [2:0] a_mv;  // the arc's x and y on the machine axes of its plane
  always @(*) begin
    case (plane)
      2'd1:    a_mv = movex ? 3'b100 : 3'b001;  // ZX
      2'd2:    a_mv = movex ? 3'b010 : 3'b100;  // YZ
      default: a_mv = movex ? 3'b001 : 3'b010;  // XY
    endcase
  end
  wire       idle = st == ST_IDLE;
  wire [2:0] mv = idle ? jog_i : (!commit ? 3'b000 : (is_line ? lmv : (is_arc ? a_mv : 3'b000)));
  wire [2:0] neg = idle ? {3{jog_neg_i}} : (is_line ? neg_h : {3{negm}});

  genvar g;
  generate
    for (g = 0; g < 3; g = g + 1) begin : g_pos
      reg  [31:0] p;
      // +-1 as one carry chain; a step that would wrap (the sign flips away
      // from the direction of the step) is not taken.
      wire [31:0] p_n = p + {{31{neg[g]}}, 1'b1};
      wire        step = mv[g] && !(p[31] == neg[g] && p_n[31] != neg[g]);
      always @(posedge clk) begin
        if (rst) p <= 32'd0;
        else if (idle && set_i[g]) p <= set_pos_i[g*32+:32];
        else if (step) p <= p_n;
      end
      assign pos_o[g*32+:32] = p;
    end
  endgenerate

  assign busy_o = st != ST_IDLE;

endmodule
