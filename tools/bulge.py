#!/usr/bin/env python3
"""Outward displacement of a zone's surface, and every zone's volume drift, in isochor runs.

    /usr/bin/python3 tools/bulge.py RUN.h5 [RUN.h5 ...] --zone biceps --time 1.0 \
        [--axis 0,0,0,1,0,0] [--bins 0.04]

Outward is away from an axis line (point, direction; default the x axis): for each surface node of
the zone, its distance from the axis at the frame nearest --time minus its rest distance. Prints
the largest and the mean, per slab along the axis when --bins is given, and the worst
|V - V0| / V0 of each zone over all frames (the rigged arm of demos/arm_flex.toml: the biceps
region bulges when the squeezed crease of the elbow keeps its volume).
"""
import argparse

import numpy as np

from run_file import open_run


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--zone", default="biceps")
    ap.add_argument("--time", type=float, default=1.0)
    ap.add_argument("--axis", default="0,0,0,1,0,0", help="point and direction of the axis, 6 numbers")
    ap.add_argument("--bins", type=float, default=0.0, help="slab width along the axis (m); 0: none")
    a = ap.parse_args()
    ax = np.array([float(v) for v in a.axis.split(",")])
    if ax.size != 6 or np.linalg.norm(ax[3:]) == 0:
        ap.error("--axis: expected 6 numbers, a point and a non-zero direction")
    p0, d = ax[:3], ax[3:] / np.linalg.norm(ax[3:])
    for path in a.runs:
        with open_run(path, "bulge.py") as run:
            if a.zone not in run.zones:
                raise SystemExit(f"{path}: no zone \"{a.zone}\" (zones: {', '.join(run.zones)})")
            X, T, S, times = run.rest_positions, run.tets, run.surface, run.times
            k = int(np.argmin(np.abs(times - a.time)))
            x = run.frame_positions(k)
            V, names = run.volumes, run.volume_columns
            nodes = np.intersect1d(np.unique(T[run.zones[a.zone]]), np.unique(S))

        def radial(P):
            r = P - p0
            return np.linalg.norm(r - np.outer(r @ d, d), axis=1)

        out = radial(x[nodes]) - radial(X[nodes])
        along = (X[nodes] - p0) @ d
        drift = np.max(np.abs(V / V[0] - 1), axis=0)
        print(f"{path}: frame {k} (t = {times[k]:g} s), zone {a.zone}: {len(nodes)} surface nodes, "
              f"largest outward displacement {out.max():.5f} m (at {along[np.argmax(out)]:.3f} m along the axis), "
              f"mean {out.mean():.5f} m")
        print("  volume drift (max |V - V0| / V0): " + ", ".join(f"{n} {v:.2e}" for n, v in zip(names, drift)))
        if a.bins > 0:
            for lo in np.arange(along.min(), along.max() + 1e-12, a.bins):
                m = (along >= lo) & (along < lo + a.bins)
                if m.any():
                    print(f"  {lo:6.3f} .. {lo + a.bins:6.3f} m: largest {out[m].max():8.5f}, mean {out[m].mean():8.5f} ({m.sum()} nodes)")


if __name__ == "__main__":
    main()
