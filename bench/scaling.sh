#!/usr/bin/env bash
# One scene's cost against its mesh: the damped ball (demos/ball_drop.toml, Rayleigh
# beta = 1e-4 s) at ~1K, 4.5K, 16K and 64K tets (add 250000 1000000 as arguments for the rest of
# the curve: hours), through its impact (50 ms: the impact at 30 ms, 20 ms of contact), with
# linear_solver = krylov and reduced, the two solvers side by side (one thread each), then
# tools/scaling_report.py: per step, per Newton iteration and per frame wall time, CG iterations
# per Newton iteration, peak memory, and the fitted exponent of each against the tets, with a
# log-log chart (docs/results/scaling.md, docs/results/scaling.png).
# DURATION (default 0.05 s), SOLVERS (default "krylov reduced") and NAME (default scaling) change
# the window, the solvers and the report's file name; a run stopped past DURATION (Ctrl-C: the 1M-tet
# ball) is read up to its frame at DURATION (tools/scaling_report.py --until).
#   bench/scaling.sh [BUILD] [TETS ...]
#   DURATION=0.033 SOLVERS=krylov NAME=scaling_33ms bench/scaling.sh build 1000 4500 16000 64000 250000 1000000
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
sizes=("${@:-1000 4500 16000 64000}")
duration=${DURATION:-0.05}
solvers=${SOLVERS:-"krylov reduced"}
name=${NAME:-scaling}
out=out/bench/$name
mkdir -p "$out"
for tets in ${sizes[*]}; do
  for ls in $solvers; do
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/ball_drop.toml -q --overwrite \
      -o "$out/ball_${tets}_$ls.h5" --set mesh.target_tets=$tets --set integrator.linear_solver=$ls \
      --set frames.duration="$duration" > "$out/ball_${tets}_$ls.log" 2>&1 &
  done
  wait
  echo "scaling: $tets tets done"
done
/usr/bin/python3 tools/scaling_report.py "$out" docs/results --until "$duration" --name "$name"
