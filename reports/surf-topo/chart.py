#!/usr/bin/env python3
"""Figure of reports/surf-topo/README.md: for A2 and A3, the profile along the feed through
the tool's path (x = 5 mm) from both maps, and the map of crest - surf-topo.

    python3 chart.py SURFTOPO_MAPS_DIR CREST_MAPS_DIR OUT.png
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from compare import read_crest

M, N, LX, LY = 2000, 1000, 10.0, 5.0


def pair(st_bin, crest_csv):
    """Both maps on surf-topo's cells, crest's x mirrored back; rows y, columns x, µm."""
    st = np.fromfile(st_bin, dtype=np.float64).reshape(M + 1, N + 1).T * 1e3
    cz, meta = read_crest(crest_csv)
    assert meta["dx_um"] == 5 and meta["x0_mm"] == 0.0025 and cz.shape == (N, M)
    # crest node k (x = 0.0025 + 0.005 k) is surf-topo cell i = 1999 - k
    cr = np.full_like(st, np.nan)
    cr[:N, :M] = cz[:, ::-1]
    return st[1:N, 1:M], cr[1:N, 1:M]


def main():
    st_dir, cr_dir, out = sys.argv[1:4]
    fig, ax = plt.subplots(2, 2, figsize=(12, 7.5), width_ratios=[1.1, 1])
    for row, case in enumerate(["a2", "a3"]):
        st, cr = pair(f"{st_dir}/{case}_5um.bin", f"{cr_dir}/{case}_crest.csv")
        y = (np.arange(1, N) + 0.5) * LY / N
        col = 1000 - 1  # surf-topo cell 1000 (x = 5.0025 mm) after dropping the border
        a = ax[row, 0]
        a.plot(y, st[:, col], lw=2.2, color="tab:orange", label="surf-topo")
        a.plot(y, cr[:, col], lw=0.9, color="k", label="crest")
        a.set_xlim(1.0, 3.0)
        a.set_xlabel("y along the feed [mm]")
        a.set_ylabel("height [µm]")
        a.set_title(f"{case.upper()}: profile at x = 5 mm (2 mm of 5)")
        a.legend(loc="upper center")
        d = cr - st
        a = ax[row, 1]
        lim = float(np.nanmax(np.abs(d)))
        im = a.imshow(
            d,
            origin="lower",
            extent=(LX / M, LX - LX / M, LY / N, LY - LY / N),
            cmap="RdBu_r",
            vmin=-lim,
            vmax=lim,
            aspect="equal",
            interpolation="nearest",
        )
        rms = float(np.sqrt(np.nanmean(d**2)))
        a.set_title(f"{case.upper()}: crest − surf-topo, RMS {rms:.3f} µm")
        a.set_xlabel("x (surf-topo's frame) [mm]")
        a.set_ylabel("y [mm]")
        fig.colorbar(im, ax=a, label="µm", shrink=0.8)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main()
