"""Bring an isochor run into Blender: one mesh animated frame by frame, up axis converted, zone and
pressure as colour attributes, the ground and contact planes as objects, camera and lights framed
on the motion; optionally render frames headless with Cycles on the CPU.

    blender -b --python tools/blender/isochor_blender.py -- RUN.h5 [options]
    build/isochor render --blender RUN.h5 [options]          (the same, through isochor)

Options:
    --save FILE.blend      save the scene (open it in Blender to play, edit, export)
    --render DIR           render frames to DIR/frame_NNNNNN.png (Cycles, CPU)
    --frames 0,10,-1 | --every N    which frames to render (default: all)
    --samples 8            Cycles samples per pixel (low: a preview; no denoiser in Debian's build)
    --size 640x480         picture size
    --mp4                  also an MP4 of the rendered frames (ffmpeg), beside the run
    --color zone|pressure|none      the colour attribute the material shows (default: zone when
                           the run has more than one zone, else pressure when written, else none)
    --pressure-frame K     the frame whose pressure is stored as the "pressure" attribute (-1)
    --cache pc2|shapekeys  how the motion is stored: a Mesh Cache modifier over a PC2 file
                           (default; tools/export.py writes RUN.pc2 when it is missing or older than
                           the run), or one shape key per frame (measured: bench/blender_cache.sh)
    --up z|y|-y|a,b,c      the run's up axis (default: from the scene, as isochor render)
    --elev 18 --azim -60   camera about up, as isochor render
    --max-frames N         import the first N frames only
    --scrub N              time N frame changes spread over the run (bench/blender_cache.sh)
    --verify K             print the largest distance between Blender's evaluated mesh at frame K
                           and the run's surface (turned to z up), for tests

Debian's Blender 3.4 has no Alembic or USD exporter (bpy.ops.wm has neither alembic_export nor
usd_export), so a saved .blend, the PC2 cache or an OBJ sequence is what goes to other packages.
"""
import argparse
import os
import subprocess
import sys
import time

import bpy
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import export  # noqa: E402  (tools/export.py: the PC2 writer)
import render  # noqa: E402  (tools/render.py: up, planes, camera angles)
from run_file import Error, Run  # noqa: E402  (the one reader of run files)


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="isochor_blender.py", description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--save", default="")
    ap.add_argument("--render", default="")
    ap.add_argument("--frames", default="")
    ap.add_argument("--every", type=int, default=0)
    ap.add_argument("--samples", type=int, default=8)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--mp4", action="store_true")
    ap.add_argument("--color", default="", choices=["", "zone", "pressure", "none"])
    ap.add_argument("--pressure-frame", type=int, default=-1)
    ap.add_argument("--cache", default="pc2", choices=["pc2", "shapekeys"])
    ap.add_argument("--up", default="")
    ap.add_argument("--elev", type=float, default=18)
    ap.add_argument("--azim", type=float, default=-60)
    ap.add_argument("--verify", type=int, default=None)
    ap.add_argument("--max-frames", type=int, default=0)
    ap.add_argument("--scrub", type=int, default=0)
    return ap.parse_args(argv)


def fail(message):
    print(f"isochor_blender: {message}", file=sys.stderr)
    sys.exit(1)


def material(name, color_attribute, base=(0.8, 0.45, 0.4, 1.0)):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.45
    if color_attribute:
        attr = m.node_tree.nodes.new("ShaderNodeAttribute")
        attr.attribute_name = color_attribute
        m.node_tree.links.new(attr.outputs["Color"], bsdf.inputs["Base Color"])
    else:
        bsdf.inputs["Base Color"].default_value = base
    return m


def colour_rows(values, lo, hi, cmap):
    t = np.clip((values - lo) / ((hi - lo) or 1.0), 0, 1)
    return np.array([cmap(x) for x in t])


def linear(rgba):
    """sRGB colours (as colour maps give them) to the linear values colour attributes hold."""
    c = np.array(rgba, dtype=float)
    c[..., :3] = np.where(c[..., :3] <= 0.04045, c[..., :3] / 12.92, ((c[..., :3] + 0.055) / 1.055) ** 2.4)
    return c


def viridis(t):
    stops = np.array([[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551],
                      [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]])
    x = t * (len(stops) - 1)
    i = min(int(x), len(stops) - 2)
    c = stops[i] + (x - i) * (stops[i + 1] - stops[i])
    return (*c, 1.0)


SET1 = [(0.6, 0.6, 0.6, 1), (0.89, 0.10, 0.11, 1), (0.22, 0.49, 0.72, 1), (0.30, 0.69, 0.29, 1),
        (0.60, 0.31, 0.64, 1), (1.0, 0.5, 0.0, 1), (1.0, 1.0, 0.2, 1), (0.65, 0.34, 0.16, 1), (0.97, 0.51, 0.75, 1)]


class Body:
    """The run's surface as a Blender mesh under one empty that turns the run's up to Blender's z."""

    def __init__(self, a, run):
        self.run = run
        self.n = run.num_frames if a.max_frames <= 0 else min(run.num_frames, a.max_frames)
        if self.n == 0:
            fail(f"{a.run}: no frames")
        self.up, self.up_from = render.up_of(run, a.up)
        self.nodes = export.surface_nodes(run)
        index = -np.ones(len(run.rest_positions), dtype=np.int64)
        index[self.nodes] = np.arange(len(self.nodes))
        # An empty scene at the run's frame rate.
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.sc = sc = bpy.context.scene
        times = run.times[:self.n]
        self.rate = 1.0 / float(np.median(np.diff(times))) if self.n > 1 else 24.0
        sc.render.fps = max(1, round(self.rate))
        sc.render.fps_base = sc.render.fps / self.rate
        sc.frame_start, sc.frame_end = 1, self.n
        self.root = bpy.data.objects.new("isochor", None)
        sc.collection.objects.link(self.root)
        R = Vector((0, 0, 1)).rotation_difference(Vector(self.up.tolist())).inverted()  # run's up -> +z
        self.root.rotation_mode = "QUATERNION"
        self.root.rotation_quaternion = R
        self.Rm = np.array(R.to_matrix())
        # The body: the surface of frame 0, smooth-shaded.
        self.mesh = bpy.data.meshes.new(os.path.basename(run.path))
        self.mesh.from_pydata(self.surface(0).tolist(), [], index[run.surface].tolist())
        self.mesh.update()
        self.mesh.polygons.foreach_set("use_smooth", [True] * len(self.mesh.polygons))
        self.obj = bpy.data.objects.new("body", self.mesh)
        sc.collection.objects.link(self.obj)
        self.obj.parent = self.root

    def surface(self, k):
        return self.run.frame_positions(k)[self.nodes]


def add_colours(a, body):
    """Colour attributes per face corner: the zone of the tet under each triangle, and the
    pressure of one frame; the body's material coloured by one of them. Returns which."""
    run, mesh = body.run, body.mesh
    under = render.tri_tet(run.surface, run.tets)
    zone_names = run.volume_columns[1:]
    zc = np.array([SET1[(z + 1) % len(SET1)] for z in run.tet_zone[under]])
    attr = mesh.color_attributes.new("zone", "FLOAT_COLOR", "CORNER")
    attr.data.foreach_set("color", np.repeat(linear(zc), 3, axis=0).ravel())
    has_pressure = run.has("pressure")
    if has_pressure:
        p = run.frame("pressure", a.pressure_frame % body.n)[under]
        lo, hi = np.percentile(p, 2), np.percentile(p, 98)
        attr = mesh.color_attributes.new("pressure", "FLOAT_COLOR", "CORNER")
        attr.data.foreach_set("color", np.repeat(linear(colour_rows(p, lo, hi, viridis)), 3, axis=0).ravel())
    color = a.color or ("zone" if len(zone_names) > 1 else "pressure" if has_pressure else "none")
    if color == "pressure" and not has_pressure:
        fail(f"{a.run}: no /frames/pressure (run the scene with output.pressure = true)")
    body.obj.data.materials.append(material("tissue", None if color == "none" else color))
    return color


def add_motion(a, body):
    """The motion: a PC2 cache (written beside the run when missing or older) or shape keys."""
    run, n = body.run, body.n
    if a.cache == "pc2":
        stem = os.path.splitext(run.path)[0]
        pc2 = stem + (f"_{n}.pc2" if a.max_frames > 0 else ".pc2")
        if not os.path.exists(pc2) or os.path.getmtime(pc2) < os.path.getmtime(run.path):
            export.write_cache(run.path, pc2, "pc2", frames=n)
        mod = body.obj.modifiers.new("isochor motion", "MESH_CACHE")
        mod.cache_format = "PC2"
        mod.filepath = pc2
        mod.frame_start = 1.0  # PC2 sample 0 at Blender frame 1
        mod.time_mode = "FRAME"
        mod.play_mode = "SCENE"
        return
    body.obj.shape_key_add(name="Basis", from_mix=False)
    for k in range(n):
        key = body.obj.shape_key_add(name=f"frame_{k}", from_mix=False)
        key.data.foreach_set("co", body.surface(k).astype(np.float32).ravel())
        key.value = 0.0
        for fr, v in ((k, 0.0), (k + 1, 1.0), (k + 2, 0.0)):
            if 1 <= fr <= n:
                key.value = v
                key.keyframe_insert("value", frame=fr)


def view_extent(body):
    """Centre and size of what the run visits (a sample of at most 200 frames, and the body's
    shadow on the ground), in Blender's world."""
    n, Rm = body.n, body.Rm
    sample = sorted(set(np.linspace(0, n - 1, min(n, 200)).astype(int)))
    pts = np.concatenate([body.surface(k) for k in sample]) @ Rm.T
    for c in body.run.colliders:
        if c.is_ground:
            point, normal = render.plane_at(body.run, c, 0)
            gp, gn = Rm @ point, Rm @ normal
            pts = np.concatenate([pts, pts - np.outer((pts - gp) @ gn, gn)])
    lo, hi = pts.min(0), pts.max(0)
    return (lo + hi) / 2, float(np.linalg.norm(hi - lo)) or 1.0


def add_planes(body, centre, span):
    """The ground and the other planes, each keyframed at every frame where it moved."""
    run = body.run
    c_run = body.Rm.T @ centre
    for c in (c for c in run.colliders if c.shape == "plane"):
        bpy.ops.mesh.primitive_plane_add(size=1.5 * span)
        obj = bpy.context.active_object
        obj.name = "ground" if c.is_ground else f"plane_{c.index}"
        obj.parent = body.root
        obj.data.materials.append(material("ground" if c.is_ground else "plane", None,
                                           (0.8, 0.8, 0.78, 1.0) if c.is_ground else (0.55, 0.7, 0.85, 1.0)))
        obj.rotation_mode = "QUATERNION"
        last = None
        for k in range(body.n):
            point, normal = render.plane_at(run, c, k)
            base = point + ((c_run - point) - ((c_run - point) @ normal) * normal)
            if last is not None and np.allclose(base, last[0]) and np.allclose(normal, last[1]):
                continue
            obj.rotation_quaternion = Vector((0, 0, 1)).rotation_difference(Vector(normal.tolist()))
            obj.location = base.tolist()
            if k > 0 or body.n > 1:
                obj.keyframe_insert("location", frame=k + 1)
                obj.keyframe_insert("rotation_quaternion", frame=k + 1)
            last = (base, normal)


def add_camera_and_lights(a, body, centre, span):
    """Camera and lights framed on the motion (the camera as isochor render places it)."""
    sc = body.sc
    toward = body.Rm @ render.Camera(body.up, a.elev, a.azim).toward
    cam_data = bpy.data.cameras.new("camera")
    cam_data.lens = 50
    cam = bpy.data.objects.new("camera", cam_data)
    sc.collection.objects.link(cam)
    cam.location = (centre + 1.9 * span * toward).tolist()
    cam.rotation_mode = "QUATERNION"
    cam.rotation_quaternion = Vector((-toward).tolist()).to_track_quat("-Z", "Y")
    sc.camera = cam
    key = bpy.data.lights.new("key", "SUN")
    key.energy = 2.5
    key_obj = bpy.data.objects.new("key light", key)
    sc.collection.objects.link(key_obj)
    key_dir = Vector((0.3 * toward + np.array([0, 0, 1.0]) + 0.3 * np.cross(toward, [0, 0, 1.0])).tolist())
    key_obj.rotation_mode = "QUATERNION"
    key_obj.rotation_quaternion = (-key_dir).to_track_quat("-Z", "Y")
    fill = bpy.data.lights.new("fill", "AREA")
    fill.energy = 15.0 * span * span
    fill.size = span
    fill_obj = bpy.data.objects.new("fill light", fill)
    sc.collection.objects.link(fill_obj)
    fill_obj.location = (centre + span * (toward - 0.5 * np.cross(toward, [0, 0, 1.0]))).tolist()
    fill_obj.rotation_mode = "QUATERNION"
    fill_obj.rotation_quaternion = Vector((centre - np.array(fill_obj.location)).tolist()).to_track_quat("-Z", "Y")
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.9, 0.9, 0.92, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    sc.world = world
    sc.view_settings.view_transform = "Standard"  # colours as the colour maps give them


def verify(body, k):
    """Frame k's evaluated surface in Blender's world against the run's, turned by Rm."""
    body.sc.frame_set(k + 1)
    dg = bpy.context.evaluated_depsgraph_get()
    ev = body.obj.evaluated_get(dg)
    co = np.empty(len(ev.data.vertices) * 3)
    ev.data.vertices.foreach_get("co", co)
    world_m = np.array(ev.matrix_world)
    got = co.reshape(-1, 3) @ world_m[:3, :3].T + world_m[:3, 3]
    x = body.surface(k)
    print(f"isochor_blender: verify frame {k}: largest distance {np.abs(got - x @ body.Rm.T).max():.3e} m "
          f"(lowest z {got[:, 2].min():.6f}, run's lowest height {np.min(x @ body.up):.6f})")


def scrub(body, count):
    t0 = time.perf_counter()
    dg = bpy.context.evaluated_depsgraph_get()
    for k in np.linspace(0, body.n - 1, count).astype(int):
        body.sc.frame_set(int(k) + 1)
        body.obj.evaluated_get(dg).data.vertices[0].co  # the evaluated mesh at that frame
    print(f"isochor_blender: scrub {count} frames: {(time.perf_counter() - t0) / count * 1e3:.2f} ms per frame")


def render_frames(a, body):
    """Cycles on the CPU, one PNG per frame asked for; an MP4 with ffmpeg."""
    n, sc = body.n, body.sc
    if a.frames:
        frames = sorted({int(k) % n for k in a.frames.split(",")})
    else:
        frames = list(range(0, n, a.every)) if a.every else list(range(n))
    try:
        w, h = (int(x) for x in a.size.lower().split("x"))
    except ValueError:
        fail(f"--size {a.size}: expected WIDTHxHEIGHT, e.g. 640x480")
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = a.samples
    sc.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
    sc.render.resolution_x, sc.render.resolution_y = w, h
    sc.render.resolution_percentage = 100
    sc.render.image_settings.file_format = "PNG"
    os.makedirs(a.render, exist_ok=True)
    written = []
    t0 = time.perf_counter()
    for k in frames:
        sc.frame_set(k + 1)
        sc.render.filepath = os.path.join(os.path.abspath(a.render), f"frame_{k:06d}.png")
        bpy.ops.render.render(write_still=True)
        written.append(sc.render.filepath)
    per = (time.perf_counter() - t0) / max(len(written), 1)
    print(f"isochor_blender: rendered {len(written)} frames to {a.render} ({per:.2f} s per frame, "
          f"{a.samples} samples, {w}x{h})")
    if a.mp4:
        write_mp4(a, body, written)


def write_mp4(a, body, written):
    if not subprocess.run(["sh", "-c", "command -v ffmpeg"], capture_output=True).stdout:
        fail("ffmpeg is not installed (apt-get install -y ffmpeg); the PNG files are written")
    listing = os.path.join(a.render, "frames.txt")
    with open(listing, "w") as lf:
        for p in written:
            lf.write(f"file '{p}'\nduration {1 / body.rate}\n")
    mp4 = os.path.splitext(body.run.path)[0] + "_blender.mp4"
    subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "concat", "-safe", "0", "-i", listing,
                    "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", mp4], check=True)
    print(f"isochor_blender: wrote {mp4}")


def main():
    a = args()
    if not os.path.exists(a.run):
        fail(f"{a.run}: no such file")
    try:
        run = Run(os.path.abspath(a.run))
    except Error as e:
        fail(str(e))
    started = time.perf_counter()
    body = Body(a, run)
    color = add_colours(a, body)
    add_motion(a, body)
    setup_seconds = time.perf_counter() - started
    centre, span = view_extent(body)
    add_planes(body, centre, span)
    add_camera_and_lights(a, body, centre, span)
    print(f"isochor_blender: {os.path.basename(run.path)}: {body.n} frames of {len(body.nodes)} surface vertices at "
          f"{body.rate:g} fps, up {np.round(body.up, 3).tolist()} ({body.up_from}) turned to z, colour {color}, "
          f"{a.cache} set up in {setup_seconds:.2f} s")
    if a.verify is not None:
        verify(body, a.verify % body.n)
    if a.scrub > 0:
        scrub(body, a.scrub)
    if a.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save))
        print(f"isochor_blender: wrote {a.save}")
    if a.render:
        render_frames(a, body)


try:
    main()
except SystemExit:
    raise
except Exception as e:  # noqa: BLE001 - Blender would print a traceback and go on; stop with the reason
    import traceback
    traceback.print_exc()
    fail(f"{type(e).__name__}: {e}")
