#!/bin/sh
# A worked `crest compare` (issue 34 §2): a prediction against a "measurement" made from a
# simulated surface with known perturbations, written as .x3p. From the repository root
# (a few seconds, release build):
#   sh reports/compare/regenerate.sh
# Needs python3 (standard library only) for the microscope's tilt, noise and missing points.
#
# Prediction: ball end R 5 mm, 4 teeth without run-out, tilt 10°, scallop 2 µm, fz 0.15 mm
# (6000 mm/min at 10000 rpm), passes along x; 1.2 × 1.2 mm at 2 µm.
# Measurement: the same program with the passes turned 4° and a tool whose teeth 2 and 4 sit
# 3 µm short (feed marks 0.3 mm apart instead of 0.15 mm), a 0.8 × 0.8 mm window moved by
# (+30, −30) µm from the centre, a tilt, noise σ 0.05 µm and 1 % missing points plus a
# drop-out streak.
set -eu
cargo build --release --quiet
crest=./target/release/crest
out=reports/compare
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
common="--tilt-deg 10 --scallop-um 2 --feed-mm-min 6000 --rpm 10000 --size-mm 4,3 --point-step-mm 0.25 --clearance-mm 1"
$crest synth plane --tool $out/tool-nominal.toml $common -o "$tmp/pred.cls" > /dev/null
$crest synth plane --tool $out/tool-nominal.toml $common --pass-angle-deg 4 -o "$tmp/meas.cls" > /dev/null
$crest simulate "$tmp/pred.cls" --tool $out/tool-nominal.toml --model ice --grid-um 2 \
  --window=-0.6,-0.6,0.6,0.6 -o "$tmp/predicted.x3p" > /dev/null
$crest simulate "$tmp/meas.cls" --tool $out/tool-measured.toml --model ice --grid-um 2 \
  --window=-0.37,-0.43,0.43,0.37 -o "$tmp/clean.x3p" > /dev/null
python3 $out/perturb.py "$tmp/clean.x3p" "$tmp/measured.x3p"
# The measurement's own parameters, as a microscope's software would report them.
$crest metrics "$tmp/measured.x3p" --level plane --params Sa,Sq,Sz,Sdq,Sal,Std > $out/metrics.txt
sed -i "s#$tmp/##" $out/metrics.txt
# Exit 1 by design: the run-out the prediction leaves out shows (feed-mark period, Sz).
rm -rf "$tmp/cmp"
$crest compare "$tmp/predicted.x3p" "$tmp/measured.x3p" -o "$tmp/cmp" --json > "$tmp/compare.json" || test $? -eq 1
for f in "$tmp"/cmp/*; do
  sed -e "s#$tmp/cmp#$out#g" -e "s#$tmp/##g" "$f" > "$out/$(basename "$f")"
done
sed -e "s#$tmp/cmp#$out#g" -e "s#$tmp/##g" "$tmp/compare.json" > $out/compare.json
