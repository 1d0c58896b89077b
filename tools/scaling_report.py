#!/usr/bin/python3
"""The scaling table and chart of bench/scaling.sh: for each run ball_<tets>_<solver>.h5 in DIR,
wall time per step, per Newton iteration and per frame, CG iterations per Newton iteration, peak
memory; the exponent of each fitted (least squares in log-log) against the number of tets.

    /usr/bin/python3 tools/scaling_report.py DIR OUT_DIR     (writes OUT_DIR/scaling.md, scaling.png)
"""
import glob
import os
import re
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def exponent(x, y):
    """Slope of log y against log x (least squares); nan with fewer than two points.

    >>> round(exponent([1, 10, 100], [2, 20, 200]), 12)
    1.0
    >>> round(exponent([1, 10, 100], [5, 500, 50000]), 12)
    2.0
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0) & np.isfinite(y)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def main():
    d, out = sys.argv[1], sys.argv[2]
    rows = []
    for path in sorted(glob.glob(os.path.join(d, "ball_*_*.h5"))):
        m = re.match(r"ball_(\d+)_(\w+)\.h5", os.path.basename(path))
        try:
            with h5py.File(path, "r") as f:
                st = dict(f["stats"].attrs)
                tets = f["mesh/tets"].shape[0]
                frames = f["frames/time"].shape[0]
                status = f.attrs["status"]
                status = status.decode() if isinstance(status, bytes) else str(status)
        except (OSError, KeyError):
            continue
        wall, steps, newton = float(st.get("wall_seconds", np.nan)), float(st.get("steps", np.nan)), \
            float(st.get("newton_iterations", np.nan))
        rows.append(dict(target=int(m.group(1)), solver=m.group(2), tets=tets, frames=frames, status=status, wall=wall,
                         per_step=wall / steps, per_newton=wall / newton, per_frame=wall / max(frames - 1, 1),
                         cg=float(st.get("linear_iterations", 0)) / newton, memory=float(st.get("peak_memory_mb", np.nan)),
                         steps=steps))
    if not rows:
        sys.exit(f"{d}: no ball_<tets>_<solver>.h5 runs")
    solvers = sorted({r["solver"] for r in rows})
    lines = ["# One scene's cost from 1K tets up (`bench/scaling.sh`)", "",
             "The damped ball (`demos/ball_drop.toml`, β = 1e-4 s), 50 ms through its impact (30 ms of flight, "
             "20 ms of contact), IDA rtol 1e-6, one thread each, the two solvers side by side.", "",
             "| tets | solver | status | steps | wall (s) | per step (ms) | per Newton it. (ms) | per frame (s) | "
             "CG it. per Newton it. | peak memory (MB) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["tets"], r["solver"])):
        lines.append(f"| {r['tets']:,} | {r['solver']} | {r['status']} | {r['steps']:,.0f} | {r['wall']:.1f} | "
                     f"{1e3 * r['per_step']:.2f} | {1e3 * r['per_newton']:.2f} | {r['per_frame']:.3f} | "
                     f"{r['cg']:.1f} | {r['memory']:.0f} |")
    lines += ["", "Fitted exponents (cost ∝ tets^p, least squares over the sizes above):", "",
              "| solver | per step | per Newton it. | per frame | CG it. per Newton it. | peak memory |", "|---|---|---|---|---|---|"]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.8))
    for s in solvers:
        rs = sorted([r for r in rows if r["solver"] == s and r["status"] == "finished"], key=lambda r: r["tets"])
        t = [r["tets"] for r in rs]
        ex = {k: exponent(t, [r[k] for r in rs]) for k in ("per_step", "per_newton", "per_frame", "cg", "memory")}
        lines.append(f"| {s} | {ex['per_step']:.2f} | {ex['per_newton']:.2f} | {ex['per_frame']:.2f} | "
                     f"{ex['cg']:.2f} | {ex['memory']:.2f} |")
        axes[0].loglog(t, [r["per_newton"] * 1e3 for r in rs], "o-", label=f"{s} (p = {ex['per_newton']:.2f})")
        axes[1].loglog(t, [r["per_frame"] for r in rs], "o-", label=f"{s} (p = {ex['per_frame']:.2f})")
        if s != "reduced":
            axes[2].loglog(t, [r["cg"] for r in rs], "o-", label=f"{s} (p = {ex['cg']:.2f})")
    for ax, title in zip(axes, ("wall per Newton iteration (ms)", "wall per frame (s)", "CG iterations per Newton it.")):
        ax.set_xlabel("tets")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(out, exist_ok=True)
    fig.savefig(os.path.join(out, "scaling.png"), dpi=100)
    lines += ["", "![cost against tets, log-log](scaling.png)", ""]
    with open(os.path.join(out, "scaling.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {out}/scaling.md and scaling.png ({len(rows)} runs)")


if __name__ == "__main__":
    main()
