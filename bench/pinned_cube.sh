#!/usr/bin/env bash
# The stable neo-Hookean test scene (demos/pinned_cube.toml, 13.2K tets, 120 frames at 60 fps):
# backward Euler at h = 1/60 s and IDA (rtol 1e-6), each on one and on two threads (OpenMP and
# OpenBLAS alike), run one after another in rounds so that machine noise spreads over all. Prints
# the median wall time per frame of each, and its ratio to the 185 ms per frame a public reference
# implementation (Eigen, conjugate gradients, one thread) takes on this machine.
#   bench/pinned_cube.sh [build] [rounds] [duration]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
duration=${3:-2.0}
cd "$(dirname "$0")/.."
mkdir -p out/bench
for r in $(seq 1 "$rounds"); do
  for threads in 1 2; do
    for kind in backward_euler ida; do
      OMP_NUM_THREADS=$threads OPENBLAS_NUM_THREADS=$threads "$build/isochor" run demos/pinned_cube.toml --overwrite -q \
        --set integrator.kind=$kind --set frames.duration="$duration" -o "out/bench/pinned_${kind}_t${threads}_r$r.h5" \
        > /dev/null
    done
  done
done
/usr/bin/python3 - "$rounds" <<'PY'
import sys, h5py, numpy as np
rounds = int(sys.argv[1])
print(f"pinned cube, median wall seconds per frame over {rounds} round(s); reference 0.185 s/frame")
print(f"{'integrator':16s} {'threads':>7s} {'s/frame':>9s} {'x faster':>9s} {'Newton/step':>11s} {'factorisations':>14s}")
for kind in ("backward_euler", "ida"):
    for t in (1, 2):
        per_frame, newton, fact = [], [], []
        for r in range(1, rounds + 1):
            f = h5py.File(f"out/bench/pinned_{kind}_t{t}_r{r}.h5", "r")
            w = f["/stats/wall_seconds"][()]
            per_frame += list(np.diff(w))
            newton.append(f["/stats"].attrs["newton_iterations"] / f["/stats"].attrs["steps"])
            fact.append(f["/stats"].attrs["fresh_factorisations"])
        m = float(np.median(per_frame))
        print(f"{kind:16s} {t:7d} {m:9.4f} {0.185 / m:9.2f} {np.median(newton):11.2f} {np.median(fact):14.0f}")
PY
