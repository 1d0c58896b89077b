"""USD's text form (.usda) of a run's surface: one stage, one Mesh prim whose points are sampled at
every frame (`isochor export RUN.h5 --format usd`).

The layer follows the USD file format's text grammar as Pixar documents it: the `#usda 1.0`
header, the stage metadata (defaultPrim, metersPerUnit, upAxis, start/endTimeCode,
timeCodesPerSecond, framesPerSecond), a `def Xform` holding a `def Mesh` with its topology
(faceVertexCounts, faceVertexIndices: triangles, counter-clockwise seen from outside, USD's
rightHanded orientation), its rest points and `points.timeSamples`, one sample per frame, and an
`extent` per frame (the bounding box USD's renderers cull by). Time codes are the frames' times
from the first frame times the frame rate (frame k of a run at a fixed rate is time code k).
"""
import os
import re

import numpy as np


def prim_name(text):
    """A USD prim name from any text: letters, digits and _, not first a digit."""
    name = re.sub(r"[^A-Za-z0-9_]", "_", text) or "run"
    return "_" + name if name[0].isdigit() else name


def frame_rate(times):
    """Frames per second of the run's frame times (their median spacing; 1 for a single frame)."""
    if len(times) < 2:
        return 1.0
    rate = 1.0 / float(np.median(np.diff(times)))
    return float(round(rate)) if abs(rate - round(rate)) < 1e-6 * rate else rate


def up_axis(up):
    """USD's stage up axis, "Y" or "Z": the one the run's up direction lies nearest."""
    return "Y" if abs(up[1]) > abs(up[2]) and abs(up[1]) >= abs(up[0]) else "Z"


def points_text(x):
    """[(x, y, z), ...] with 7 significant digits (float32's precision: point3f)."""
    return "[" + ", ".join(f"({a:.7g}, {b:.7g}, {c:.7g})" for a, b, c in x) + "]"


def write_usda(f, name, tris, rest, frames, times, up):
    """Writes the layer into the text file f. `frames` yields blocks of (frames, vertices, 3)
    positions in frame order; `times` are the frames' times (s)."""
    rate = frame_rate(times)
    codes = (np.asarray(times) - times[0]) * rate
    prim = prim_name(name)
    f.write("#usda 1.0\n(\n")
    f.write(f'    defaultPrim = "{prim}"\n')
    label = re.sub(r'[^ -~]|["\\]', "_", os.path.basename(name))  # printable, nothing to escape
    f.write(f'    doc = "isochor run {label}: {len(times)} frames, {len(rest)} vertices"\n')
    f.write(f"    metersPerUnit = 1\n    upAxis = \"{up_axis(up)}\"\n")
    f.write(f"    startTimeCode = 0\n    endTimeCode = {codes[-1]:.9g}\n")
    f.write(f"    timeCodesPerSecond = {rate:.9g}\n    framesPerSecond = {rate:.9g}\n)\n\n")
    f.write(f'def Xform "{prim}" (\n    kind = "component"\n)\n{{\n    def Mesh "surface"\n    {{\n')
    f.write('        uniform token subdivisionScheme = "none"\n        uniform token orientation = "rightHanded"\n')
    f.write("        int[] faceVertexCounts = [" + ", ".join(["3"] * len(tris)) + "]\n")
    f.write("        int[] faceVertexIndices = [" + ", ".join(str(int(i)) for i in np.ravel(tris)) + "]\n")
    f.write("        point3f[] points = " + points_text(rest) + "\n")
    extents = []
    f.write("        point3f[] points.timeSamples = {\n")
    k = 0
    for block in frames:
        for x in block:
            f.write(f"            {codes[k]:.9g}: {points_text(x)},\n")
            extents.append((x.min(axis=0), x.max(axis=0)))
            k += 1
    f.write("        }\n        float3[] extent.timeSamples = {\n")
    for code, (lo, hi) in zip(codes, extents):
        f.write(f"            {code:.9g}: {points_text([lo, hi])},\n")
    f.write("        }\n    }\n}\n")
    return k
