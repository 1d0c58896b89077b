#!/usr/bin/python3
"""Write a run's surface motion as a point cache or an animated glTF (`isochor export`).

    /usr/bin/python3 tools/export.py RUN.h5 [--format pc2|mdd|glb|usd] [--out FILE] [--all-nodes]

pc2 (the default): Blender's, 3ds Max's and Houdini's point cache (little-endian: the header
"POINTCACHE2\\0", version 1, the number of points, the start frame 0, the sample rate 1, the number
of frames; then x, y, z per point per frame as float32). mdd: LightWave's, read by Blender and
Maya's plug-ins (big-endian: frames, points, each frame's time, then x, y, z per point per frame).
The points are the surface's nodes in increasing node index (`--all-nodes`: every node), in the
run's coordinates (its up axis unchanged: tools/blender/ turns it); a run of a [character]: its
render mesh's vertices in the glTF file's order, so that the cache applies to the artist's mesh
(Blender's Mesh Cache modifier). 10^4 frames of a 1K-node surface are 120 MB; frames are read
and written 500 at a time.

glb: binary glTF 2.0 that any glTF viewer plays: the render mesh (a run without one: the tet
mesh's surface) baked per frame, one node and mesh per frame sharing one index buffer, with
smooth normals; the animation switches the frames by a STEP scale channel on each node (1 from
its frame's time to the next frame's, 0 elsewhere), at the run's frame times. Baked meshes, not
morph targets: morph targets would need a weight per target per key, F^2 numbers for F frames,
and viewers cap the targets blended at once; baked frames grow linearly (a 3K-vertex mesh: 72 KB
per frame) and play everywhere, without interpolation between frames. Every node is visible at
rest (scale 1), so a viewer that does not play animations shows every frame at once.

usd: USD's text form (.usda, tools/usd.py): one Mesh prim, the render mesh (a run without one: the
tet mesh's surface) with its points sampled at every frame (`points.timeSamples`), for usdview,
Houdini, Maya, Omniverse and Blender builds with USD. Written directly: Debian's Blender 3.4 is
built without USD and Alembic (docs/animation.md).
"""
import argparse
import os
import struct
import sys

import numpy as np

from run_file import Error, Run, check_output, note_input, write_whole

CHUNK = 500  # frames per read


def surface_nodes(run):
    """The surface's nodes in increasing index: the vertex order of the caches."""
    return np.unique(run.surface)


def cache_points(run, all_nodes, render):
    """(name, count, block -> points) of what a cache writes: a character's render mesh where
    `render`, else the surface's nodes or every node."""
    if run.render_rest is not None and render and not all_nodes:
        return "render vertices", len(run.render_rest), run.render_positions
    nodes = np.arange(len(run.rest_positions)) if all_nodes else surface_nodes(run)
    return ("nodes" if all_nodes else "surface nodes"), len(nodes), lambda block: block[..., nodes, :]


def vertex_normals(x, tris):
    """Area-weighted vertex normals (V,3) of triangles (T,3) at positions x (V,3)."""
    f = np.cross(x[tris[:, 1]] - x[tris[:, 0]], x[tris[:, 2]] - x[tris[:, 0]])
    n = np.zeros_like(x)
    for c in range(3):
        np.add.at(n, tris[:, c], f)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(length > 0, length, 1.0)


def surface_of(run, render):
    """(triangles, block -> vertices) of what a glb or usd export draws: a character's render
    mesh where `render`, else the tet mesh's surface over its surface nodes."""
    if run.render_rest is not None and render:
        return run.render_triangles, run.render_positions
    nodes, inverse = np.unique(run.surface, return_inverse=True)
    return inverse.reshape(-1, 3), lambda block: block[..., nodes, :]


def write_usd(h5_path, out, render=True):
    """The .usda stage; returns (vertices, frames)."""
    from usd import write_usda

    note_input(h5_path)
    with Run(h5_path) as run:
        tris, carry = surface_of(run, render)
        frames = run.num_frames
        blocks = (carry(run.frame_range("positions", k0, min(k0 + CHUNK, frames))) for k0 in range(0, frames, CHUNK))
        rest = run.render_rest if run.render_rest is not None and render else carry(run.rest_positions)
        name = os.path.splitext(os.path.basename(h5_path))[0]
        write_whole(out, lambda f: write_usda(f, name, tris, rest, blocks, run.times[:frames], run.up))
        return len(rest), frames


def write_glb(h5_path, out, frames=0, render=True):
    """The baked animated glTF; returns (vertices, frames)."""
    from glb import Glb

    note_input(h5_path)
    with Run(h5_path) as run:
        frames = min(run.num_frames, frames or run.num_frames)
        tris, carry = surface_of(run, render)
        g = Glb()
        index = g.triangles(tris)
        times = (run.times[:frames] - run.times[0]).astype(np.float32)
        samplers, channels = [], []
        for k0 in range(0, frames, CHUNK):
            for k, x in enumerate(carry(run.frame_range("positions", k0, min(k0 + CHUNK, frames))), k0):
                prim = {"attributes": {"POSITION": g.accessor(x.astype(np.float32), bounds=True, target=34962),
                                       "NORMAL": g.accessor(vertex_normals(x, tris).astype(np.float32), target=34962)},
                        "indices": index}
                node = g.node(name=f"frame_{k:05d}", mesh=g.mesh(prim, name=f"frame_{k:05d}"))
                keys = [t for t in (times[k - 1] if k else None, times[k], times[k + 1] if k + 1 < frames else None)
                        if t is not None]
                scale = [[0.0] * 3 if t != times[k] else [1.0] * 3 for t in keys]
                samplers.append({"input": g.accessor(np.array(keys, np.float32), bounds=True),
                                 "output": g.accessor(np.array(scale, np.float32)), "interpolation": "STEP"})
                channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": "scale"}})
        g.gltf["scenes"] = [{"nodes": list(range(frames))}]
        g.gltf["animations"] = [{"name": os.path.basename(os.path.splitext(h5_path)[0]), "samplers": samplers,
                                 "channels": channels}]
        data = g.to_bytes()
        write_whole(out, lambda f: f.write(data), "wb")
        return int(tris.max()) + 1, frames


def write_cache(h5_path, out, fmt="pc2", all_nodes=False, frames=0, render=False):
    """Writes the cache (the first `frames` frames, 0: all); returns (what, points, frames)."""
    note_input(h5_path)
    with Run(h5_path) as run:
        times = run.times
        frames = min(run.num_frames, frames or run.num_frames)
        what, count, points = cache_points(run, all_nodes, render)

        def write(o):
            if fmt == "pc2":
                o.write(b"POINTCACHE2\0" + struct.pack("<iiffi", 1, count, 0.0, 1.0, frames))
                dtype = "<f4"
            else:
                o.write(struct.pack(">ii", frames, count))
                o.write(times[:frames].astype(">f4").tobytes())
                dtype = ">f4"
            for k0 in range(0, frames, CHUNK):
                block = run.frame_range("positions", k0, min(k0 + CHUNK, frames))
                o.write(np.ascontiguousarray(points(block)).astype(dtype).tobytes())

        write_whole(out, write, "wb")  # a complete cache or none
    return what, count, frames


EXTENSIONS = {".pc2": "pc2", ".mdd": "mdd", ".glb": "glb", ".usda": "usd", ".usd": "usd"}


def format_and_path(fmt, out, run):
    """The format and the file: --format, else --out's extension; a file whose extension names
    another format than the one written (a point cache in FILE.glb), or no known format, is refused."""
    if not out:
        fmt = fmt or "pc2"
        return fmt, os.path.splitext(run)[0] + "." + ("usda" if fmt == "usd" else fmt)
    note_input(run)
    check_output(out)  # a directory, a device or the run itself: refused first, whatever the name says
    named = EXTENSIONS.get(os.path.splitext(out)[1].lower())
    if fmt and named and named != fmt:
        sys.exit(f"--out {out}: the extension says {named}, --format says {fmt} (expected one format)")
    if not fmt and not named:
        sys.exit(f"--out {out}: no format from its extension (expected .pc2, .mdd, .glb or .usda, or --format)")
    return fmt or named, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--format", default="", choices=["pc2", "mdd", "glb", "usd"],
                    help="default: from --out's extension, else pc2")
    ap.add_argument("--out", default="")
    ap.add_argument("--all-nodes", action="store_true")
    ap.add_argument("--surface", action="store_true",
                    help="a character's run: the tet mesh's surface instead of the render mesh")
    a = ap.parse_args()
    if not os.path.exists(a.run):
        sys.exit(f"{a.run}: no such file")
    a.format, out = format_and_path(a.format, a.out, a.run)
    try:
        if a.format in ("glb", "usd"):
            n, frames = (write_glb if a.format == "glb" else write_usd)(a.run, out, render=not a.surface)
            what = "vertices"
        else:
            what, n, frames = write_cache(a.run, out, a.format, a.all_nodes, render=not a.surface)
    except Error as e:
        sys.exit(str(e))
    except (OSError, KeyError) as e:
        sys.exit(f"{a.run}: cannot be exported ({e}; expected a run's .h5 file)")
    print(f"wrote {out}: {frames} frames of {n} {what} ({a.format})")


if __name__ == "__main__":
    main()
