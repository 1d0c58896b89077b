"""tools/render.py's geometry: up from the run, the camera, the rigid fit that the
deformation colour subtracts, the surface triangles' tets; and a picture of a y-up run."""
import os
import subprocess
import sys

import numpy as np
import pytest

from paths import SOURCE

sys.path.insert(0, os.path.join(SOURCE, "tools"))
import render  # noqa: E402


def rotation(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K  # Rodrigues


class _Recorded:
    up, up_source = np.array([0.0, 1.0, 0.0]), "the ground's normal"


def test_up_is_what_the_run_recorded_unless_the_option_says_otherwise():
    # The rule itself (ground, gravity, z) is the C++ side's: SceneRecord.UpIsTheGroundsNormal...
    assert np.allclose(render.up_of(_Recorded, "")[0], [0, 1, 0])
    assert render.up_of(_Recorded, "")[1] == "the ground's normal"
    assert np.allclose(render.up_of(_Recorded, "-x")[0], [-1, 0, 0])
    assert np.allclose(render.parse_up("1,1,0"), np.array([1, 1, 0]) / np.sqrt(2))
    with pytest.raises(SystemExit):
        render.parse_up("w")


@pytest.mark.parametrize("up", [[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, -1, 0], [1, 2, 3]])
@pytest.mark.parametrize("elev, azim", [(18, -60), (0, 0), (45, 120), (-20, 30)])
def test_the_camera_keeps_up_upright_on_the_screen(up, elev, azim):
    cam = render.Camera(up, elev, azim)
    basis = np.array([cam.right, cam.screen_up, cam.toward])
    assert np.allclose(basis @ basis.T, np.eye(3), atol=1e-12)  # orthonormal
    assert np.linalg.det(basis) > 0  # right-handed: not a mirror image
    u = np.asarray(up, float) / np.linalg.norm(up)
    assert abs(cam.right @ u) < 1e-12  # no roll: up has no sideways component on screen
    assert cam.screen_up @ u > 0  # a point above another is drawn above it
    assert np.isclose(cam.toward @ u, np.sin(np.radians(elev)))  # the elevation above the horizon


def test_z_up_views_keep_matplotlibs_angles():
    # matplotlib's view_init(elev, azim) looks from (cos e cos a, cos e sin a, sin e).
    cam = render.Camera([0, 0, 1], 18, -60)
    e, a = np.radians(18), np.radians(-60)
    assert np.allclose(cam.toward, [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def test_the_rigid_fit_leaves_only_the_deformation():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(200, 3))
    w = rng.uniform(0.5, 2, size=200)
    R0, t0 = rotation([1, 2, -1], 0.9), np.array([3.0, -1.0, 12.0])
    x = X @ R0.T + t0
    R, Xc, xc = render.rigid_fit(X, x, w)
    assert np.allclose(R, R0, atol=1e-12)
    assert np.abs(x - ((X - Xc) @ R.T + xc)).max() < 1e-12
    # A stretch along z on top of the motion, of a grid symmetric about its centre (its weighted
    # covariance diagonal, so that the stretch has no rotational part): the fit keeps the
    # rotation, and what is left is the stretch.
    g = np.linspace(-1, 1, 5)
    X = np.array(np.meshgrid(g, 2 * g, 3 * g)).reshape(3, -1).T
    w = np.ones(len(X))
    Xs = X * [1, 1, 1.1]
    x = Xs @ R0.T + t0
    R, Xc, xc = render.rigid_fit(X, x, w)
    assert np.allclose(R, R0, atol=1e-12)
    assert np.allclose(x - ((X - Xc) @ R.T + xc), (Xs - X) @ R0.T, atol=1e-12)


def test_every_surface_triangle_gets_the_tet_that_holds_it():
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    surface = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 4, 2], [1, 3, 4], [2, 4, 3]])
    under = render.tri_tet(surface, tets)
    assert under.tolist() == [0, 0, 0, 1, 1, 1]


def test_a_y_up_run_is_drawn_standing(tmp_path):
    exe = os.environ.get("ISOCHOR_EXE")
    if not exe:
        pytest.skip("ISOCHOR_EXE not set (CTest sets it)")
    run = tmp_path / "jelly.h5"
    subprocess.run([exe, "run", os.path.join(SOURCE, "demos", "jelly_yup.toml"), "-q", "-o", str(run),
                    "--set", "frames.duration=0.02"], check=True, capture_output=True)
    png = tmp_path / "jelly.png"
    p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "tools", "render.py"), str(run), "--frames", "-1",
                        "--out", str(png), "--size", "300"], check=True, capture_output=True, text=True)
    assert p.stdout.startswith(f"wrote {png} (")
    import matplotlib.image
    img = matplotlib.image.imread(png)
    assert img.shape[:2] == (300, 300)
    # The body (saturated colours) is above the ground (light grey): its lowest coloured row is
    # above the ground's highest grey row, as for a body standing on the ground.
    rgb = img[..., :3]
    sat = rgb.max(-1) - rgb.min(-1)
    body = np.argwhere(sat > 0.15)[:, 0]
    grey = np.argwhere((np.abs(rgb - [0.86, 0.85, 0.82]).max(-1) < 0.02))[:, 0]
    assert len(body) > 100 and len(grey) > 100
    assert np.median(body) < np.median(grey)  # image rows grow downwards
