#!/usr/bin/python3
"""Draw frames of an isochor run to PNG (and an MP4 with ffmpeg).

    /usr/bin/python3 tools/render.py RUN.h5 [--frames 0,10,-1 | flattest | --every N]
        [--color deformation|displacement|pressure|zone] [--up z|y|-y|x,y,z] [--elev 18 --azim -60]
        [--out DIR | --out FILE.png] [--size 800] [--mp4] [--loads] [--contact] [--skinning]

The surface is shaded smoothly (per-vertex normals, a key light, a fill light and a highlight)
and drawn back to front with Gouraud triangles (matplotlib's Agg renderer). The colour is, per
vertex:
  deformation   distance from where the body's best rigid motion takes the rest position (m):
                the deformation, not the fall (the default)
  displacement  distance from the rest position (m)
  pressure      the pressure of the tets around the vertex (Pa; runs with output.pressure = true)
  zone          the zone of the tet under each triangle (smaller zones drawn over larger ones)

Up is what the run recorded (the ground's normal when the scene has a ground, else against
gravity, else z); --up overrides it (a mesh modelled y-up: --up y). --elev and --azim place the
camera relative to up. The ground and every plane (where it is at the frame) are drawn in their
own planes; the body casts a shadow on the ground. Solid colliders (/colliders, posed by
/frames/collider_pose) are drawn translucent. --loads draws the applied loads (/frames/load) as
arrows, the largest a fifth of the body's size; --contact the colliders' force on each node
(/frames/contact) the same way. --out FILE.png with one frame writes that file. --skinning (a
[character]'s run): the artist's render mesh twice, side by side: moved by linear blend skinning
of the bones alone (what the clip gives without tissue) and carried by the simulated tissue, with
how far they part; with --mp4, the side-by-side video.
"""
import argparse
import os
import shutil
import subprocess
import sys
import time as clock

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from run_file import Error, open_run, write_whole  # noqa: E402  (the one reader of run files)


# ---- The scene: up, planes, colliders (as the run file records them) -------------------------

AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}


def parse_up(text):
    """'z', '-y' or 'x,y,z' to a unit vector."""
    t = text.strip().lower()
    sign = -1.0 if t.startswith("-") else 1.0
    if t.lstrip("+-") in AXES:
        return sign * np.array(AXES[t.lstrip("+-")], float)
    try:
        v = np.array([float(c) for c in t.split(",")])
    except ValueError:
        v = np.zeros(0)
    if v.shape != (3,) or np.linalg.norm(v) == 0:
        sys.exit(f"--up {text}: expected x, y, z (optionally with a sign) or a vector a,b,c")
    return v / np.linalg.norm(v)


def up_of(run, override):
    """Up and why: --up, else what the run recorded (the ground's normal, against gravity, z)."""
    if override:
        return parse_up(override), "--up"
    return run.up, run.up_source


def unit(v):
    v = np.asarray(v, float)
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def plane_at(run, c, k):
    """A plane collider at frame k: its point and normal (the pose's origin and third axis)."""
    A, b = run.collider_pose(k, c.index)
    return b, unit(A[:, 2])


def ring(radius, z, m=32):
    a = np.linspace(0, 2 * np.pi, m, endpoint=False)
    return np.stack([radius * np.cos(a), radius * np.sin(a), np.full(m, float(z))], axis=1)


def band(r0, r1, m=32):
    """Triangles between two rings (arrays of m points), as (2m, 3, 3)."""
    j = np.roll(np.arange(m), -1)
    i = np.arange(m)
    return np.concatenate([np.stack([r0[i], r0[j], r1[j]], 1), np.stack([r0[i], r1[j], r1[i]], 1)])


def round_triangles(kind, r, half):
    """A sphere's or capsule's surface (axis z) as triangles."""
    polar = np.linspace(0, np.pi, 13)
    rings = [ring(r * np.sin(p), r * np.cos(p) + (half if p <= np.pi / 2 else -half)) for p in polar]
    if kind == "capsule":  # the cylinder between the two caps
        rings = rings[:7] + [ring(r, -half)] + rings[7:]
    return np.concatenate([band(a, b) for a, b in zip(rings[:-1], rings[1:])])


def box_triangles(size):
    h = 0.5 * np.asarray(size, float)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return np.array([corners[[q[0], q[1], q[2]]] for q in faces] + [corners[[q[0], q[2], q[3]]] for q in faces])


def cylinder_triangles(r, half, wall):
    outer = r + wall if wall > 0 else r
    top, bottom = ring(outer, half), ring(outer, -half)
    tris = [band(bottom, top)]
    if wall > 0:  # the hole's wall and two annuli
        itop, ibot = ring(r, half), ring(r, -half)
        tris += [band(itop, ibot), band(top, itop), band(ibot, bottom)]
    else:
        tris += [band(top, 0 * top + [0, 0, half]), band(0 * bottom + [0, 0, -half], bottom)]
    return np.concatenate(tris)


def shape_triangles(c):
    """A collider's surface as triangles (T, 3, 3) in its own frame (axis z; a mesh's: its file's,
    scaled), for drawing; None for a plane. Rounded edges are drawn sharp."""
    d = c.dimensions
    if c.shape == "mesh":
        return c.vertices[c.triangles] if c.vertices is not None and c.triangles is not None else np.zeros((0, 3, 3))
    if c.shape in ("sphere", "capsule"):
        return round_triangles(c.shape, d["radius"], 0.5 * d.get("length", 0.0))
    if c.shape == "box":
        return box_triangles([d["size_x"], d["size_y"], d["size_z"]])
    if c.shape == "cylinder":
        return cylinder_triangles(d["radius"], 0.5 * d["length"], d.get("wall", 0.0))
    return None


# ---- Geometry -----------------------------------------------------------------------------

def rigid_fit(X, x, w):
    """The rotation R and translation c of the best rigid motion x ~ R (X - Xc) + c (Kabsch,
    weights w): what is left, x - (R (X - Xc) + c), is the deformation."""
    w = w / w.sum()
    Xc, xc = w @ X, w @ x
    H = (X - Xc).T @ ((x - xc) * w[:, None])
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return R, Xc, xc


def node_weights(X, tets, vols):
    """Lumped volume per node (a quarter of each tet's rest volume)."""
    w = np.zeros(len(X))
    np.add.at(w, tets.ravel(), np.repeat(np.abs(vols) / 4, 4))
    return np.maximum(w, 1e-300)


def vertex_normals(x, S):
    """Area-weighted normals at the surface's vertices, and each triangle's normal."""
    tri = x[S]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    vn = np.zeros_like(x)
    for i in range(3):
        np.add.at(vn, S[:, i], fn)
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    return vn, fn


def tri_tet(surface, tets):
    """For each surface triangle, the tet that holds it."""
    faces = np.concatenate([tets[:, [0, 1, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 3]], tets[:, [1, 2, 3]]])
    owner = np.tile(np.arange(len(tets)), 4)
    keys = np.sort(faces, axis=1)
    order = np.lexsort(keys.T[::-1])
    keys, owner = keys[order], owner[order]
    want = np.sort(surface, axis=1)
    # Binary search of each surface triangle among the sorted faces (as a structured view).
    dt = np.dtype([("a", keys.dtype), ("b", keys.dtype), ("c", keys.dtype)])
    kv = np.ascontiguousarray(keys).view(dt).ravel()
    wv = np.ascontiguousarray(want.astype(keys.dtype)).view(dt).ravel()
    pos = np.clip(np.searchsorted(kv, wv), 0, len(kv) - 1)
    return owner[pos]


# ---- Camera and drawing ---------------------------------------------------------------------

class Camera:
    """Orthographic camera at elevation/azimuth about `up` (for z up: matplotlib's angles)."""

    def __init__(self, up, elev, azim):
        self.up = unit(up)
        ref = np.array([1.0, 0.0, 0.0]) if abs(self.up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = unit(ref - (ref @ self.up) * self.up)
        e2 = np.cross(self.up, e1)
        el, az = np.radians(elev), np.radians(azim)
        self.toward = unit(np.cos(el) * (np.cos(az) * e1 + np.sin(az) * e2) + np.sin(el) * self.up)  # to the camera
        fwd = -self.toward
        self.right = unit(np.cross(fwd, self.up)) if abs(fwd @ self.up) < 0.999 else e2
        self.screen_up = np.cross(self.right, fwd)

    def project(self, p):
        """Screen coordinates (right, up) and depth (larger: nearer the camera)."""
        return np.stack([p @ self.right, p @ self.screen_up], axis=-1), p @ self.toward


class GouraudTriangles(Artist):
    """Triangles with a colour at each corner, interpolated (the Agg renderer's Gouraud fill)."""

    def __init__(self, tris2d, colors, zorder):
        super().__init__()
        self.tris, self.colors = tris2d, colors
        self.set_zorder(zorder)

    def draw(self, renderer):
        if len(self.tris) == 0:
            return
        gc = renderer.new_gc()
        renderer.draw_gouraud_triangles(gc, self.tris, self.colors, self.axes.transData.frozen())
        gc.restore()


def shade(normals, cam):
    """Per-vertex light: ambient, a key light over the camera's shoulder, a fill light from the
    other side and a soft highlight (Blinn-Phong)."""
    key = unit(0.55 * cam.toward + 0.6 * cam.screen_up - 0.45 * cam.right)
    fill = unit(0.7 * cam.toward - 0.2 * cam.screen_up + 0.6 * cam.right)
    half = unit(key + cam.toward)
    d_key = np.clip(normals @ key, 0, 1)
    d_fill = np.clip(normals @ fill, 0, 1)
    spec = np.clip(normals @ half, 0, 1) ** 40
    return 0.28 + 0.62 * d_key + 0.18 * d_fill, 0.25 * spec


def plane_quad(point, normal, centre, half):
    """A square in the plane through `point` with `normal`, centred under `centre`."""
    n = unit(normal)
    c = centre - ((centre - point) @ n) * n
    a = unit(np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0]))
    b = np.cross(n, a)
    return np.array([c - half * a - half * b, c + half * a - half * b, c + half * a + half * b, c - half * a + half * b]), a, b


# ---- Main -----------------------------------------------------------------------------------

def arguments():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--frames", default="")
    ap.add_argument("--every", type=int, default=0)
    ap.add_argument("--color", default="deformation", choices=["deformation", "displacement", "pressure", "zone"])
    ap.add_argument("--out", default="")
    ap.add_argument("--mp4", action="store_true")
    ap.add_argument("--up", default="")
    ap.add_argument("--elev", type=float, default=18)
    ap.add_argument("--azim", type=float, default=-60)
    ap.add_argument("--size", type=int, default=700, help="picture width and height in pixels")
    ap.add_argument("--loads", action="store_true")
    ap.add_argument("--contact", action="store_true", help="draw the colliders' force on each node (/frames/contact)")
    ap.add_argument("--no-shadow", action="store_true")
    ap.add_argument("--skinning", action="store_true",
                    help="a character's run: its render mesh skinned by the bones alone beside it simulated")
    a = ap.parse_args()
    # A picture's side in pixels: a larger one takes memory no screen shows (1e9 px: 4e18 bytes).
    if not 16 <= a.size <= 8192:
        sys.exit(f"--size {a.size}: expected 16 to 8192 pixels")
    return a


def choose_frames(a, run, up):
    """The frames to draw: --frames (indices, or the flattest along up), --every N, or all."""
    n = run.num_frames
    if a.frames == "flattest":  # the frame where the body is flattest along up
        ratio = []
        for k in range(n):
            x = run.frame_positions(k)
            h = x @ up
            w = np.linalg.norm(x - np.outer(h, up), axis=1)
            ratio.append(np.ptp(h) / max(2 * w.max(), 1e-300))
        return [int(np.argmin(ratio))]
    if a.frames:
        try:
            picked = [int(k) for k in a.frames.split(",")]
        except ValueError:
            sys.exit(f"--frames {a.frames}: expected frame indices like 0,10,-1, or flattest")
        for k in picked:
            if not -n <= k < n:
                sys.exit(f"--frames {a.frames}: {a.run} has no frame {k} (expected 0 to {n - 1}, or -1 to -{n} from the end)")
        return sorted({k % n for k in picked})
    if a.every < 0:
        sys.exit(f"--every {a.every}: expected a positive step between frames (0: every frame)")
    return list(range(0, n, a.every)) if a.every else list(range(n))


def check_series(a, run):
    """What the options draw must be in the file."""
    if a.loads and not run.has("load"):
        sys.exit(f"{a.run}: no /frames/load (the scene has no [[load]])")
    if a.contact and not run.has("contact"):
        sys.exit(f"{a.run}: no /frames/contact (the scene has no collider, or its integrator projects contact)")
    if a.color == "pressure" and not run.has("pressure"):
        sys.exit(f"{a.run}: no /frames/pressure (run the scene with output.pressure = true)")


class Colouring:
    """Per-vertex colour values of a frame, one range over every frame drawn, and the colour map."""

    def __init__(self, a, run, frames, surf_nodes):
        self.kind, self.run = a.color, run
        X, T = run.rest_positions, run.tets
        self.weights = node_weights(X, T, run.rest_volumes)
        self.zone_names, self.zone_of = [], np.zeros(len(T), dtype=int)
        if self.kind == "zone":
            for z, name in enumerate(sorted(run.zones, key=lambda nm: -len(run.zones[nm]))):
                self.zone_of[run.zones[name]] = z + 1  # smaller zones last: drawn over the larger
                self.zone_names.append(name)
            tab = plt.get_cmap("tab10")
            self.cmap = matplotlib.colors.ListedColormap([(0.6, 0.6, 0.6)] + [tab(i) for i in range(9)])
            self.vmin, self.vmax = 0, 9
            return
        allv = np.concatenate([self.values(k, run.frame_positions(k))[surf_nodes] for k in frames])
        if self.kind == "pressure":
            self.vmin, self.vmax = np.percentile(allv, 2), np.percentile(allv, 98)
        else:  # a range of at least 1e-4 of the body's size: rounding is not drawn as deformation
            self.vmin, self.vmax = 0.0, max(float(allv.max()), 1e-4 * float(np.ptp(X, axis=0).max()))
        self.cmap = plt.get_cmap("viridis")

    def values(self, k, x):
        X, T = self.run.rest_positions, self.run.tets
        if self.kind == "deformation":
            R, Xc, xc = rigid_fit(X, x, self.weights)
            return np.linalg.norm(x - ((X - Xc) @ R.T + xc), axis=1)
        if self.kind == "displacement":
            return np.linalg.norm(x - X, axis=1)
        p = self.run.frame("pressure", k)
        acc, cnt = np.zeros(len(X)), np.zeros(len(X))
        np.add.at(acc, T.ravel(), np.repeat(p, 4))
        np.add.at(cnt, T.ravel(), 1)
        return acc / np.maximum(cnt, 1)

    def legend(self, fig, ax):
        if self.kind == "zone":
            from matplotlib.patches import Patch
            handles = [Patch(color=self.cmap((z + 1) / 9), label=nm) for z, nm in enumerate(self.zone_names[:9])]
            ax.legend(handles=handles, loc="upper right", title="zone", fontsize=8)
            return
        sm = plt.cm.ScalarMappable(cmap=self.cmap, norm=plt.Normalize(self.vmin, self.vmax))
        cax = fig.add_axes([0.86, 0.25, 0.025, 0.5])
        label = {"deformation": "deformation (m, from the best rigid motion)",
                 "displacement": "displacement (m)", "pressure": "pressure (Pa)"}[self.kind]
        fig.colorbar(sm, cax=cax, label=label)
        cax.yaxis.label.set_size(8)
        cax.tick_params(labelsize=7)


class Scene:
    """What is drawn besides the body: the planes (the ground first) and the solid colliders."""

    def __init__(self, run, frames, surf_nodes):
        self.run = run
        self.planes = [c for c in run.colliders if c.shape == "plane"]
        self.solids = [(c, tri) for c in run.colliders if c.shape != "plane"
                       for tri in [shape_triangles(c)] if tri is not None and len(tri)]
        # The view: every frame drawn, and the body's shadow on the ground.
        all_x = np.concatenate([run.frame_positions(k)[surf_nodes] for k in frames])
        for c in self.planes:
            if c.is_ground:
                point, normal = plane_at(run, c, frames[0])
                all_x = np.concatenate([all_x, all_x - np.outer((all_x - point) @ normal, normal)])
        lo, hi = all_x.min(0), all_x.max(0)
        self.mid, self.span = (lo + hi) / 2, float(np.linalg.norm(hi - lo))

    def planes_at(self, k, cam):
        """The planes' quads at frame k, split into those behind the body and those in front."""
        behind, in_front = [], []
        for c in self.planes:
            point, normal = plane_at(self.run, c, k)
            quad, _, _ = plane_quad(point, normal, self.mid, 0.75 * self.span)
            q2, qd = cam.project(quad)
            colour = (0.86, 0.85, 0.82, 1.0) if c.is_ground else (0.55, 0.7, 0.85, 0.35)
            if normal @ cam.toward <= 0:
                colour = (0.55, 0.55, 0.55, 0.25)
            on_top = not c.is_ground and qd.mean() >= (self.mid @ cam.toward)
            (in_front if on_top else behind).append((q2, colour, c, quad, point, normal))
        return behind, in_front


def draw_ground(ax, cam, quad, point, normal, x, S, fn, span, shadow):
    """Grid lines (a tenth of the square) in the ground's plane, and the body's shadow on it."""
    for s in np.linspace(0, 1, 11)[1:-1]:
        for e0, e1 in ((quad[0] + s * (quad[1] - quad[0]), quad[3] + s * (quad[2] - quad[3])),
                       (quad[0] + s * (quad[3] - quad[0]), quad[1] + s * (quad[2] - quad[1]))):
            seg, _ = cam.project(np.array([e0, e1]))
            ax.plot(seg[:, 0], seg[:, 1], color=(0.7, 0.7, 0.68), lw=0.5, zorder=0.5)
    if shadow:  # the body's shadow straight down onto the ground
        sx = x - np.outer((x - point) @ normal, normal) + 1e-4 * span * normal
        s2, _ = cam.project(sx)
        ax.add_collection(PolyCollection(s2[S[fn @ normal > 0]], facecolors=(0.3, 0.3, 0.3, 0.08),
                                         edgecolors="none", zorder=0.6))


def draw_solids(ax, cam, scene, k, up, body_depth):
    """The colliders translucent, flat-shaded, far to near; behind the body or in front."""
    for c, tri in scene.solids:
        A, b = scene.run.collider_pose(k, c.index)
        w = tri @ A.T + b
        fn_c = np.cross(w[:, 1] - w[:, 0], w[:, 2] - w[:, 0])
        fn_c /= np.maximum(np.linalg.norm(fn_c, axis=1, keepdims=True), 1e-300)
        light = 0.45 + 0.45 * np.abs(fn_c @ unit(cam.toward + 0.5 * up))
        w2, wd = cam.project(w.reshape(-1, 3))
        w2, wd = w2.reshape(-1, 3, 2), wd.reshape(-1, 3).mean(1)
        order_c = np.argsort(wd)
        rgba = np.column_stack([0.45 * light, 0.55 * light, 0.75 * light, np.full(len(light), 0.45)])
        near = wd[order_c] > body_depth
        for sel, z in ((~near, 0.8), (near, 2.5)):
            ax.add_collection(PolyCollection(w2[order_c][sel], facecolors=rgba[order_c][sel], edgecolors="none", zorder=z))


def draw_arrows(ax, cam, run, name, k, frames, x, span, colour):
    """Per-node vectors of /frames/NAME as arrows, the largest over the frames a fifth of the view;
    returns their sum's length."""
    V = run.frame(name, k)
    on = np.linalg.norm(V, axis=1) > 0
    biggest = max(np.linalg.norm(run.frame(name, j), axis=1).max() for j in frames) or 1.0
    if on.any():
        s0, _ = cam.project(x[on])
        s1, _ = cam.project(x[on] + 0.2 * span / biggest * V[on])
        ax.quiver(s0[:, 0], s0[:, 1], s1[:, 0] - s0[:, 0], s1[:, 1] - s0[:, 1], angles="xy", scale_units="xy",
                  scale=1, color=colour, width=0.003, zorder=3)
    return float(np.linalg.norm(V.sum(0)))


def draw_body(ax, cam, run, colouring, under, k, x):
    """The surface, Gouraud-shaded, back faces hidden, far to near; returns the faces' normals."""
    S = run.surface
    vn, fn = vertex_normals(x, S)
    front = fn @ cam.toward > 0  # back faces of the closed surface are hidden
    tris = S[front]
    xy, depth = cam.project(x)
    order = np.argsort(depth[tris].mean(1))  # far to near
    tris = tris[order]
    diffuse, spec = shade(vn, cam)
    cm = colouring.cmap
    if colouring.kind == "zone":
        base = cm(np.clip(colouring.zone_of[under[front][order]] / 9, 0, 1))[:, None, :3].repeat(3, axis=1)
    else:
        v = colouring.values(k, x)
        base = cm(np.clip((v - colouring.vmin) / ((colouring.vmax - colouring.vmin) or 1), 0, 1))[:, :3][tris]
    rgb = np.clip(base * diffuse[tris][..., None] + spec[tris][..., None], 0, 1)
    colors = np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,))], axis=2)
    ax.add_artist(GouraudTriangles(xy[tris], colors, zorder=1))
    return fn, depth


def draw_frame(a, run, k, cam, up, up_from, scene, colouring, under, frames, path):
    x = run.frame_positions(k)
    t = float(run.times[k])
    fig = plt.figure(figsize=(a.size / 100, a.size / 100), dpi=100)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_axis_off()
    ax.set_aspect("equal")
    behind, in_front = scene.planes_at(k, cam)
    fn, depth = draw_body(ax, cam, run, colouring, under, k, x)
    for q2, colour, c, quad, point, normal in behind:
        ax.add_collection(PolyCollection([q2], facecolors=[colour], edgecolors=(0.6, 0.6, 0.6, 0.6), zorder=0))
        if c.is_ground:
            draw_ground(ax, cam, quad, point, normal, x, run.surface, fn, scene.span, not a.no_shadow)
    draw_solids(ax, cam, scene, k, up, float(np.median(depth[np.unique(run.surface)])))
    for q2, colour, *_ in in_front:
        ax.add_collection(PolyCollection([q2], facecolors=[colour], edgecolors=(0.3, 0.4, 0.6, 0.8), zorder=2))
    title = ""
    if a.loads:
        title = f"  load {draw_arrows(ax, cam, run, 'load', k, frames, x, scene.span, 'crimson'):.3g} N"
    if a.contact:
        title += f"  contact {draw_arrows(ax, cam, run, 'contact', k, frames, x, scene.span, 'darkorange'):.3g} N"
    c2, _ = cam.project(scene.mid)
    ax.set_xlim(c2[0] - 0.55 * scene.span, c2[0] + 0.55 * scene.span)
    ax.set_ylim(c2[1] - 0.55 * scene.span, c2[1] + 0.55 * scene.span)
    colouring.legend(fig, ax)
    ax.text(0.02, 0.97, f"{os.path.basename(a.run)}  t = {t:.4f} s{title}", transform=ax.transAxes, fontsize=9, va="top")
    ax.text(0.02, 0.02, f"up: {(np.round(up, 3) + 0.0).tolist()} ({up_from})", transform=ax.transAxes, fontsize=7,
            color=(0.4, 0.4, 0.4))
    write_whole(path, lambda f: fig.savefig(f, dpi=100, format="png"), "wb")
    plt.close(fig)


def draw_mesh(ax, cam, x, tris, colour):
    """A render mesh (any soup: no face hidden), Gouraud-shaded in one colour, far to near."""
    vn, _ = vertex_normals(x, tris)
    xy, depth = cam.project(x)
    tris = tris[np.argsort(depth[tris].mean(1))]
    facing = np.where((vn @ cam.toward)[:, None] < 0, -vn, vn)  # light a face seen from behind as its front
    diffuse, spec = shade(facing, cam)
    rgb = np.clip(np.asarray(colour)[None, None, :] * diffuse[tris][..., None] + spec[tris][..., None], 0, 1)
    ax.add_artist(GouraudTriangles(xy[tris], np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,))], axis=2), zorder=1))


def draw_versus(a, run, k, cam, scene, path):
    """The render mesh at frame k: skinned by the bones alone (left) and carried by the tissue."""
    try:
        skinned, simulated = run.render_skinned(k), run.render_positions(run.frame_positions(k))
    except Error as e:
        sys.exit(str(e))
    fig = plt.figure(figsize=(2 * a.size / 100, a.size / 100), dpi=100)
    off = np.linalg.norm(simulated - skinned, axis=1)
    for i, (x, label) in enumerate(((skinned, "skinned: the bones alone"),
                                    (simulated, f"simulated: {1e3 * off.max():.0f} mm from skinning at most, "
                                                f"{1e3 * off.mean():.0f} mm on average"))):
        ax = fig.add_axes([i / 2, 0, 0.5, 1])
        ax.set_axis_off()
        ax.set_aspect("equal")
        behind, _ = scene.planes_at(k, cam)
        for q2, colour, c, quad, point, normal in behind:
            ax.add_collection(PolyCollection([q2], facecolors=[colour], edgecolors=(0.6, 0.6, 0.6, 0.6), zorder=0))
        draw_mesh(ax, cam, x, run.render_triangles, (0.85, 0.62, 0.5))
        c2, _ = cam.project(scene.mid)
        ax.set_xlim(c2[0] - 0.55 * scene.span, c2[0] + 0.55 * scene.span)
        ax.set_ylim(c2[1] - 0.55 * scene.span, c2[1] + 0.55 * scene.span)
        ax.text(0.02, 0.97, f"{label}\nt = {float(run.times[k]):.3f} s", transform=ax.transAxes, fontsize=9, va="top")
    write_whole(path, lambda f: fig.savefig(f, dpi=100, format="png"), "wb")
    plt.close(fig)


def write_mp4(run, written, out):
    if not shutil.which("ffmpeg"):
        sys.exit("ffmpeg is not installed (apt-get install -y ffmpeg); the PNG files are written")
    times = run.times
    rate = max(1, round(1 / np.median(np.diff(times)))) if len(times) > 1 else 1
    listing = os.path.join(out, "frames.txt")
    with open(listing, "w") as lf:
        for p in written:
            lf.write(f"file '{os.path.abspath(p)}'\nduration {1 / rate}\n")
    mp4 = os.path.splitext(run.path)[0] + ".mp4"
    subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "concat", "-safe", "0", "-i", listing,
                    "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", mp4], check=True)
    print(f"wrote {mp4}")


def main():
    a = arguments()
    run = open_run(a.run)
    if run.num_frames == 0:
        sys.exit(f"{a.run}: no frames")
    up, up_from = up_of(run, a.up)
    frames = choose_frames(a, run, up)
    single = a.out.endswith(".png")
    if single and len(frames) != 1:
        sys.exit("--out FILE.png needs exactly one frame")
    out = (os.path.dirname(a.out) or ".") if single else (a.out or os.path.splitext(a.run)[0] + "_png")
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        sys.exit(f"{out}: cannot be created ({e.strerror or e})")
    check_series(a, run)
    if a.skinning and run.render_rest is None:
        sys.exit(f"{a.run}: has no render mesh (--skinning draws a [character]'s run)")
    cam = Camera(up, a.elev, a.azim)
    surf_nodes = np.unique(run.surface)
    scene = Scene(run, frames, surf_nodes)
    colouring = Colouring(a, run, frames, surf_nodes)
    under = tri_tet(run.surface, run.tets)
    written = []
    started = clock.perf_counter()
    for k in frames:
        path = a.out if single else os.path.join(out, f"frame_{k:06d}.png")
        if a.skinning:
            draw_versus(a, run, k, cam, scene, path)
        else:
            draw_frame(a, run, k, cam, up, up_from, scene, colouring, under, frames, path)
        written.append(path)
    per = (clock.perf_counter() - started) / max(len(written), 1)
    where = a.out if single else f"{len(written)} PNG file{'' if len(written) == 1 else 's'} to {out}"
    print(f"wrote {where} ({per:.2f} s per frame, {len(run.surface)} surface triangles)")
    if a.mp4:
        write_mp4(run, written, out)


if __name__ == "__main__":
    main()
