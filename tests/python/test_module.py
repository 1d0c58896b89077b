"""The Python module: a run from Python equals the command line's, frame by frame;
the callback sees what the file holds and can stop the run; errors arrive with the command
line's message; isochor.open reads what was written; studies run from Python.

Run by CTest (python.pytest) with PYTHONPATH=build/python, ISOCHOR_EXE and ISOCHOR_SOURCE set,
and OMP_NUM_THREADS=1 (so that the module's run and the command line's are the same arithmetic).
"""
import ctypes
import os
import subprocess
import tomllib

import numpy as np
import pytest

import isochor
from paths import EXE, JELLY, SOURCE, SWING  # noqa: F401
from scenes import BUNDLE

SHORT = {"frames.duration": 0.05}  # 6 frames of the 144-tet swinging block


def cli(*args, check=True):
    return subprocess.run([EXE, *args], capture_output=True, text=True, check=check,
                          env={**os.environ, "OMP_NUM_THREADS": "1"})


def tet_volumes(x, tets):
    """Signed volume of every tet, det[x1-x0, x2-x0, x3-x0] / 6 (independent of isochor)."""
    a, b, c, d = (x[tets[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def test_a_run_from_python_equals_the_command_lines_frame_by_frame(tmp_path):
    cli("run", SWING, "-q", "-o", str(tmp_path / "cli.h5"), "--set", "frames.duration=0.05")
    seen = []
    result = isochor.run(SWING, tmp_path / "py.h5", overrides=SHORT, on_frame=seen.append)
    assert result.frames == 6 and not result.stopped and result.steps > 0
    with isochor.open(tmp_path / "cli.h5") as a, isochor.open(tmp_path / "py.h5") as b:
        assert a.num_frames == b.num_frames == 6
        assert a.status == b.status == "finished"
        np.testing.assert_array_equal(a.times, b.times)
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.velocities, b.velocities)
        np.testing.assert_array_equal(a.volumes, b.volumes)
        assert a.scene == b.scene  # the scene as run, the override included
        # The callback saw every frame as written.
        assert [f.index for f in seen] == list(range(6))
        for f in seen:
            np.testing.assert_array_equal(f.positions, b.positions[f.index])
            np.testing.assert_array_equal(f.velocities, b.velocities[f.index])
            np.testing.assert_array_equal(f.volumes, b.volumes[f.index])
            assert f.time == b.times[f.index]
            assert f.pressure.shape == (len(b.tets),)


def test_a_run_keeps_openblas_on_one_thread_and_gives_the_count_back(tmp_path, monkeypatch):
    # The OpenBLAS that CHOLMOD (and numpy) use, as Debian installs it; run_scene sets it to one
    # thread for the run unless OPENBLAS_NUM_THREADS is set (README, "Threads"), then restores it.
    try:
        blas = ctypes.CDLL("libopenblas.so.0")
    except OSError:
        pytest.skip("OpenBLAS is not the BLAS here")
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    blas.openblas_set_num_threads(2)
    isochor.run(SWING, tmp_path / "one.h5", overrides=SHORT)
    assert blas.openblas_get_num_threads() == 2
    with isochor.open(tmp_path / "one.h5") as r:
        assert r.totals["blas_threads"] == 1
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    isochor.run(SWING, tmp_path / "two.h5", overrides=SHORT)
    with isochor.open(tmp_path / "two.h5") as r:
        assert r.totals["blas_threads"] == 2


def test_the_callback_stops_the_run_and_the_run_resumes(tmp_path):
    out = tmp_path / "stopped.h5"
    result = isochor.run(SWING, out, overrides=SHORT, on_frame=lambda f: f.index < 2)
    assert result.stopped and result.frames == 3
    assert "stopped by the frame callback" in result.stop_reason
    with isochor.open(out) as r:
        assert r.num_frames == 3 and r.status == "interrupted"
    resumed = isochor.run(SWING, out, overrides=SHORT, resume=True)
    assert resumed.resumed_from == 2 and resumed.frames == 6
    with isochor.open(out) as r:
        assert r.num_frames == 6 and r.status == "finished"


def test_an_exception_in_the_callback_is_raised_and_the_frames_are_kept(tmp_path):
    out = tmp_path / "raised.h5"

    def boom(f):
        if f.index == 3:
            raise ValueError("enough")

    with pytest.raises(ValueError, match="enough"):
        isochor.run(SWING, out, overrides=SHORT, on_frame=boom)
    with isochor.open(out) as r:
        assert r.num_frames == 4 and r.status == "interrupted"


@pytest.mark.parametrize("args, overrides", [
    (["tests/data/bad_key.toml"], None),
    (["demos/swing.toml", "--set", "integrator.rtol=-1"], {"integrator.rtol": -1}),
    (["demos/swing.toml", "--set", "material.modell=cnh"], {"material": {"modell": "cnh"}}),
    (["tests/data/no_such_scene.toml"], None),
])
def test_errors_arrive_with_the_command_lines_message(tmp_path, args, overrides):
    p = cli("run", os.path.join(SOURCE, args[0]), *args[1:], "-q", "-o", str(tmp_path / "x.h5"), check=False)
    assert p.returncode == 1
    line = p.stderr.strip().splitlines()[-1]
    assert line.startswith("isochor: ")
    with pytest.raises(isochor.Error) as e:
        isochor.run(os.path.join(SOURCE, args[0]), tmp_path / "y.h5", overrides=overrides)
    assert "isochor: " + str(e.value) == line
    assert not (tmp_path / "y.h5").exists()


def test_an_existing_output_is_refused_unless_overwritten(tmp_path):
    out = tmp_path / "r.h5"
    isochor.run(SWING, out, overrides={"frames.duration": 0.01})
    with pytest.raises(isochor.Error, match="exists"):
        isochor.run(SWING, out, overrides={"frames.duration": 0.01})
    assert isochor.run(SWING, out, overrides={"frames.duration": 0.02}, overwrite=True).frames == 3


def test_overrides_reach_the_scene_exactly():
    mu = 0.1 + 0.2  # 0.30000000000000004: a value that must not be rounded on the way
    s = isochor.load(SWING, {"material.mu": mu, "frames": {"duration": 0.05}, "integrator.kind": "ida"})
    table = tomllib.loads(s.text)
    assert table["material"]["mu"] == mu
    assert table["frames"]["duration"] == 0.05
    assert len(s.frame_times) == 6
    assert isochor.load(SWING, ["material.mu=3e4"]).text == isochor.load(SWING, {"material.mu": 3e4}).text


def test_a_scene_from_a_dict_runs_like_its_file_and_takes_what_overrides_cannot(tmp_path):
    with open(SWING, "rb") as f:
        table = tomllib.load(f)
    table["frames"]["duration"] = 0.05
    a = isochor.run(isochor.scene(table, directory=os.path.dirname(SWING)), tmp_path / "dict.h5")
    b = isochor.run(SWING, tmp_path / "file.h5", overrides=SHORT)
    with isochor.open(a.output) as ra, isochor.open(b.output) as rb:
        np.testing.assert_array_equal(ra.positions, rb.positions)
    # An array of tables (a named zone), which `--set` cannot address.
    table["zones"] = {"zone": [{"name": "tip", "select": {"kind": "box", "min": [0.2, -1, -1], "max": [1, 1, 1]}}]}
    s = isochor.scene(table, directory=os.path.dirname(SWING))
    assert list(s.zones) == ["global", "tip"] and 0 < len(s.zones["tip"]) < s.num_tets
    isochor.run(s, tmp_path / "tip.h5")
    with isochor.open(tmp_path / "tip.h5") as r:
        assert r.volume_columns == ["total", "global", "tip"]
        # Every frame's zone volumes, from the positions by the determinant formula.
        for k in range(r.num_frames):
            v = tet_volumes(r.positions[k], r.tets)
            np.testing.assert_allclose(r.volumes[k], [v.sum(), v[r.zones["global"]].sum(), v[r.zones["tip"]].sum()],
                                       rtol=1e-12)
        # ... and each zone keeps its rest volume to the Newton tolerance.
        rest = [r.rest_volumes.sum(), r.rest_volumes[r.zones["global"]].sum(), r.rest_volumes[r.zones["tip"]].sum()]
        np.testing.assert_allclose(r.volumes, np.tile(rest, (r.num_frames, 1)), rtol=1e-9)
        assert r.positions[-1][:, 2].min() < -0.005  # and it swings down


def test_the_callback_gets_pressures_that_match_the_written_ones(tmp_path):
    seen = {}
    isochor.run(SWING, tmp_path / "p.h5", overrides={**SHORT, "output.pressure": True},
                on_frame=lambda f: seen.__setitem__(f.index, f.pressure))
    with isochor.open(tmp_path / "p.h5") as r:
        for k, p in seen.items():
            np.testing.assert_array_equal(p, r.pressure[k])
        assert np.abs(r.pressure[-1]).max() > 0


def test_open_refuses_what_is_not_a_run(tmp_path):
    with pytest.raises(isochor.Error, match="no such file"):
        isochor.open(tmp_path / "none.h5")
    (tmp_path / "text.h5").write_text("not hdf5")
    with pytest.raises(isochor.Error, match="cannot be read as HDF5"):
        isochor.open(tmp_path / "text.h5")


def test_a_study_runs_from_python(tmp_path):
    study = tmp_path / "tiny.toml"
    study.write_text(f"""
[study]
scene = "{SWING}"
output = "{tmp_path / 'tiny'}"
jobs = 2
set = ["frames.duration=0.1"]

[reference]
set = ["integrator.rtol=1e-9", "integrator.atol=1e-11"]

[[method]]
name = "ida"
sweep = {{ "integrator.rtol" = [1e-2, 1e-5] }}
set = ["integrator.atol=1e-9"]
""")
    cases = isochor.study_cases(study)
    assert [c["method"] for c in cases] == ["reference", "ida", "ida"]
    rows = isochor.study(study)
    assert [r["status"] for r in rows] == ["ok"] * 3, rows
    by_rtol = {float(r["sweep"].split("=")[1]): r for r in rows if r["method"] == "ida"}
    loose, tight = by_rtol[1e-2], by_rtol[1e-5]
    # A tolerance 1000 times tighter gives a smaller error against the reference.
    assert tight["error_l2"] < loose["error_l2"] / 10


def test_ctrl_c_stops_a_run_at_a_frame_and_keeps_the_file(tmp_path):
    import signal
    import threading

    out = tmp_path / "ctrl_c.h5"
    # SIGINT while the run is in C++ (no callback): Python's handler only sets a flag, which the
    # module checks at every frame.
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            isochor.run(SWING, out, overrides={"frames.duration": 100.0})
    finally:
        timer.cancel()
    with isochor.open(out) as r:
        assert r.status == "interrupted" and 1 <= r.num_frames < 10001


def test_the_documented_example_is_the_example_file():
    with open(os.path.join(SOURCE, "python", "examples", "sweep_mu.py")) as f:
        script = f.read()
    with open(os.path.join(SOURCE, "docs", "python.md")) as f:
        assert "```python\n" + script + "```" in f.read()


def test_values_python_can_hold_and_toml_cannot_are_explained(tmp_path):
    # A dict that contains itself would recurse without end: refused by its depth, as a scene,
    # as overrides and inside a value.
    d = {}
    d["x"] = d
    with pytest.raises(isochor.Error, match="nested more than 64 levels deep"):
        isochor.load(SWING, {"material": d})
    with open(SWING, "rb") as f:
        table = tomllib.load(f)
    table["material"]["extra"] = d
    with pytest.raises(isochor.Error, match=r"material\.extra(\.x)+: nested more than 64 levels deep"):
        isochor.scene(table, directory=os.path.dirname(SWING))
    loop = []
    loop.append(loop)
    with pytest.raises(isochor.Error, match="nested more than 64 levels deep"):
        isochor.load(SWING, {"mesh.cells": loop})
    # An integer beyond 64 bits is named with its key, not as a failed cast.
    with pytest.raises(isochor.Error, match=r"--set mesh\.cells: 1180591620717411303424 does not fit in a 64-bit integer"):
        isochor.load(SWING, {"mesh.cells": 2**70})


def test_a_callback_that_returns_neither_a_boolean_nor_none_stops_with_a_type_error(tmp_path):
    out = tmp_path / "s.h5"
    with pytest.raises(TypeError, match=r"on_frame returned a str \(expected None or True to go on, False to stop"):
        isochor.run(SWING, out, on_frame=lambda f: "yes")
    with isochor.open(out) as r:  # the frame written before the callback ran is kept
        assert r.status == "interrupted" and r.num_frames == 1


def test_a_callback_that_is_not_a_function_is_refused_before_the_run(tmp_path):
    # An int as on_frame raised "'int' object is not callable" at the first frame, after the
    # output was made; a list as a scene raised dict()'s own message.
    for kwargs in ({"on_frame": 5}, {"activation": "0.5"}):
        what = next(iter(kwargs))
        with pytest.raises(TypeError, match=f"run\\(\\): {what} must be a function or None, got a"):
            isochor.run(SWING, tmp_path / "s.h5", **kwargs)
    assert not (tmp_path / "s.h5").exists()
    with pytest.raises(TypeError, match=r"scene\(\): expected a dict of the scene's tables .*, got a list"):
        isochor.scene([("mesh", {})])


def test_an_activation_function_acts_as_the_scenes_keyframes_would(tmp_path):
    # The keyframes 0 -> 0.8 over the pseudo-time and a function giving the same values: the
    # same solves, so the same positions; the file records what the function gave.
    s = isochor.scene(BUNDLE)
    assert s.muscles == ["bundle"] and s.activations(0.5) == [0.4]
    keyed = isochor.run(s, tmp_path / "keyed.h5")
    called = isochor.run(s, tmp_path / "called.h5", activation=lambda t: {"bundle": 0.8 * t})
    with isochor.open(keyed.output) as a, isochor.open(called.output) as b:
        np.testing.assert_allclose(b.positions, a.positions, rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.activation[:, 0], 0.8 * b.times, rtol=1e-14)
        assert b.muscles == ["bundle"] and (b.tet_muscle == 0).all()
        assert b.positions[-1][:, 0].max() < 0.9  # it shortened
    # Set between frames: on_frame raises the value from frame 2 on; frames 0-2 stay at rest.
    level = {"a": 0.0}

    def on_frame(f):
        if f.index == 2:
            level["a"] = 0.5
    stepped = isochor.run(s, tmp_path / "stepped.h5", on_frame=on_frame, activation=lambda t: [level["a"]])
    with isochor.open(stepped.output) as r:
        assert r.activation[:, 0].tolist() == [0, 0, 0, 0.5, 0.5, 0.5]
        np.testing.assert_allclose(r.positions[2], r.rest_positions, atol=1e-12)
        assert r.positions[3][:, 0].max() < 0.95


def test_bad_activations_stop_the_run_with_a_reason(tmp_path):
    s = isochor.scene(BUNDLE)
    with pytest.raises(isochor.Error, match=r"gave 1.5 at t = .*expected activations in \[0, 1\]"):
        isochor.run(s, tmp_path / "a.h5", activation=lambda t: [1.5])
    with pytest.raises(KeyError, match="no muscle 'biceps'"):
        isochor.run(s, tmp_path / "b.h5", activation=lambda t: {"biceps": 0.5})
    with pytest.raises(ZeroDivisionError):
        isochor.run(s, tmp_path / "c.h5", activation=lambda t: [1 / 0])


def test_a_scene_tells_its_notes_and_inf_sup_constant_and_a_run_warns_with_them(tmp_path):
    """A CNH beam two cells thick with no zone named: its default 2-ring patches span the
    thickness (one note, and isochor.run warns with it); infsup() counts the scene's zones and
    gives a constant in (0, 1.5] (the global zone's on a clamped box is about 1.3); a fine enough
    beam has no note."""
    table = {"mesh": {"shape": "box", "size": [1.0, 0.1, 0.1], "cells": [20, 2, 2], "center": [0.5, 0, 0]},
             "material": {"mu": 1e6, "lambda": 1e6}, "forces": {"gravity": [0.0, 0.0, -9.81]},
             "boundary": [{"select": {"kind": "set", "name": "xmin"}}],
             "integrator": {"kind": "static"}, "frames": {"count": 2}}
    sc = isochor.scene(table)
    assert len(sc.notes) == 1 and "2-ring patches are 1.0 across" in sc.notes[0]
    r = sc.infsup()
    assert r["zones"] == len(sc.zones) and all(name.startswith("patch2_") for name in sc.zones)
    assert 0 < r["beta"] <= r["beta_next"] <= 1.5 and r["zero_modes"] == 0
    with pytest.warns(isochor.SceneNote, match="2-ring patches are 1.0 across"):
        isochor.run(sc, tmp_path / "beam.h5")
    assert isochor.scene(table, {"mesh.cells": [80, 8, 8]}).notes == []
