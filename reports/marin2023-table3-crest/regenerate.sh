#!/bin/sh
# Regenerates reports/marin2023-table3-crest/ (002 Table 3, Eq 14, Eqs 7-8, Fig 14) from the
# repository root:
#   sh reports/marin2023-table3-crest/regenerate.sh
# Needs a release build (cargo build --release) and jq. CREST overrides the binary.
set -eu
CREST=${CREST:-target/release/crest}
OUT=reports/marin2023-table3-crest
TOOL=samples/tools/ball-r5-z4.toml
for lead in 5 15 25; do
  "$CREST" tool --tool "$TOOL" --lead-deg "$lead" --ap-mm 0.4 --fz-mm 0.05 --rule paper --json > "$OUT/tool-lead$lead.json"
  "$CREST" tool --tool "$TOOL" --lead-deg "$lead" --ap-mm 0.4 --fz-mm 0.05 --rule exact --json > "$OUT/tool-lead$lead-exact.json"
done
"$CREST" plot trochoid --tool "$TOOL" --lead-deg 5,15,25 --fz-mm 0.2 --crest-fz-mm 0.05,0.2 \
  -o "$OUT/fig14-trochoid.svg" --json > "$OUT/fig14-trochoid.json"

# Table 3 as crest computes it: R_ef (R = 5), Vc %, then R_ef / error % for each tooth.
{
  echo "| lead | R_ef (R=5) [mm] | Vc,ef [%] | R_ef Rt=4.990 / err % | 4.985 | 4.976 | 4.975 |"
  echo "|---|---|---|---|---|---|---|"
  for lead in 5 15 25; do
    jq -r '"| \(.lead_deg)° | \(.effective_radius_mm*1e5|round/1e5) | \(.cutting_speed_pct*1e3|round/1e3) | " +
      ([.teeth[] | "\(.effective_radius_mm*1e5|round/1e5) / \(.effective_radius_error_pct*1e5|round/1e5)"] | join(" | ")) + " |"' \
      "$OUT/tool-lead$lead.json"
  done
} > "$OUT/table3.md"

# Eq 14 and Eqs 7-8 per lead, paper rule and exact envelope.
{
  echo "| lead | hc(fz = 0.05) [µm] | teeth (paper rule) | zc | fz_eff [mm] | hc(fz_eff) [µm] | teeth (exact) | exact crest [µm] |"
  echo "|---|---|---|---|---|---|---|---|"
  for lead in 5 15 25; do
    jq -r --slurpfile x "$OUT/tool-lead$lead-exact.json" '"| \(.lead_deg)° | \(.crest_height_um*1e7|round/1e7) | \(.participating_teeth) | \(.zc) | \(.fz_effective_mm) | \(.crest_height_corrected_um*1e7|round/1e7) | \($x[0].participating_teeth) | \(.crest_height_exact_um*1e4|round/1e4) |"' \
      "$OUT/tool-lead$lead.json"
  done
} > "$OUT/eq14.md"
