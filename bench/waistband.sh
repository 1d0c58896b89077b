#!/usr/bin/env bash
# The waistband (demos/waistband_dynamic.toml: ~12.7K tets, a band tightening by 10% over 1 s, IDA):
# wall seconds per frame, steps and volume change for CNH with its 10 zones, UNH nu = 0.4545 and
# UNH nu = 0.499 (zones measured only), run alternately in rounds on one thread. Prints medians.
#   bench/waistband.sh [build] [rounds]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
cd "$(dirname "$0")/.."
mkdir -p out/bench
for r in $(seq 1 "$rounds"); do
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/waistband_dynamic.toml --overwrite -q \
    -o "out/bench/waist_cnh_r$r.h5" > /dev/null
  for nu in 0.4545 0.499; do
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/waistband_dynamic.toml --overwrite -q \
      --set material.model=unh --set material.nu=$nu --set zones.keep=false -o "out/bench/waist_unh${nu}_r$r.h5" > /dev/null
  done
done
/usr/bin/python3 - "$rounds" <<'PY'
import sys, h5py, numpy as np
rounds = int(sys.argv[1])
print(f"waistband (dynamic, 1 s, 20 frames), medians over {rounds} round(s), one thread")
print(f"{'model':14s} {'s/frame':>9s} {'wall s':>8s} {'steps':>7s} {'volume change':>14s}")
for name, tag in (("CNH, zones", "cnh"), ("UNH 0.4545", "unh0.4545"), ("UNH 0.499", "unh0.499")):
    per_frame, wall, steps, dv = [], [], [], []
    for r in range(1, rounds + 1):
        f = h5py.File(f"out/bench/waist_{tag}_r{r}.h5", "r")
        a = f["/stats"].attrs
        per_frame += list(np.diff(f["/stats/wall_seconds"][()]))
        wall.append(a["wall_seconds"])
        steps.append(a["steps"])
        V = f["/frames/volume"][()]
        dv.append(V[-1, 0] / V[0, 0] - 1)
    print(f"{name:14s} {np.median(per_frame):9.3f} {np.median(wall):8.2f} {np.median(steps):7.0f} {100 * np.median(dv):13.3g}%")
PY
