#!/usr/bin/python3
"""Summarise isochor runs: cost per frame, solver counts, volume error and loss.

usage: run_report.py FILE.h5 [FILE.h5 ...]
"""
import sys

import numpy as np

from run_file import open_run


def report(path):
    with open_run(path, "run_report.py") as run:
        t = run.times
        vol = run.volumes
        attrs = {k: float(v) for k, v in run.totals.items() if np.isscalar(v) and not isinstance(v, str)}
        frames = len(t) - 1
        total = vol[:, 0]
        rel = (total - total[0]) / total[0]
        print(f"{path}: {len(t)} frames to t = {t[-1]:.4g} s")
        if frames > 0 and "wall_seconds" in attrs:
            w = attrs["wall_seconds"]
            print(f"  wall {w:.2f} s, {w / frames:.4f} s per frame;"
                  f" steps per frame {attrs.get('steps', 0) / frames:.2f},"
                  f" Newton iterations {attrs.get('newton_iterations', 0):.0f},"
                  f" Jacobians {attrs.get('jacobian_evaluations', 0):.0f}")
            parts = ["assembly_seconds", "factorisation_seconds", "solve_seconds"]
            print("  time split: " + ", ".join(f"{p.split('_')[0]} {attrs.get(p, 0):.2f} s ({100 * attrs.get(p, 0) / w:.0f}%)"
                                              for p in parts))
        print(f"  total volume: worst relative error {np.abs(rel).max():.3e}, lowest {1 + rel.min():.4f} of V0"
              f" (t = {t[np.argmin(rel)]:.4g} s), highest {1 + rel.max():.4f}")
        for j in range(1, vol.shape[1]):
            z = vol[:, j]
            print(f"  zone {j}: worst relative error {np.abs((z - z[0]) / z[0]).max():.3e}")
        if "failure" in run.totals:
            print(f"  FAILED: {run.totals['failure']}")


for p in sys.argv[1:]:
    report(p)
