#!/usr/bin/python3
"""Paint the rigged arm's muscle bellies (demos/arm_muscles.toml) as labelled points on its surface.

    /usr/bin/python3 tools/paint_arm.py demos/meshes/arm_muscles.csv

The arm is the capsule of demos/arm_flex.toml (axis x from 0 to 0.55 m, radius 0.045 m; the
forearm lifts towards +z, so +z is the front, the flexor side). Writes a CSV (x,y,z,label) of
points on that surface, every 3 mm, for [[zones.paint]]. Labels (phi: the angle about the x axis
from +z):
  1 biceps              the front of the upper arm (|phi| < 60 degrees), 0.06 < x < 0.24
  2 triceps             its back (|phi| > 120 degrees), 0.06 < x < 0.24
  3 forearm_flexors     the front of the forearm, 0.36 < x < 0.50
  4 forearm_extensors   its back, 0.36 < x < 0.50
  0 elsewhere (the elbow, the shoulder and wrist, the sides)
"""
import sys

import numpy as np


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.splitlines()[2].strip())
    r, L, h = 0.045, 0.55, 0.003
    pts = []
    for x in np.arange(0, L + 1e-9, h):  # the cylinder
        for a in np.arange(0, 2 * np.pi, h / r):
            pts.append((x, r * np.sin(a), r * np.cos(a)))
    for end, sign in ((0.0, -1), (L, 1)):  # the caps
        for t in np.arange(h / r, np.pi / 2 + 1e-9, h / r):
            rr = r * np.cos(t)
            for a in np.arange(0, 2 * np.pi, h / max(rr, h)):
                pts.append((end + sign * r * np.sin(t), rr * np.sin(a), rr * np.cos(a)))
    p = np.array(pts)
    phi = np.degrees(np.arctan2(p[:, 1], p[:, 2]))
    front, back = np.abs(phi) < 60, np.abs(phi) > 120
    upper = (p[:, 0] > 0.06) & (p[:, 0] < 0.24)
    lower = (p[:, 0] > 0.36) & (p[:, 0] < 0.50)
    lab = np.zeros(len(p), dtype=int)
    lab[upper & front], lab[upper & back] = 1, 2
    lab[lower & front], lab[lower & back] = 3, 4
    with open(sys.argv[1], "w") as f:
        f.write("x,y,z,label\n")
        for q, l in zip(p, lab):
            f.write(f"{q[0]:.5f},{q[1]:.5f},{q[2]:.5f},{l}\n")
    print(f"painted {len(p)} points: labels {dict(zip(*np.unique(lab, return_counts=True)))}")


if __name__ == "__main__":
    main()
