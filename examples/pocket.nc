(pocket.nc: a 30 x 20 mm rectangular pocket, 2 mm deep in two 1 mm passes,)
(cleared by concentric offsets 2 mm apart with a 3 mm end mill, then a finishing pass.)
G21 G90 G17 G94
M3 S15000
G0 Z5
G0 X15 Y10
G1 Z-1 F200
G1 X13 Y8 F900
G1 X17
G1 Y12
G1 X13
G1 Y8
G1 X11 Y6
G1 X19
G1 Y14
G1 X11
G1 Y6
G1 X9 Y4
G1 X21
G1 Y16
G1 X9
G1 Y4
G1 X7 Y2
G1 X23
G1 Y18
G1 X7
G1 Y2
G1 X15 Y10
G1 Z-2 F200
G1 X13 Y8 F900
G1 X17
G1 Y12
G1 X13
G1 Y8
G1 X11 Y6
G1 X19
G1 Y14
G1 X11
G1 Y6
G1 X9 Y4
G1 X21
G1 Y16
G1 X9
G1 Y4
G1 X7 Y2
G1 X23
G1 Y18
G1 X7
G1 Y2
(finishing pass along the wall, tool radius 1.5 mm inside the 30 x 20 outline)
G1 X1.5 Y1.5 F600
G1 X28.5
G1 Y18.5
G1 X1.5
G1 Y1.5
G0 Z5
M5
G0 X0 Y0
M30
