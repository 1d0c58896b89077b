#!/usr/bin/env bash
# Tolerance proportionality and backward Euler's convergence on the two test DAEs
# (bench/dae_accuracy.cpp): writes docs/results/tolerance/runs.csv and the chart
# docs/results/tolerance/tolerance.png, and prints each IDA solver's fitted slope and offset.
#   bench/dae_accuracy.sh [build]
set -euo pipefail
build=${1:-build}
cd "$(dirname "$0")/.."
cmake --build "$build" --target isochor_bench_dae -j"$(nproc)" > /dev/null
out=docs/results/tolerance
mkdir -p "$out"
"$build/isochor_bench_dae" all > "$out/runs.csv"
/usr/bin/python3 - "$out" <<'PY'
import csv, sys, collections
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/runs.csv")))
ida = collections.defaultdict(list)
for r in rows:
    if r["method"] == "ida" and r["ok"] == "1":
        ida[(r["problem"], r["solver"])].append((float(r["tol"]), float(r["trajectory_digits"]), int(r["newton"]), int(r["steps"])))
fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
print("| problem | solver | slope | digits at rtol 1e-7 | largest residual | steps | Newton iterations |")
print("|---|---|---|---|---|---|---|")
for ax, problem in zip(axes, ["pendulum", "caraxis"]):
    for (p, solver), pts in sorted(ida.items()):
        if p != problem:
            continue
        pts.sort()
        x = -np.log10([t for t, _, _, _ in pts])
        y = np.array([d for _, d, _, _ in pts])
        slope, c = np.polyfit(x, y, 1)
        resid = np.max(np.abs(y - (c + slope * x)))
        print(f"| {problem} | {solver} | {slope:.3f} | {c + 7 * slope:.3f} | {resid:.2f} | "
              f"{sum(s for *_, s in pts):,} | {sum(n for _, _, n, _ in pts):,} |")
        ax.plot(x, y, "o-", label=f"{solver} (slope {slope:.2f})", ms=4)
    ax.plot([4, 10], [4 - 1, 10 - 1], "k:", lw=0.8, label="slope 1")
    ax.set_title({"pendulum": "MEBDFDAE pendulum, t in [0, 1]", "caraxis": "car axis, t in [0, 3]"}[problem])
    ax.set_xlabel("-log10(rtol)   (atol = rtol)")
    ax.set_ylabel("correct digits along the run")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(f"{out}/tolerance.png", dpi=110)
PY
echo "wrote $out/runs.csv and $out/tolerance.png"
