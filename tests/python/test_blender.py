"""Animation packages: the point caches `isochor export` writes, read back by their
published layouts, and a Blender smoke test (when Blender is installed): one frame of a
1,275-tet y-up run imported, checked against the run and rendered with Cycles."""
import os
import shutil
import struct
import subprocess

import numpy as np
import pytest

import isochor
from paths import EXE, JELLY, SOURCE, SWING  # noqa: F401



@pytest.fixture(scope="module")
def jelly(tmp_path_factory):
    out = tmp_path_factory.mktemp("blender") / "jelly.h5"
    isochor.run(JELLY, out, overrides={"frames.duration": 0.12, "output.pressure": True})
    return out


def test_pc2_holds_every_frame_of_the_surface(jelly, tmp_path):
    pc2 = tmp_path / "jelly.pc2"
    subprocess.run([EXE, "export", str(jelly), "--out", str(pc2)], check=True, capture_output=True)
    data = pc2.read_bytes()
    # PC2: char[12] "POINTCACHE2\0", int32 version 1, int32 points, float32 start, float32 rate,
    # int32 samples, then float32 x, y, z per point per sample, little-endian.
    assert data[:12] == b"POINTCACHE2\0"
    version, points, start, rate, samples = struct.unpack("<iiffi", data[12:32])
    with isochor.open(jelly) as r:
        surface = np.unique(r.surface)
        assert (version, points, start, rate, samples) == (1, len(surface), 0.0, 1.0, r.num_frames)
        xyz = np.frombuffer(data[32:], dtype="<f4").reshape(samples, points, 3)
        np.testing.assert_array_equal(xyz, r.positions[:, surface, :].astype(np.float32))


def test_mdd_holds_every_frame_and_its_time(jelly, tmp_path):
    mdd = tmp_path / "jelly.mdd"
    subprocess.run([EXE, "export", str(jelly), "--format", "mdd", "--out", str(mdd), "--all-nodes"], check=True,
                   capture_output=True)
    data = mdd.read_bytes()
    # MDD: int32 frames, int32 points, float32 time per frame, then x, y, z per point per frame,
    # big-endian.
    frames, points = struct.unpack(">ii", data[:8])
    with isochor.open(jelly) as r:
        assert (frames, points) == (r.num_frames, len(r.rest_positions))
        times = np.frombuffer(data[8:8 + 4 * frames], dtype=">f4")
        np.testing.assert_array_equal(times, r.times.astype(np.float32))
        xyz = np.frombuffer(data[8 + 4 * frames:], dtype=">f4").reshape(frames, points, 3)
        np.testing.assert_array_equal(xyz, r.positions.astype(np.float32))


@pytest.mark.skipif(not shutil.which("blender"), reason="Blender not installed (optional: apt-get install blender)")
def test_blender_imports_the_run_turned_z_up_and_renders_a_frame(jelly, tmp_path):
    script = os.path.join(SOURCE, "tools", "blender", "isochor_blender.py")
    p = subprocess.run(["blender", "-b", "--python-exit-code", "1", "--python", script, "--", str(jelly),
                        "--verify", "8", "--render", str(tmp_path / "png"), "--frames", "8", "--samples", "2",
                        "--size", "160x120", "--save", str(tmp_path / "jelly.blend")],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("isochor_blender:")]
    assert "up [0.0, 1.0, 0.0] (the ground's normal) turned to z" in lines[0]
    # Blender's evaluated mesh at frame 8 (the mesh cache over the PC2 file, under the empty that
    # turns y up to z) is the run's surface at frame 8, to float32's rounding.
    verify = next(ln for ln in lines if "verify frame 8" in ln)
    distance = float(verify.split("largest distance ")[1].split()[0])
    assert distance < 1e-6
    # ... and its lowest point is the run's lowest height, now along z.
    lowest_z = float(verify.split("lowest z ")[1].split(",")[0])
    lowest_h = float(verify.split("run's lowest height ")[1].rstrip(")"))
    assert lowest_z == pytest.approx(lowest_h, abs=1e-6)
    assert (tmp_path / "jelly.blend").exists()
    import matplotlib.image
    img = matplotlib.image.imread(tmp_path / "png" / "frame_000008.png")
    assert img.shape[:2] == (120, 160)
    rgb = img[..., :3]
    assert ((rgb.max(-1) - rgb.min(-1)) > 0.25).sum() > 100  # the coloured body is in the picture
