#!/usr/bin/env bash
# The bodies, seconds per frame measured side by side, run alternately in rounds on
# one thread; medians:
#   demos/waistband_dynamic.toml (~12.7K tets, a band tightening by 10% over 1 s, IDA): CNH with
#     its 9 zones, UNH nu = 0.4545 and UNH nu = 0.499 (zones measured only);
#   demos/squeeze_cylinders.toml (~5.8K tets, two cylinders pressing a jelly, IDA): CNH with its
#     global zone (lambda 60, beta 12) and SNH (lambda 400), the CNH paper's Table 1;
#   demos/ball_on_torso.toml (~1.5K tets, a ball dropped on a rigid triangle-mesh torso, IDA):
#     CNH with its zone (the wall time includes sampling the torso's distance, ~4 s);
#   demos/arm_muscles.toml to full flexion (1 s; ~6K tets, contact between parts, IDA): CNH with
#     its muscles as zones.
#   bench/bodies.sh [build] [rounds]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
for r in $(seq 1 "$rounds"); do
  bench_run "waist_cnh_r$r" demos/waistband_dynamic.toml
  for nu in 0.4545 0.499; do
    bench_run "waist_unh${nu}_r$r" demos/waistband_dynamic.toml --set material.model=unh --set material.nu=$nu --set zones.keep=false
  done
  bench_run "squeeze_cnh_r$r" demos/squeeze_cylinders.toml
  bench_run "squeeze_snh_r$r" demos/squeeze_cylinders.toml --set material.model=snh --set material.lambda=400.0 --set zones.global=false
  bench_run "torso_ball_r$r" demos/ball_on_torso.toml
  bench_run "arm_muscles_r$r" demos/arm_muscles.toml --set frames.duration=1.0
done
/usr/bin/python3 - "$rounds" <<'PY'
import sys, h5py, numpy as np
rounds = int(sys.argv[1])
print(f"bodies, medians over {rounds} round(s), one thread")
# s/frame: the median frame; mean: wall over frames (where contact comes and goes, the two differ)
print(f"{'scene':11s} {'model':12s} {'s/frame':>9s} {'mean':>7s} {'wall s':>8s} {'steps':>7s} {'Jacobians':>9s} {'largest volume change':>22s}")
for scene, name, tag in (("waistband", "CNH, zones", "waist_cnh"), ("waistband", "UNH 0.4545", "waist_unh0.4545"),
                         ("waistband", "UNH 0.499", "waist_unh0.499"), ("squeeze", "CNH, zone", "squeeze_cnh"),
                         ("squeeze", "SNH", "squeeze_snh"), ("torso ball", "CNH, zone", "torso_ball"),
                         ("arm muscles", "CNH, zones", "arm_muscles")):
    per_frame, wall, mean, steps, jac, dv = [], [], [], [], [], []
    for r in range(1, rounds + 1):
        f = h5py.File(f"out/bench/{tag}_r{r}.h5", "r")
        a = f["/stats"].attrs
        per_frame += list(np.diff(f["/stats/wall_seconds"][()]))
        wall.append(a["wall_seconds"])
        mean.append(a["wall_seconds"] / (len(f["/frames/time"]) - 1))
        steps.append(a["steps"])
        jac.append(a["jacobian_evaluations"])
        V = f["/frames/volume"][()]
        dv.append(np.abs(V[:, 0] / V[0, 0] - 1).max())
    print(f"{scene:11s} {name:12s} {np.median(per_frame):9.3f} {np.median(mean):7.3f} {np.median(wall):8.2f} {np.median(steps):7.0f} "
          f"{np.median(jac):9.0f} {100 * np.median(dv):21.3g}%")
PY
