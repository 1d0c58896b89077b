#!/usr/bin/python3
"""Draw frames of an isochor run to PNG (and an MP4 with ffmpeg).

    /usr/bin/python3 tools/render.py RUN.h5 [--frames 0,10,-1 | flattest | --every N] [--color displacement|pressure|zone]
                                     [--out DIR] [--mp4] [--elev 20 --azim -60] [--loads]

The surface is shaded by its normals and coloured per triangle: by displacement from rest (m),
(--out FILE.png with one frame writes that file),
by the pressure of the tet under it (Pa; runs with output.pressure = true), or by zone (the
first zone holding the tet). The ground (z = 0 plane under the body) is drawn when the run's
scene enables contact with the ground. --loads draws the applied loads (/frames/load, runs whose
scene has [[load]]) as arrows at the loaded nodes, the largest a fifth of the body's size, with
the total force in the title.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tomllib

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def tri_tet(surface, tets):
    """For each surface triangle, a tet that holds it."""
    index = {}
    for e, t in enumerate(tets):
        for f in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
            index.setdefault(tuple(sorted(t[list(f)])), e)
    return np.array([index.get(tuple(sorted(s)), 0) for s in surface])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--frames", default="")
    ap.add_argument("--every", type=int, default=0)
    ap.add_argument("--color", default="displacement", choices=["displacement", "pressure", "zone"])
    ap.add_argument("--out", default="")
    ap.add_argument("--mp4", action="store_true")
    ap.add_argument("--elev", type=float, default=18)
    ap.add_argument("--azim", type=float, default=-60)
    ap.add_argument("--loads", action="store_true")
    a = ap.parse_args()
    f = h5py.File(a.run, "r")
    X = f["/mesh/rest_positions"][()]
    S = f["/mesh/surface"][()]
    T = f["/mesh/tets"][()]
    P = f["/frames/positions"]
    times = f["/frames/time"][()]
    n = len(times)
    if a.frames == "flattest":  # the frame where the body is lowest relative to its width
        ratio = [np.ptp(P[k][:, 2]) / max(np.ptp(P[k][:, 0]), 1e-300) for k in range(n)]
        frames = [int(np.argmin(ratio))]
    elif a.frames:
        frames = sorted({int(k) % n for k in a.frames.split(",")})
    elif a.every:
        frames = list(range(0, n, a.every))
    else:
        frames = list(range(n))
    single = a.out.endswith(".png")  # one frame straight into this file
    if single and len(frames) != 1:
        sys.exit("--out FILE.png needs exactly one frame")
    out = (os.path.dirname(a.out) or ".") if single else (a.out or os.path.splitext(a.run)[0] + "_png")
    os.makedirs(out, exist_ok=True)
    under = tri_tet(S, T)
    ground, gz = False, 0.0
    try:
        scene = tomllib.loads(f.attrs["scene"] if isinstance(f.attrs["scene"], str) else f.attrs["scene"].decode())
        ground = bool(scene.get("contact", {}).get("ground", False))
        gz = float(scene.get("contact", {}).get("point", [0, 0, 0])[2])
    except Exception:  # noqa: BLE001 - a run without its scene text is drawn without the ground
        pass
    if a.loads and "/frames/load" not in f:
        sys.exit(f"{a.run}: no /frames/load (the scene has no [[load]])")
    if a.color == "pressure" and "/frames/pressure" not in f:
        sys.exit(f"{a.run}: no /frames/pressure (run the scene with output.pressure = true)")
    zone_of = np.zeros(len(T), dtype=int)
    zone_names = []
    if a.color == "zone" and "/zones" in f:
        # Smaller zones first, so that a zone inside a larger one (e.g. inside "global") shows.
        for z, name in enumerate(sorted(f["/zones"].keys(), key=lambda nm: f["/zones"][nm].shape[0])):
            tets = f["/zones"][name][()]
            mask = zone_of[tets] == 0
            zone_of[tets[mask]] = z + 1
            zone_names.append(name)
    lo = np.min([P[k].min(0) for k in frames], axis=0)
    hi = np.max([P[k].max(0) for k in frames], axis=0)
    span = (hi - lo).max()
    mid = (hi + lo) / 2
    if a.color == "displacement":
        vmax = max(np.linalg.norm(P[k] - X, axis=1).max() for k in frames) or 1.0
        vmin = 0.0
    elif a.color == "pressure":
        allp = np.concatenate([f["/frames/pressure"][k] for k in frames])
        vmin, vmax = np.percentile(allp, 2), np.percentile(allp, 98)
    else:
        vmin, vmax = 0, 9  # tab10: one colour per zone index, 0 (grey) for tets in no zone
    cmap = plt.get_cmap("viridis")
    if a.color == "zone":
        tab = plt.get_cmap("tab10")
        cmap = matplotlib.colors.ListedColormap([(0.6, 0.6, 0.6)] + [tab(i) for i in range(9)])
    light = np.array([0.3, -0.5, 0.8])
    light /= np.linalg.norm(light)
    written = []
    for k in frames:
        x = P[k]
        tri = x[S]
        nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
        if a.color == "displacement":
            val = np.linalg.norm(x - X, axis=1)[S].mean(1)
        elif a.color == "pressure":
            val = f["/frames/pressure"][k][under]
        else:
            val = zone_of[under]
        rgb = cmap(np.clip((val - vmin) / ((vmax - vmin) or 1), 0, 1))[:, :3]
        shade = 0.35 + 0.65 * np.clip(nrm @ light, 0, 1)
        fig = plt.figure(figsize=(6, 6))
        ax = fig.add_subplot(projection="3d", computed_zorder=False)  # the ground first, the body over it
        if ground:
            g = np.array([[mid[0] - span, mid[1] - span, 0], [mid[0] + span, mid[1] - span, 0],
                          [mid[0] + span, mid[1] + span, 0], [mid[0] - span, mid[1] + span, 0]])
            g[:, 2] = gz
            ax.add_collection3d(Poly3DCollection([g], facecolors=(0.8, 0.8, 0.78, 1.0), zorder=0))
        # Back-to-front by depth along the view direction, so nearer triangles cover farther ones.
        el, az = np.radians(a.elev), np.radians(a.azim)
        view = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        order = np.argsort(tri.mean(1) @ view)
        ax.add_collection3d(Poly3DCollection(tri[order], facecolors=(rgb * shade[:, None])[order], edgecolors="none",
                                             zorder=1))
        title_load = ""
        if a.loads:
            L = f["/frames/load"][k]
            on = np.linalg.norm(L, axis=1) > 0
            biggest = max(np.linalg.norm(f["/frames/load"][j], axis=1).max() for j in frames) or 1.0
            s = 0.2 * span / biggest
            ax.quiver(x[on, 0], x[on, 1], x[on, 2], s * L[on, 0], s * L[on, 1], s * L[on, 2], color="crimson",
                      arrow_length_ratio=0.3, linewidth=0.8, zorder=2)
            tot = L.sum(0)
            title_load = f"  load {np.linalg.norm(tot):.3g} N"
        ax.set_xlim(mid[0] - span / 2, mid[0] + span / 2)
        ax.set_ylim(mid[1] - span / 2, mid[1] + span / 2)
        ax.set_zlim(mid[2] - span / 2, mid[2] + span / 2)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=a.elev, azim=a.azim)
        ax.set_axis_off()
        if a.color == "zone":
            from matplotlib.patches import Patch
            handles = [Patch(color=cmap((z + 1) / 9), label=nm) for z, nm in enumerate(zone_names[:9])]
            if (zone_of[under] == 0).any() or not zone_names:
                handles.append(Patch(color=cmap(0.0), label="no zone"))
            ax.legend(handles=handles, loc="upper right", title="zone")
        else:
            sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(vmin, vmax))
            label = {"displacement": "displacement (m)", "pressure": "pressure (Pa)"}[a.color]
            fig.colorbar(sm, ax=ax, shrink=0.6, label=label)
        ax.set_title(f"{os.path.basename(a.run)}  t = {times[k]:.4f} s{title_load}")
        path = a.out if single else os.path.join(out, f"frame_{k:06d}.png")
        fig.savefig(path, dpi=100, bbox_inches="tight")
        plt.close(fig)
        written.append(path)
    print(f"wrote {len(written)} PNG files to {out}")
    if a.mp4:
        if not shutil.which("ffmpeg"):
            sys.exit("ffmpeg is not installed (apt-get install -y ffmpeg); the PNG files are written")
        rate = max(1, round(1 / np.median(np.diff(times)))) if n > 1 else 1
        listing = os.path.join(out, "frames.txt")
        with open(listing, "w") as lf:
            for p in written:
                lf.write(f"file '{os.path.abspath(p)}'\nduration {1 / rate}\n")
        mp4 = os.path.splitext(a.run)[0] + ".mp4"
        subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "concat", "-safe", "0", "-i", listing,
                        "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", mp4], check=True)
        print(f"wrote {mp4}")


if __name__ == "__main__":
    main()
