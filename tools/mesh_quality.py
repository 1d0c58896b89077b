#!/usr/bin/env python3
"""Quality of a run's mesh (how bad is the bad cube?): per tet, its smallest face angle
(the smallest interior angle of its four triangles, degrees) and its edge ratio (longest over
shortest edge). Prints the histograms and the extremes; draws both with -o.

    tools/mesh_quality.py RUN.h5 [-o quality.png] [--frame K]

RUN.h5 is any isochor output (the rest mesh is /mesh/rest_positions and /mesh/tets); --frame
measures the deformed mesh of frame K instead (its flipped tets are counted too).
"""
import argparse
import sys

import numpy as np

from run_file import Error, Run

ANGLE_BINS = [0, 0.1, 0.5, 1, 2, 5, 10, 20, 30, 45, 60]
RATIO_BINS = [1, 1.5, 2, 3, 5, 10, 20, 50, 100, 1000, np.inf]


def measure(x, tets):
    p = x[tets]  # (tets, 4, 3)
    faces = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
    smallest = np.full(len(tets), 180.0)
    for f in faces:
        for c in range(3):
            o, a, b = p[:, f[c]], p[:, f[(c + 1) % 3]], p[:, f[(c + 2) % 3]]
            u, v = a - o, b - o
            ang = np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.einsum("ij,ij->i", u, v)))
            smallest = np.minimum(smallest, ang)
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    lengths = np.stack([np.linalg.norm(p[:, a] - p[:, b], axis=1) for a, b in edges], axis=1)
    ratio = lengths.max(axis=1) / np.maximum(lengths.min(axis=1), 1e-300)
    e1, e2, e3 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    volume = np.einsum("ij,ij->i", e1, np.cross(e2, e3)) / 6
    return smallest, ratio, volume


def histogram(values, bins, unit):
    counts, _ = np.histogram(values, bins=bins)
    rows = []
    for lo, hi, c in zip(bins[:-1], bins[1:], counts):
        rows.append(f"  [{lo:g}, {hi:g}) {unit}: {c} ({100.0 * c / len(values):.1f}%)")
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run")
    ap.add_argument("-o", "--output", help="PNG (or SVG) with both histograms")
    ap.add_argument("--frame", type=int, help="measure this frame's deformed mesh instead of the rest mesh")
    a = ap.parse_args()
    try:
        with Run(a.run) as run:
            tets = run.tets
            if a.frame is None:
                x = run.rest_positions
            else:
                if not 0 <= a.frame < run.num_frames:
                    sys.exit(f"{a.run}: --frame {a.frame}: expected 0..{run.num_frames - 1}")
                x = run.frame_positions(a.frame)
    except Error as e:
        sys.exit(str(e))
    except (OSError, KeyError) as e:
        sys.exit(f"{a.run}: not an isochor output with a mesh ({e})")
    angle, ratio, volume = measure(x, tets)
    what = "rest mesh" if a.frame is None else f"frame {a.frame}"
    print(f"{a.run}: {what}, {len(tets)} tets")
    print(f"smallest face angle: min {angle.min():.3g} deg, median {np.median(angle):.3g} deg; "
          f"{(angle < 1).sum()} tets below 1 deg")
    print(histogram(angle, ANGLE_BINS, "deg"))
    print(f"edge ratio: max {ratio.max():.3g}, median {np.median(ratio):.3g}; {(ratio > 50).sum()} tets above 50")
    print(histogram(ratio, RATIO_BINS, ""))
    if a.frame is not None:
        print(f"flipped (volume <= 0): {(volume <= 0).sum()}")
    if a.output:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (l, r) = plt.subplots(1, 2, figsize=(10, 3.6))
        l.hist(np.clip(angle, 1e-3, None), bins=np.logspace(-3, np.log10(60), 40))
        l.set_xscale("log")
        l.set_xlabel("smallest face angle (degrees)")
        l.set_ylabel("tets")
        r.hist(ratio, bins=np.logspace(0, np.log10(max(ratio.max(), 10) * 1.1), 40))
        r.set_xscale("log")
        r.set_xlabel("edge ratio (longest / shortest)")
        fig.suptitle(f"{a.run.split('/')[-1]}: {what}, {len(tets)} tets")
        fig.tight_layout()
        fig.savefig(a.output, dpi=110)
        print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
