"""A glTF character's run read back in Python: the render mesh carried by the tets
(Run.render_positions) and the same mesh under linear blend skinning by the bones
(Run.render_skinned), on a bar made with tools/glb.py and the export to .glb."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import isochor
from paths import EXE, SOURCE

sys.path.insert(0, os.path.join(SOURCE, "tools"))
from glb import Glb  # noqa: E402

ANGLE, LIFT = math.pi / 3, 0.1  # the clip: joint b turns 60 degrees about z, a rises 0.1 m


def bar_glb(path):
    """A bar [0, 1] x [-0.2, 0.2]^2: its x = 0 corners skinned to joint a at (0.1, 0, 0), its x = 1
    corners to a's child b at (0.5, 0, 0), the middle vertices half and half; clip "bend" (1 s)."""
    x = np.array([[i / 2, (k & 1) * 0.4 - 0.2, (k >> 1) * 0.4 - 0.2] for i in range(3) for k in range(4)], np.float32)
    joints = np.array([[0, 1, 0, 0]] * 12, np.uint16)
    weights = np.array([[1 - i / 2, i / 2, 0, 0] for i in range(3) for _ in range(4)], np.float32)
    quad = lambda a, b, c, d: [(a, b, c), (a, c, d)]  # noqa: E731
    tris = []
    for i in range(2):  # the sides, between slices i and i + 1 (vertex 4 i + k)
        s, t = 4 * i, 4 * i + 4
        tris += quad(s + 0, t + 0, t + 1, s + 1) + quad(s + 1, t + 1, t + 3, s + 3)
        tris += quad(s + 3, t + 3, t + 2, s + 2) + quad(s + 2, t + 2, t + 0, s + 0)
    tris += quad(0, 1, 3, 2) + quad(8, 10, 11, 9)  # the ends
    g = Glb()
    prim = {"attributes": {"POSITION": g.accessor(x, bounds=True), "JOINTS_0": g.accessor(joints, component=5123),
                           "WEIGHTS_0": g.accessor(weights)}, "indices": g.triangles(np.array(tris))}
    g.mesh(prim)
    g.node(mesh=0, skin=0)
    g.node(name="a", translation=[0.1, 0, 0], children=[2])
    g.node(name="b", translation=[0.4, 0, 0])
    ibm = np.array([np.eye(4) for _ in range(2)])
    ibm[0, :3, 3], ibm[1, :3, 3] = [-0.1, 0, 0], [-0.5, 0, 0]
    g.gltf["skins"] = [{"joints": [1, 2], "inverseBindMatrices": g.accessor(
        np.array([m.T.reshape(-1) for m in ibm], np.float32), per=16)}]
    g.gltf["scenes"] = [{"nodes": [0, 1]}]
    times = g.accessor(np.array([0, 0.5, 1], np.float32), bounds=True)
    turn = [[0, 0, math.sin(f * ANGLE / 2), math.cos(f * ANGLE / 2)] for f in (0, 0.5, 1)]
    rise = [[0.1, 0, f * LIFT] for f in (0, 0.5, 1)]
    g.gltf["animations"] = [{"name": "bend", "samplers": [
        {"input": times, "output": g.accessor(np.array(turn, np.float32))},
        {"input": times, "output": g.accessor(np.array(rise, np.float32))}], "channels": [
        {"sampler": 0, "target": {"node": 2, "path": "rotation"}},
        {"sampler": 1, "target": {"node": 1, "path": "translation"}}]}]
    with open(path, "wb") as f:
        f.write(g.to_bytes())


@pytest.fixture(scope="module")
def bar_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("character")
    bar_glb(d / "bar.glb")
    out = d / "bar.h5"
    table = {"character": {"file": "bar.glb", "clip": "bend", "edge_length": 0.1, "loop": False, "blend_in": 0.0},
             "material": {"model": "cnh", "mu": 1e5, "lambda": 1e5}, "damping": {"beta": 0.01},
             "forces": {"gravity": [0.0, 0.0, 0.0]}, "frames": {"rate": 10.0, "duration": 1.2}}
    isochor.run(isochor.scene(table, directory=str(d)), out)
    return out


def test_the_skinned_mesh_is_the_clips_blend(bar_run):
    """At the clip's end (and held after it) linear blend skinning moves the x = 0 corners up by
    LIFT, turns the x = 1 corners by ANGLE about z through b's joint (0.5, 0, 0) and lifts them,
    and puts the middle vertices half way between the two motions: the formula, not the program."""
    with isochor.open(bar_run) as run:
        rest = run.render_rest
        c, s = math.cos(ANGLE), math.sin(ANGLE)
        Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        pivot, lift = np.array([0.5, 0, 0]), np.array([0, 0, LIFT])
        w_b = rest[:, 0]  # the middle's weight on b is 1/2 at x = 1/2: w_b = x
        expected = (1 - w_b)[:, None] * (rest + lift) + w_b[:, None] * (pivot + (rest - pivot) @ Rz.T + lift)
        for k in (run.num_frames - 2, run.num_frames - 1):  # t = 1.1, 1.2: the last pose held
            np.testing.assert_allclose(run.render_skinned(k), expected, atol=1e-6)  # float32 keys
        np.testing.assert_allclose(run.render_skinned(0), rest, atol=1e-8)  # 0.1 in float32: 1.5e-9 off


def test_the_carried_render_mesh_starts_at_the_artists_mesh(bar_run):
    with isochor.open(bar_run) as run:
        # The embedding is exact: the rest tets carry the artist's vertices to round-off.
        np.testing.assert_allclose(run.render_positions(run.rest_positions), run.render_rest, atol=1e-12)
        # Frame 0 is IDA's consistent start, within its position tolerance (atol = 1e-8) of rest.
        np.testing.assert_allclose(run.render_positions(run.frame_positions(0)), run.render_rest, atol=1e-8)
        frames = run.render_positions(run.positions)
        assert frames.shape == (run.num_frames, len(run.render_rest), 3)
        np.testing.assert_allclose(frames[3], run.render_positions(run.frame_positions(3)), atol=1e-12)


def test_export_writes_the_render_mesh(bar_run, tmp_path):
    """The PC2 cache holds the render mesh's vertices (the glTF's order), frame by frame."""
    out = tmp_path / "bar.pc2"
    subprocess.run([EXE, "export", str(bar_run), "--out", str(out)], check=True, capture_output=True)
    with isochor.open(bar_run) as run, open(out, "rb") as f:
        head = f.read(32)
        points, frames = np.frombuffer(head[16:20], "<i4")[0], np.frombuffer(head[28:32], "<i4")[0]
        assert (points, frames) == (len(run.render_rest), run.num_frames)
        cache = np.frombuffer(f.read(), "<f4").reshape(frames, points, 3)
        np.testing.assert_allclose(cache, run.render_positions(run.positions), atol=1e-6)


def test_export_writes_a_usd_stage(bar_run, tmp_path):
    """The .usda layer: USD's text header and stage metadata, one Mesh prim with the render mesh's
    triangles, its rest points and a points sample per frame at time code = frame time x rate,
    each the render mesh's vertices at that frame (7 digits, point3f), its extent their box."""
    import re

    out = tmp_path / "bar.usda"
    p = subprocess.run([EXE, "export", str(bar_run), "--format", "usd", "--out", str(out)], capture_output=True,
                       text=True, check=True)
    assert p.stdout.startswith(f"wrote {out}")
    text = out.read_text()
    assert text.startswith("#usda 1.0\n(\n")
    assert text.count("{") == text.count("}") and text.count("[") == text.count("]")
    meta = dict(re.findall(r"^    (\w+) = (.+)$", text.split("\n)\n", 1)[0], re.M))

    def numbers(s):
        return np.array([float(v) for v in re.findall(r"-?[\d.]+(?:e[-+]?\d+)?", s)])

    with isochor.open(bar_run) as run:
        rate = float(meta["timeCodesPerSecond"])
        assert abs(rate - 1 / np.median(np.diff(run.times))) < 1e-6 * rate
        up = '"Y"' if abs(run.up[1]) > abs(run.up[2]) and abs(run.up[1]) >= abs(run.up[0]) else '"Z"'
        assert meta["upAxis"] == up and float(meta["endTimeCode"]) == pytest.approx((run.times[-1] - run.times[0]) * rate)
        counts = numbers(re.search(r"int\[\] faceVertexCounts = (\[.*\])", text).group(1))
        indices = numbers(re.search(r"int\[\] faceVertexIndices = (\[.*\])", text).group(1))
        assert len(counts) == len(run.render_triangles) and set(counts) == {3}
        np.testing.assert_array_equal(indices, np.ravel(run.render_triangles))
        rest = numbers(re.search(r"point3f\[\] points = (\[.*\])", text).group(1)).reshape(-1, 3)
        np.testing.assert_allclose(rest, run.render_rest, rtol=1e-6, atol=1e-7)
        block = text.split("points.timeSamples = {", 1)[1].split("}", 1)[0]
        samples = re.findall(r"^\s+([\d.e+-]+): (\[.*\]),$", block, re.M)
        assert len(samples) == run.num_frames
        frames = run.render_positions(run.positions)
        for k, (code, points) in enumerate(samples):
            assert float(code) == pytest.approx((run.times[k] - run.times[0]) * rate, abs=1e-6)
            np.testing.assert_allclose(numbers(points).reshape(-1, 3), frames[k], rtol=1e-6, atol=1e-7)
        extent = text.split("extent.timeSamples = {", 1)[1].split("}", 1)[0]
        last = numbers(re.findall(r"^\s+[\d.e+-]+: (\[.*\]),$", extent, re.M)[-1]).reshape(2, 3)
        np.testing.assert_allclose(last, [frames[-1].min(axis=0), frames[-1].max(axis=0)], rtol=1e-6, atol=1e-7)
    # Onto a full disk (a 4 KB file size limit): one line, exit 1, neither the stage nor a part file.
    full = tmp_path / "full.usda"
    p = subprocess.run(["sh", "-c", f"ulimit -f 4; exec '{EXE}' export '{bar_run}' --format usd --out '{full}'"],
                       capture_output=True, text=True)
    assert p.returncode == 1 and len(p.stderr.strip().splitlines()) == 1 and "cannot be written" in p.stderr
    assert not full.exists() and not (tmp_path / "full.usda.part").exists()


def test_render_draws_skinned_beside_simulated(bar_run, tmp_path):
    """`isochor render --skinning`: one picture twice as wide as tall, the render mesh drawn (its
    skin colour: red over green over blue) in both halves; a run without a character: one line."""
    import matplotlib.image

    png = tmp_path / "versus.png"
    subprocess.run([EXE, "render", str(bar_run), "--frames", "-1", "--skinning", "--size", "300", "--out", str(png)],
                   check=True, capture_output=True)
    img = matplotlib.image.imread(png)
    assert img.shape[:2] == (300, 600)
    skin = (img[..., 0] > img[..., 1] + 0.05) & (img[..., 1] > img[..., 2] + 0.03)
    assert skin[:, :300].sum() > 500 and skin[:, 300:].sum() > 500
    plain = tmp_path / "plain.h5"
    isochor.run(isochor.scene({"mesh": {"shape": "box", "cells": [1, 1, 1]}, "frames": {"rate": 10.0, "duration": 0.1}}),
                plain)
    r = subprocess.run([EXE, "render", str(plain), "--frames", "0", "--skinning", "--out", str(tmp_path / "p.png")],
                       capture_output=True, text=True)
    assert r.returncode == 1 and "has no render mesh" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_a_run_without_a_character_exports_its_surface_as_glb(tmp_path):
    """The tet mesh's surface, one mesh per frame over its surface nodes, switched by one scale
    channel per frame; the binary glTF's header and chunks as the specification lays them out."""
    import json
    import struct

    run_path = tmp_path / "box.h5"
    isochor.run(isochor.scene({"mesh": {"shape": "box", "cells": [2, 1, 1]}, "frames": {"rate": 10.0, "duration": 0.2}}),
                run_path)
    out = tmp_path / "box.glb"
    subprocess.run([EXE, "export", str(run_path), "--format", "glb", "--out", str(out)], check=True, capture_output=True)
    data = out.read_bytes()
    magic, version, length = struct.unpack("<III", data[:12])
    assert (magic, version, length) == (0x46546C67, 2, len(data))
    json_length, kind = struct.unpack("<II", data[12:20])
    assert kind == 0x4E4F534A and json_length % 4 == 0
    doc = json.loads(data[20:20 + json_length])
    with isochor.open(run_path) as run:
        frames, surface_nodes = run.num_frames, len(np.unique(run.surface))
        assert len(doc["meshes"]) == len(doc["nodes"]) == frames == 3
        assert doc["scenes"][0]["nodes"] == list(range(frames))
        for mesh in doc["meshes"]:
            prim = mesh["primitives"][0]
            assert doc["accessors"][prim["attributes"]["POSITION"]]["count"] == surface_nodes
            assert doc["accessors"][prim["indices"]]["count"] == 3 * len(run.surface)
        channels = doc["animations"][0]["channels"]
        assert sorted(c["target"]["node"] for c in channels) == list(range(frames))
        assert all(c["target"]["path"] == "scale" for c in channels)


def test_the_demo_character_is_what_its_script_makes(tmp_path):
    """demos/meshes/character.glb is tools/make_character.py's output, byte for byte."""
    out = tmp_path / "character.glb"
    subprocess.run([sys.executable, os.path.join(SOURCE, "tools", "make_character.py"), "--out", str(out)],
                   check=True, capture_output=True)
    with open(os.path.join(SOURCE, "demos", "meshes", "character.glb"), "rb") as f:
        assert out.read_bytes() == f.read()
