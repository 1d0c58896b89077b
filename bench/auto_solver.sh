#!/usr/bin/env bash
# Backward Euler's step matrix on CHOLMOD ("reduced"), on block-Jacobi PCG ("krylov") and on
# "auto" (PCG from 1,300 dofs, switching to CHOLMOD by the cost estimate of
# integrators/src/backward_euler.cpp), on the cases where the choice matters: the Figure 8 cube
# (demos/cube_gravity.toml, 16^3 cells, 0.5 s) stiff in UNH and SNH at lambda = 900-9900 Pa and in
# CNH, at 8 and 33 ms; the twist demo; the pinned cube at 7^3 and 13^3 cells. One thread each
# (OpenMP and OpenBLAS). Rounds run in pairs, one per core (taskset), each round through every
# case and solver, the pair's two rounds in different orders, so every run has another run beside
# it. Prints, per case, the median wall seconds of each solver over the rounds, auto's ratio to
# the faster of the two, and auto's switches.
#   bench/auto_solver.sh [build] [rounds]        (default: build 4)
set -euo pipefail
build=${1:-build}
rounds=${2:-4}
cd "$(dirname "$0")/.."
out=out/bench/auto_solver
mkdir -p "$out"
source bench/auto_solver_cases.sh
solvers=(reduced krylov auto)
round() {  # round R CORE ORDER(0: as listed, 1: reversed)
  local r=$1 core=$2 order=$3 list=("${cases[@]}")
  if [[ $order == 1 ]]; then
    list=(); for ((i=${#cases[@]}-1; i>=0; i--)); do list+=("${cases[$i]}"); done
  fi
  for c in "${list[@]}"; do
    local name=${c%%|*} args=${c#*|}
    for s in "${solvers[@]}"; do
      # shellcheck disable=SC2086  # args is a word list of the scene and its --set options
      OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 taskset -c "$core" "$build/isochor" run $args --overwrite -q \
        --set integrator.linear_solver="$s" -o "$out/${name}_${s}_r$r.h5" > "$out/${name}_${s}_r$r.log" 2>&1
    done
  done
}
for ((r = 1; r <= rounds; r += 2)); do
  round "$r" 0 0 &
  (( r + 1 <= rounds )) && round $((r + 1)) 1 1 &
  wait
  echo "auto_solver: rounds $r-$((r + 1 <= rounds ? r + 1 : r)) done" >&2
done
names=(); for c in "${cases[@]}"; do names+=("${c%%|*}"); done
/usr/bin/python3 - "$out" "$rounds" "${names[@]}" <<'PY'
import sys, h5py, numpy as np
out, rounds, names = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print(f"backward Euler's step matrix, one thread each, wall seconds, medians over {rounds} rounds")
print("| case | CHOLMOD | PCG | auto | auto / faster | auto's switches | CG per Newton (PCG) |")
print("|---|---|---|---|---|---|---|")
for n in names:
    wall, sw, cg = {}, [], []
    for s in ("reduced", "krylov", "auto"):
        w = []
        for r in range(1, rounds + 1):
            with h5py.File(f"{out}/{n}_{s}_r{r}.h5", "r") as f:
                a = f["/stats"].attrs
                w.append(a["wall_seconds"])
                if s == "auto": sw.append(a["solver_switches"])
                if s == "krylov": cg.append(a["linear_iterations"] / a["newton_iterations"])
        wall[s] = float(np.median(w))
    best = min(wall["reduced"], wall["krylov"])
    print(f"| {n} | {wall['reduced']:.2f} | {wall['krylov']:.2f} | {wall['auto']:.2f} | {wall['auto'] / best:.2f} | "
          f"{int(np.median(sw))} | {np.median(cg):.0f} |")
PY
