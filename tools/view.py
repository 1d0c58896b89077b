#!/usr/bin/python3
"""Play a run in the browser (`isochor view`): a local page with the surface in WebGL, a timeline
and the run's charts (docs/viewer.md).

    /usr/bin/python3 tools/view.py RUN.h5 [--port N] [--no-browser] [--export DIR [--every K]]

Serves on 127.0.0.1 only (port 0, the default, takes a free one) and opens the browser unless
--no-browser. The page asks for what it shows: /api/meta (the surface, zones, colliders, charts;
asked again while the run is being written, so a growing run grows on the page) and
/api/frame/K (one frame, binary: its time, the surface nodes' positions, each surface face's
volume change, each surface node's contact force, the colliders' and the bones' poses), so a run of 10^5
frames opens as fast as one of ten. --export DIR writes a folder that opens from disk with no
server (every K-th frame; data as scripts, which a page opened from file:// may load).
The page itself (viewer/, three.js pinned in its lockfile) is built by CMake into
build/viewer/static; an installed package carries it in isochor/viewer.
"""
import argparse
import base64
import http.server
import json
import os
import shutil
import struct
import sys
import threading
import time
import urllib.parse
import webbrowser

import numpy as np

from run_file import Error, Run

CHART_POINTS = 2000  # the charts' points at most: longer series are binned (their maxima kept)


def static_directory(given=""):
    """The built page: --static, else an installed package's isochor/viewer, else the build tree's."""
    here = os.path.dirname(os.path.abspath(__file__))
    for d in (given, os.path.join(here, os.pardir, "viewer"), os.path.join(here, os.pardir, "build", "viewer", "static")):
        if d and os.path.isfile(os.path.join(d, "viewer.js")):
            return os.path.abspath(d)
    sys.exit("isochor view: the viewer page is not built (make build builds it with npm: "
             "tools/install-deps.sh installs npm; viewer/README.md)")


def face_tets(tets, faces):
    """The tet each surface face belongs to: its three nodes, sorted, matched among the tets' faces."""
    n = int(max(tets.max(), faces.max())) + 1

    def keys(tri):
        s = np.sort(tri, axis=1).astype(np.int64)
        return (s[:, 0] * n + s[:, 1]) * n + s[:, 2]
    all_faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    k = keys(all_faces)
    order = np.argsort(k, kind="stable")
    at = np.searchsorted(k[order], keys(faces))
    return order[np.minimum(at, len(order) - 1)] % len(tets)


def binned(t, y, reduce=np.nanmax):
    """At most CHART_POINTS points of the series y(t): the maximum of each bin."""
    if len(t) <= CHART_POINTS:
        return t, y
    edges = np.linspace(0, len(t), CHART_POINTS + 1).astype(int)
    with np.errstate(all="ignore"):
        return (np.array([t[a] for a in edges[:-1]]),
                np.array([reduce(y[a:b]) if np.isfinite(y[a:b]).any() else np.nan for a, b in zip(edges[:-1], edges[1:])]))


def charts(run):
    """The per-frame series the page plots against time: volume error, step size, Newton
    iterations per step (from the cumulative counts)."""
    t = run.times
    v = run.volumes
    with np.errstate(all="ignore"):
        out = {"volume_error": np.nanmax(np.abs(v / v[0] - 1), axis=1) if len(v) else np.zeros(0)}
        if "step_size" in run.stats:
            out["step_size"] = run.stats["step_size"]
        if "newton_iterations" in run.stats and "steps" in run.stats:
            dn, ds = np.diff(run.stats["newton_iterations"]), np.diff(run.stats["steps"])
            out["newton_per_step"] = np.r_[np.nan, np.where(ds > 0, dn / np.where(ds > 0, ds, 1), np.nan)]
    result = {}
    for name, y in out.items():
        tt, yy = binned(t, np.asarray(y, float))
        result[name] = {"t": finite_list(tt), "y": finite_list(yy)}
    return result


def finite_list(a):
    """A list for JSON, NaN and inf as None."""
    return [float(x) if np.isfinite(x) else None for x in np.asarray(a, float)]


def looks_like_hdf5(path):
    """Whether the file starts with HDF5's signature (a run's file does, even mid-write)."""
    try:
        with open(path, "rb") as f:
            return f.read(8) == b"\x89HDF\r\n\x1a\n"
    except OSError:
        return False


def open_run(path, tries=20):
    """The run at `path`. A run being written can be caught between a frame's writes (HDF5 then
    reads addresses past the file's end): such a read is tried again, 50 ms apart, before it is
    an error."""
    for attempt in range(tries):
        try:
            return Run(path)
        except (Error, OSError, KeyError, ValueError) as e:
            if attempt + 1 == tries or not looks_like_hdf5(path):
                raise Error(str(e)) from None
            time.sleep(0.05)


class Model:
    """The run as the page sees it: the surface's nodes and faces, each face's tet and zone, and
    per frame the bytes of /api/frame/K. Reopened when the page asks for the meta again, so that
    frames written since appear."""

    def __init__(self, path):
        self.path = path
        self.lock = threading.Lock()
        self.run = open_run(path)
        self._topology()

    def _topology(self):
        r = self.run
        self.nodes, local = np.unique(r.surface, return_inverse=True)
        self.faces = local.reshape(-1, 3).astype(np.int32)
        self.face_tet = face_tets(r.tets, r.surface)
        self.rest_volume = self.tet_volumes(r.rest_positions)  # signed, as the frames'
        zone = r.tet_zone[self.face_tet] if len(r.tet_zone) else np.full(len(self.faces), -1)
        self.face_zone = zone.astype(int)
        self.has_contact = r.has("contact")

    def tet_volumes(self, x):
        t = self.run.tets[self.face_tet]
        a, b, c, d = (x[t[:, i]] for i in range(4))
        return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0

    def reopen(self):
        """The file again (frames written since appear). Closed first: HDF5 would hand back the
        open file, and a file replaced in place would be read as it was."""
        with self.lock:
            if self.run is not None:
                self.run.close()
            self.run = None
            self.run = open_run(self.path)

    def meta(self):
        r = self.run
        return {"file": os.path.basename(self.path), "status": r.status, "frames": r.num_frames,
                "time_end": float(r.times[-1]) if r.num_frames else 0.0,
                "up": [float(u) for u in r.up], "rest": r.rest_positions[self.nodes].astype(float).ravel().tolist(),
                "faces": self.faces.ravel().tolist(), "face_zone": self.face_zone.tolist(),
                "zones": r.volume_columns[1:], "has_contact": bool(self.has_contact),
                "colliders": [collider_json(c) for c in r.colliders],
                "bones": [{"name": b.name, "parent": b.parent, "from": b.start.tolist(), "to": b.end.tolist(),
                           "radius": b.radius} for b in r.bones],
                "charts": charts(r)}

    def frame(self, k):
        """Frame k's bytes: time (float64), then float32 positions (S,3), face volume change (F),
        contact force magnitude (S, when the run has contact), collider poses (C,12) and scales (C),
        bone poses (B,12)."""
        with self.lock:
            r = self.run
            if r is None:
                raise Error(f"{self.path}: could not be read again (reload the page)")
            x = np.asarray(r.frame("positions", k), float)
            parts = [x[self.nodes], self.tet_volumes(x) / np.where(self.rest_volume != 0, self.rest_volume, 1) - 1]
            if self.has_contact:
                parts.append(np.linalg.norm(r.frame("contact", k)[self.nodes], axis=1))
            for c in range(len(r.colliders)):
                A, b = r.collider_pose(k, c)
                parts.append(np.r_[A.ravel(), b])
            parts.append([r.collider_scale(k, c) for c in range(len(r.colliders))])
            for b in range(len(r.bones)):
                A, t = r.bone_pose(k, b)
                parts.append(np.r_[A.ravel(), t])
            body = b"".join(np.asarray(p, "<f4").tobytes() for p in parts)
            return struct.pack("<d", float(r.times[k])) + body


def collider_json(c):
    d = {"name": c.name, "shape": c.shape, "dimensions": c.dimensions, "rest_pose": [float(v) for v in c.rest_pose]}
    if c.vertices is not None:
        d["vertices"] = np.asarray(c.vertices, float).ravel().tolist()
        d["triangles"] = np.asarray(c.triangles, int).ravel().tolist()
    return d


def handler(model, static):
    class Handler(http.server.BaseHTTPRequestHandler):
        def log_message(self, *args):  # quiet: the terminal shows the address and errors only
            pass

        def send(self, code, body, kind):
            self.send_response(code)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(body)

        def do_GET(self):
            path = urllib.parse.urlparse(self.path).path
            try:
                if path == "/api/meta":
                    model.reopen()
                    return self.send(200, json.dumps(model.meta()).encode(), "application/json")
                if path.startswith("/api/frame/"):
                    return self.send(200, model.frame(int(path.rsplit("/", 1)[1])), "application/octet-stream")
                if path == "/data/meta.js":  # an exported folder's data; served, the page asks /api/meta
                    return self.send(200, b"", "text/javascript; charset=utf-8")
                name = {"/": "index.html"}.get(path, path.lstrip("/"))
                kinds = {"index.html": "text/html", "viewer.js": "text/javascript", "style.css": "text/css"}
                if name not in kinds:
                    return self.send(404, b"not found", "text/plain")
                with open(os.path.join(static, name), "rb") as f:
                    return self.send(200, f.read(), kinds[name] + "; charset=utf-8")
            except (Error, OSError, KeyError, IndexError, ValueError) as e:
                print(f"isochor view: {e}", file=sys.stderr)
                return self.send(500, json.dumps({"error": str(e)}).encode(), "application/json")
    return Handler


EXPORT_ENTRIES = {"index.html", "viewer.js", "style.css", "data"}


def earlier_export(out):
    """True where OUT may be replaced by an export: nothing is there, or a folder holding only what
    an export writes (a folder of the user's, the run's own folder or a file is never removed)."""
    if not os.path.lexists(out):
        return True
    if os.path.islink(out) or not os.path.isdir(out):
        return False
    entries = set(os.listdir(out))
    return "index.html" in entries and entries <= EXPORT_ENTRIES


def export(model, static, out, every):
    """A folder that opens from disk: the page, its meta and every `every`-th frame as scripts.
    Written into OUT.part and renamed into place (an earlier OUT replaced only then): a full disk
    or a file size limit leaves OUT as it was and no part folder, with one line."""
    out = os.path.normpath(out)
    part = out + ".part"
    if not earlier_export(out):
        sys.exit(f"isochor view: {out}: exists and is not a folder this command wrote (expected a new path, or an "
                 "earlier export to replace); nothing was written")
    frames = list(range(0, model.run.num_frames, max(1, every)))
    try:
        shutil.rmtree(part, ignore_errors=True)
        os.makedirs(os.path.join(part, "data"))
        for name in ("index.html", "viewer.js", "style.css"):
            shutil.copyfile(os.path.join(static, name), os.path.join(part, name))
        meta = model.meta()
        meta["exported_frames"] = frames
        with open(os.path.join(part, "data", "meta.js"), "w") as f:
            f.write("window.ISOCHOR_META = " + json.dumps(meta) + ";\n")
        for k in frames:
            with open(os.path.join(part, "data", f"frame_{k}.js"), "w") as f:
                f.write(f"window.ISOCHOR_FRAME({k}, \"{base64.b64encode(model.frame(k)).decode()}\");\n")
        if os.path.isdir(out):
            shutil.rmtree(out)
        os.replace(part, out)
    except OSError as e:
        shutil.rmtree(part, ignore_errors=True)
        sys.exit(f"isochor view: {out}: cannot be written ({e.strerror or e}); nothing was written")
    print(f"isochor view: wrote {out}/index.html ({len(frames)} frames; open it in a browser)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--port", type=int, default=0, help="the port on 127.0.0.1 (0: a free one)")
    ap.add_argument("--no-browser", action="store_true", help="print the address only")
    ap.add_argument("--export", default="", help="write a folder that opens from disk instead of serving")
    ap.add_argument("--every", type=int, default=1, help="with --export: every K-th frame")
    ap.add_argument("--static", default="", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if not 0 <= a.port <= 65535:
        sys.exit(f"isochor view: --port {a.port}: expected 0 (a free port) to 65535")
    static = static_directory(a.static)
    try:
        model = Model(a.run)
    except Error as e:
        sys.exit(f"isochor view: {e}")
    if model.run.num_frames == 0:
        sys.exit(f"isochor view: {a.run}: has no frame yet")
    if a.export:
        return export(model, static, a.export, a.every)
    try:
        server = http.server.ThreadingHTTPServer(("127.0.0.1", a.port), handler(model, static))
    except OSError as e:
        sys.exit(f"isochor view: port {a.port} on 127.0.0.1: {e.strerror or e}")
    url = f"http://127.0.0.1:{server.server_address[1]}/"
    print(f"isochor view: {a.run} at {url} (Ctrl-C stops)", flush=True)
    if not a.no_browser:
        webbrowser.open(url)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
