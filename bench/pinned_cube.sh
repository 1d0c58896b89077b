#!/usr/bin/env bash
# The stable neo-Hookean test scene (demos/pinned_cube.toml: 120 frames at 60 fps) at 7^3, 13^3 and
# 26^3 cells (2.1K, 13.2K and 105K tets), with backward Euler at h = 1/60 s and with IDA at
# rtol 1e-4, each on one thread (OpenMP and OpenBLAS), the scene's own linear solver ("auto")
# unless LINEAR_SOLVER names one. The two integrators of a size run side by side, one per core
# (taskset), their cores swapped each round, so that machine noise and the slower core spread over
# both. Prints, per size and integrator, the median over the rounds of the whole run's wall time per
# frame (total / 120: the frames where tets invert cost most), Newton iterations per step, and
# the speed against the peer HOBAK (Kim & Eberle; backward Euler, one CG solve per step with a
# PSD-projected Hessian), measured on this kind of machine and reported with the target: 0.185 s per
# frame at 13.2K tets and 1.9-2.7 s per frame at ~100K (the faster figure is used). No HOBAK
# figure was recorded at 2.1K; the script prints the peer time that would meet the aim there
# (3x with backward Euler, 1x with IDA).
#   bench/pinned_cube.sh [build] [rounds] [cells ...]        (default: build 3 7 13 26)
#   LINEAR_SOLVER=reduced bench/pinned_cube.sh build 1 26     (CHOLMOD, for comparison)
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
shift 2 || shift $# || true
sizes=("${@:-7 13 26}")
ls_set=()
[[ -n "${LINEAR_SOLVER:-}" ]] && ls_set=(--set "integrator.linear_solver=$LINEAR_SOLVER")
cd "$(dirname "$0")/.."
out=out/bench/pinned_cube
mkdir -p "$out"
run() {  # run CELLS KIND CORE ROUND
  local sets=(--set integrator.kind="$2")
  [[ $2 == ida ]] && sets+=(--set integrator.rtol=1e-4)
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 taskset -c "$3" "$build/isochor" run demos/pinned_cube.toml --overwrite -q \
    --set mesh.cells="$1" "${sets[@]}" "${ls_set[@]}" -o "$out/c$1_$2_r$4.h5" > "$out/c$1_$2_r$4.log" 2>&1
}
for cells in ${sizes[*]}; do
  for r in $(seq 1 "$rounds"); do
    a=$(( r % 2 )); b=$(( 1 - a ))
    run "$cells" backward_euler "$a" "$r" &
    run "$cells" ida "$b" "$r" &
    wait
  done
  echo "pinned_cube: $cells^3 cells done" >&2
done
/usr/bin/python3 - "$out" "$rounds" ${sizes[*]} <<'PY'
import sys, h5py, numpy as np
out, rounds, sizes = sys.argv[1], int(sys.argv[2]), [int(c) for c in sys.argv[3:]]
hobak = {13: 0.185, 26: 1.9}  # s per frame
print(f"pinned cube, 120 frames, one thread each, medians over {rounds} round(s)")
print("| cells | tets | integrator | solver | s per frame | Newton per step | HOBAK s per frame | x HOBAK |")
print("|---|---|---|---|---|---|---|---|")
for c in sizes:
    for kind in ("backward_euler", "ida"):
        per_frame, newton, solver = [], [], ""
        for r in range(1, rounds + 1):
            with h5py.File(f"{out}/c{c}_{kind}_r{r}.h5", "r") as f:
                w = f["/stats/wall_seconds"][()]
                a = f["/stats"].attrs
                per_frame.append(w[-1] / (len(w) - 1))
                newton.append(a["newton_iterations"] / a["steps"])
                solver = "krylov" if a["linear_iterations"] > 0 else "direct"
                if a.get("solver_switches", 0) > 0:  # auto moved between PCG and CHOLMOD
                    solver += f" ({int(a['solver_switches'])} switch)"
                tets = f["/mesh/tets"].shape[0] if "/mesh/tets" in f else 6 * c**3
        m = float(np.median(per_frame))
        if c in hobak:
            ref, ratio = f"{hobak[c]:.3f}", f"{hobak[c] / m:.1f}"
        else:
            target = 3 if kind == "backward_euler" else 1  # the aims: 3x with backward Euler, 1x with IDA
            ref, ratio = "–", f"({target}x needs HOBAK ≥ {target * m:.4f})"
        print(f"| {c}^3 | {tets:,} | {kind} | {solver} | {m:.4f} | {np.median(newton):.2f} | {ref} | {ratio} |")
PY
