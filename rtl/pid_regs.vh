// Register addresses of pid_core's configuration port.
// Mirrors hls/pid_regs.hpp; tests/test_regs_agree.cpp checks they agree.
// Address = {axis[3:0], reg[3:0]}; axis 15 selects the global registers.
localparam [3:0] PID_REG_KP    = 4'h0;
localparam [3:0] PID_REG_KI    = 4'h1;
localparam [3:0] PID_REG_KD_A  = 4'h2;
localparam [3:0] PID_REG_KD_B  = 4'h3;
localparam [3:0] PID_REG_KF1   = 4'h4;
localparam [3:0] PID_REG_KF2   = 4'h5;
localparam [3:0] PID_REG_ILIM  = 4'h6;
localparam [3:0] PID_REG_OLIM  = 4'h7;
localparam [3:0] PID_REG_DBAND = 4'h8;
localparam [3:0] PID_REG_ELIM  = 4'h9;
localparam [3:0] PID_REG_CTRL  = 4'hF;
localparam [3:0] PID_NREGS_RAM = 4'hA;
localparam [3:0] PID_GLOBAL_AXIS = 4'hF;
localparam [3:0] PID_G_TS      = 4'h0;
localparam [3:0] PID_G_LATENCY = 4'h1;
localparam [3:0] PID_G_NAXES   = 4'h2;
