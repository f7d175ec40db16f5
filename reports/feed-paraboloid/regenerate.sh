#!/bin/sh
# Regenerates reports/feed-paraboloid/ (000 §3.1 Fig 5 and §4 Fig 11: the hyperbolic
# paraboloid at a programmed 5 m/min on the Table I machine) from the repository root:
#   sh reports/feed-paraboloid/regenerate.sh
# Needs a release build (cargo build --release) and jq. CREST overrides the binary.
set -eu
CREST=${CREST:-target/release/crest}
OUT=reports/feed-paraboloid
AC=samples/machines/table1_ac.toml
NUT=samples/machines/table1_nutating45.toml
TOOL=samples/synth/torus-r5-rc1.5.toml
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# The path: z = x·y/200 mm over 40 × 40 mm, passes along the rulings 5 mm apart, tilt 1°,
# 5 m/min, 15000 rpm, one tooth (000 §3.1 and §4).
"$CREST" synth hyperbolic-paraboloid --tool "$TOOL" --tilt-deg 1 --stepover-mm 5 \
  --feed-mm-min 5000 --rpm 15000 --point-step-mm 1 -o "$TMP/hp.cls" --json \
  | jq "del(.output)" > "$OUT/synth.json"

# Predicted feed (Level 2) on the AC table-table machine and on the 45° nutating variant.
for m in ac nutating45; do
  "$CREST" feed "$TMP/hp.cls" --machine "samples/machines/table1_$m.toml" --json -o "$TMP/feed-$m.csv" \
    | jq '{machine, total_time_s, programmed_time_s, time_ratio, self_check_ok,
           paths: [.paths[] | {name, cycles, fallbacks, stop_recoveries, branch_switches, level1_time_s}]}' \
    > "$OUT/feed-$m.json"
done

# Fig 5: the feed along the path, programmed against predicted (resampled every 0.1 mm of
# the cutting moves; the plot's abscissa is the cutting path length over all passes).
for m in ac nutating45; do
  "$CREST" resample "$TMP/hp.cls" --mode fz --fz-mm 0.1 --teeth 1 \
    --feed predicted --machine "samples/machines/table1_$m.toml" -o "$TMP/res-$m.csv" --json > /dev/null
  cut -d, -f1,19 "$TMP/res-$m.csv" > "$TMP/actual-$m.csv"
done
"$CREST" plot feed "$TMP/hp.cls" --actual "$TMP/actual-ac.csv" \
  --title "Feed along the paraboloid passes, Table I AC machine (programmed 5 m/min)" \
  -o "$OUT/fig5-feed-ac.svg"
"$CREST" plot feed "$TMP/hp.cls" --actual "$TMP/actual-nutating45.csv" \
  --title "Feed along the paraboloid passes, 45° nutating variant (programmed 5 m/min)" \
  -o "$OUT/fig5-feed-nutating45.svg"

# The feed on the middle pass (through the saddle point, y = 0), per 2 mm of the pass.
{
  echo "| x [mm] | programmed [mm/min] | predicted AC [mm/min] | predicted 45° nutating [mm/min] |"
  echo "|---|---|---|---|"
  paste -d, "$TMP/res-ac.csv" "$TMP/res-nutating45.csv" | awk -F, '
    NR > 1 && $10 != "" && $11 > -0.01 && $11 < 0.01 {
      # columns: 10 x, 11 y of the CC point; 19 feed (AC), 38 feed (nutating)
      k = int(($10 + 22) / 2); if (!(k in seen)) { seen[k] = 1;
        printf "| %.1f | 5000 | %.0f | %.0f |\n", $10, $19, $38 } }'
} > "$OUT/middle-pass-feed.md"

# Fig 11: the topography at the middle of the path, programmed against predicted feed.
for f in programmed predicted; do
  extra=""
  [ "$f" = predicted ] && extra="--machine $AC"
  # shellcheck disable=SC2086
  "$CREST" simulate "$TMP/hp.cls" --tool "$TOOL" --model ice --dtheta-deg 2 --grid-um 10 \
    --window=-2,-3,2,3 --feed "$f" $extra -o "$TMP/topo-$f.sdf" --json \
    | jq '{feed, rpm, fz_mm, nx, ny, nodes_cut, heights_um}' > "$OUT/topo-$f.json"
  "$CREST" plot heightmap "$TMP/topo-$f.sdf" \
    --title "Paraboloid, middle of the path, $f feed" -o "$OUT/fig11-topo-$f.png"
done
{
  echo "| feed | cutting time [s] | sample feed min / mean [mm/min] | Sz [µm] | Sa [µm] | Sq [µm] |"
  echo "|---|---|---|---|---|---|"
  for f in programmed predicted; do
    jq -r --arg f "$f" '"| \($f) | \(.feed.cut_time_s*1000|round/1000) | \(.feed.sample_feed_mm_min.min|round) / \(.feed.sample_feed_mm_min.mean|round) | \(.heights_um.sz*1000|round/1000) | \(.heights_um.sa*1000|round/1000) | \(.heights_um.sq*1000|round/1000) |"' \
      "$OUT/topo-$f.json"
  done
} > "$OUT/topography.md"
