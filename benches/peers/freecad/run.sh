#!/bin/sh
# FreeCAD PathSimulator z-map against crest's dome model on the same raster and grid, side by
# side (alternating runs), then both height maps against the exact scallop of the raster.
# Run from the repository root: sh benches/peers/freecad/run.sh   (RUNS=n, default 3)
set -eu
crest=${CREST:-./target/release/crest}
dir=benches/peers/freecad
runs=${RUNS:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 $dir/raster_cls.py "$tmp/raster.cls"
uptime
for i in $(seq "$runs"); do
  /usr/bin/time -f "freecadcmd whole process: %e s wall, %U s user, %M KB" \
    freecadcmd $dir/zmap.py 2>&1 | grep -a -o "freecad 0.*\|freecadcmd whole.*"
  /usr/bin/time -f "crest whole process: %e s wall, %U s user, %M KB" \
    $crest simulate "$tmp/raster.cls" --tool $dir/ball-r3.toml --rpm 10000 --feed-mm-min 200 \
    --model dome --grid-um 10 --window=0.005,0.005,9.995,9.995 -o "$tmp/crest.gsf" 2>&1
  # The same with a mesh as coarse as FreeCAD's heights are fine (1 µm chord, 10 µm cells)
  # and a first band above the 10.4 µm scallop (so that no tile is computed twice).
  /usr/bin/time -f "crest --chord-tol-um 1 --band-um 15 whole process: %e s wall, %U s user, %M KB" \
    $crest simulate "$tmp/raster.cls" --tool $dir/ball-r3.toml --rpm 10000 --feed-mm-min 200 \
    --model dome --grid-um 10 --window=0.005,0.005,9.995,9.995 --chord-tol-um 1 --band-um 15 \
    -o "$tmp/crest.gsf" 2>&1
  # The swept-ball model: FreeCAD's own ground (the tool body swept along each move, no
  # teeth), with exact float heights.
  /usr/bin/time -f "crest --model swept whole process: %e s wall, %U s user, %M KB" \
    $crest simulate "$tmp/raster.cls" --tool $dir/ball-r3.toml --rpm 10000 --feed-mm-min 200 \
    --model swept --grid-um 10 --window=0.005,0.005,9.995,9.995 --band-um 15 \
    -o "$tmp/crest.gsf" 2>&1
done
uptime
# Heights: FreeCAD's absolute z (mm), crest's above the nominal plane z = -0.3 (µm).
ZMAP_OUT="$tmp/freecad.csv" freecadcmd $dir/zmap.py 2>&1 | grep -a -o "wrote.*"
$crest simulate "$tmp/raster.cls" --tool $dir/ball-r3.toml --rpm 10000 --feed-mm-min 200 \
  --model dome --grid-um 10 --window=0.005,0.005,9.995,9.995 -o "$tmp/crest.csv" > /dev/null
$crest simulate "$tmp/raster.cls" --tool $dir/ball-r3.toml --rpm 10000 --feed-mm-min 200 \
  --model dome --grid-um 10 --window=0.005,0.005,9.995,9.995 --chord-tol-um 1 --band-um 15 \
  -o "$tmp/coarse.csv" > /dev/null
$crest simulate "$tmp/raster.cls" --tool $dir/ball-r3.toml --rpm 10000 --feed-mm-min 200 \
  --model swept --grid-um 10 --window=0.005,0.005,9.995,9.995 --band-um 15 \
  -o "$tmp/swept.csv" > /dev/null
python3 - "$tmp/freecad.csv" "$tmp/crest.csv" "$tmp/coarse.csv" "$tmp/swept.csv" <<'PY'
import sys
import numpy as np
fc = np.loadtxt(sys.argv[1], delimiter=",")
cr = np.loadtxt(sys.argv[2], delimiter=",", comments="#")
co = np.loadtxt(sys.argv[3], delimiter=",", comments="#")
sw = np.loadtxt(sys.argv[4], delimiter=",", comments="#")
c = (np.arange(1000) + 0.5) * 0.01
dy = np.abs(c - np.round(c / 0.5) * 0.5)          # distance to the nearest pass
exact = (3.0 - np.sqrt(9.0 - dy ** 2)) * 1e3      # scallop above z = -0.3, µm
exact = np.repeat(exact[:, None], 1000, axis=1)    # rows = y
for name, z in (("freecad", (fc + 0.3) * 1e3), ("crest", cr), ("crest coarse", co), ("crest swept", sw)):
    e = z - exact
    print(f"{name}: {len(np.unique(np.round(z, 6)))} distinct heights, error vs exact "
          f"mean {e.mean():+.3f} µm, max |e| {np.abs(e).max():.3f} µm, rms {np.sqrt((e**2).mean()):.3f} µm")
PY
