#!/bin/sh
# 001 Fig 6: plane, filleted end mill R 5 rc 1.5 (one tooth), tilt 1°, yaw 0, scallop 5 µm,
# 15000 rpm, the feed falling linearly from 4000 to 500 mm/min along each 10 mm pass (one
# FEDRAT per 0.25 mm move). Run from the repository root (about a minute, release build):
#   sh reports/lavernhe-fig6/regenerate.sh
# Needs python3 with numpy and matplotlib for the along-the-pass analysis.
set -eu
cargo build --release --quiet
crest=./target/release/crest
tool=samples/tools/torus-r5-rc1.5.toml
out=reports/lavernhe-fig6
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
$crest synth plane --tool $tool --tilt-deg 1 --yaw-deg 0 --scallop-um 5 \
  --feed-mm-min 4000 --feed-end-mm-min 500 --rpm 15000 --size-mm 10,5.5 --point-step-mm 0.25 \
  --clearance-mm 1 -o $out/fig6.cls --json > $out/synth.json
# The whole pass (x −4.5…4.5 mm) across one pass interval centred on the middle pass.
$crest simulate $out/fig6.cls --tool $tool --model ice --dtheta-deg 0.5 --grid-um 2 \
  --window=-4.5,-1.4,4.5,1.4 -o "$tmp/pass.gsf" --json | sed -e "s#$tmp/##" -e 's/,"time_s":[^,}]*//' > $out/simulate.json
$crest plot heightmap "$tmp/pass.gsf" -o $out/heightmap.png \
  --title "001 Fig 6: feed 4000 to 500 mm/min along the pass (x −4.5…4.5 mm)"
# Close-ups at the start, middle and end of the pass (1 mm each).
for spec in "start -4.5 -3.5" "middle -0.5 0.5" "end 3.5 4.5"; do
  set -- $spec
  $crest simulate $out/fig6.cls --tool $tool --model ice --dtheta-deg 0.5 --grid-um 2 \
    --window=$2,-1.4,$3,1.4 -o "$tmp/$1.gsf" > /dev/null
  $crest plot heightmap "$tmp/$1.gsf" -o $out/heightmap-$1.png \
    --title "001 Fig 6, $1 of the pass: x $2…$3 mm"
done
python3 $out/along.py "$tmp/pass.gsf" $out
