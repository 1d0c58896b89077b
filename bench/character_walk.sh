#!/usr/bin/env bash
# The glTF character walking (demos/character_walk.toml) at several tet sizes, one thread, and at
# the first size again without contact between body parts: the tets, wall seconds per frame
# (median and mean over the frames), IDA's steps, the zones' worst volume error, how far the
# surface goes below the ground (the contact's penetration), and how far the simulated render mesh
# is from plain linear blend skinning by the same bones (mean and largest over frames and vertices);
# and at the first size with CG to IDA's default linear tolerance (_cg_default: linear_tol = 0,
# min(1e-12, 1e-6 rtol)) instead of the demo's 1e-4.
#   bench/character_walk.sh [build] [rounds] [duration] [edge lengths...]
set -euo pipefail
build=${1:-build}
rounds=${2:-1}
duration=${3:-1.5}
shift $(($# < 3 ? $# : 3))
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(0.025 0.02)
cd "$(dirname "$0")/.."
mkdir -p out/bench
walk() {  # NAME EDGE [OVERRIDES...]
  local name=$1 h=$2
  shift 2
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/character_walk.toml --overwrite -q \
    --set frames.duration="$duration" --set character.edge_length="$h" -o "out/bench/$name.h5" "$@" > /dev/null
}
for r in $(seq 1 "$rounds"); do
  for h in "${sizes[@]}"; do walk "walk_${h}_r$r" "$h"; done
  walk "walk_${sizes[0]}_apart_r$r" "${sizes[0]}" --set contact.self.enabled=false
  walk "walk_${sizes[0]}_cg_default_r$r" "${sizes[0]}" --set integrator.linear_tol=0
done
/usr/bin/python3 - "$rounds" "${sizes[@]}" "${sizes[0]}_apart" "${sizes[0]}_cg_default" <<'PY'
import sys
import numpy as np
sys.path.insert(0, "python")
import isochor

rounds, cases = int(sys.argv[1]), sys.argv[2:]
print(f"character_walk, {rounds} round(s), one thread; _apart: without contact between body parts; "
      "_cg_default: IDA's default CG tolerance")
print(f"{'edge m':>12s} {'tets':>7s} {'s/frame med':>11s} {'mean':>7s} {'steps':>7s} {'zone dV/V':>10s} "
      f"{'below ground mm':>15s} {'off skinning mm mean, max':>26s}")
for case in cases:
    med, mean, steps, dv, below, off_mean, off_max = [], [], [], [], [], [], []
    for r in range(1, rounds + 1):
        run = isochor.open(f"out/bench/walk_{case}_r{r}.h5")
        wall = np.diff(run.stats["wall_seconds"])
        med.append(np.median(wall))
        mean.append(wall.mean())
        steps.append(run.totals["steps"])
        v = run.volumes[:, 1:]
        dv.append(np.abs(v / v[0] - 1).max())
        ground = [c for c in run.colliders if c.is_ground][0]
        n, p = ground.rest_pose[:9].reshape(3, 3) @ [0, 0, 1], ground.rest_pose[9:]
        below.append(-min(0.0, ((run.positions[:, np.unique(run.surface)] - p) @ n).min()) * 1e3)
        off = np.array([np.linalg.norm(run.render_positions(run.frame_positions(k)) - run.render_skinned(k), axis=1)
                        for k in range(run.num_frames)])
        off_mean.append(off.mean() * 1e3)
        off_max.append(off.max() * 1e3)
    print(f"{case:>12s} {len(run.tets):7d} {np.median(med):11.3f} {np.median(mean):7.3f} {np.median(steps):7.0f} "
          f"{np.median(dv):10.1e} {np.median(below):15.2f} {np.median(off_mean):12.1f}, {np.median(off_max):11.1f}")
PY
