#!/bin/sh
# 001 (Lavernhe et al.) §4: the 16-run design of the appendix (Fig 11) and the 6-level yaw
# design (Fig 12), each with the exact scallop steps and with convention-B steps. Run from the
# repository root (about half a minute in a release build on 2 cores):
#   sh reports/lavernhe-doe/regenerate.sh
set -eu
cargo build --release --quiet
crest=./target/release/crest
for d in doe16 yaw6 doe16-step-b yaw6-step-b; do
  $crest study samples/studies/lavernhe-$d.toml -o reports/lavernhe-doe/$d
done
