#!/usr/bin/env python3
"""Writes examples/surface.nc: a 3D surface finished by raster, the kind of
program a CAM system emits for a relief: many short G1 moves.

z(x, y) = -1 + 0.6 cos(2 pi x / 20) cos(2 pi y / 10), over 20 x 10 mm, raster
rows along X every 0.2 mm, points every 0.1 mm: 51 rows of 200 moves, 10,200
moves of at most 0.1 mm at F3000.

    python3 examples/make_surface.py > examples/surface.nc
"""
import math

W, H, DX, DY, F = 20.0, 10.0, 0.1, 0.2, 3000


def z(x, y):
    return -1 + 0.6 * math.cos(2 * math.pi * x / W) * math.cos(2 * math.pi * y / H)


def main():
    print("(surface.nc: a raster finish of z = -1 + 0.6 cos[2 pi x/20] cos[2 pi y/10] over 20 x 10 mm)")
    print("(written by examples/make_surface.py: 51 rows of 200 moves of 0.1 mm at F3000)")
    print("G21 G90 G17 G94 G64")
    print("M3 S18000")
    print("G0 Z2")
    print("G0 X0 Y0")
    print("G1 Z%.4f F600" % z(0, 0))
    rows = int(round(H / DY)) + 1
    cols = int(round(W / DX))
    for r in range(rows):
        y = r * DY
        if r > 0:
            x = 0.0 if r % 2 == 0 else W
            print("G1 Y%.4f Z%.4f" % (y, z(x, y)))
        for c in range(1, cols + 1):
            x = c * DX if r % 2 == 0 else W - c * DX
            line = "X%.4f Z%.4f" % (x, z(x, y))
            print(("G1 " + line + " F%d" % F) if (r == 0 and c == 1) else line)
    print("G0 Z2")
    print("M5")
    print("G0 X0 Y0")
    print("M30")


main()
