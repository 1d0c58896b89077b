#!/usr/bin/python3
"""The scaling table and chart of bench/scaling.sh: for each run ball_<tets>_<solver>.h5 in DIR,
wall time per step, per Newton iteration and per frame, CG iterations per Newton iteration, peak
memory; the exponent of each fitted (least squares in log-log) against the number of tets.

    /usr/bin/python3 tools/scaling_report.py DIR OUT_DIR     (writes OUT_DIR/scaling.md, scaling.png)
    /usr/bin/python3 tools/scaling_report.py DIR OUT_DIR --until 0.034 --name scaling_34ms

With --until T every run is read up to its frame at time T from the per-frame cumulative series
(/stats wall_seconds, steps, newton_iterations, resident_mb), so a run stopped past T (interrupted:
the 1M-tet ball) joins runs that ended there; CG iterations per Newton iteration are then the whole
run's (attributes only). A run that did not reach T is listed and left out of the fits.
"""
import glob
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from run_file import Error, Run  # noqa: E402


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


def window(series, times, until):
    """The cumulative series at the frame at time `until` (the last frame if until is None); None
    when the run has no frame there.

    >>> window([0, 5, 9, 12], [0.0, 0.01, 0.02, 0.03], 0.02)
    9.0
    >>> window([0, 5, 9, 12], [0.0, 0.01, 0.02, 0.03], None)
    12.0
    >>> window([0, 5], [0.0, 0.01], 0.02) is None
    True
    """
    times = np.asarray(times, float)
    if until is None:
        return float(series[len(times) - 1])
    k = np.flatnonzero(np.abs(times - until) <= 1e-9 * max(1.0, abs(until)))
    return float(series[k[0]]) if k.size else None


def read_row(path, until):
    """One run's row: its size, status and costs (whole, or read at its frame at `until`);
    None for a file that is not a readable run."""
    m = re.match(r"ball_(\d+)_(\w+)\.h5", os.path.basename(path))
    try:
        with Run(path) as run:
            st = run.totals
            tets = len(run.tets)
            times = run.times
            series = {k: run.stats[k] for k in ("wall_seconds", "steps", "newton_iterations", "resident_mb")}
            status = run.status
    except (Error, OSError, KeyError):
        return None
    if until is None:
        wall, steps, newton = float(st.get("wall_seconds", np.nan)), float(st.get("steps", np.nan)), \
            float(st.get("newton_iterations", np.nan))
        frames, memory = len(times), float(st.get("peak_memory_mb", np.nan))
        used = status == "finished"
    else:
        wall, steps, newton = (window(series[k], times, until) for k in ("wall_seconds", "steps", "newton_iterations"))
        used = wall is not None
        if not used:
            wall = steps = newton = np.nan
            status += f", ended before {until:g} s"
        frames = int(np.sum(times <= until + 1e-12))
        memory = float(np.max(series["resident_mb"][:frames])) if frames else np.nan
    return dict(target=int(m.group(1)), solver=m.group(2), tets=tets, frames=frames, status=status, wall=wall,
                per_step=wall / steps, per_newton=wall / newton, per_frame=wall / max(frames - 1, 1),
                cg=float(st.get("linear_iterations", 0)) / float(st.get("newton_iterations", np.nan)),
                memory=memory, steps=steps, used=used, last=float(times[-1]))


def main():
    args = sys.argv[1:]
    until, name = None, "scaling"
    if "--until" in args:
        i = args.index("--until")
        until = float(args[i + 1])
        del args[i:i + 2]
    if "--name" in args:
        i = args.index("--name")
        name = args[i + 1]
        del args[i:i + 2]
    if len(args) != 2:
        sys.exit("usage: scaling_report.py DIR OUT_DIR [--until T] [--name NAME]")
    d, out = args
    rows = [r for path in sorted(glob.glob(os.path.join(d, "ball_*_*.h5"))) for r in [read_row(path, until)] if r]
    if not rows:
        sys.exit(f"{d}: no ball_<tets>_<solver>.h5 runs")
    solvers = sorted({r["solver"] for r in rows})
    span = until if until is not None else max(r["last"] for r in rows)
    lines = ["# One scene's cost from 1K tets up (`bench/scaling.sh`)", "",
             f"The damped ball (`demos/ball_drop.toml`, β = 1e-4 s), {1e3 * span:.0f} ms through its impact (30 ms of "
             f"flight, {1e3 * span - 30:.0f} ms of contact), IDA rtol 1e-6, one thread each"
             + (", the solvers side by side." if until is None else
                f"; every run read at its frame at {until:g} s (`--until`)."), "",
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
        rs = sorted([r for r in rows if r["solver"] == s and r["used"]], key=lambda r: r["tets"])
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
    fig.savefig(os.path.join(out, name + ".png"), dpi=100)
    lines += ["", f"![cost against tets, log-log]({name}.png)", ""]
    with open(os.path.join(out, name + ".md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {out}/{name}.md and {name}.png ({len(rows)} runs)")


if __name__ == "__main__":
    main()
