"""The same picture as tools/render.py (one frame, coloured by deformation, ground, one light)
drawn by VTK offscreen, for bench/render_engines.sh. Run by ParaView's pvpython under xvfb-run
(Debian's VTK has no display-free offscreen build):
    xvfb-run -a pvpython bench/render_vtk.py RUN.h5 FRAME OUT.png
"""
import os
import sys
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
import render  # noqa: E402  (rigid_fit, node_weights, Camera, up_of, scene_of)

from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray  # noqa: E402
from vtkmodules.vtkCommonCore import vtkPoints  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData  # noqa: E402
from vtkmodules.vtkFiltersCore import vtkPolyDataNormals  # noqa: E402
from vtkmodules.vtkFiltersSources import vtkPlaneSource  # noqa: E402
from vtkmodules.vtkIOImage import vtkPNGWriter  # noqa: E402
from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow,  # noqa: E402
                                         vtkWindowToImageFilter, vtkColorTransferFunction)
import vtkmodules.vtkRenderingOpenGL2  # noqa: E402,F401

t0 = time.perf_counter()
path, k, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
f = h5py.File(path, "r", locking=False)
X, S, T = f["/mesh/rest_positions"][()], f["/mesh/surface"][()], f["/mesh/tets"][()]
x = f["/frames/positions"][k]
scene = render.scene_of(f)
up, _ = render.up_of(scene, "")
R, Xc, xc = render.rigid_fit(X, x, render.node_weights(X, T, f["/mesh/rest_volumes"][()]))
val = np.linalg.norm(x - ((X - Xc) @ R.T + xc), axis=1)
pts = vtkPoints()
pts.SetData(numpy_to_vtk(np.ascontiguousarray(x), deep=True))
cells = vtkCellArray()
conn = np.hstack([np.full((len(S), 1), 3), S]).astype(np.int64).ravel()
cells.SetCells(len(S), numpy_to_vtkIdTypeArray(conn, deep=True))
poly = vtkPolyData()
poly.SetPoints(pts)
poly.SetPolys(cells)
poly.GetPointData().SetScalars(numpy_to_vtk(val, deep=True))
normals = vtkPolyDataNormals()
normals.SetInputData(poly)
normals.SplittingOff()
mapper = vtkPolyDataMapper()
mapper.SetInputConnection(normals.GetOutputPort())
lut = vtkColorTransferFunction()
vmax = max(val.max(), 1e-4 * np.ptp(X, axis=0).max())
for s, c in ((0, (0.267, 0.005, 0.329)), (0.5, (0.128, 0.567, 0.551)), (1, (0.993, 0.906, 0.144))):
    lut.AddRGBPoint(s * vmax, *c)
mapper.SetLookupTable(lut)
mapper.SetScalarRange(0, vmax)
actor = vtkActor()
actor.SetMapper(mapper)
actor.GetProperty().SetSpecular(0.25)
actor.GetProperty().SetSpecularPower(40)
ren = vtkRenderer()
ren.SetBackground(1, 1, 1)
ren.AddActor(actor)
if scene.get("contact", {}).get("ground", False):
    lo, hi = x.min(0), x.max(0)
    span = np.linalg.norm(hi - lo)
    mid = (lo + hi) / 2
    quad, _, _ = render.plane_quad(np.array(scene["contact"].get("point", [0, 0, 0]), float), up, mid, 0.75 * span)
    plane = vtkPlaneSource()
    plane.SetOrigin(*quad[0])
    plane.SetPoint1(*quad[1])
    plane.SetPoint2(*quad[3])
    plane.SetResolution(10, 10)
    pm = vtkPolyDataMapper()
    pm.SetInputConnection(plane.GetOutputPort())
    pa = vtkActor()
    pa.SetMapper(pm)
    pa.GetProperty().SetColor(0.86, 0.85, 0.82)
    ren.AddActor(pa)
cam = render.Camera(up, 18, -60)
c = ren.GetActiveCamera()
c.SetViewUp(*up)
mid = (x.min(0) + x.max(0)) / 2
c.SetFocalPoint(*mid)
c.SetPosition(*(mid + 10 * np.ptp(x, axis=0).max() * cam.toward))
ren.ResetCamera()
win = vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(700, 700)
win.AddRenderer(ren)
win.Render()
grab = vtkWindowToImageFilter()
grab.SetInput(win)
grab.Update()
w = vtkPNGWriter()
w.SetFileName(out)
w.SetInputConnection(grab.GetOutputPort())
w.Write()
print(f"vtk: {time.perf_counter() - t0:.2f} s in the script, {len(S)} surface triangles")
