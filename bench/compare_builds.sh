#!/usr/bin/env bash
# Two builds of isochor side by side on backward Euler (one thread each, runs interleaved in
# rounds so that machine noise spreads over both): the pinned cube (demos/pinned_cube.toml, 13.2K
# tets, h = 1/60 s) and the coarse ball through its impact (1,000 tets, h = 0.25 ms). Prints per
# scene and build the median wall seconds per frame, Newton iterations per step and
# factorisations, and the largest node distance between the two builds' frames.
# OLD_SET / NEW_SET (environment) add --set overrides to that build's cube runs, e.g. each build's
# own Newton tolerance when its meaning changed.
#   OLD_SET="integrator.newton_tol=1e-6" bench/compare_builds.sh OLD_BUILD NEW_BUILD [rounds] [cube duration]
set -euo pipefail
old=$1
new=$2
rounds=${3:-3}
duration=${4:-1.0}
cd "$(dirname "$0")/.."
mkdir -p out/bench
for r in $(seq 1 "$rounds"); do
  for b in old new; do
    exe=$old/isochor
    extra=()
    for o in ${OLD_SET:-}; do extra+=(--set "$o"); done
    if [ "$b" = new ]; then
      exe=$new/isochor
      extra=()
      for o in ${NEW_SET:-}; do extra+=(--set "$o"); done
    fi
    # Removed first rather than --overwrite: an old build does not know the flag.
    rm -f out/bench/cmp_{cube,ball}_${b}_r$r.{h5,xdmf}
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$exe" run demos/pinned_cube.toml -q --set integrator.kind=backward_euler \
      --set frames.duration="$duration" "${extra[@]}" -o "out/bench/cmp_cube_${b}_r$r.h5" > /dev/null
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$exe" run demos/ball_drop.toml -q --set integrator.kind=backward_euler \
      --set mesh.target_tets=1000 --set frames.duration=0.1 --set frames.rate=250 --set integrator.dt=0.00025 \
      -o "out/bench/cmp_ball_${b}_r$r.h5" > /dev/null
  done
done
/usr/bin/python3 - "$rounds" <<'PY'
import sys, h5py, numpy as np
rounds = int(sys.argv[1])
print(f"backward Euler, two builds, median over {rounds} round(s), one thread")
print(f"{'scene':6s} {'build':5s} {'s/frame':>9s} {'Newton/step':>11s} {'factorisations':>14s}")
for scene in ("cube", "ball"):
    last = {}
    for b in ("old", "new"):
        per_frame, newton, fact = [], [], []
        for r in range(1, rounds + 1):
            with h5py.File(f"out/bench/cmp_{scene}_{b}_r{r}.h5", "r") as f:
                s = f["stats"].attrs
                frames = f["frames/time"].shape[0]
                per_frame.append(s["wall_seconds"] / max(frames - 1, 1))
                newton.append(s["newton_iterations"] / s["steps"])
                fact.append(s["fresh_factorisations"])
                last[b] = f["frames/positions"][:]
        print(f"{scene:6s} {b:5s} {np.median(per_frame):9.4f} {np.median(newton):11.2f} {np.median(fact):14.0f}")
    d = np.abs(last["old"] - last["new"]).max()
    print(f"{scene:6s} largest distance between the builds' frames: {d:.3e} m")
PY
