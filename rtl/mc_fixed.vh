// Fixed-point widths of the MotionCore datapath. Mirrors hls/mc_fixed.hpp
// (the one place the formats are defined); tests/test_regs_agree.cpp checks
// that the two agree.
localparam integer MC_POS_W     = 32;  // positions, errors: counts
localparam integer MC_OUT_W     = 16;  // controller output: drive units
localparam integer MC_ACC_W     = 50;  // accumulator Q17.32
localparam integer MC_ACC_FRAC  = 32;
localparam integer MC_COEF_M_W  = 24;  // coefficient mantissa
localparam integer MC_COEF_S_W  = 6;   // coefficient shift
localparam integer MC_MUL_X_W   = 32;  // multiplier data operand
localparam integer MC_D_OPER_FRAC = 15; // derivative state as operand: Q17.15
