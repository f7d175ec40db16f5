#!/bin/sh
# The demo's 3-D viewer page and its screenshot (issue 21), with a profile clicked across
# the feed marks by the page's test hook. Needs Debian's `chromium`; run from the
# repository root after `cargo build --release`.
set -eu
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
target/release/crest demo -o "$tmp/demo" >/dev/null
chromium --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader \
  --disable-background-networking --disable-component-update --disable-sync --no-first-run \
  --user-data-dir="$tmp/profile" --window-size=1280,800 --hide-scrollbars \
  --screenshot=reports/viewer/demo.png \
  "file://$tmp/demo/view.html?crest-test=click:0.25,0.6,0.7,0.45" 2>/dev/null
