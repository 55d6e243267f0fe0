(drill.nc: a 4 x 3 pattern of 3 mm holes on a 10 mm pitch, as the 3-axis)
(drill of the source documents runs it: G81 for the 4 mm deep row, G83 with)
(1.5 mm pecks for the 8 mm deep rows, retracting to R between holes.)
G21 G90 G17 G94
M3 S8000
G0 Z10
G99
G81 X10 Y10 Z-4 R2 F250
X20
X30
X40
G83 X10 Y20 Z-8 R2 Q1.5 F200
X20
X30
X40
G98
G83 X10 Y30 Z-8 R2 Q1.5 F200
X20
X30
X40
G80
G0 Z10
M5
G0 X0 Y0
M30
