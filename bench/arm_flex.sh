#!/usr/bin/env bash
# The rigged arm (demos/arm_flex.toml: ~6K tets, two Simbody bones, IDA with three zones): wall
# seconds per frame and the share of it spent realizing the skeleton in Simbody, for CNH and for
# UNH (nu = 0.45, zones measured only), run alternately in rounds on one thread. Prints medians.
#   bench/arm_flex.sh [build] [rounds] [duration]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
duration=${3:-2.0}
cd "$(dirname "$0")/.."
mkdir -p out/bench
for r in $(seq 1 "$rounds"); do
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/arm_flex.toml --overwrite -q --set frames.duration="$duration" \
    -o "out/bench/arm_cnh_r$r.h5" > /dev/null
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/arm_flex.toml --overwrite -q --set frames.duration="$duration" \
    --set material.model=unh --set material.lambda=27000 --set zones.keep=false -o "out/bench/arm_unh_r$r.h5" > /dev/null
done
/usr/bin/python3 - "$rounds" <<'PY'
import sys, h5py, numpy as np
rounds = int(sys.argv[1])
print(f"arm_flex, medians over {rounds} round(s), one thread")
print(f"{'model':6s} {'s/frame':>9s} {'Simbody s':>10s} {'Simbody %':>10s} {'realizations':>12s} {'steps':>7s}")
for model in ("cnh", "unh"):
    per_frame, sb, share, real, steps = [], [], [], [], []
    for r in range(1, rounds + 1):
        f = h5py.File(f"out/bench/arm_{model}_r{r}.h5", "r")
        a = f["/stats"].attrs
        per_frame += list(np.diff(f["/stats/wall_seconds"][()]))
        sb.append(a["simbody_seconds"])
        share.append(100 * a["simbody_seconds"] / a["wall_seconds"])
        real.append(a["simbody_realizations"])
        steps.append(a["steps"])
    print(f"{model:6s} {np.median(per_frame):9.4f} {np.median(sb):10.3f} {np.median(share):10.2f} {np.median(real):12.0f} {np.median(steps):7.0f}")
PY
