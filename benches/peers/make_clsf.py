#!/usr/bin/env python3
"""Write a large 5-axis CLSF with 12-number contact GOTOs for the parsing throughput of
issue 19 (`crest convert` / `crest inspect`; the file is not committed).

Usage: python3 benches/peers/make_clsf.py OUT.cls [MB=100]
Zig-zag passes 0.05 mm apart along x over a wavy surface, tool axis tilted 15 deg and
varying a little, contact point and surface normal on every GOTO (the layout of
samples/clsf/ball_lead15_contact.cls), a RAPID between passes.
"""
import math
import sys

out = sys.argv[1]
target = int(float(sys.argv[2] if len(sys.argv) > 2 else 100) * 1e6)
head = (
    "TOOL PATH/BIG_CONTACT,TOOL,BALL_D10\n"
    "TLDATA/MILL,10.0000,5.0000,75.0000,0.0000,0.0000\n"
    "MSYS/0.0000,0.0000,0.0000,1.0000000,0.0000000,0.0000000,0.0000000,1.0000000,0.0000000\n"
    "$$ centerline data\n"
    "$$ GOTO/x,y,z,i,j,k,cx,cy,cz,nx,ny,nz = CL (tool tip), tool axis, CC point, surface normal\n"
    "SPINDL/RPM,8000,CLW\nFEDRAT/MMPM,1200.0000\n"
)
size = 0
with open(out, "w") as f:
    f.write(head)
    size += len(head)
    p = 0
    while size < target:
        y = p * 0.3
        lines = ["RAPID\n", f"GOTO/-1.0000,{y:.4f},10.0000,0.2588190,0.0000000,0.9659258\n"]
        for k in range(2000):
            x = k * 0.05 if p % 2 == 0 else (1999 - k) * 0.05
            z = 2 * math.sin(x / 20) * math.cos(y / 15)
            gx, gy = 0.1 * math.cos(x / 20) * math.cos(y / 15), -2 / 15 * math.sin(x / 20) * math.sin(y / 15)
            n = 1 / math.sqrt(1 + gx * gx + gy * gy)
            nx_, ny_, nz_ = -gx * n, -gy * n, n
            t = math.radians(15 + 2 * math.sin(x / 7))
            i, j, kk = math.sin(t), 0.0, math.cos(t)
            lines.append(
                f"GOTO/{x + 5 * nx_ - 5 * i:.4f},{y + 5 * ny_:.4f},{z + 5 * nz_ - 5 * kk:.4f},"
                f"{i:.7f},{j:.7f},{kk:.7f},{x:.4f},{y:.4f},{z:.4f},{nx_:.7f},{ny_:.7f},{nz_:.7f}\n"
            )
        s = "".join(lines)
        f.write(s)
        size += len(s)
        p += 1
    f.write("END-OF-PATH\n")
