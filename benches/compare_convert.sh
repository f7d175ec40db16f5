#!/bin/bash
# compare_convert.sh OLD NEW FILE... : convert every FILE with two crest binaries to contact12
# CSV and to CLSF (the same output name for both, so messages compare too) and report any
# difference in exit code, messages or output bytes. Issue 19 checks that the faster
# reader and writers print exactly what they printed before:
#   benches/compare_convert.sh ./crest-old target/release/crest \
#       ../shared/samples-external/* $(find samples -type f) big.cls
set -u
A=$1; B=$2; shift 2
d=$(mktemp -d)
n=0; bad=0
for f in "$@"; do
  for ext in csv cls; do
    for who in a b; do
      bin=$A; [ $who = b ] && bin=$B
      rm -f "$d/out.$ext" "$d/$who.$ext"
      "$bin" convert "$f" -o "$d/out.$ext" > "$d/$who.msg" 2>&1
      echo $? >> "$d/$who.msg"
      [ -f "$d/out.$ext" ] && mv "$d/out.$ext" "$d/$who.$ext"
    done
    n=$((n + 1))
    if ! cmp -s "$d/a.msg" "$d/b.msg"; then
      echo "differs (exit code or messages): $f -> .$ext"; bad=$((bad + 1))
    elif [ -f "$d/a.$ext" ] || [ -f "$d/b.$ext" ]; then
      cmp -s "$d/a.$ext" "$d/b.$ext" || { echo "differs (output): $f -> .$ext"; bad=$((bad + 1)); }
    fi
  done
done
rm -rf "$d"
echo "$n conversions, $bad differing"
[ $bad -eq 0 ]
