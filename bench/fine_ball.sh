#!/usr/bin/env bash
# The fine-ball figure: the ball of demos/ball_drop.toml at ~64K tets, damped (beta = 1e-4 s),
# the default demo's tolerances (rtol 1e-4, atol 1e-6 m), the whole 0.3 s (300 frames), one thread.
# Prints each run's wall seconds per frame, steps and worst volume error, and the median over the
# rounds; with a second build, the two run side by side in each round (one thread each), so that
# the ratio is measured in the same machine state.
#   bench/fine_ball.sh [build] [rounds] [other build]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
other=${3:-}
cd "$(dirname "$0")/.."
mkdir -p out/bench
builds=("$build")
[ -n "$other" ] && builds+=("$other")
# Side by side, each run is pinned to its own core and the two swap cores every round: on this
# machine one core was at times 35-40% slower than the other (docs/decisions.md), which
# an unpinned pair turns into a difference between builds.
pin=()
for r in $(seq 1 "$rounds"); do
  for i in "${!builds[@]}"; do
    [ ${#builds[@]} -gt 1 ] && command -v taskset > /dev/null && pin=(taskset -c $(((i + r) % 2)))
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "${pin[@]}" "${builds[$i]}/isochor" run demos/ball_drop.toml -q --overwrite \
      --set mesh.target_tets=64000 --set integrator.rtol=1e-4 --set integrator.atol=1e-6 \
      -o "out/bench/fine_ball_b${i}_r$r.h5" > /dev/null &
  done
  wait
done
/usr/bin/python3 - "$rounds" "${builds[@]}" <<'PY'
import sys, statistics, h5py, numpy as np
rounds, builds = int(sys.argv[1]), sys.argv[2:]
for i, b in enumerate(builds):
    per_frame = []
    for r in range(1, rounds + 1):
        f = h5py.File(f"out/bench/fine_ball_b{i}_r{r}.h5", "r")
        a = f["stats"].attrs
        frames = len(f["frames/time"]) - 1
        vol = f["frames/volume"][:]
        err = float(np.max(np.abs(vol / vol[0] - 1)))
        per_frame.append(float(a["wall_seconds"]) / frames)
        print(f"{b}: round {r}: {per_frame[-1]:.3f} s/frame, {int(a['steps'])} steps, worst volume change {err:.1e}")
    print(f"{b}: median {statistics.median(per_frame):.3f} s per frame over {rounds} rounds (target <= 0.9)")
PY
