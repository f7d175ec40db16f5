#!/bin/sh
# The plane-sweep trials of 001 Table 2/3 and 000 Table II/III (model.md R7) through the
# whole pipeline: CLSF from `crest synth` (samples/trials/trial*-paper-step.cls, the paper's
# path intervals), parsed, resampled and simulated with the ICE model on one unit cell
# fz × s at 2 µm. Run from the repository root after `cargo build --release`:
#   sh reports/trials-r7/regenerate.sh
set -eu
crest=./target/release/crest
tool=samples/synth/torus-r5-rc1.5.toml
out=$(mktemp -d)
echo "| test | tilt/yaw | feed mm/min | step mm | nodes | Sz µm | Sq µm | Sa µm |"
echo "|---|---|---|---|---|---|---|---|"
for spec in "1 1 0 2000 0.133333 2.63" "2 1 0 4000 0.266667 2.62" "3 10 0 4000 0.266667 1.18" "4 10 20 4000 0.266667 0.43"; do
  set -- $spec
  x1=$(awk "BEGIN{print $5 - 0.002}")
  y1=$(awk "BEGIN{print $6 - 0.002}")
  $crest simulate samples/trials/trial$1-paper-step.cls --tool $tool --model ice --dtheta-deg 0.25 \
    --grid-um 2 --window=0,0,$x1,$y1 -o "$out/trial$1.gsf" --json \
  | python3 -c "import json,sys; d=json.load(sys.stdin); h=d['heights_um']; print('| $1 | $2°/$3° | $4 | $6 | %d | %.3f | %.4f | %.4f |' % (d['nodes'], h['sz'], h['sq'], h['sa']))"
done
rm -rf "$out"
