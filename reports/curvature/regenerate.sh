#!/bin/sh
# What the geometry alone gives on curved parts (issue 15): the 002 ball end (R 5 mm, 4 teeth,
# presetter run-out 10/15/24/25 µm), fz 0.05 mm, ae 0.2 mm along the surface, leads 5/15/25°,
# on a plane and on convex and concave cylinders of radius 20 mm, with the curvature across the
# feed (passes along the cylinder axis) and along it (passes around the cylinder). Each path is
# written with its design surface (STL) by `crest synth`, simulated with the ICE model on a
# 1 × 1 mm patch at 2 µm along the part's normals (`crest simulate --part`), and measured.
# Run from the repository root (a few minutes, release build; python3 with matplotlib for the
# chart):
#   sh reports/curvature/regenerate.sh
set -eu
cargo build --release --quiet
crest=${CREST:-./target/release/crest}
tool=samples/tools/ball-r5-z4.toml
out=reports/curvature
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
rpm=2546        # 80 m/min on Ø10 mm (002 §2.6)
feed=509.2      # fz 0.05 mm × 4 teeth × 2546 rpm
echo "surface,direction,lead_deg,Sa_um,Sz_um,Rz_feed_um,Ra_feed_um,Rz_across_um,nodes_cut" > $out/results.csv
run() { # surface direction lead pass-angle
  name="$1-$2-$3"
  $crest synth "$1" --tool $tool --lead-deg "$3" --stepover-mm 0.2 --stepover-along-surface \
    --pass-angle-deg "$4" --size-mm 3,3 --point-step-mm 0.05 --feed-mm-min $feed --rpm $rpm \
    --clearance-mm 1 -o "$tmp/$name.cls" --part-stl "$tmp/$1-$4.stl" --part-tol-um 0.01 > /dev/null
  $crest simulate "$tmp/$name.cls" --tool $tool --part "$tmp/$1-$4.stl" --model ice \
    --dtheta-deg 1 --grid-um 2 --fz-mm 0.05 --patch-near 0,0,0 --patch-mm 1,1 \
    -o "$tmp/$name.gsf" --json > "$tmp/$name.json"
  areal=$($crest metrics "$tmp/$name.gsf" --params Sa,Sz --json)
  # Profiles through the patch centre: along the feed (row 250) and across it (column 250).
  feedp=$($crest metrics "$tmp/$name.gsf" --profile row:250 --params Rz,Ra --json)
  across=$($crest metrics "$tmp/$name.gsf" --profile col:250 --params Rz --json)
  python3 - "$1" "$2" "$3" "$areal" "$feedp" "$across" "$tmp/$name.json" >> $out/results.csv <<'PY'
import json, sys
s, d, lead, a, f, c, sim = sys.argv[1:8]
a, f, c = json.loads(a), json.loads(f), json.loads(c)
n = json.load(open(sim))["nodes_cut"]
print(f"{s},{d},{lead},{a['Sa']:.4f},{a['Sz']:.4f},{f['Rz']:.4f},{f['Ra']:.4f},{c['Rz']:.4f},{n}")
PY
}
for lead in 5 15 25; do
  run plane - $lead 0
  run convex-cylinder across $lead 0
  run concave-cylinder across $lead 0
  run convex-cylinder along $lead 90
  run concave-cylinder along $lead 90
done
for name in plane---15 convex-cylinder-across-15 concave-cylinder-across-15 \
  convex-cylinder-along-15 concave-cylinder-along-15; do
  $crest plot heightmap "$tmp/$name.gsf" -o "$out/$name.png" \
    --title "$name (lead 15°): heights along the normal above the design surface" > /dev/null
done
python3 $out/chart.py $out/results.csv $out/crests.svg
echo "wrote $out/results.csv, $out/crests.svg and the height maps"
