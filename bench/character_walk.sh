#!/usr/bin/env bash
# The glTF character walking (demos/character_walk.toml) at two tet sizes, one thread: the tets,
# wall seconds per frame (median and mean over the frames), IDA's steps, the zones' worst volume
# error, and how far the surface goes below the ground (the contact's penetration).
#   bench/character_walk.sh [build] [rounds] [duration] [edge lengths...]
set -euo pipefail
build=${1:-build}
rounds=${2:-1}
duration=${3:-1.5}
shift $(($# < 3 ? $# : 3))
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(0.04 0.025)
cd "$(dirname "$0")/.."
mkdir -p out/bench
for r in $(seq 1 "$rounds"); do
  for h in "${sizes[@]}"; do
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/character_walk.toml --overwrite -q \
      --set frames.duration="$duration" --set character.edge_length="$h" -o "out/bench/walk_${h}_r$r.h5" > /dev/null
  done
done
/usr/bin/python3 - "$rounds" "${sizes[@]}" <<'PY'
import sys
import numpy as np
sys.path.insert(0, "python")
import isochor

rounds, sizes = int(sys.argv[1]), sys.argv[2:]
print(f"character_walk, {rounds} round(s), one thread")
print(f"{'edge m':>7s} {'tets':>7s} {'s/frame med':>11s} {'mean':>7s} {'steps':>7s} {'zone dV/V':>10s} "
      f"{'below ground mm':>15s} {'off skinning mm':>15s}")
for h in sizes:
    med, mean, steps, dv, below = [], [], [], [], []
    for r in range(1, rounds + 1):
        run = isochor.open(f"out/bench/walk_{h}_r{r}.h5")
        wall = np.diff(run.stats["wall_seconds"])
        med.append(np.median(wall))
        mean.append(wall.mean())
        steps.append(run.totals["steps"])
        v = run.volumes[:, 1:]
        dv.append(np.abs(v / v[0] - 1).max())
        ground = [c for c in run.colliders if c.is_ground][0]
        n, p = ground.rest_pose[:9].reshape(3, 3) @ [0, 0, 1], ground.rest_pose[9:]
        below.append(-min(0.0, ((run.positions[:, np.unique(run.surface)] - p) @ n).min()) * 1e3)
    print(f"{h:>7s} {len(run.tets):7d} {np.median(med):11.3f} {np.median(mean):7.3f} {np.median(steps):7.0f} "
          f"{np.median(dv):10.1e} {np.median(below):15.2f}")
PY
