#!/usr/bin/python3
"""Measure waistband runs (demos/waistband.toml) and draw them side by side (the CNH paper's Figure 1).

    /usr/bin/python3 tools/waistband.py LABEL=RUN.h5 [LABEL=RUN.h5 ...] [--out docs/images/waistband.png]
        [--markdown FILE.md] [--band-z 0.40] [--band-height 0.05] [--garment Z0,Z1]

For each run, at its last frame against its first: the total and per-zone volume change (every
zone in /frames/volume, constrained or only measured), the waist circumference in the planes
just above the band, at its middle and just below it (the length of the surface's cross-section),
and the bulge: the largest outward radial displacement of a surface node above and below the band
(within 10 cm of it). The picture shows each body's cross-section in the plane y = 0 (front view:
rest dashed, last frame solid), the band at its last radius, and a zoom on the waist. A run with
no band (demos/waistband_tight.toml: a garment's pressure) is measured at --band-z alike, and
--garment Z0,Z1 marks the garment's span in the picture instead of the band.
"""
import argparse
import sys

import numpy as np

from run_file import labelled_runs, open_run


def slice_segments(x, tris, axis, level):
    """Segments where the plane x[axis] = level cuts the triangles (array (k, 2, 3))."""
    d = x[tris][:, :, axis] - level  # (T, 3)
    segs = []
    for t, dd in zip(x[tris], d):
        pts = []
        for i in range(3):
            a, b = dd[i], dd[(i + 1) % 3]
            if (a < 0) != (b < 0):
                s = a / (a - b)
                pts.append(t[i] + s * (t[(i + 1) % 3] - t[i]))
        if len(pts) == 2:
            segs.append(pts)
    return np.array(segs).reshape(-1, 2, 3)


def circumference(x, tris, z):
    s = slice_segments(x, tris, 2, z)
    return float(np.linalg.norm(s[:, 1] - s[:, 0], axis=1).sum())


def band_radius(run):
    """The band (the first solid collider): its hole's radius at the last frame, its length, its
    wall and its centre there."""
    c = next(c for c in run.colliders if c.shape == "cylinder")
    r = c.dimensions["radius"] * run.collider_scale(-1, c.index)
    _, centre = run.collider_pose(-1, c.index)
    return r, c.dimensions["length"], c.dimensions.get("wall", 0.0), centre


def measure(path, band_z, band_h):
    run = open_run(path, "waistband.py")
    X, x, S, V = run.frame_positions(0), run.frame_positions(-1), run.surface, run.volumes
    out = {"time": float(run.times[-1]), "frames": run.num_frames,
           "volume": {c: float(V[-1, k] / V[0, k] - 1) for k, c in enumerate(run.volume_columns)}}
    for name, z in (("above", band_z + 0.5 * band_h + 0.01), ("at", band_z), ("below", band_z - 0.5 * band_h - 0.01)):
        out["circ_" + name] = (circumference(X, S, z), circumference(x, S, z))
    nodes = np.unique(S)
    dr = np.hypot(x[nodes, 0], x[nodes, 1]) - np.hypot(X[nodes, 0], X[nodes, 1])
    zr = X[nodes, 2]
    above = (zr > band_z + 0.5 * band_h) & (zr < band_z + 0.5 * band_h + 0.1)
    below = (zr < band_z - 0.5 * band_h) & (zr > band_z - 0.5 * band_h - 0.1)
    under = np.abs(zr - band_z) < 0.5 * band_h
    out["bulge_above"] = float(dr[above].max())
    out["bulge_below"] = float(dr[below].max())
    out["squeeze"] = float(-dr[under].min())
    out["wall"] = float(run.totals.get("wall_seconds", np.nan))
    out["status"] = run.status
    return out, run


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="LABEL=RUN.h5")
    ap.add_argument("--out", default="")
    ap.add_argument("--markdown", default="")
    ap.add_argument("--band-z", type=float, default=0.40)
    ap.add_argument("--band-height", type=float, default=0.05)
    ap.add_argument("--garment", default="", help="Z0,Z1: the garment's span (m), drawn instead of a band")
    a = ap.parse_args()
    garment = [float(v) for v in a.garment.split(",")] if a.garment else None
    if garment is not None and len(garment) != 2:
        sys.exit(f"waistband.py: --garment {a.garment}: expected Z0,Z1")
    runs = []
    for label, path in labelled_runs(a.runs, "waistband.py"):
        m, f = measure(path, a.band_z, a.band_height)
        runs.append((label, path, m, f))
    zones = [c for c in runs[0][2]["volume"]]
    lines = ["| | " + " | ".join(label for label, *_ in runs) + " |", "|---" * (len(runs) + 1) + "|"]
    lines.append("| status (last frame, time) | " + " | ".join(f"{m['status']}, {m['time']:.2f} s" for _, _, m, _ in runs) + " |")
    for z in zones:
        lines.append(f"| volume change: {z} | " + " | ".join(f"{100 * m['volume'][z]:+.3g}%" for _, _, m, _ in runs) + " |")
    for name, what in (("above", "just above the band"), ("at", "at the band"), ("below", "just below the band")):
        lines.append(f"| waist circumference {what} (rest → last, cm) | " + " | ".join(
            f"{100 * m['circ_' + name][0]:.2f} → {100 * m['circ_' + name][1]:.2f}" for _, _, m, _ in runs) + " |")
    lines.append("| squeeze under the band (largest inward, mm) | " + " | ".join(f"{1000 * m['squeeze']:.1f}" for _, _, m, _ in runs) + " |")
    lines.append("| bulge above / below (largest outward, mm) | " + " | ".join(
        f"{1000 * m['bulge_above']:.2f} / {1000 * m['bulge_below']:.2f}" for _, _, m, _ in runs) + " |")
    lines.append("| wall time (s) | " + " | ".join(f"{m['wall']:.1f}" for _, _, m, _ in runs) + " |")
    table = "\n".join(lines)
    print(table)
    if a.markdown:
        open(a.markdown, "w").write(table + "\n")
    if a.out:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.patches import Rectangle
        fig, axes = plt.subplots(2, len(runs), figsize=(4.2 * len(runs), 9), gridspec_kw={"height_ratios": [3, 2]})
        axes = np.array(axes).reshape(2, len(runs))
        for j, (label, path, m, f) in enumerate(runs):
            X, x, S = f.frame_positions(0), f.frame_positions(-1), f.surface
            c = np.array([0.0, 0.0, a.band_z])
            for row in range(2):
                ax = axes[row, j]
                for pos, style in ((X, dict(color="0.6", ls="--", lw=0.8)), (x, dict(color="tab:blue", lw=1.4))):
                    for s in slice_segments(pos, S, 1, 0.0):
                        ax.plot(s[:, 0], s[:, 2], **style)
                if garment is not None:
                    ax.axhspan(garment[0], garment[1], color="tab:red", alpha=0.08, lw=0)
                else:
                    R, L, wall, c = band_radius(f)
                    for sign in (-1, 1):
                        x0 = sign * R if sign > 0 else -R - wall
                        ax.add_patch(Rectangle((x0, c[2] - L / 2), wall, L, color="tab:red", alpha=0.6))
                ax.set_aspect("equal")
                if row == 0:
                    ax.set_title(f"{label}\nvolume {100 * m['volume']['total']:+.2g}%", fontsize=10)
                    ax.set_xlabel("x (m)")
                else:
                    ax.set_xlim(0.06, 0.17)
                    ax.set_ylim(c[2] - 0.12, c[2] + 0.12)
                    ax.set_title(f"waist: circumference {100 * m['circ_at'][1]:.1f} cm (rest {100 * m['circ_at'][0]:.1f})"
                                 if garment is not None else
                                 f"waist: bulge {1000 * m['bulge_above']:.1f} / {1000 * m['bulge_below']:.1f} mm", fontsize=9)
                    ax.set_xlabel("x (m)")
                ax.set_ylabel("z (m)")
        what = ("A garment's pressure (shaded span)" if garment is not None
                else "A band tightening by 10% around the waist")
        fig.suptitle(f"{what}: cross-sections at y = 0 (rest dashed, last frame solid)", fontsize=11)
        fig.tight_layout()
        fig.savefig(a.out, dpi=110)
        print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
