#!/bin/sh
# Regenerates the paper reproductions under reports/ that have a script, from the repository
# root:
#   sh reports/regenerate.sh
set -eu
cargo build --release
sh reports/marin2023-table3-crest/regenerate.sh
