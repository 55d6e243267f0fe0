// The interpolator's segment format. Mirrors hls/interp_seg.hpp (the
// reference, with the word-by-word table); tests/test_regs_agree.cpp checks
// that the two agree.
localparam integer SEG_WORDS = 10;
localparam integer SEG_PH_W = 48;   // feed phase accumulator bits
localparam integer SEG_N_W = 26;    // iteration counts, line deltas
localparam integer SEG_ARC_W = 23;  // arc coordinates relative to the centre
localparam integer SEG_D_W = 27;    // circle decision variable
localparam integer SEG_TICK_LOG2 = 4;  // at most one iteration per 2^this clocks
// word indices
localparam integer SEG_W_HDR = 0;
localparam integer SEG_W_N = 1;
localparam integer SEG_W_INC_LO = 2;
localparam integer SEG_W_INC_HI = 3;
localparam integer SEG_W_A = 4;
localparam integer SEG_W_B = 5;
localparam integer SEG_W_C = 6;
localparam integer SEG_W_D = 7;
localparam integer SEG_W_E = 8;
localparam integer SEG_W_K_LO = 9;
// header
localparam integer SEG_T_LINE = 0;
localparam integer SEG_T_ARC = 1;
localparam integer SEG_T_DWELL = 2;
localparam integer SEG_H_TYPE_LSB = 0;
localparam integer SEG_H_LAST = 2;
localparam integer SEG_H_CCW = 3;
localparam integer SEG_H_PLANE_LSB = 4;
localparam integer SEG_H_NQ_LSB = 6;
localparam integer SEG_H_NEG_LSB = 9;
