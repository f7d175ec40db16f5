#!/bin/sh
# 001 Fig 7: the extruded parabola z = −0.004·x² + 0.1 mm (along y), filleted end mill R 5
# rc 1.5 (one tooth), tilt 5°, yaw 0, scallop 10 µm, 5000 mm/min, 15000 rpm, parallel drive
# planes at 45° in the XY plane, one-way. Run from the repository root (under a minute,
# release build):
#   sh reports/lavernhe-fig7/regenerate.sh
set -eu
cargo build --release --quiet
crest=./target/release/crest
tool=samples/tools/torus-r5-rc1.5.toml
out=reports/lavernhe-fig7
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
$crest synth extruded-parabola --tool $tool --tilt-deg 5 --yaw-deg 0 --scallop-um 10 \
  --pass-angle-deg 45 --feed-mm-min 5000 --rpm 15000 --size-mm 14,14 --point-step-mm 0.25 \
  --clearance-mm 1 -o $out/fig7.cls --json > $out/synth.json
# A 3 × 3 mm window of the WCS xy plane at the top of the parabola and one at x = 4 mm
# (surface slope 1.8°); heights above the nominal surface (from the contact data).
for spec in "top -1.5 -1.5 1.5 1.5" "x4 2.5 -1.5 5.5 1.5"; do
  set -- $spec
  $crest simulate $out/fig7.cls --tool $tool --model ice --dtheta-deg 0.5 --grid-um 2 \
    --window=$2,$3,$4,$5 -o "$tmp/$1.gsf" --json | sed -e "s#$tmp/##" -e 's/,"time_s":[^,}]*//' > $out/simulate-$1.json
  $crest plot heightmap "$tmp/$1.gsf" -o $out/heightmap-$1.png \
    --title "001 Fig 7: extruded parabola, passes at 45°, x $2…$4 mm, y $3…$5 mm"
  $crest metrics "$tmp/$1.gsf" --params Sz,Sq,Sa,Ssk,Sku,Sal,Str,Std --json | sed "s#$tmp/##" > $out/metrics-$1.json
done
