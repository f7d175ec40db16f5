#!/usr/bin/env python3
"""crest's height map against surf-topo's on the same cells (reports/surf-topo/README.md).

surf-topo writes its surface as (m+1) x (n+1) doubles, mm, x-major (cell i along x, j along
y); cell (i, j) holds the lowest edge point that fell in [i dx, (i+1) dx) x [j dy, (j+1) dy),
and points beyond the window are clamped into the last row and column, so the border cells
(i = 0, i = m, j = 0, j = n) are left out. crest's CSV (µm, rows = y ascending) carries its
spacing and origin in its `# crest height map:` line. surf-topo's spindle turns
counter-clockwise seen from +z and crest's clockwise, so the case is mirrored in x: crest
x = Lx - surf-topo x. Every crest node is put in the surf-topo cell that contains it; a cell
with several crest nodes (a finer crest grid) takes their lowest, as surf-topo does.

    python3 compare.py SURFTOPO.bin CREST.csv [--lx-mm 10 --ly-mm 5 --m 2000 --n 1000]

Prints one JSON object: compared cells, RMS/mean/max/99th percentile of crest - surf-topo
(µm), and Sa, Sq, Sz of both maps over the compared cells.
"""
import argparse
import json
import re

import numpy as np


def read_crest(path):
    with open(path) as f:
        head = f.readline()
    m = re.match(r"# crest height map: (.*?);", head)
    if not m:
        raise SystemExit(f"{path}: no '# crest height map:' line")
    meta = {k: float(v) for k, v in (kv.split("=") for kv in m.group(1).split(", "))}
    z = np.loadtxt(path, delimiter=",", comments="#")
    return z, meta


def stats(z):
    zm = z - z.mean()
    return {
        "Sa_um": float(np.abs(zm).mean()),
        "Sq_um": float(np.sqrt((zm**2).mean())),
        "Sz_um": float(z.max() - z.min()),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("surftopo")
    ap.add_argument("crest")
    ap.add_argument("--lx-mm", type=float, default=10.0)
    ap.add_argument("--ly-mm", type=float, default=5.0)
    ap.add_argument("--m", type=int, default=2000)
    ap.add_argument("--n", type=int, default=1000)
    a = ap.parse_args()
    m, n = a.m, a.n
    st = np.fromfile(a.surftopo, dtype=np.float64)
    if st.size != (m + 1) * (n + 1):
        raise SystemExit(f"{a.surftopo}: {st.size} values, expected {(m + 1) * (n + 1)}")
    st = st.reshape(m + 1, n + 1) * 1e3  # [i, j], µm
    dx, dy = a.lx_mm / m, a.ly_mm / n

    cz, meta = read_crest(a.crest)
    ny, nx = cz.shape
    x = meta["x0_mm"] + 1e-3 * meta["dx_um"] * np.arange(nx)
    y = meta["y0_mm"] + 1e-3 * meta["dy_um"] * np.arange(ny)
    ci = np.floor((a.lx_mm - x) / dx + 1e-9).astype(int)  # mirrored
    cj = np.floor(y / dy + 1e-9).astype(int)
    I, J = np.meshgrid(ci, cj)  # shape (ny, nx) like cz
    keep = np.isfinite(cz) & (I > 0) & (I < m) & (J > 0) & (J < n)
    flat = I[keep] * (n + 1) + J[keep]
    low = np.full((m + 1) * (n + 1), np.inf)
    np.minimum.at(low, flat, cz[keep])
    cells = np.unique(flat)
    b = low[cells]
    s = st.reshape(-1)[cells]
    d = b - s
    out = {
        "cells": int(cells.size),
        "crest_nodes_per_cell": round(int(keep.sum()) / cells.size, 3),
        "rms_um": float(np.sqrt((d**2).mean())),
        "mean_um": float(d.mean()),
        "max_abs_um": float(np.abs(d).max()),
        "p99_abs_um": float(np.percentile(np.abs(d), 99)),
        "surftopo": stats(s),
        "crest": stats(b),
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
