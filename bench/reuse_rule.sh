#!/usr/bin/env bash
# Two builds side by side on the cases of bench/auto_solver.sh (bench/auto_solver_cases.sh), for a
# change to backward Euler's factor reuse or solver choice: in each round every case runs on both
# builds at once, one per core (taskset), the cores swapped every round; one thread each (OpenMP
# and OpenBLAS). Prints, per case and solver, each build's median wall seconds, Newton
# iterations and fresh matrices, and new / old.
#   bench/reuse_rule.sh OLD_BUILD NEW_BUILD [rounds] [solvers]   (default: 3 "reduced krylov auto")
set -euo pipefail
old=$(realpath "$1")
new=$(realpath "$2")
rounds=${3:-3}
read -r -a solvers <<< "${4:-reduced krylov auto}"
cd "$(dirname "$0")/.."
out=out/bench/reuse_rule
mkdir -p "$out"
source bench/auto_solver_cases.sh
one() {  # one BUILD_DIR TAG CORE NAME SOLVER ROUND ARGS...
  local exe=$1/isochor tag=$2 core=$3 name=$4 s=$5 r=$6
  shift 6
  rm -f "$out/${name}_${s}_${tag}_r$r".{h5,xdmf}  # not --overwrite: an old build may not know it
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 taskset -c "$core" "$exe" run "$@" -q \
    --set integrator.linear_solver="$s" -o "$out/${name}_${s}_${tag}_r$r.h5" > "$out/${name}_${s}_${tag}_r$r.log" 2>&1
}
for ((r = 1; r <= rounds; r++)); do
  for c in "${cases[@]}"; do
    name=${c%%|*}
    read -r -a args <<< "${c#*|}"
    for s in "${solvers[@]}"; do
      one "$old" old $((r % 2)) "$name" "$s" "$r" "${args[@]}" &
      one "$new" new $(((r + 1) % 2)) "$name" "$s" "$r" "${args[@]}" &
      wait
    done
  done
  echo "reuse_rule: round $r done" >&2
done
names=(); for c in "${cases[@]}"; do names+=("${c%%|*}"); done
/usr/bin/python3 - "$out" "$rounds" "${solvers[*]}" "${names[@]}" <<'PY'
import sys, h5py, numpy as np
out, rounds, solvers, names = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4:]
print(f"backward Euler, two builds side by side, one thread each, medians over {rounds} rounds")
print("| case | solver | old s | new s | new / old | old Newton | new Newton | old fresh | new fresh |")
print("|---|---|---|---|---|---|---|---|---|")
for n in names:
    for s in solvers:
        m = {}
        for tag in ("old", "new"):
            w, k, f = [], [], []
            for r in range(1, rounds + 1):
                with h5py.File(f"{out}/{n}_{s}_{tag}_r{r}.h5", "r") as h:
                    a = h["/stats"].attrs
                    w.append(a["wall_seconds"]); k.append(a["newton_iterations"]); f.append(a["fresh_factorisations"])
            m[tag] = (float(np.median(w)), float(np.median(k)), float(np.median(f)))
        o, e = m["old"], m["new"]
        print(f"| {n} | {s} | {o[0]:.2f} | {e[0]:.2f} | {e[0] / o[0]:.2f} | {o[1]:.0f} | {e[1]:.0f} | {o[2]:.0f} | {e[2]:.0f} |")
PY
