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
# Single tolerances: the spread between solvers at each decade's rtol, beside the band (nine
# rtols within 4%): the largest range of one solver's digits over its band, and the spread
# between the solvers' band medians.
single = collections.defaultdict(dict)
band = collections.defaultdict(lambda: collections.defaultdict(list))
for r in rows:
    if r["ok"] != "1":
        continue
    dec = round(-np.log10(float(r["tol"])))
    pair = (float(r["digits"]), float(r["trajectory_digits"]))
    if r["method"] == "ida":
        single[(r["problem"], dec)][r["solver"]] = pair
    elif r["method"] == "ida_band":
        band[(r["problem"], dec)][r["solver"]].append(pair)
print()
print("| problem | rtol | solvers' spread, end / along the run | one solver's range over the band, end / along | spread of the band medians, end / along |")
print("|---|---|---|---|---|")
for key in sorted(single, key=lambda k: (k[0] != "pendulum", k[1])):
    s = single[key]
    spread = [max(v[i] for v in s.values()) - min(v[i] for v in s.values()) for i in (0, 1)]
    b = band.get(key, {})
    if b:
        rng = [max(max(p[i] for p in v) - min(p[i] for p in v) for v in b.values()) for i in (0, 1)]
        med = [[float(np.median([p[i] for p in v])) for v in b.values()] for i in (0, 1)]
        tail = f"{rng[0]:.2f} / {rng[1]:.2f} | {max(med[0]) - min(med[0]):.2f} / {max(med[1]) - min(med[1]):.2f}"
    else:
        tail = "– | –"
    print(f"| {key[0]} | 1e-{key[1]} | {spread[0]:.2f} / {spread[1]:.2f} | {tail} |")
PY
echo "wrote $out/runs.csv and $out/tolerance.png"
