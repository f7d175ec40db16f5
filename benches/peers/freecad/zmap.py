# FreeCAD PathSimulator z-map of a 3-axis ball-end raster, headless (run by freecadcmd).
# Window 10 x 10 mm at 0.01 mm cells, ball D6, stepover 0.5 mm, 0.3 mm deep, passes along x.
# Environment: ZMAP_OUT (CSV of cell heights, optional), ZMAP_STEP (stepover, mm).
# Prints the times of the simulation (stock + tool + all moves) and of the mesh read-back.
import os
import time

import FreeCAD
import Part
import Path
import PathSimulator

R = 3.0
SIDE = 10.0
RES = 0.01
DEPTH = 0.3
STEP = float(os.environ.get("ZMAP_STEP", "0.5"))

t0 = time.perf_counter()
stock = Part.makeBox(SIDE, SIDE, 2.0, FreeCAD.Vector(0, 0, -2.0))
tool = Part.makeCylinder(R, 20.0, FreeCAD.Vector(0, 0, R)).fuse(
    Part.makeSphere(R, FreeCAD.Vector(0, 0, R))
)
sim = PathSimulator.PathSim()
sim.BeginSimulation(stock, RES)
sim.SetToolShape(tool, RES)
pos = FreeCAD.Placement(FreeCAD.Vector(-R - 0.5, 0, 5.0), FreeCAD.Rotation())
n = int(round(SIDE / STEP))
moves = 0
for k in range(n + 1):
    y = k * STEP
    for c in (
        Path.Command("G0", {"X": -R - 0.5, "Y": y, "Z": 5.0}),
        Path.Command("G0", {"X": -R - 0.5, "Y": y, "Z": -DEPTH}),
        Path.Command("G1", {"X": SIDE + R + 0.5, "Y": y, "Z": -DEPTH}),
        Path.Command("G0", {"X": SIDE + R + 0.5, "Y": y, "Z": 5.0}),
    ):
        pos = sim.ApplyCommand(pos, c)
        moves += 1
t1 = time.perf_counter()
mesh, inner = sim.GetResultMesh()
t2 = time.perf_counter()
print(f"freecad {FreeCAD.Version()[0]}.{FreeCAD.Version()[1]}.{FreeCAD.Version()[2]}: "
      f"{n + 1} passes, {moves} moves, simulate {t1 - t0:.3f} s, mesh {t2 - t1:.3f} s, "
      f"{mesh.CountPoints + inner.CountPoints} mesh points")
out = os.environ.get("ZMAP_OUT")
if out:
    # Cell heights: the stock's mesh merges cells of equal height into large facets, so
    # every upward facet is rasterised back onto the cell centres ((i + 0.5) RES).
    import numpy as np

    nc = int(round(SIDE / RES))
    c = (np.arange(nc) + 0.5) * RES
    X, Y = np.meshgrid(c, c)
    Z = np.full((nc, nc), np.nan)
    # The stock comes back as two meshes: the uncut faces and the cut ones.
    for f in list(mesh.Facets) + list(inner.Facets):
        if f.Normal.z < 0.999:
            continue
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = f.Points
        i0, i1 = (np.clip([min(ax, bx, cx) / RES - 1, max(ax, bx, cx) / RES + 1], 0, nc)).astype(int)
        j0, j1 = (np.clip([min(ay, by, cy) / RES - 1, max(ay, by, cy) / RES + 1], 0, nc)).astype(int)
        x, y = X[j0:j1, i0:i1], Y[j0:j1, i0:i1]
        det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        if abs(det) < 1e-15:
            continue
        u = ((x - ax) * (cy - ay) - (y - ay) * (cx - ax)) / det
        v = ((bx - ax) * (y - ay) - (by - ay) * (x - ax)) / det
        inside = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9)
        zz = az + u * (bz - az) + v * (cz - az)
        sub = Z[j0:j1, i0:i1]
        sub[inside] = np.fmax(sub[inside], zz[inside])
    np.savetxt(out, Z, fmt="%.6f", delimiter=",")
    levels = np.unique(np.round(Z[np.isfinite(Z)], 6))
    print(f"wrote {out}: {nc} x {nc} cells, {np.isfinite(Z).sum()} with a height, "
          f"{len(levels)} distinct heights {levels[:8]}")
