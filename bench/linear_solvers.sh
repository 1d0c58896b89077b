#!/usr/bin/env bash
# The linear solvers side by side (integrator.linear_solver = klu | reduced | krylov) on the
# ball drop: the coarse ball (4.7K tets), the fine ball (64K) and a 250K-tet sphere, IDA at
# rtol 1e-4 through the impact (the first `duration` seconds), THREADS threads (default 1), one
# run each in turn, with any further scene settings in EXTRA (e.g. EXTRA="damping.beta=1e-4").
# Prints per run: wall seconds (all, the mean and the median per frame), steps, Jacobians,
# symbolic seconds (ordering and symbolic analysis: CHOLMOD's, or METIS plus KLU's analysis
# timed once apart), factorisation seconds (symbolic included), solve seconds, factor entries,
# CG iterations and peak resident memory, and which BLAS the binary loads.
#   bench/linear_solvers.sh [build] [duration] [sizes] [solvers]
#   bench/linear_solvers.sh build 0.04 "4700 64000" "klu reduced krylov"
#   THREADS=2 EXTRA="damping.beta=1e-4" bench/linear_solvers.sh build 0.3 64000 krylov
set -euo pipefail
build=${1:-build}
duration=${2:-0.04}
sizes=${3:-"4700 64000"}
solvers=${4:-"klu reduced krylov"}
threads=${THREADS:-1}
extra=()
for e in ${EXTRA:-}; do extra+=(--set "$e"); done
cd "$(dirname "$0")/.."
mkdir -p out/bench
echo "BLAS: $(ldd "$build/isochor" | grep -Eo 'lib(open)?blas[^ ]*' | head -1) -> $(readlink -f /etc/alternatives/libblas.so.3-x86_64-linux-gnu 2>/dev/null || echo '?')"
for n in $sizes; do
  for s in $solvers; do
    OMP_NUM_THREADS=$threads OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/ball_drop.toml --overwrite -q -o "out/bench/ls_${n}_${s}.h5" \
      --set mesh.target_tets="$n" --set frames.duration="$duration" --set integrator.rtol=1e-4 \
      --set integrator.atol=1e-7 --set integrator.linear_solver="$s" "${extra[@]}" > /dev/null || echo "tets $n, $s: failed"
  done
done
/usr/bin/python3 - "$sizes" "$solvers" <<'PY'
import os, sys, h5py, numpy as np
sizes, solvers = sys.argv[1].split(), sys.argv[2].split()
print(f"{'tets':>7s} {'solver':8s} {'wall s':>8s} {'mean s/fr':>9s} {'median':>7s} {'steps':>6s} {'Jac':>5s} {'symbolic s':>10s} {'factor s':>9s} {'solve s':>8s} "
      f"{'assembly s':>10s} {'factor nnz':>11s} {'CG its':>7s} {'peak MB':>8s}")
for n in sizes:
    for s in solvers:
        p = f"out/bench/ls_{n}_{s}.h5"
        if not os.path.exists(p):
            continue
        with h5py.File(p, "r") as f:
            a = f["/stats"].attrs
            w = f["/stats/wall_seconds"][()]
            tets = f["/mesh/tets"].shape[0]
            if "failure" in a:
                print(f"{tets:7d} {s:8s} failed: {a['failure']}")
                continue
            print(f"{tets:7d} {s:8s} {w[-1]:8.1f} {w[-1] / (len(w) - 1):9.3f} {np.median(np.diff(w)):7.3f} {a['steps']:6.0f} {a['jacobian_evaluations']:5.0f} "
                  f"{a.get('symbolic_seconds', float('nan')):10.2f} {a['factorisation_seconds']:9.2f} {a['solve_seconds']:8.2f} {a['assembly_seconds']:10.2f} "
                  f"{a['factor_nnz']:11.3g} {a['linear_iterations']:7.0f} {a['peak_memory_mb']:8.0f}")
PY
