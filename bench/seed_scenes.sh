#!/usr/bin/env bash
# The seeds' scanned and garment scenes, seconds per frame measured side by side, run
# alternately in rounds on one thread; medians:
#   demos/armadillo.toml (~18.4K tets, two cylinders squeezing the Stanford Armadillo, IDA): CNH
#     with its zones (lambda 60, beta 12) and SNH (lambda 400), both with the epidermis
#     (lambda_e 40): the CNH paper's Table 1, 6.97 and 6.26 s per frame there;
#   demos/waistband_tight.toml (~12.7K tets, a garment's 4 kPa on the torso, IDA): CNH with its
#     9 zones, UNH nu = 0.4545 and UNH nu = 0.499 (zones measured only).
#   bench/seed_scenes.sh [build] [rounds]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
for r in $(seq 1 "$rounds"); do
  bench_run "armadillo_cnh_r$r" demos/armadillo.toml
  bench_run "armadillo_snh_r$r" demos/armadillo.toml --set material.model=snh --set material.lambda=400.0 --set zones.keep=false
  bench_run "garment_cnh_r$r" demos/waistband_tight.toml
  for nu in 0.4545 0.499; do
    bench_run "garment_unh${nu}_r$r" demos/waistband_tight.toml --set material.model=unh --set material.nu=$nu --set zones.keep=false
  done
done
PYTHONPATH=python /usr/bin/python3 - "$rounds" <<'PY'
import sys
import numpy as np
from isochor.runfile import Run
rounds = int(sys.argv[1])
print(f"seed scenes, medians over {rounds} round(s), one thread")
print(f"{'scene':10s} {'model':12s} {'s/frame':>8s} {'steps':>7s} {'Jacobians':>9s} {'Newton':>7s} {'largest volume change':>22s}")
for scene, name, tag in (("armadillo", "CNH, zones", "armadillo_cnh"), ("armadillo", "SNH", "armadillo_snh"),
                         ("garment", "CNH, zones", "garment_cnh"), ("garment", "UNH 0.4545", "garment_unh0.4545"),
                         ("garment", "UNH 0.499", "garment_unh0.499")):
    per_frame, steps, jac, newton, dv = [], [], [], [], []
    for r in range(1, rounds + 1):
        with Run(f"out/bench/{tag}_r{r}.h5") as run:
            t = run.totals
            per_frame.append(float(t["wall_seconds"]) / (run.num_frames - 1))
            steps.append(float(t["steps"]))
            jac.append(float(t["jacobian_evaluations"]))
            newton.append(float(t["newton_iterations"]))
            dv.append(np.abs(run.volumes[:, 0] / run.volumes[0, 0] - 1).max())
    print(f"{scene:10s} {name:12s} {np.median(per_frame):8.3f} {np.median(steps):7.0f} {np.median(jac):9.0f} "
          f"{np.median(newton):7.0f} {100 * np.median(dv):21.3g}%")
PY
