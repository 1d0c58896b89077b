#!/usr/bin/python3
"""Write a run's surface motion as a point cache for animation packages (`isochor export`).

    /usr/bin/python3 tools/export.py RUN.h5 [--format pc2|mdd] [--out FILE] [--all-nodes]

pc2 (the default): Blender's, 3ds Max's and Houdini's point cache (little-endian: the header
"POINTCACHE2\\0", version 1, the number of points, the start frame 0, the sample rate 1, the number
of frames; then x, y, z per point per frame as float32). mdd: LightWave's, read by Blender and
Maya's plug-ins (big-endian: frames, points, each frame's time, then x, y, z per point per frame).
The points are the surface's nodes in increasing node index (`--all-nodes`: every node), in the
run's coordinates (its up axis unchanged: tools/blender/ turns it). 10^4 frames of a 1K-node
surface are 120 MB; frames are read and written 500 at a time.
"""
import argparse
import os
import struct
import sys

import numpy as np

from run_file import Error, Run, write_whole

CHUNK = 500  # frames per read


def surface_nodes(run):
    """The surface's nodes in increasing index: the vertex order of the caches."""
    return np.unique(run.surface)


def write_cache(h5_path, out, fmt="pc2", all_nodes=False, frames=0):
    """Writes the cache (the first `frames` frames, 0: all); returns (points, frames)."""
    with Run(h5_path) as run:
        times = run.times
        frames = min(run.num_frames, frames or run.num_frames)
        nodes = np.arange(len(run.rest_positions)) if all_nodes else surface_nodes(run)

        def write(o):
            if fmt == "pc2":
                o.write(b"POINTCACHE2\0" + struct.pack("<iiffi", 1, len(nodes), 0.0, 1.0, frames))
                dtype = "<f4"
            else:
                o.write(struct.pack(">ii", frames, len(nodes)))
                o.write(times[:frames].astype(">f4").tobytes())
                dtype = ">f4"
            for k0 in range(0, frames, CHUNK):
                block = run.frame_range("positions", k0, min(k0 + CHUNK, frames))
                o.write(np.ascontiguousarray(block[:, nodes, :]).astype(dtype).tobytes())

        write_whole(out, write, "wb")  # a complete cache or none
    return len(nodes), frames


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--format", default="pc2", choices=["pc2", "mdd"])
    ap.add_argument("--out", default="")
    ap.add_argument("--all-nodes", action="store_true")
    a = ap.parse_args()
    if not os.path.exists(a.run):
        sys.exit(f"{a.run}: no such file")
    out = a.out or os.path.splitext(a.run)[0] + "." + a.format
    try:
        n, frames = write_cache(a.run, out, a.format, a.all_nodes)
    except Error as e:
        sys.exit(str(e))
    except (OSError, KeyError) as e:
        sys.exit(f"{a.run}: cannot be exported ({e}; expected a run's .h5 file)")
    print(f"wrote {out}: {frames} frames of {n} {'nodes' if a.all_nodes else 'surface nodes'} ({a.format})")


if __name__ == "__main__":
    main()
