"""Rz along the feed and across it against the lead, per surface (reports/curvature)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

plt.rcParams["svg.hashsalt"] = "crest"  # reproducible ids

rows = list(csv.DictReader(open(sys.argv[1])))
fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)
styles = {
    ("plane", "-"): ("plane", "k", "o", "-"),
    ("convex-cylinder", "across"): ("convex R 20, curved across the feed", "tab:red", "s", "-"),
    ("concave-cylinder", "across"): ("concave R 20, curved across the feed", "tab:blue", "s", "-"),
    ("convex-cylinder", "along"): ("convex R 20, curved along the feed", "tab:red", "^", "--"),
    ("concave-cylinder", "along"): ("concave R 20, curved along the feed", "tab:blue", "^", "--"),
}
for (surface, direction), (label, colour, marker, line) in styles.items():
    sel = [r for r in rows if r["surface"] == surface and r["direction"] == direction]
    sel.sort(key=lambda r: float(r["lead_deg"]))
    x = [float(r["lead_deg"]) for r in sel]
    for ax, key in zip(axes, ["Rz_feed_um", "Rz_across_um"]):
        ax.plot(x, [float(r[key]) for r in sel], marker=marker, linestyle=line, color=colour, label=label)
axes[0].set_title("Rz along the feed (profile through the patch centre)")
axes[1].set_title("Rz across the feed (scallops between passes)")
for ax in axes:
    ax.set_xlabel("lead angle (°)")
    ax.set_ylabel("Rz (µm)")
    ax.grid(alpha=0.3)
    ax.set_xticks([5, 15, 25])
axes[1].legend(fontsize=8, loc="best")
fig.suptitle("002 tool (presetter run-out), fz 0.05 mm, ae 0.2 mm: what the geometry alone gives")
fig.tight_layout()
fig.savefig(sys.argv[2], metadata={"Date": None})  # no timestamp: regenerates byte-identical
