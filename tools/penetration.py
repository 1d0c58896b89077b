#!/usr/bin/python3
"""How deep the surface of a run's body passes into its own other parts (self-penetration).

    /usr/bin/python3 tools/penetration.py RUN.h5 [--frames 0,25,-1] [--exclude 0.05] [--region xmin,xmax]

For each surface node, the nearest surface triangle whose corners were all farther than
--exclude (m) from the node at rest (not its own neighbourhood), by centroid; the node's signed
distance to that triangle's plane along its outward normal (deformed). A negative distance whose
projection falls inside the triangle is a penetration; prints the deepest per frame (m), the
node, and how many nodes are inside. --region keeps only nodes whose rest x lies in the range
(e.g. the forearm's tissue).
"""
import argparse

import h5py
import numpy as np


def deepest(X, x, S, exclude, nodes):
    a, b, c = x[S[:, 0]], x[S[:, 1]], x[S[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    cen = (a + b + c) / 3
    rest = X[S]  # (T, 3, 3)
    worst, where, inside = 0.0, -1, 0
    for p in nodes:
        far = (np.linalg.norm(rest - X[p], axis=2) > exclude).all(axis=1)
        if not far.any():
            continue
        idx = np.flatnonzero(far)
        d2 = ((cen[idx] - x[p]) ** 2).sum(1)
        for t in idx[np.argsort(d2)[:6]]:  # the nearest few by centroid
            s = (x[p] - a[t]) @ n[t]
            q = x[p] - s * n[t]
            # inside the triangle: barycentric coordinates all >= 0
            v0, v1, v2 = b[t] - a[t], c[t] - a[t], q - a[t]
            d00, d01, d11, d20, d21 = v0 @ v0, v0 @ v1, v1 @ v1, v2 @ v0, v2 @ v1
            den = d00 * d11 - d01 * d01
            if den <= 0:
                continue
            l1, l2 = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
            if l1 >= 0 and l2 >= 0 and l1 + l2 <= 1:
                if s < 0:
                    inside += 1
                    if -s > worst:
                        worst, where = -s, p
                break
    return worst, where, inside


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--frames", default="-1")
    ap.add_argument("--exclude", type=float, default=0.05)
    ap.add_argument("--region", default="")
    a = ap.parse_args()
    f = h5py.File(a.run, "r", locking=False)
    X = f["/mesh/rest_positions"][()]
    S = f["/mesh/surface"][()]
    nodes = np.unique(S)
    if a.region:
        lo, hi = (float(v) for v in a.region.split(","))
        nodes = nodes[(X[nodes, 0] >= lo) & (X[nodes, 0] <= hi)]
    times = f["/frames/time"][()]
    for k in (int(v) for v in a.frames.split(",")):
        w, p, inside = deepest(X, f["/frames/positions"][k], S, a.exclude, nodes)
        print(f"frame {k % len(times)} t = {times[k]:.3f} s: deepest penetration {1000 * w:.2f} mm (node {p}), {inside} nodes inside")


if __name__ == "__main__":
    main()
