#!/usr/bin/env python3
"""001 Fig 6: feed-mark spacing and Sz along the pass of a simulated height map.

Usage: python3 along.py MAP.gsf OUT_DIR
Reads the Gwyddion .gsf written by `crest simulate` (rows = y ascending, heights in metres),
takes the row through the centre pass (y = 0), finds the crests between consecutive tooth
passes (local maxima that are the highest point within ±40 % of the local spacing, at least
5 µm apart), and writes
  OUT_DIR/along.csv  x_mm, spacing_mm, expected_mm   (one line per crest interval)
  OUT_DIR/segments.md   Sz, Sq per 1 mm segment (all rows: one pass interval across)
  OUT_DIR/along.svg  spacing and Sz against x (matplotlib).
The expected spacing is the local feed per tooth V(x)/(Z n): the feed falls from 4000 to
500 mm/min linearly over the pass x = -5..5 mm, one FEDRAT per 0.25 mm move, Z = 1,
n = 15000 rpm.
"""
import sys
import numpy as np


def read_gsf(path):
    raw = open(path, "rb").read()
    end = raw.index(b"\x00")
    head = raw[:end].decode()
    meta = {}
    for line in head.splitlines()[1:]:
        if "=" in line:
            k, v = line.split("=", 1)
            meta[k.strip()] = v.strip()
    nx, ny = int(meta["XRes"]), int(meta["YRes"])
    start = (end + 4) // 4 * 4
    z = np.frombuffer(raw[start:start + 4 * nx * ny], dtype="<f4").reshape(ny, nx)
    dx = float(meta["XReal"]) / nx
    x0 = float(meta.get("XOffset", 0.0))
    y0 = float(meta.get("YOffset", 0.0))
    dy = float(meta["YReal"]) / ny
    return z.astype(float) * 1e6, dx * 1e3, dy * 1e3, x0 * 1e3, y0 * 1e3


def feed(x):
    # The move ending at CC point i (every 0.25 mm from -5) runs at the lerp of its end.
    i = np.clip(np.ceil((x + 5.0) / 0.25 - 1e-9), 0, 40)
    return 4000.0 + (500.0 - 4000.0) * i / 40.0


def main():
    path, out = sys.argv[1], sys.argv[2]
    z, dx, dy, x0, y0 = read_gsf(path)
    ny, nx = z.shape
    x = x0 + dx * np.arange(nx)
    y = y0 + dy * np.arange(ny)
    row = z[int(np.argmin(np.abs(y))), :]
    expected = feed(x) / 15000.0
    crests = []
    for i in range(1, nx - 1):
        half = max(int(0.4 * expected[i] / dx), 2)
        lo, hi = max(0, i - half), min(nx, i + half + 1)
        if row[i] >= row[lo:hi].max() and row[i] > row[i - 1]:
            if not crests or x[i] - x[crests[-1]] > 0.005:
                crests.append(i)
    xc = x[crests]
    mid = 0.5 * (xc[1:] + xc[:-1])
    spacing = np.diff(xc)
    exp_mid = feed(mid) / 15000.0
    with open(f"{out}/along.csv", "w") as f:
        f.write("x_mm,spacing_mm,expected_mm\n")
        for a, b, c in zip(mid, spacing, exp_mid):
            f.write(f"{a:.4f},{b:.5f},{c:.5f}\n")
    segs = []
    lines = ["| segment x (mm) | mean feed (mm/min) | fz (mm) | crests | mean spacing (mm) | Sz (µm) | Sq (µm) |",
             "|---|---|---|---|---|---|---|"]
    for a in np.arange(x[0], x[-1] - 0.5, 1.0):
        m = (x >= a) & (x < a + 1.0)
        if m.sum() < 10:
            continue
        w = z[:, m]
        w = w[np.isfinite(w)]
        sz = w.max() - w.min()
        sq = np.sqrt(np.mean((w - w.mean()) ** 2))
        inseg = (mid >= a) & (mid < a + 1.0)
        sp = spacing[inseg].mean() if inseg.any() else float("nan")
        fm = feed(x[m]).mean()
        segs.append((a + 0.5, sp, sz, sq))
        lines.append(f"| {a:.1f} … {a + 1:.1f} | {fm:.0f} | {fm / 15000:.4f} | {inseg.sum()} | {sp:.4f} | {sz:.3f} | {sq:.3f} |")
    open(f"{out}/segments.md", "w").write("\n".join(lines) + "\n")
    err = np.abs(spacing - exp_mid)
    print(f"{len(crests)} crests; spacing vs local fz: max |error| {err.max() * 1e3:.2f} µm, "
          f"median {np.median(err) * 1e3:.2f} µm")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.rcParams["svg.hashsalt"] = "crest"  # reproducible ids
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    ax[0].plot(mid, spacing, ".", ms=4, label="crest spacing (simulated)")
    xs = np.linspace(x[0], x[-1], 2000)
    ax[0].plot(xs, feed(xs) / 15000.0, "-", lw=1, label="local fz = V/(Z n)")
    ax[0].set_ylabel("feed-mark spacing [mm]")
    ax[0].legend()
    s = np.array(segs)
    ax[1].plot(s[:, 0], s[:, 2], "o-", label="Sz per 1 mm segment")
    ax[1].plot(s[:, 0], s[:, 3], "s-", label="Sq per 1 mm segment")
    ax[1].set_ylabel("height [µm]")
    ax[1].set_xlabel("x along the pass [mm] (feed 4000 → 500 mm/min)")
    ax[1].legend()
    fig.suptitle("001 Fig 6: feed falling linearly along the pass")
    fig.tight_layout()
    fig.savefig(f"{out}/along.svg", metadata={"Date": None})


if __name__ == "__main__":
    main()
