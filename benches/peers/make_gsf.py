#!/usr/bin/env python3
"""Write an N x N Gwyddion Simple Field (.gsf) for the metrics comparison (not committed).

Usage: python3 benches/peers/make_gsf.py OUT.gsf [N=4000]
A rough anisotropic surface: two sine lays plus seeded Gaussian noise, about 1 um high,
dx = dy = 0.5 um, heights in metres as float32 (what `crest metrics` and the C peer read).
"""
import sys

import numpy as np

out = sys.argv[1]
n = int(sys.argv[2]) if len(sys.argv) > 2 else 4000
dx = 0.5e-6
x = np.arange(n, dtype=np.float64) * dx
rng = np.random.default_rng(19)
z = np.empty((n, n), dtype=np.float32)
for r in range(n):
    y = r * dx
    z[r] = (
        0.8e-6 * np.sin(2 * np.pi * x / 60e-6 + 0.3 * np.sin(2 * np.pi * y / 400e-6))
        + 0.2e-6 * np.cos(2 * np.pi * y / 25e-6)
        + 0.05e-6 * rng.standard_normal(n)
        + 0.02e-6 * (x / (n * dx))
    ).astype(np.float32)
h = (
    "Gwyddion Simple Field 1.0\n"
    f"XRes = {n}\nYRes = {n}\nXReal = {n * dx:e}\nYReal = {n * dx:e}\n"
    "XYUnits = m\nZUnits = m\nTitle = issue 19 metrics field\n"
)
pad = 4 - len(h) % 4
with open(out, "wb") as f:
    f.write(h.encode())
    f.write(b"\0" * pad)
    f.write(z.astype("<f4").tobytes())
