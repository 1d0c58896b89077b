#!/usr/bin/env python3
"""A muscle's activation, cross-section, bulge and volume at every frame of isochor runs.

    /usr/bin/python3 tools/muscle_report.py RUN.h5 [RUN.h5 ...] --muscle biceps \
        [--axis 0,0,0,1,0,0] [--at 0.15] [--chart out/biceps.png]

Per frame: the muscle's activation (/frames/activation), the area of its cross-section by the
plane normal to the axis through --at (default: the muscle's rest centroid along the axis; the
deformed tets cut by that plane, each cut a triangle or a quadrilateral), the largest outward
displacement of its surface nodes from the axis (distance from the axis at the frame minus at
rest), the volume-weighted mean fibre stretch |F a0| over its tets, and |V - V0| / V0 of its
tets' volume. With --chart, a picture of area and bulge against
time for every run.
"""
import argparse

import numpy as np

from run_file import open_run, write_whole


def cut_area(x, tets, p0, d):
    """Area of the cut of the tets (positions x) by the plane through p0 normal to d."""
    area = 0.0
    s = (x[tets] - p0) @ d  # (T, 4) signed distances
    for k in np.nonzero((s.min(axis=1) < 0) & (s.max(axis=1) > 0))[0]:
        pts = []
        for i in range(4):
            for j in range(i + 1, 4):
                if (s[k, i] < 0) != (s[k, j] < 0):
                    w = s[k, i] / (s[k, i] - s[k, j])
                    pts.append((1 - w) * x[tets[k, i]] + w * x[tets[k, j]])
        pts = np.array(pts)
        c = pts.mean(axis=0)
        e1 = pts[0] - c
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(d, e1)
        order = np.argsort(np.arctan2((pts - c) @ e2, (pts - c) @ e1))
        p = pts[order]
        for i in range(1, len(p) - 1):
            area += 0.5 * np.linalg.norm(np.cross(p[i] - p[0], p[i + 1] - p[0]))
    return area


def tets_volume(x, tets):
    a, b, c, e = (x[tets[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, e - a)).sum() / 6.0


def fibre_stretch(X, x, tets, fibre, weight):
    """The volume-weighted mean of |F a0| over the tets (F of each linear tet)."""
    Dm = np.stack([X[tets[:, i]] - X[tets[:, 0]] for i in (1, 2, 3)], axis=2)
    Ds = np.stack([x[tets[:, i]] - x[tets[:, 0]] for i in (1, 2, 3)], axis=2)
    F = Ds @ np.linalg.inv(Dm)
    return float((np.linalg.norm(np.einsum("tij,tj->ti", F, fibre), axis=1) * weight).sum() / weight.sum())


def report(path, muscle, p0, d, at):
    """Rows (t, activation, area, largest outward, fibre stretch, volume drift) of one run."""
    with open_run(path, "muscle_report.py") as run:
        if muscle not in run.muscles:
            raise SystemExit(f"{path}: no muscle \"{muscle}\" (muscles: {', '.join(run.muscles) or 'none'})")
        m = run.muscles.index(muscle)
        tets, fibre, weight = run.tets[run.tet_muscle == m], run.tet_fibre[run.tet_muscle == m], run.rest_volumes[run.tet_muscle == m]
        X = run.rest_positions
        nodes = np.intersect1d(np.unique(tets), np.unique(run.surface))
        plane = p0 + d * (at if at is not None else (X[np.unique(tets)] - p0).mean(axis=0) @ d)

        def radial(P):
            r = P - p0
            return np.linalg.norm(r - np.outer(r @ d, d), axis=1)

        V0 = tets_volume(X, tets)
        act = run.activation
        rows = []
        for k in range(run.num_frames):
            x = run.frame_positions(k)
            rows.append((run.times[k], act[k, m] if act is not None else 0.0, cut_area(x, tets, plane, d),
                         (radial(x[nodes]) - radial(X[nodes])).max(), fibre_stretch(X, x, tets, fibre, weight),
                         abs(tets_volume(x, tets) / V0 - 1)))
    return np.array(rows), (plane - p0) @ d


def chart(path, results, muscle):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for name, rows in results:
        a1.plot(rows[:, 0], rows[:, 2] * 1e4, label=name)
        a2.plot(rows[:, 0], rows[:, 3] * 1e3, label=name)
    a1.set(xlabel="t (s)", ylabel="cross-section (cm²)", title=f"{muscle}: mid-belly cross-section")
    a2.set(xlabel="t (s)", ylabel="largest outward displacement (mm)", title=f"{muscle}: bulge")
    a1.legend(fontsize=8)
    fig.tight_layout()
    write_whole(path, lambda f: fig.savefig(f, dpi=110, format="png"), mode="wb")
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--muscle", default="biceps")
    ap.add_argument("--axis", default="0,0,0,1,0,0", help="point and direction of the axis, 6 numbers")
    ap.add_argument("--at", type=float, default=None, help="the cut's position along the axis (m)")
    ap.add_argument("--chart", default="", help="a PNG of area and bulge against time")
    a = ap.parse_args()
    ax = np.array([float(v) for v in a.axis.split(",")])
    if ax.size != 6 or np.linalg.norm(ax[3:]) == 0:
        ap.error("--axis: expected 6 numbers, a point and a non-zero direction")
    p0, d = ax[:3], ax[3:] / np.linalg.norm(ax[3:])
    results = []
    for path in a.runs:
        rows, at = report(path, a.muscle, p0, d, a.at)
        print(f"{path}: muscle {a.muscle}, cut at {at:.4f} m along the axis")
        print("      t  activation  area (cm2)  largest outward (mm)  fibre stretch  volume drift")
        for r in rows:
            print(f"  {r[0]:5.2f}  {r[1]:10.3f}  {r[2] * 1e4:10.3f}  {r[3] * 1e3:20.2f}  {r[4]:13.3f}  {r[5]:12.1e}")
        results.append((path, rows))
    if a.chart:
        chart(a.chart, results, a.muscle)


if __name__ == "__main__":
    main()
