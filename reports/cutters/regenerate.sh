#!/bin/sh
# The profile figures of reports/cutters/README.md, from the repository root (after
# `cargo build --release`):
#   sh reports/cutters/regenerate.sh
set -eu
crest=target/release/crest
out=reports/cutters
for t in round-insert-r10-ri5 barrel-r8-rs250 lens-r5-rs50 oval-r5-rs20 taper-barrel-r3-rs250 \
         apt-taper-corner profile-chamfer; do
  "$crest" plot cutter --tool "samples/tools/$t.toml" -o "$out/$t.png"
done
# The APT files of samples/apt/cutters: their CUTTER/ as tool.toml would say it.
"$crest" tool --tool samples/tools/round-insert-a2.toml --lead-deg 1 --ap-mm 0.4 --fz-mm 0.4 \
  --rule exact > "$out/round-insert-a2-tool.txt"
