#!/usr/bin/env bash
# Two builds of isochor side by side on IDA: the default demo (the coarse ball through its
# impact, rtol 1e-4, atol 1e-6) on the krylov and reduced solvers, one thread each, runs
# interleaved in rounds so that machine noise spreads over both. Prints per solver and build the
# median wall seconds, steps and Newton iterations, and the frames' largest node distance from a
# tight reference (the new build at rtol 1e-7, atol 1e-9, reduced), for a change to IDA's Newton
# iteration or its defaults. With `collapse` as fourth argument: the 16^3 cube collapse to 0.2 s
# instead (rtol 1e-4, krylov only; reference at rtol 1e-6, atol 1e-9).
#   bench/ida_builds.sh OLD_BUILD NEW_BUILD [rounds] [ball|collapse]
set -euo pipefail
old=$(realpath "$1")
new=$(realpath "$2")
rounds=${3:-3}
what=${4:-ball}
cd "$(dirname "$0")/.."
scene=demos/ball_drop.toml
sets=(integrator.atol=1e-6)
ref_sets=(integrator.rtol=1e-7 integrator.atol=1e-9 integrator.linear_solver=reduced)
solvers=(krylov reduced)
if [ "$what" = collapse ]; then
  scene=demos/cube_collapse.toml
  sets=(frames.duration=0.2)
  ref_sets=(frames.duration=0.2 integrator.rtol=1e-6 integrator.atol=1e-9)
  solvers=(krylov)
fi
out=out/bench/ida_builds/$what
mkdir -p "$out"
run() {  # EXE OUTPUT SETS...
  local exe=$1 o=$2
  shift 2
  local sets=() kv
  for kv in "$@"; do sets+=(--set "$kv"); done
  rm -f "$o".{h5,xdmf}  # not --overwrite: an old build may not know it
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$exe/isochor" run "$scene" -q "${sets[@]}" -o "$o.h5" > /dev/null
}
[ -f "$out/reference.h5" ] || run "$new" "$out/reference" "${ref_sets[@]}"
for r in $(seq 1 "$rounds"); do
  for s in "${solvers[@]}"; do
    for b in old new; do
      exe=$old
      [ "$b" = new ] && exe=$new
      run "$exe" "$out/${s}_${b}_r$r" integrator.rtol=1e-4 "${sets[@]}" integrator.linear_solver=$s
    done
  done
done
/usr/bin/python3 - "$out" "$rounds" "$what" "${solvers[@]}" <<'PY'
import sys, h5py, numpy as np
out, rounds, what, solvers = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4:]
with h5py.File(f"{out}/reference.h5", "r") as f:
    ref = f["frames/positions"][:]
title = {"ball": "the coarse ball, rtol 1e-4, atol 1e-6", "collapse": "the 16^3 collapse to 0.2 s, rtol 1e-4"}[what]
print(f"IDA on {title}, median over {rounds} round(s), one thread")
print(f"{'solver':8s} {'build':5s} {'wall s':>8s} {'steps':>7s} {'Newton':>7s} {'error m':>9s}")
for s in solvers:
    for b in ("old", "new"):
        wall, steps, newton = [], [], []
        for r in range(1, rounds + 1):
            with h5py.File(f"{out}/{s}_{b}_r{r}.h5", "r") as f:
                a = f["stats"].attrs
                wall.append(a["wall_seconds"])
                steps.append(a["steps"])
                newton.append(a["newton_iterations"])
                err = np.abs(f["frames/positions"][:] - ref).max()
        print(f"{s:8s} {b:5s} {np.median(wall):8.2f} {np.median(steps):7.0f} {np.median(newton):7.0f} {err:9.2e}")
PY
