#!/usr/bin/env bash
# Scene timing of the CNH paper's ball drop (Figures 10/11): wall seconds per frame, steps per
# frame, Newton iterations, Jacobians and the split between assembly, factorisation and solve.
#   bench/ball_drop.sh [build] [quick]
# quick: the coarse ball only on the reduced solver. Results land in out/bench/.
set -euo pipefail
build=${1:-build}
quick=${2:-}
cd "$(dirname "$0")/.."
mkdir -p out/bench
run() {  # name, then overrides
  local name=$1; shift
  local sets=()
  for s in "$@"; do sets+=(--set "$s"); done
  "$build/isochor" run demos/ball_drop.toml --overwrite "${sets[@]}" -o "out/bench/$name.h5" -q > "out/bench/$name.log" 2>&1 \
    || echo "$name: FAILED ($(tail -n 1 "out/bench/$name.log"))"
  /usr/bin/python3 tools/run_report.py "out/bench/$name.h5"
}
run coarse_cnh_reduced
[ "$quick" = quick ] && exit 0
run coarse_cnh_klu integrator.linear_solver=klu
run coarse_cnh_reduced_rtol1e-4 integrator.rtol=1e-4 integrator.atol=1e-6
run coarse_unh_nu045 material.model=unh
run coarse_unh_nu0495 material.model=unh material.nu=0.495
# The fine ball (~64K tets): a few frames of free fall, for the cost per frame.
run fine_cnh_reduced_5frames mesh.target_tets=64000 frames.duration=0.005
