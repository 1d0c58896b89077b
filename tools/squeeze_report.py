#!/usr/bin/python3
"""Measure a body squeezed between cylinder colliders (demos/armadillo.toml, squeeze_cylinders.toml).

    /usr/bin/python3 tools/squeeze_report.py LABEL=RUN.h5 [LABEL=RUN.h5 ...] [--out PICTURE.png]
        [--markdown FILE.md] [--cut x=0.05]

For each run: every zone's volume change at the tightest frame (where the cylinders' axes are
nearest each other) and the largest over the run, both against frame 0; the deepest a surface
node goes into a cylinder over the run (its depth below the curved surface, inside the cylinder's
length; negative: the contact kept every node outside); the gap left between the cylinders at the tightest frame and the body's
depth there; wall time per frame and steps. The picture: each run's cross-section in the plane
--cut (rest dashed, tightest frame solid) with the cylinders there.
"""
import argparse
import sys

import numpy as np

from run_file import labelled_runs, open_run, write_png, write_whole
from waistband import slice_segments


def cylinders(run):
    return [c for c in run.colliders if c.shape == "cylinder"]


def cylinder_depth(run, k, c, x):
    """Each point's depth inside cylinder c at frame k (positive: inside; -inf beyond its ends)."""
    A, b = run.collider_pose(k, c.index)
    local = (x - b) @ A  # A is a rotation: l = A^T (x - b)
    radius = c.dimensions["radius"] * run.collider_scale(k, c.index)
    depth = radius - np.hypot(local[:, 0], local[:, 1])
    depth[np.abs(local[:, 2]) > 0.5 * c.dimensions["length"]] = -np.inf
    return depth


def axis_distance(run, k, cyl):
    """The distance between the first two cylinders' axes at frame k (their centres' distance
    across the axis for parallel axes)."""
    (A0, b0), (A1, b1) = run.collider_pose(k, cyl[0].index), run.collider_pose(k, cyl[1].index)
    a = A0[:, 2]
    d = b1 - b0
    return float(np.linalg.norm(d - (d @ a) * a))


def measure(path):
    run = open_run(path, "squeeze_report.py")
    cyl = cylinders(run)
    if len(cyl) < 2:
        sys.exit(f"squeeze_report.py: {path}: expected two cylinder colliders, found {len(cyl)}")
    gaps = [axis_distance(run, k, cyl) for k in range(run.num_frames)]
    tight = int(np.argmin(gaps))
    nodes = np.unique(run.surface)
    pen = -np.inf
    for k in range(run.num_frames):
        x = run.frame_positions(k)[nodes]
        pen = max(pen, max(float(cylinder_depth(run, k, c, x).max()) for c in cyl))
    V = run.volumes
    rel = V / V[0] - 1
    radii = [c.dimensions["radius"] for c in cyl[:2]]
    frames = max(run.num_frames - 1, 1)
    return {"run": run, "tight": tight, "time": float(run.times[tight]), "status": run.status,
            "end": float(run.times[-1]), "columns": run.volume_columns,
            "at_tight": rel[tight], "worst": rel[np.argmax(np.abs(rel), axis=0), np.arange(rel.shape[1])],
            "penetration": pen, "gap": gaps[tight] - sum(radii), "gap0": gaps[0] - sum(radii),
            "s_per_frame": float(run.totals.get("wall_seconds", np.nan)) / frames,
            "steps": float(run.totals.get("steps", np.nan))}


def table(runs):
    cols = runs[0][1]["columns"]
    lines = ["| | " + " | ".join(label for label, _ in runs) + " |", "|---" * (len(runs) + 1) + "|"]

    def row(name, fmt):
        lines.append(f"| {name} | " + " | ".join(fmt(m) for _, m in runs) + " |")

    row("status (last frame)", lambda m: f"{m['status']}, {m['end']:.2f} s")
    row("tightest frame (t)", lambda m: f"{m['time']:.2f} s")
    row("gap between the cylinders, start → tightest (cm)", lambda m: f"{100 * m['gap0']:.1f} → {100 * m['gap']:.1f}")
    for j, c in enumerate(cols):
        name = "whole body" if c == "total" else f"zone {c}"
        row(f"volume change at the tightest frame: {name}",
            lambda m, j=j: f"{100 * m['at_tight'][j]:+.3g}%" if j < len(m["at_tight"]) else "–")
    for j, c in enumerate(cols):
        name = "whole body" if c == "total" else f"zone {c}"
        row(f"largest volume change over the run: {name}",
            lambda m, j=j: f"{abs(m['worst'][j]):.2g}" if j < len(m["worst"]) else "–")
    row("deepest surface node into a cylinder over the run (mm; < 0: never inside)", lambda m: f"{1000 * m['penetration']:+.2f}")
    row("steps; wall time per frame (s)", lambda m: f"{m['steps']:.0f}; {m['s_per_frame']:.3f}")
    return "\n".join(lines)


def picture(runs, out, cut_axis, cut):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle
    ax_u, ax_v = [a for a in range(3) if a != cut_axis][::-1]  # x cut: z across, y up
    fig, axes = plt.subplots(1, len(runs), figsize=(4.6 * len(runs), 5.2), squeeze=False)
    for ax, (label, m) in zip(axes[0], runs):
        run, k = m["run"], m["tight"]
        for pos, style in ((run.frame_positions(0), dict(color="0.6", ls="--", lw=0.8)),
                           (run.frame_positions(k), dict(color="tab:blue", lw=1.3))):
            for s in slice_segments(pos, run.surface, cut_axis, cut):
                ax.plot(s[:, ax_u], s[:, ax_v], **style)
        for c in cylinders(run):
            A, b = run.collider_pose(k, c.index)
            ax.add_patch(Circle((b[ax_u], b[ax_v]), c.dimensions["radius"] * run.collider_scale(k, c.index),
                                color="tab:red", alpha=0.35))
        ax.set_aspect("equal")
        ax.set_title(f"{label}\nbody {100 * m['at_tight'][0]:+.2g}% at t = {m['time']:.2f} s", fontsize=10)
        ax.set_xlabel("xyz"[ax_u] + " (m)")
        ax.set_ylabel("xyz"[ax_v] + " (m)")
    fig.suptitle(f"Cross-sections at {'xyz'[cut_axis]} = {cut:g} m (rest dashed, tightest frame solid)", fontsize=11)
    fig.tight_layout()
    write_png(out, fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="LABEL=RUN.h5")
    ap.add_argument("--out", default="")
    ap.add_argument("--markdown", default="")
    ap.add_argument("--cut", default="x=0.05", help="the cross-section's plane, AXIS=VALUE (m)")
    a = ap.parse_args()
    axis, _, value = a.cut.partition("=")
    if axis not in ("x", "y", "z") or not value:
        sys.exit(f"squeeze_report.py: --cut {a.cut}: expected x=VALUE, y=VALUE or z=VALUE")
    runs = [(label, measure(path)) for label, path in labelled_runs(a.runs, "squeeze_report.py")]
    text = table(runs)
    print(text)
    if a.markdown:
        write_whole(a.markdown, lambda f: f.write(text + "\n"))
    if a.out:
        picture(runs, a.out, "xyz".index(axis), float(value))


if __name__ == "__main__":
    main()
