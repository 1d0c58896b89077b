#!/usr/bin/env bash
# What CNH's default zones cost in dynamics: demos/ball_drop.toml (4,700 tets) through its impact
# (frames.duration = 0.06 s) with the CNH paper's global zone (zones.default = "global") and with
# the default 2-ring patches, on IDA with `krylov` and `reduced`. One thread, wall seconds of the
# solver, medians of the rounds with the cases interleaved; steps and the number of zones.
# Writes docs/results/infsup/default_zones.csv.
#   bench/default_zones.sh [build] [rounds] [csv]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
csv=${3:-docs/results/infsup/default_zones.csv}
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
for ((k = 0; k < rounds; ++k)); do
  for ls in krylov reduced; do
    for z in global patches; do
      bench_run default_zones demos/ball_drop.toml --set zones.default=$z frames.duration=0.06 integrator.linear_solver=$ls
      /usr/bin/python3 - out/bench/default_zones.h5 "$z" "$ls" >> "$tmp" <<'PY'
import sys, h5py
f = h5py.File(sys.argv[1], "r")
s = f["/stats"].attrs
print(f"{sys.argv[2]},{sys.argv[3]},{len(f['/zones'])},{s['wall_seconds']:.3f},{s['steps']:.0f},{s['newton_iterations']:.0f}")
PY
    done
  done
done
echo "zones,solver,zone_count,wall_s,steps,newton" > "$csv"
median_rows "$tmp" 2 3 >> "$csv"
column -s, -t "$csv"
