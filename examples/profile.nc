%
(profile.nc: the outline of a 60 x 40 mm plate with 8 mm corner radii and a)
(20 mm half-round notch in its top edge, cut 1 mm deep in one pass.)
(Machine zero is the plate's lower-left corner and its top face.)
G21 G90 G17 G94 G54
G64 P0.01
M3 S12000
G0 Z5
G0 X8 Y0
G1 Z-1 F300
G1 X52 F1200
G3 X60 Y8 I0 J8
G1 Y32
G3 X52 Y40 I-8 J0
G1 X40
G2 X20 Y40 I-10 J0
G1 X8
G3 X0 Y32 I0 J-8
G1 Y8
G3 X8 Y0 I8 J0
G0 Z5
M5
G0 X0 Y0
M30
%
