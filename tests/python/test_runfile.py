"""The one reader of run files (isochor._runfile): pure Python, so tools/ read runs without the
compiled module; the colliders, their poses and scales, and up as the run recorded them."""
import os
import stat
import subprocess
import sys
import tomllib

import numpy as np
import pytest

import isochor
from paths import SOURCE, SWING


@pytest.fixture(scope="module")
def swing_with_colliders(tmp_path_factory):
    """The swinging block with a ground, a plane that moves 0.1 m along x from t0 = 0.01 to
    t1 = 0.03 s, and a sphere that tightens to 0.8 of its radius; 6 frames to 0.05 s."""
    out = tmp_path_factory.mktemp("runfile") / "swing.h5"
    with open(SWING, "rb") as f:
        table = tomllib.load(f)
    table["frames"]["duration"] = 0.05
    table["contact"] = {"ground": True, "point": [0, 0, -1.0],
                        "plane": [{"point": [2.0, 0, 0], "normal": [-1.0, 0, 0], "displacement": [0.1, 0, 0],
                                   "t0": 0.01, "t1": 0.03}]}
    table["collider"] = [{"shape": "sphere", "radius": 0.05, "center": [0.0, 0.0, 3.0],
                          "resize": {"times": [0.0, 0.05], "factors": [1.0, 0.8]}}]
    isochor.run(isochor.scene(table, directory=os.path.dirname(SWING)), out)
    return out


def test_colliders_come_back_as_the_scene_gave_them(swing_with_colliders):
    with isochor.open(swing_with_colliders) as run:
        assert [(c.name, c.shape) for c in run.colliders] == [
            ("contact.ground", "plane"), ("contact.plane[0]", "plane"), ("collider[0]", "sphere")]
        assert run.colliders[0].is_ground and not run.colliders[1].is_ground
        assert run.colliders[2].dimensions == {"radius": 0.05}
        np.testing.assert_allclose(run.colliders[2].rest_pose[9:], [0, 0, 3.0])
        np.testing.assert_allclose(run.up, [0, 0, 1])  # the ground's default normal
        assert run.up_source == "the ground's normal"


def test_a_moving_plane_is_where_its_ramp_puts_it_at_every_frame(swing_with_colliders):
    # docs/scenes.md: the point moves linearly by `displacement` from t0 to t1, still before and after.
    with isochor.open(swing_with_colliders) as run:
        for k, t in enumerate(run.times):
            A, b = run.collider_pose(k, 1)
            s = np.clip((t - 0.01) / 0.02, 0, 1)
            np.testing.assert_allclose(b, [2.0 + 0.1 * s, 0, 0], atol=1e-12)
            np.testing.assert_allclose(A[:, 2], [-1, 0, 0], atol=1e-15)
            assert run.collider_scale(k, 2) == pytest.approx(1.0 - 0.2 * t / 0.05, abs=1e-12)  # linear keys


def test_the_reader_needs_no_compiled_module(swing_with_colliders):
    # The source tree's package has no _isochor beside it: isochor.open works, isochor.load says why not.
    code = ("import isochor, sys\n"
            "assert isochor._api._isochor is None\n"
            f"r = isochor.open({str(swing_with_colliders)!r})\n"
            "print(r.num_frames, len(r.colliders))\n"
            "try:\n    isochor.load('x.toml')\nexcept isochor.Error as e:\n    print(e)\n")
    env = dict(os.environ, PYTHONPATH=os.path.join(SOURCE, "python"), PYTHONDONTWRITEBYTECODE="1")
    p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    lines = p.stdout.splitlines()
    assert lines[0] == "6 3"
    assert "compiled part (_isochor) is not importable" in lines[1] and "isochor.open reads run files without it" in lines[1]


def test_a_file_that_is_not_a_run_is_one_line(tmp_path):
    bad = tmp_path / "not.h5"
    bad.write_text("plain text")
    with pytest.raises(isochor.Error, match=r"not\.h5: cannot be read as HDF5"):
        isochor.open(bad)
    p = subprocess.run([sys.executable, os.path.join(SOURCE, "tools", "render.py"), str(bad)], capture_output=True, text=True)
    assert p.returncode == 1 and p.stderr.count("\n") == 1 and "cannot be read as HDF5" in p.stderr
    with pytest.raises(isochor.Error, match=r"/dev/zero: is not a regular file"):
        isochor.open("/dev/zero")


def test_bones_and_their_poses_are_where_the_joint_puts_them(tmp_path):
    # A box with a bone on a pin about z through the origin, turned by keyframes from 0 to 75
    # degrees over 0.1 s (linear in the angle; the run stops at 0.04 s, within the ramp, so that
    # IDA meets no kink), binding the nodes with x > 0.4: the recorded pose
    # is R_z(a(t)) about the origin, and every bound node is at A X + b.
    table = {"mesh": {"shape": "box", "cells": 2, "size": [1.0, 1.0, 1.0]},
             "material": {"model": "cnh", "mu": 1e4, "lambda": 1e4},
             "forces": {"gravity": [0.0, 0.0, 0.0]},
             "skeleton": {"bone": [{"name": "arm", "joint": "pin", "origin": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0],
                                    "direction": [1.0, 0.0, 0.0], "length": 0.4, "radius": 0.05,
                                    "motion": "keyframes", "times": [0.0, 0.1], "angles": [0.0, 75.0],
                                    "select": {"kind": "box", "min": [0.4, -1, -1], "max": [1, 1, 1]}}]},
             "frames": {"rate": 100.0, "duration": 0.04}}
    out = tmp_path / "bone.h5"
    isochor.run(isochor.scene(table), out)
    with isochor.open(out) as run:
        assert [(b.name, b.parent) for b in run.bones] == [("arm", -1)]
        np.testing.assert_allclose(run.bones[0].start, [0, 0, 0], atol=1e-15)
        np.testing.assert_allclose(run.bones[0].end, [0.4, 0, 0], atol=1e-15)
        assert run.bones[0].radius == 0.05
        X = run.rest_positions
        bound = X[:, 0] > 0.4
        assert bound.sum() == 9  # the box's +x face of a 2x2x2 grid
        for k, t in enumerate(run.times):
            a = np.radians(75.0 * t / 0.1)
            R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
            A, b = run.bone_pose(k, 0)
            np.testing.assert_allclose(A, R, atol=1e-12)
            np.testing.assert_allclose(b, 0, atol=1e-12)
            np.testing.assert_allclose(run.frame_positions(k)[bound], X[bound] @ A.T + b, atol=1e-12)
        assert run.num_frames == 5


def test_a_tool_never_writes_over_what_it_reads_or_over_a_device(swing_with_colliders, tmp_path):
    # export --out onto the run it reads, onto a FIFO and onto a directory: one line, exit 1, the
    # run byte for byte as it was and the FIFO still a FIFO (a rename would have replaced it).
    run = swing_with_colliders
    before = open(run, "rb").read()
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    export = os.path.join(SOURCE, "tools", "export.py")
    for out, message in ((run, "is the input"), (fifo, "is a FIFO (named pipe), not a regular file"),
                         (tmp_path, "is a directory")):
        p = subprocess.run([sys.executable, export, str(run), "--out", str(out)], capture_output=True, text=True)
        assert p.returncode == 1 and len(p.stderr.splitlines()) == 1 and message in p.stderr, p.stderr
    assert open(run, "rb").read() == before
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_an_export_writes_the_format_its_file_names_or_refuses(swing_with_colliders, tmp_path):
    # --out FILE.glb without --format wrote a PC2 cache into FILE.glb, exit 0. The format now comes
    # from the extension (glTF's binary starts with b"glTF", PC2 with b"POINTCACHE2"); an extension
    # of no format, or one that contradicts --format, is one line, exit 1, and no file.
    run = swing_with_colliders
    export = os.path.join(SOURCE, "tools", "export.py")

    def call(*args):
        return subprocess.run([sys.executable, export, str(run), *args], capture_output=True, text=True)

    for name, magic in (("a.glb", b"glTF"), ("a.pc2", b"POINTCACHE2"), ("a.usda", b"#usda 1.0")):
        assert call("--out", str(tmp_path / name)).returncode == 0
        assert (tmp_path / name).read_bytes().startswith(magic), name
    for args, message in ((("--out", str(tmp_path / "b.xyz")), "no format from its extension"),
                          (("--format", "pc2", "--out", str(tmp_path / "b.glb")),
                           "the extension says glb, --format says pc2")):
        p = call(*args)
        assert p.returncode == 1 and len(p.stderr.splitlines()) == 1 and message in p.stderr, p.stderr
    assert sorted(os.listdir(tmp_path)) == ["a.glb", "a.pc2", "a.usda"]


def test_a_render_refuses_frames_the_run_has_not_and_sizes_no_screen_has(swing_with_colliders, tmp_path):
    # --frames 99999999 drew frame 99999999 mod 6 and said it wrote it; --size 1e9 asked
    # matplotlib for a picture of 1e18 pixels. Each is one line, exit 1, nothing written.
    render = os.path.join(SOURCE, "tools", "render.py")
    for args, message in ((("--frames", "99999999"), "has no frame 99999999 (expected 0 to 5, or -1 to -6 from the end)"),
                          (("--frames", "0,-7"), "has no frame -7"),
                          (("--every", "-2"), "--every -2: expected a positive step"),
                          (("--frames", "0", "--size", "1000000000"), "--size 1000000000: expected 16 to 8192 pixels")):
        p = subprocess.run([sys.executable, render, str(swing_with_colliders), *args, "--out", str(tmp_path / "f.png")],
                           capture_output=True, text=True)
        assert p.returncode == 1 and len(p.stderr.splitlines()) == 1 and message in p.stderr, p.stderr
    assert os.listdir(tmp_path) == []


def test_a_run_file_with_a_broken_mesh_is_one_line(swing_with_colliders, tmp_path):
    # A run whose /mesh/tets was deleted or points past the nodes (edited by hand, or another
    # program's file): render printed a KeyError or IndexError traceback, export-obj wrote faces
    # with indices past the vertices, exit 0. The reader (Python and C++) refuses it in one line.
    import shutil
    import h5py

    broken = []
    for name, edit in (("no_tets", lambda f: f["mesh"].__delitem__("tets")),
                       ("far_node", lambda f: f["mesh/tets"].__setitem__((0, 0), 10 ** 6)),
                       ("negative", lambda f: f["mesh/surface"].__setitem__((1, 2), -1))):
        path = tmp_path / f"{name}.h5"
        shutil.copy(swing_with_colliders, path)
        with h5py.File(path, "a") as f:
            edit(f)
        broken.append(path)
    render = os.path.join(SOURCE, "tools", "render.py")
    for path, message in zip(broken, ("is not a whole run", "/mesh/tets refers to node 1000000 of",
                                      "/mesh/surface refers to node -1 of")):
        with pytest.raises(isochor.Error, match=message.replace("/", "/")):
            isochor.open(path)
        p = subprocess.run([sys.executable, render, str(path), "--frames", "0", "--out", str(tmp_path / "f.png")],
                           capture_output=True, text=True)
        assert p.returncode == 1 and len(p.stderr.splitlines()) == 1 and message in p.stderr, p.stderr
    exe = os.environ.get("ISOCHOR_EXE")
    if exe:  # the C++ reader checks the cells a command reads: export-obj the surface's
        p = subprocess.run([exe, "export-obj", str(broken[2]), "--dir", str(tmp_path / "obj")], capture_output=True,
                           text=True)
        assert p.returncode == 1 and len(p.stderr.splitlines()) == 1, p.stderr
        assert "/mesh/surface row 1 refers to node -1 of" in p.stderr, p.stderr
    assert not (tmp_path / "f.png").exists() and not (tmp_path / "obj").exists()
