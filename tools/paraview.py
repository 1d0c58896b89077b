#!/usr/bin/python3
"""Write a ParaView script that opens an isochor run ready to play (`isochor paraview RUN.h5`).

    /usr/bin/python3 tools/paraview.py RUN.h5 [--out SCRIPT.py]

The script (default RUN_paraview.py beside the run) opens the run's XDMF sidecar with ParaView's
default XDMF reader, with every frame's time, in two linked views: the tets' pressure on the left
(runs with output.pressure = true; else the height along up) and their zones on the right (the
smallest zone holding each tet, named), the ground drawn, the camera's up from the scene. Use it
    paraview --script=RUN_paraview.py                       (the GUI, press play)
    xvfb-run -a pvpython RUN_paraview.py --screenshot F.png [--frame K]   (a picture)
(Debian's ParaView 5.11 crashes with pvpython --force-offscreen-rendering: use xvfb-run.)
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import render  # noqa: E402  (up_of, plane_at, Camera)
from run_file import open_run, write_whole  # noqa: E402

TEMPLATE = r'''# ParaView script for {run} (written by `isochor paraview`; regenerate it rather than edit).
#   paraview --script={script}
#   xvfb-run -a pvpython {script} --screenshot FRAME.png [--frame K] [--size 1200,600]
import argparse
import sys

from paraview.simple import *  # noqa: F401,F403

XDMF = {xdmf!r}
UP = {up!r}               # {up_from}
ZONES = {zones!r}         # cell array "zone": index into this list, -1 in no zone
HAS_PRESSURE = {pressure!r}
GROUND = {ground!r}       # (point, normal) of the ground, or None
FRAMES = {frames}
CENTER = {center!r}       # of every node at every frame (and their shadow on the ground)
SPAN = {span!r}

args = argparse.ArgumentParser()
args.add_argument("--screenshot", default="")
args.add_argument("--frame", type=int, default=-1)
args.add_argument("--size", default="1200,600")
a, _ = args.parse_known_args(sys.argv[1:])

reader = Xdmf3ReaderS(registrationName={name!r}, FileName=[XDMF])
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues) if reader.TimestepValues else [0.0]
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.PlayMode = "Snap To TimeSteps"

left = GetActiveViewOrCreate("RenderView")
layout = GetLayout(left)
layout.SplitHorizontal(0, 0.5)
right = CreateView("RenderView")
AssignViewToLayout(view=right, layout=layout, hint=2)
AddCameraLink(left, right, "isochor_link")

ground_source = None
if GROUND is not None:
    import math
    (p, n) = GROUND
    ground_source = Plane(registrationName="ground")
    c, span = CENTER, SPAN
    d = sum((c[i] - p[i]) * n[i] for i in range(3))
    c = [c[i] - d * n[i] for i in range(3)]
    ref = [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]
    u = [n[1] * ref[2] - n[2] * ref[1], n[2] * ref[0] - n[0] * ref[2], n[0] * ref[1] - n[1] * ref[0]]
    un = math.sqrt(sum(x * x for x in u))
    u = [x / un for x in u]
    v = [n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]]
    h = 0.75 * span
    ground_source.Origin = [c[i] - h * u[i] - h * v[i] for i in range(3)]
    ground_source.Point1 = [c[i] + h * u[i] - h * v[i] for i in range(3)]
    ground_source.Point2 = [c[i] - h * u[i] + h * v[i] for i in range(3)]
    ground_source.XResolution = ground_source.YResolution = 10

if HAS_PRESSURE:
    left_source, left_array, left_assoc = reader, "pressure", "CELLS"
else:  # the height along up, for something to see
    left_source = Calculator(registrationName="height", Input=reader)
    left_source.ResultArrayName = "height"
    left_source.Function = "coordsX*({ux})+coordsY*({uy})+coordsZ*({uz})"
    left_array, left_assoc = "height", "POINTS"

for view, source, array, assoc in ((left, left_source, left_array, left_assoc), (right, reader, "zone", "CELLS")):
    disp = Show(source, view)
    disp.Representation = "Surface"
    if assoc == "CELLS" and array == "zone" and not ZONES:
        ColorBy(disp, None)
    else:
        ColorBy(disp, (assoc, array))
        lut = GetColorTransferFunction(array)
        if array == "zone":
            lut.InterpretValuesAsCategories = 1
            lut.Annotations = sum(([str(i), name] for i, name in enumerate(ZONES)), ["-1", "no zone"])
            lut.ApplyPreset("Brewer Qualitative Set1", True)
            lut.IndexedColors = lut.IndexedColors  # keep the preset's colours for the categories
        else:
            disp.RescaleTransferFunctionToDataRange(True, False)
            lut.ApplyPreset("Viridis (matplotlib)", True)
        disp.SetScalarBarVisibility(view, True)
    if ground_source is not None:
        g = Show(ground_source, view)
        g.DiffuseColor = [0.86, 0.85, 0.82]
        g.AmbientColor = [0.86, 0.85, 0.82]
    view.OrientationAxesVisibility = 1
    view.CameraViewUp = UP

# Rescale pressure over the whole run, so that the colours mean the same at every frame.
if HAS_PRESSURE:
    GetColorTransferFunction("pressure").RescaleTransferFunction({p_lo!r}, {p_hi!r})

# Look from 18 degrees above the horizon at everything the run visits, as isochor render does
# (the linked right view follows).
toward = {toward!r}
for view in (left, right):
    view.CameraFocalPoint = CENTER
    view.CameraPosition = [CENTER[i] + 2.8 * SPAN * toward[i] for i in range(3)]
    view.CameraViewUp = UP
    view.CameraViewAngle = 30
SetActiveView(left)
SetActiveSource(reader)
k = a.frame if a.frame >= 0 else len(times) + a.frame
scene.AnimationTime = times[max(0, min(k, len(times) - 1))]
print("isochor paraview: %d time steps (%g .. %g s), arrays %s" % (
    len(times), times[0], times[-1], sorted(reader.CellData.keys() + reader.PointData.keys())))
if a.screenshot:
    w, h = (int(x) for x in a.size.split(","))
    SaveScreenshot(a.screenshot, layout, ImageResolution=[w, h])
    print("isochor paraview: wrote", a.screenshot)
else:
    Render()
'''


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--out", default="")
    ap.add_argument("--up", default="")
    a = ap.parse_args()
    run = os.path.abspath(a.run)
    if not os.path.exists(run):
        sys.exit(f"{a.run}: no such file")
    xdmf = os.path.splitext(run)[0] + ".xdmf"
    if not os.path.exists(xdmf):
        sys.exit(f"{a.run}: no XDMF sidecar {xdmf} beside it (expected the output of isochor run)")
    f = open_run(run, "paraview.py")
    up, up_from = render.up_of(f, a.up)
    zones = f.volume_columns[1:]  # /mesh/zone's indices name these
    pressure = f.has("pressure")
    p_lo = p_hi = 0.0
    if pressure and f.num_frames > 0:
        p = f.pressure
        p_lo, p_hi = float(np.percentile(p, 2)), float(np.percentile(p, 98))
    ground = None
    for c in f.colliders:
        if c.is_ground:
            point, normal = render.plane_at(f, c, 0) if f.num_frames else (c.rest_pose[9:], c.rest_pose[:9].reshape(3, 3)[:, 2])
            ground = (np.asarray(point).tolist(), np.asarray(normal).tolist())
    cam = render.Camera(up, 18, -60)
    # What the run visits: a sample of at most 200 frames (and its shadow on the ground).
    n = f.num_frames
    pts = np.concatenate([f.frame_positions(k) for k in sorted(set(np.linspace(0, max(n - 1, 0), min(n, 200)).astype(int)))]) \
        if n else f.rest_positions
    if ground is not None:
        gp, gn = np.array(ground[0]), np.array(ground[1])
        pts = np.concatenate([pts, pts - np.outer((pts - gp) @ gn, gn)])
    lo, hi = pts.min(0), pts.max(0)
    center, span = ((lo + hi) / 2).tolist(), float(np.linalg.norm(hi - lo)) or 1.0
    out = a.out or os.path.splitext(run)[0] + "_paraview.py"
    text = TEMPLATE.format(run=os.path.basename(run), script=os.path.basename(out), xdmf=xdmf, up=up.tolist(),
                           up_from=up_from, zones=zones, pressure=pressure, ground=ground,
                           frames=n, name=os.path.basename(xdmf), ux=up[0], uy=up[1],
                           uz=up[2], p_lo=p_lo, p_hi=p_hi, toward=cam.toward.tolist(),
                           center=center, span=span)
    write_whole(out, lambda o: o.write(text))
    print(f"wrote {out}: paraview --script={out}  (or: xvfb-run -a pvpython {out} --screenshot FRAME.png)")


if __name__ == "__main__":
    main()
