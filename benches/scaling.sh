#!/bin/sh
# Scaling of `crest simulate` (issue 19): wall time against window area, path length and
# thread count, for a window, a patch and the part N-buffer (--part), with fitted exponents.
# B-SIM tool and process (ball R 5, 4 teeth, run-out 10 µm, fz 0.05, lead 15°, ICE Δθ = 1°).
# Run from the repository root after `cargo build --release` (a few minutes; python3):
#   sh benches/scaling.sh            # prints Markdown tables
# CREST=path/to/crest to time another binary; REPEAT=n (default 3) runs per point, best kept.
set -eu
crest=${CREST:-./target/release/crest}
repeat=${REPEAT:-3}
tool=samples/trials/ball-r5-z4-runout10.toml
proc=samples/process/bsim.toml
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
synth() { # kind size stepover out [extra...]
  kind=$1 size=$2 step=$3 out=$4
  shift 4
  $crest synth "$kind" --tool $tool --lead-deg 15 --stepover-mm "$step" --size-mm "$size" \
    --point-step-mm 1 --feed-mm-min 2000 --rpm 10000 -o "$out" "$@" > /dev/null
}
best() { # threads cmd... : best wall time of $repeat runs, s
  th=$1
  shift
  b=
  for _ in $(seq "$repeat"); do
    s=$(date +%s.%N)
    "$@" --threads "$th" > /dev/null
    e=$(date +%s.%N)
    b=$(python3 -c "t = $e - $s; b = '$b'; print(min(t, float(b)) if b else t)")
  done
  echo "$b"
}
row() { # series size threads seconds
  echo "$1,$2,$3,$4" >> "$tmp/rows.csv"
}
sim() { $crest simulate "$@" --tool $tool --process $proc --model ice --dtheta-deg 1 -o "$tmp/o.gsf"; }

# Window area at a fixed path (5 × 5 mm raster): sides 0.5, 1, 2, 4 mm at 1 µm.
synth plane 5,5 0.2 "$tmp/p5.cls"
for th in 1 2; do
  for side in 0.5 1 2 4; do
    h=$(python3 -c "print($side / 2)")
    t=$(best $th sim "$tmp/p5.cls" --grid-um 1 --window=-$h,-$h,$h,$h)
    row window-area "$(python3 -c "print(round(($side * 1000 + 1) ** 2))")" $th "$t"
  done
done
# Path length at a fixed window (2 × 2 mm at 1 µm): passes 3, 6, 12, 24 mm long.
for th in 1 2; do
  for len in 3 6 12 24; do
    synth plane "$len,3" 0.2 "$tmp/l$len.cls"
    t=$(best $th sim "$tmp/l$len.cls" --grid-um 1 --window=-1,-1,1,1)
    row path-length-mm "$(python3 -c "print($len * 16)")" $th "$t"
  done
done
# Path density in the window (stepover 0.4, 0.2, 0.1, 0.05 mm): cutting path inside it.
for th in 1 2; do
  for ae in 0.4 0.2 0.1 0.05; do
    synth plane 3,3 $ae "$tmp/s$ae.cls"
    t=$(best $th sim "$tmp/s$ae.cls" --grid-um 1 --window=-1,-1,1,1)
    row path-in-window-mm "$(python3 -c "print(round(2 * (2 / $ae + 1), 1))")" $th "$t"
  done
done
# Patch on the tangent plane (heights along the normal): 0.5, 1, 2 mm squares at 1 µm.
for th in 1 2; do
  for side in 0.5 1 2; do
    t=$(best $th sim "$tmp/p5.cls" --grid-um 1 --patch-near 0,0,0 --patch-mm $side,$side)
    row patch-area "$(python3 -c "print(round(($side * 1000 + 1) ** 2))")" $th "$t"
  done
done
# Part N-buffer: convex cylinder R 20 mm with its STL, heights along the part's normals.
synth convex-cylinder 5,5 0.2 "$tmp/c.cls" --surface-radius-mm 20 --stepover-along-surface \
  --part-stl "$tmp/c.stl" --part-tol-um 0.01
for th in 1 2; do
  for side in 0.5 1 2; do
    t=$(best $th sim "$tmp/c.cls" --part "$tmp/c.stl" --grid-um 1 --patch-near 0,0,0 \
      --patch-mm $side,$side)
    row part-nbuffer-area "$(python3 -c "print(round(($side * 1000 + 1) ** 2))")" $th "$t"
  done
done
python3 - "$tmp/rows.csv" <<'PY'
import math, sys
from collections import defaultdict
rows = defaultdict(list)
for line in open(sys.argv[1]):
    s, n, th, t = line.strip().split(",")
    rows[s].append((float(n), int(th), float(t)))
print("| series | size | 1 thread, s | 2 threads, s | speed-up |")
print("|---|---|---|---|---|")
fits = []
for s, pts in rows.items():
    by = defaultdict(dict)
    for n, th, t in pts:
        by[n][th] = t
    for n in sorted(by):
        t1, t2 = by[n].get(1), by[n].get(2)
        print(f"| {s} | {n:g} | {t1:.3f} | {t2:.3f} | {t1 / t2:.2f} |")
    for th in (1, 2):
        xs = [math.log(n) for n in sorted(by) if th in by[n]]
        ys = [math.log(by[n][th]) for n in sorted(by) if th in by[n]]
        k = len(xs)
        mx, my = sum(xs) / k, sum(ys) / k
        b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
        fits.append(f"| {s} | {th} | {b:.2f} |")
print()
print("| series | threads | exponent (log-log fit of wall time) |")
print("|---|---|---|")
print("\n".join(fits))
PY
