#!/usr/bin/python3
"""Paint the waistband torso's zones (the CNH paper's Figure 4) on its surface, as vertex labels.

    /usr/bin/python3 tools/paint_torso.py torso.stl torso_paint.ply

Reads a binary STL, merges its corners into vertices and writes a binary PLY (x, y, z, uchar
label) for [[zones.paint]] (demos/waistband.toml). The body faces -y, z is up (demos/meshes/
torso.geo). Labels, by position on the surface (phi: the angle about the z axis, -90 degrees in
front):
  1 leg_left, 2 leg_right      the thigh stumps below z = 0.10 (x < 0, x > 0)
  3 breast_left, 4 breast_right within 0.07 m of each breast's centre
  5 belly                      the front (phi within 45 degrees of -90) for 0.20 < z < 0.46
  6 waist_left, 7 waist_right  the sides (phi within 45 degrees of 180 or 0) for 0.30 < z < 0.50
  8 back                       the back (phi within 45 degrees of 90) for 0.28 < z < 0.50
  0 elsewhere (unpainted: only in the whole-body zone)
"""
import struct
import sys

import numpy as np


def read_stl(path):
    data = open(path, "rb").read()
    n = struct.unpack_from("<I", data, 80)[0]
    rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), count=n, offset=84)
    corners = rec["v"].reshape(-1, 3).astype(float)
    return np.unique(corners, axis=0)


def labels_of(x):
    X, Y, Z = x[:, 0], x[:, 1], x[:, 2]
    phi = np.degrees(np.arctan2(Y, X))
    lab = np.zeros(len(x), dtype=np.uint8)
    near = lambda a, c: np.abs((phi - c + 180) % 360 - 180) < a  # noqa: E731
    lab[(Z > 0.30) & (Z < 0.50) & near(45, 180)] = 6
    lab[(Z > 0.30) & (Z < 0.50) & near(45, 0)] = 7
    lab[(Z > 0.28) & (Z < 0.50) & near(45, 90)] = 8
    lab[(Z > 0.20) & (Z < 0.46) & near(45, -90)] = 5
    for label, cx in ((3, -0.075), (4, 0.075)):
        lab[np.linalg.norm(x - [cx, -0.085, 0.56], axis=1) < 0.07] = label
    lab[(Z < 0.10) & (X < 0)] = 1
    lab[(Z < 0.10) & (X > 0)] = 2
    return lab


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.splitlines()[2].strip())
    x = read_stl(sys.argv[1])
    lab = labels_of(x)
    with open(sys.argv[2], "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\ncomment isochor tools/paint_torso.py: the CNH paper's Figure 4 "
                 f"zones\nelement vertex {len(x)}\nproperty float x\nproperty float y\nproperty float z\n"
                 "property uchar label\nend_header\n").encode())
        rec = np.zeros(len(x), dtype=np.dtype([("x", "<f4", 3), ("label", "u1")]))
        rec["x"], rec["label"] = x, lab
        f.write(rec.tobytes())
    counts = {int(k): int(v) for k, v in zip(*np.unique(lab, return_counts=True))}
    print(f"painted {len(x)} vertices: labels {counts}")


if __name__ == "__main__":
    main()
