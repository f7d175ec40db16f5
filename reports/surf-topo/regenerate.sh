#!/bin/sh
# crest on surf-topo's published cases A2 and A3 (reports/surf-topo/README.md), from the
# repository root after `cargo build --release`:
#   sh reports/surf-topo/regenerate.sh
# crest's maps go to $OUT (default: a temporary folder; 2 M nodes each, not committed). The
# comparison needs surf-topo's own maps, a2_5um.bin and a3_5um.bin, in $SURFTOPO_MAPS
# (fetching and running surf-topo is the user's step, see the README); without them it is
# skipped and the script still succeeds.
set -eu
crest=target/release/crest
here=reports/surf-topo
out=${OUT:-$(mktemp -d)}
window=0.0025,0.0025,9.9975,4.9975
"$crest" simulate "$here/a2.cls" --tool samples/tools/round-insert-a2.toml \
  --window "$window" --grid-um 5 --ap-mm 0.4 -o "$out/a2_crest.csv" --json > "$out/a2_crest.json"
"$crest" simulate "$here/a3.cls" --tool samples/tools/round-insert-a3.toml \
  --window "$window" --grid-um 5 --ap-mm 0.3 -o "$out/a3_crest.csv" --json > "$out/a3_crest.json"
echo "crest maps in $out"
maps=${SURFTOPO_MAPS:-}
if [ -z "$maps" ] || [ ! -f "$maps/a2_5um.bin" ] || [ ! -f "$maps/a3_5um.bin" ]; then
  echo "surf-topo maps not found (set SURFTOPO_MAPS to the folder with a2_5um.bin and a3_5um.bin): comparison skipped"
  exit 0
fi
for c in a2 a3; do
  python3 "$here/compare.py" "$maps/${c}_5um.bin" "$out/${c}_crest.csv" > "$here/${c}-compare.json"
  cat "$here/${c}-compare.json"
done
python3 "$here/chart.py" "$maps" "$out" "$here/profiles.png"
