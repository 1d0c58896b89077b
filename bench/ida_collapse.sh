#!/usr/bin/env bash
# IDA's linear solvers through the 16^3 collapse (demos/cube_collapse.toml,
# 24.6K tets, rtol 1e-4, atol 1e-8, max_step 33 ms, one thread), runs interleaved in rounds so that
# machine noise spreads over both. Prints per solver the median wall seconds, IDA's steps and the
# wall seconds per step; the steps must agree (the linear solver does not change them).
# COLLAPSE_SET (environment) adds --set overrides to every run, e.g. the settings of the collapse's
# figure in docs/decisions.md: COLLAPSE_SET="integrator.jacobian_age=10 integrator.linear_tol=1e-6".
#   bench/ida_collapse.sh [rounds] [duration s]
set -euo pipefail
rounds=${1:-3}
duration=${2:-0.12}
extra=()
for o in ${COLLAPSE_SET:-}; do extra+=(--set "$o"); done
cd "$(dirname "$0")/.."
mkdir -p out/bench
for r in $(seq 1 "$rounds"); do
  for s in reduced krylov; do
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 build/isochor run demos/cube_collapse.toml -q --overwrite \
      --set frames.duration="$duration" --set integrator.rtol=1e-4 --set integrator.atol=1e-8 \
      --set integrator.max_step=0.033 --set integrator.linear_solver=$s "${extra[@]}" -o "out/bench/collapse_${s}_r$r.h5" > /dev/null
  done
done
/usr/bin/python3 - "$rounds" <<'PY'
import sys, statistics, h5py
rounds = int(sys.argv[1])
for s in ("reduced", "krylov"):
    wall, steps = [], []
    for r in range(1, rounds + 1):
        a = h5py.File(f"out/bench/collapse_{s}_r{r}.h5", "r")["stats"].attrs
        wall.append(float(a["wall_seconds"]))
        steps.append(int(a["steps"]))
    w = statistics.median(wall)
    print(f"{s:8s} median wall {w:7.2f} s  steps {steps}  {1000 * w / statistics.median(steps):.2f} ms per step")
PY
