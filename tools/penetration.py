#!/usr/bin/python3
"""How deep the surface of a run's body passes into its own other parts (self-penetration).

    /usr/bin/python3 tools/penetration.py RUN.h5 [--frames 0,25,-1] [--exclude 0.05] [--region xmin,xmax] [--into xmin,xmax]

A surface node has passed into another part of the body when it lies inside a deformed tet whose
four corners were all farther than --exclude (m) from the node at rest (not its own
neighbourhood). Its depth is then its distance to the nearest surface triangle of that far part
(corners all farther than --exclude at rest). Prints the deepest per frame (m), the node, and how
many nodes are inside. --region keeps only nodes whose rest x lies in the range (e.g. the
forearm's tissue), --into only tets and triangles whose corners' rest x all lie in it (e.g. the
upper arm's). (The sign is not taken from the nearest far triangle's plane: that counts nodes
near a triangle several cm away, on another side of the limb, as inside.)
"""
import argparse

import numpy as np

from run_file import open_run


def point_triangle_distance(p, a, b, c):
    """Distance from p to each triangle (a, b, c: (T, 3) arrays), by the closest point's region."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp, cp = p - b, p - c
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    # va, vb, vc >= 0: p projects inside the face (Ericson's regions)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    den = np.where(va + vb + vc == 0, 1.0, va + vb + vc)
    v, w = vb / den, vc / den
    q = a + ab * v[:, None] + ac * w[:, None]
    face = np.where((va >= 0) & (vb >= 0) & (vc >= 0), np.linalg.norm(p - q, axis=1), np.inf)  # the face's region
    edges = np.full(len(a), np.inf)  # otherwise the nearest point of an edge (or corner)
    for s, e in ((a, b), (b, c), (c, a)):
        t = np.clip(((p - s) * (e - s)).sum(1) / np.maximum(((e - s) ** 2).sum(1), 1e-300), 0, 1)
        edges = np.minimum(edges, np.linalg.norm(p - (s + (e - s) * t[:, None]), axis=1))
    return np.minimum(face, edges)


def deepest(X, x, T, S, exclude, nodes, into=None):
    x0 = x[T[:, 0]]
    E = np.stack([x[T[:, 1]] - x0, x[T[:, 2]] - x0, x[T[:, 3]] - x0], axis=2)  # (T, 3, 3)
    ok = np.abs(np.linalg.det(E)) > 1e-30
    tri_ok = np.ones(len(S), bool)
    if into is not None:
        ok &= ((X[T, 0] >= into[0]) & (X[T, 0] <= into[1])).all(axis=1)
        tri_ok = ((X[S, 0] >= into[0]) & (X[S, 0] <= into[1])).all(axis=1)
    Einv = np.zeros_like(E)
    Einv[ok] = np.linalg.inv(E[ok])
    worst, where, count = 0.0, -1, 0
    for p in nodes:
        far_tets = ok & (np.linalg.norm(X[T] - X[p], axis=2) > exclude).all(axis=1)
        lam = np.einsum("tij,tj->ti", Einv[far_tets], x[p] - x0[far_tets])
        tol = 1e-12
        if not ((lam >= -tol).all(1) & (lam.sum(1) <= 1 + tol)).any():
            continue
        far_tris = tri_ok & (np.linalg.norm(X[S] - X[p], axis=2) > exclude).all(axis=1)
        s = S[far_tris]
        depth = point_triangle_distance(x[p], x[s[:, 0]], x[s[:, 1]], x[s[:, 2]]).min()
        count += 1
        if depth > worst:
            worst, where = depth, p
    return worst, where, count


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--frames", default="-1")
    ap.add_argument("--exclude", type=float, default=0.05)
    ap.add_argument("--region", default="")
    ap.add_argument("--into", default="")
    a = ap.parse_args()
    run = open_run(a.run, "penetration.py")
    X, T, S = run.rest_positions, run.tets, run.surface
    nodes = np.unique(S)
    if a.region:
        lo, hi = (float(v) for v in a.region.split(","))
        nodes = nodes[(X[nodes, 0] >= lo) & (X[nodes, 0] <= hi)]
    into = [float(v) for v in a.into.split(",")] if a.into else None
    times = run.times
    for k in (int(v) for v in a.frames.split(",")):
        w, p, inside = deepest(X, run.frame_positions(k), T, S, a.exclude, nodes, into)
        print(f"frame {k % len(times)} t = {times[k]:.3f} s: deepest penetration {1000 * w:.2f} mm (node {p}), {inside} nodes inside")


if __name__ == "__main__":
    main()
