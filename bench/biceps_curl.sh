#!/usr/bin/env bash
# What contraction costs: demos/biceps_curl.toml with its biceps active (the demo) against the same
# scene passive (muscles.activation_scale = 0: the fibre terms are still assembled, at activation
# 0), and against the arm without muscles at all (demos/arm_muscles.toml's scene: its [[muscle]]
# tables removed). Rounds interleaved, one thread; wall seconds and the assembly's share, medians.
#   bench/biceps_curl.sh [build] [duration_s] [rounds]
set -euo pipefail
build=${1:-build}
duration=${2:-0.5}
rounds=${3:-3}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
/usr/bin/python3 - "$tmp" <<'PY'
import re, sys
t = open("demos/biceps_curl.toml").read().replace('"meshes/', '"' + __import__("os").path.abspath("demos/meshes") + "/")
open(f"{sys.argv[1]}/muscles.toml", "w").write(t)
bare = re.sub(r"\[\[muscle\]\].*?(?=\n\[)", "", t, flags=re.S)
assert "[[muscle]]" not in bare
open(f"{sys.argv[1]}/bare.toml", "w").write(bare)
PY
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
run() {  # scene, out, settings... -> "wall assembly"
  local scene=$1 out=$2; shift 2
  OMP_NUM_THREADS=1 "$build/isochor" run "$tmp/$scene.toml" --overwrite -q -o "$tmp/$out.h5" \
    --set frames.duration="$duration" "$@" > /dev/null
  PYTHONPATH=python /usr/bin/python3 -c "
import isochor, sys
with isochor.open(sys.argv[1]) as r: print(r.totals['wall_seconds'], r.totals['assembly_seconds'])" "$tmp/$out.h5"
}
for i in $(seq "$rounds"); do
  run muscles active >> "$tmp/active.txt"
  run muscles passive --set muscles.activation_scale=0 >> "$tmp/passive.txt"
  run bare bare >> "$tmp/bare.txt"
done
printf "%-10s %10s %12s\n" case wall_s assembly_s
for c in active passive bare; do
  printf "%-10s %10.2f %12.2f\n" "$c" "$(cut -d' ' -f1 < "$tmp/$c.txt" | median)" "$(cut -d' ' -f2 < "$tmp/$c.txt" | median)"
done
a=$(cut -d' ' -f1 < "$tmp/active.txt" | median)
p=$(cut -d' ' -f1 < "$tmp/passive.txt" | median)
b=$(cut -d' ' -f1 < "$tmp/bare.txt" | median)
printf "active / passive %.2f, active / no muscles %.2f (medians of %s rounds, %s s of the curl)\n" \
  "$(echo "$a / $p" | bc -l)" "$(echo "$a / $b" | bc -l)" "$rounds" "$duration"
