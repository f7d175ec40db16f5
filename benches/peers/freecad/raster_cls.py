#!/usr/bin/env python3
"""Write the FreeCAD peer's raster as an NX-style CLSF with contact data for crest.

Ball D6, passes along +x over a 10 x 10 mm window from x = -3.5 to 13.5 mm, stepover 0.5 mm
(or argv[2]), tip 0.3 mm below the top z = 0: the nominal surface is the plane z = -0.3.
Usage: raster_cls.py OUT.cls [STEPOVER_MM]
"""
import sys

R, SIDE, DEPTH = 3.0, 10.0, 0.3
out = sys.argv[1]
step = float(sys.argv[2]) if len(sys.argv) > 2 else 0.5
n = int(round(SIDE / step))
x0, x1 = -R - 0.5, SIDE + R + 0.5
with open(out, "w") as f:
    f.write("TOOL PATH/FREECAD_PEER,TOOL,BALL_D6\n")
    f.write(f"TLDATA/MILL,{2 * R:.4f},{R:.4f},75.0000,0.0000,0.0000\n")
    f.write("SPINDL/RPM,10000.0000,CLW\n")
    for k in range(n + 1):
        y = k * step
        f.write(f"RAPID\nGOTO/{x0:.4f},{y:.4f},5.0000\n")
        f.write("FEDRAT/MMPM,200.0000\n")
        for x in (x0, x1):
            z = -DEPTH
            f.write(
                f"GOTO/{x:.4f},{y:.4f},{z:.4f},0.0,0.0,1.0,"
                f"{x:.4f},{y:.4f},{z:.4f},0.0,0.0,1.0\n"
            )
        f.write(f"RAPID\nGOTO/{x1:.4f},{y:.4f},5.0000\n")
    f.write("END-OF-PATH\n")
