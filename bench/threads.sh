#!/usr/bin/env bash
# Threads of one run (README, "Threads"): the stiff cube on CHOLMOD (bench/auto_solver.sh's UNH
# lambda = 9900 Pa, 8 ms) and the 13^3 pinned cube on PCG, each with OpenMP on every core and
# OpenBLAS on every core (OPENBLAS_NUM_THREADS = nproc), with isochor's default (OpenBLAS on one
# thread), and on one thread everywhere. The settings interleave within each round; prints the
# median wall seconds over the rounds. With "busy", a one-thread run of the 18^3 pinned cube keeps
# the last core busy throughout.
#   bench/threads.sh [build] [rounds] [idle|busy]      (default: build 3 idle)
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
mode=${3:-idle}
cd "$(dirname "$0")/.."
out=out/bench/threads
mkdir -p "$out"
last=$(( $(nproc) - 1 ))
neighbour=
if [[ $mode == busy ]]; then
  ( while true; do OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 taskset -c "$last" "$build/isochor" run demos/pinned_cube.toml \
      --set mesh.cells=18 -q --overwrite -o "$out/neighbour.h5" > /dev/null 2>&1; done ) &
  neighbour=$!
  trap 'kill $neighbour 2>/dev/null; pkill -f "$out/neighbour.h5" || true' EXIT
  sleep 2
fi
stiff=(demos/cube_gravity.toml --set frames.duration=0.5 --set integrator.kind=backward_euler --set zones.global=false
       --set material.model=unh --set material.lambda=9900 --set integrator.dt=0.008 --set integrator.linear_solver=reduced)
pinned=(demos/pinned_cube.toml --set mesh.cells=13)
for ((r = 1; r <= rounds; r++)); do
  for c in stiff pinned; do
    if [[ $c == stiff ]]; then args=("${stiff[@]}"); else args=("${pinned[@]}"); fi
    env -u OMP_NUM_THREADS OPENBLAS_NUM_THREADS="$(nproc)" "$build/isochor" run "${args[@]}" -q --overwrite -o "$out/${c}_blas_r$r.h5" > /dev/null
    env -u OMP_NUM_THREADS -u OPENBLAS_NUM_THREADS "$build/isochor" run "${args[@]}" -q --overwrite -o "$out/${c}_default_r$r.h5" > /dev/null
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run "${args[@]}" -q --overwrite -o "$out/${c}_one_r$r.h5" > /dev/null
  done
done
/usr/bin/python3 - "$out" "$rounds" "$mode" <<'PY'
import sys, h5py, numpy as np
out, rounds, mode = sys.argv[1], int(sys.argv[2]), sys.argv[3]
print(f"wall seconds, medians over {rounds} rounds, machine {mode}")
print("| case | OpenMP + OpenBLAS on every core | default (OpenBLAS on one) | one thread |")
print("|---|---|---|---|")
for c, name in (("stiff", "stiff cube, CHOLMOD"), ("pinned", "13^3 pinned cube, PCG")):
    m = [float(np.median([h5py.File(f"{out}/{c}_{s}_r{r}.h5", "r")["/stats"].attrs["wall_seconds"]
                          for r in range(1, rounds + 1)])) for s in ("blas", "default", "one")]
    print(f"| {name} | {m[0]:.2f} | {m[1]:.2f} | {m[2]:.2f} |")
PY
