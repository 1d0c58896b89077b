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
import h5py
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import export  # noqa: E402  (tools/export.py: the PC2 writer)
import render  # noqa: E402  (tools/render.py: up from the scene, planes, camera angles)


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


def main():
    a = args()
    if not os.path.exists(a.run):
        fail(f"{a.run}: no such file")
    run = os.path.abspath(a.run)
    f = h5py.File(run, "r")
    S = f["/mesh/surface"][()]
    T = f["/mesh/tets"][()]
    P = f["/frames/positions"]
    times = f["/frames/time"][()]
    n = min(P.shape[0], len(times))
    if a.max_frames > 0:
        n = min(n, a.max_frames)
    if n == 0:
        fail(f"{a.run}: no frames")
    scene_table = render.scene_of(f)
    up, up_from = render.up_of(scene_table, a.up)
    nodes = export.surface_nodes(f)
    index = -np.ones(P.shape[1], dtype=np.int64)
    index[nodes] = np.arange(len(nodes))
    faces = index[S]
    started = time.perf_counter()

    # An empty scene at the run's frame rate.
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    rate = 1.0 / float(np.median(np.diff(times[:n]))) if n > 1 else 24.0
    sc.render.fps = max(1, round(rate))
    sc.render.fps_base = sc.render.fps / rate
    sc.frame_start, sc.frame_end = 1, n

    # Everything of the run hangs under one empty that turns its up to Blender's z.
    root = bpy.data.objects.new("isochor", None)
    sc.collection.objects.link(root)
    R = Vector((0, 0, 1)).rotation_difference(Vector(up.tolist())).inverted()  # run's up -> +z
    root.rotation_mode = "QUATERNION"
    root.rotation_quaternion = R
    Rm = np.array(R.to_matrix())

    # The body: the surface of frame 0, smooth-shaded.
    mesh = bpy.data.meshes.new(os.path.basename(run))
    mesh.from_pydata(P[0][nodes].tolist(), [], faces.tolist())
    mesh.update()
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    body = bpy.data.objects.new("body", mesh)
    sc.collection.objects.link(body)
    body.parent = root

    # Colour attributes per face corner: the zone of the tet under each triangle, and the
    # pressure of one frame.
    under = render.tri_tet(S, T)
    if "/mesh/zone" in f:
        zone = f["/mesh/zone"][()]
        names = f["/mesh/zone"].attrs.get("zones", b"")
        zone_names = (names.decode() if isinstance(names, bytes) else str(names)).split(",")
    else:
        zone, zone_names = np.full(len(T), -1), []
    zc = np.array([SET1[(z + 1) % len(SET1)] for z in zone[under]])
    attr = mesh.color_attributes.new("zone", "FLOAT_COLOR", "CORNER")
    attr.data.foreach_set("color", np.repeat(linear(zc), 3, axis=0).ravel())
    has_pressure = "/frames/pressure" in f
    if has_pressure:
        k = a.pressure_frame % n
        p = f["/frames/pressure"][k][under]
        lo, hi = np.percentile(p, 2), np.percentile(p, 98)
        attr = mesh.color_attributes.new("pressure", "FLOAT_COLOR", "CORNER")
        attr.data.foreach_set("color", np.repeat(linear(colour_rows(p, lo, hi, viridis)), 3, axis=0).ravel())
    color = a.color or ("zone" if len(zone_names) > 1 else "pressure" if has_pressure else "none")
    if color == "pressure" and not has_pressure:
        fail(f"{a.run}: no /frames/pressure (run the scene with output.pressure = true)")
    body.data.materials.append(material("tissue", None if color == "none" else color))

    # The motion.
    if a.cache == "pc2":
        pc2 = os.path.splitext(run)[0] + ".pc2"
        if a.max_frames > 0:
            pc2 = os.path.splitext(run)[0] + f"_{n}.pc2"
        if not os.path.exists(pc2) or os.path.getmtime(pc2) < os.path.getmtime(run):
            export.write_cache(run, pc2, "pc2", frames=n)
        mod = body.modifiers.new("isochor motion", "MESH_CACHE")
        mod.cache_format = "PC2"
        mod.filepath = pc2
        mod.frame_start = 1.0  # PC2 sample 0 at Blender frame 1
        mod.time_mode = "FRAME"
        mod.play_mode = "SCENE"
    else:
        body.shape_key_add(name="Basis", from_mix=False)
        for k in range(n):
            key = body.shape_key_add(name=f"frame_{k}", from_mix=False)
            key.data.foreach_set("co", P[k][nodes].astype(np.float32).ravel())
            key.value = 0.0
            for fr, v in ((k, 0.0), (k + 1, 1.0), (k + 2, 0.0)):
                if 1 <= fr <= n:
                    key.value = v
                    key.keyframe_insert("value", frame=fr)
    setup_seconds = time.perf_counter() - started

    # What the run visits (a sample of at most 200 frames), in Blender's world.
    sample = sorted(set(np.linspace(0, n - 1, min(n, 200)).astype(int)))
    pts = np.concatenate([P[k][nodes] for k in sample]) @ Rm.T
    planes = render.planes_of(scene_table)
    for pl in planes:
        if pl["ground"]:
            gp, gn = Rm @ pl["point"], Rm @ pl["normal"]
            pts = np.concatenate([pts, pts - np.outer((pts - gp) @ gn, gn)])
    lo, hi = pts.min(0), pts.max(0)
    centre, span = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) or 1.0

    # The ground and the contact planes (moving ones keyframed from t0 to t1).
    for i, pl in enumerate(planes):
        bpy.ops.mesh.primitive_plane_add(size=1.5 * span)
        obj = bpy.context.active_object
        obj.name = "ground" if pl["ground"] else f"plane_{i}"
        obj.parent = root
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector((0, 0, 1)).rotation_difference(Vector(pl["normal"].tolist()))
        c_run = Rm.T @ centre
        base = pl["point"] + ((c_run - pl["point"]) - ((c_run - pl["point"]) @ pl["normal"]) * pl["normal"])
        obj.location = base.tolist()
        m = material("ground" if pl["ground"] else "plane", None,
                     (0.8, 0.8, 0.78, 1.0) if pl["ground"] else (0.55, 0.7, 0.85, 1.0))
        obj.data.materials.append(m)
        if "displacement" in pl and np.any(pl["displacement"]):
            for t, s in ((pl["t0"], 0.0), (pl["t1"], 1.0)):
                obj.location = (base + s * pl["displacement"]).tolist()
                obj.keyframe_insert("location", frame=1 + t * rate)

    # Camera and lights framed on the motion (the camera as isochor render places it).
    cam_angles = render.Camera(up, a.elev, a.azim)
    toward = Rm @ cam_angles.toward
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
    print(f"isochor_blender: {os.path.basename(run)}: {n} frames of {len(nodes)} surface vertices at "
          f"{rate:g} fps, up {np.round(up, 3).tolist()} ({up_from}) turned to z, colour {color}, "
          f"{a.cache} set up in {setup_seconds:.2f} s")

    if a.verify is not None:
        k = a.verify % n
        sc.frame_set(k + 1)
        dg = bpy.context.evaluated_depsgraph_get()
        ev = body.evaluated_get(dg)
        co = np.empty(len(ev.data.vertices) * 3)
        ev.data.vertices.foreach_get("co", co)
        world_m = np.array(ev.matrix_world)
        got = co.reshape(-1, 3) @ world_m[:3, :3].T + world_m[:3, 3]
        want = P[k][nodes] @ Rm.T
        print(f"isochor_blender: verify frame {k}: largest distance {np.abs(got - want).max():.3e} m "
              f"(lowest z {got[:, 2].min():.6f}, run's lowest height {np.min(P[k][nodes] @ up):.6f})")

    if a.scrub > 0:
        t0 = time.perf_counter()
        dg = bpy.context.evaluated_depsgraph_get()
        for k in np.linspace(0, n - 1, a.scrub).astype(int):
            sc.frame_set(int(k) + 1)
            body.evaluated_get(dg).data.vertices[0].co  # the evaluated mesh at that frame
        print(f"isochor_blender: scrub {a.scrub} frames: {(time.perf_counter() - t0) / a.scrub * 1e3:.2f} ms per frame")

    if a.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save))
        print(f"isochor_blender: wrote {a.save}")

    if a.render:
        if a.frames:
            frames = sorted({int(k) % n for k in a.frames.split(",")})
        elif a.every:
            frames = list(range(0, n, a.every))
        else:
            frames = list(range(n))
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
            if not subprocess.run(["sh", "-c", "command -v ffmpeg"], capture_output=True).stdout:
                fail("ffmpeg is not installed (apt-get install -y ffmpeg); the PNG files are written")
            listing = os.path.join(a.render, "frames.txt")
            with open(listing, "w") as lf:
                for p in written:
                    lf.write(f"file '{p}'\nduration {1 / rate}\n")
            mp4 = os.path.splitext(run)[0] + "_blender.mp4"
            subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "concat", "-safe", "0", "-i", listing,
                            "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p", mp4], check=True)
            print(f"isochor_blender: wrote {mp4}")


try:
    main()
except SystemExit:
    raise
except Exception as e:  # noqa: BLE001 - Blender would print a traceback and go on; stop with the reason
    import traceback
    traceback.print_exc()
    fail(f"{type(e).__name__}: {e}")
