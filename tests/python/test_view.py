"""`isochor view` (tools/view.py and the page in viewer/) in headless Chromium (Debian's chromium;
skipped where it is not installed, as CI installs it with the other optional viewers).

The page reports what it drew in #state: the frame, the camera's view-projection matrix and the
canvas's place, and every error the page itself met. The silhouette in the screenshot is checked
against the run's own surface at that frame projected with that matrix here (numpy and PIL), so
the drawing is tested against the positions in the file, not against itself.
"""
import concurrent.futures
import json
import os
import re
import shutil
import signal
import subprocess

import numpy as np
import pytest

import isochor
from paths import EXE, SWING

PIL = pytest.importorskip("PIL.Image")
from PIL import Image, ImageDraw  # noqa: E402

CHROMIUM = shutil.which("chromium")
PAGE = os.path.join(os.path.dirname(EXE), "viewer", "static", "viewer.js")  # built where npm reached its registry
pytestmark = pytest.mark.skipif(not os.path.isfile(PAGE), reason="the page is not built (npm: viewer/build.sh)")
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (optional: apt-get install chromium)")
BACKGROUND = np.array([244, 244, 242])  # the page's clear colour, #f4f4f2


@pytest.fixture(scope="module")
def swing(tmp_path_factory):
    out = tmp_path_factory.mktemp("view") / "swing.h5"
    subprocess.run([EXE, "run", SWING, "-o", str(out), "-q", "--set", "frames.duration=0.3"], check=True,
                   env={**os.environ, "OMP_NUM_THREADS": "1"})
    return out


class Server:
    """`isochor view RUN --no-browser` on a free port; its address from its first line."""

    def __init__(self, run):
        self.p = subprocess.Popen([EXE, "view", str(run), "--no-browser"], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True, start_new_session=True)
        line = self.p.stdout.readline()
        m = re.search(r"at (http://127\.0\.0\.1:\d+/)", line)
        assert m, line + self.p.stderr.read()
        self.url = m.group(1)

    def stop(self):
        os.killpg(self.p.pid, signal.SIGINT)
        return self.p.communicate(timeout=10)


def browse(url, shot):
    """The page after its scripts ran (virtual time): the #state JSON, the screenshot, and what
    Chromium printed from the page's console."""
    p = subprocess.run([CHROMIUM, "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
                        "--enable-unsafe-swiftshader", "--window-size=1200,700", "--virtual-time-budget=10000",
                        "--no-first-run", "--disable-extensions", "--disable-background-networking",
                        "--enable-logging=stderr", "--v=0", f"--screenshot={shot}", "--dump-dom", url],
                       capture_output=True, text=True, timeout=120)
    m = re.search(r'<pre id="state"[^>]*>([^<]*)</pre>', p.stdout)
    assert m, p.stdout[-2000:] + p.stderr[-2000:]
    error = re.search(r'<div id="error"[^>]*>([^<]*)</div>', p.stdout)
    console = [line for line in p.stderr.splitlines() if ":CONSOLE" in line]
    return json.loads(m.group(1).replace("&quot;", '"')), shot, console, error.group(1) if error else ""


def drawn_mask(shot, state):
    """Pixels of the canvas that are not the background."""
    img = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    x0, y0 = int(round(state["left"])), int(round(state["top"]))
    canvas = img[y0:y0 + state["height"], x0:x0 + state["width"]]
    return np.abs(canvas - BACKGROUND).max(axis=2) > 12


def projected_mask(run_path, frame, state):
    """The run's surface at `frame` projected with the page's view-projection matrix, filled."""
    with isochor.open(run_path) as run:
        x = run.frame_positions(frame)
        faces = run.surface
    vp = np.array(state["view_projection"]).reshape(4, 4).T  # three.js stores column-major
    clip = np.c_[x, np.ones(len(x))] @ vp.T
    ndc = clip[:, :3] / clip[:, 3:4]
    w, h = state["width"], state["height"]
    px = np.c_[(ndc[:, 0] + 1) / 2 * w, (1 - ndc[:, 1]) / 2 * h]
    img = Image.new("1", (w, h), 0)
    draw = ImageDraw.Draw(img)
    for f in faces:
        draw.polygon([tuple(px[i]) for i in f], fill=1)
    return np.asarray(img, bool)


def iou(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


@needs_chromium
def test_the_page_draws_the_runs_surface_and_steps_through_frames(swing, tmp_path):
    server = Server(swing)
    try:
        with concurrent.futures.ThreadPoolExecutor(2) as pool:  # two browsers at once: each mostly waits
            first = pool.submit(browse, server.url + "?size=760x520&frame=0", tmp_path / "f0.png")
            second = pool.submit(browse, server.url + "?size=760x520&frame=28&steps=2", tmp_path / "f30.png")
            s0, shot0, console0, error0 = first.result()
            s1, shot1, console1, error1 = second.result()
    finally:
        server.stop()
    for s, console, error in ((s0, console0, error0), (s1, console1, error1)):
        assert s["ready"] and s["errors"] == [] and console == [] and error == "", (s, console, error)
    assert (s0["frame"], s1["frame"], s0["frames"]) == (0, 30, 31)
    m0, m1 = drawn_mask(shot0, s0), drawn_mask(shot1, s1)
    assert m0.mean() > 0.02  # not blank
    assert iou(m0, projected_mask(swing, 0, s0)) > 0.95
    assert iou(m1, projected_mask(swing, 30, s1)) > 0.95
    assert iou(m0, m1) < 0.9  # stepping moved it: the swing has fallen by frame 30


@needs_chromium
def test_an_exported_folder_opens_from_disk_like_the_served_page(swing, tmp_path):
    out = tmp_path / "page"
    p = subprocess.run([EXE, "view", str(swing), "--export", str(out), "--every", "10"], capture_output=True,
                       text=True)
    assert p.returncode == 0 and "4 frames" in p.stdout, p.stdout + p.stderr
    s, shot, console, error = browse((out / "index.html").as_uri() + "?size=760x520&frame=20", tmp_path / "export.png")
    assert s["ready"] and s["errors"] == [] and console == [] and error == "", (s, console, error)
    assert s["frame"] == 20
    assert iou(drawn_mask(shot, s), projected_mask(swing, 20, s)) > 0.95


@needs_chromium
def test_a_bad_file_is_one_line_on_the_terminal_and_a_message_on_the_page(swing, tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_text("not a run")
    p = subprocess.run([EXE, "view", str(bad), "--no-browser"], capture_output=True, text=True, timeout=30)
    assert p.returncode == 1 and len(p.stderr.splitlines()) == 1 and "cannot be read as HDF5" in p.stderr, p.stderr
    # A run that breaks while it is served (overwritten by something else): the page says why.
    broken = tmp_path / "broken.h5"
    shutil.copyfile(swing, broken)
    server = Server(broken)
    try:
        broken.write_text("overwritten")
        s, _, _, error = browse(server.url, tmp_path / "broken.png")
    finally:
        _, err = server.stop()
    assert "error" in s and "cannot be read as HDF5" in s["error"] and "cannot be read as HDF5" in error
    assert "cannot be read as HDF5" in err  # and on the terminal


def test_an_export_onto_a_full_disk_is_one_line_and_leaves_the_old_folder(swing, tmp_path):
    # A file size limit (as a nearly full disk) below the first frame's script: one line, exit 1,
    # the earlier export untouched and no part folder left.
    out = tmp_path / "page"
    out.mkdir()
    (out / "index.html").write_text("an earlier export")
    p = subprocess.run(["sh", "-c", f"ulimit -f 64; exec '{EXE}' view '{swing}' --export '{out}'"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 1 and len(p.stderr.splitlines()) == 1, p.stderr
    assert "cannot be written" in p.stderr and "nothing was written" in p.stderr
    assert (out / "index.html").read_text() == "an earlier export"
    assert not os.path.exists(str(out) + ".part")


def test_an_export_never_removes_a_folder_it_did_not_write(swing, tmp_path):
    # A folder with the user's own files (here the run itself): refused in one line, every file
    # kept; an earlier export (only what an export writes) is replaced.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    (mine / "index.html").write_text("mine too")
    p = subprocess.run([EXE, "view", str(swing), "--export", str(mine)], capture_output=True, text=True, timeout=60)
    assert p.returncode == 1 and len(p.stderr.splitlines()) == 1, p.stderr
    assert "is not a folder this command wrote" in p.stderr
    assert (mine / "notes.txt").read_text() == "keep me" and (mine / "index.html").read_text() == "mine too"
    here = subprocess.run([EXE, "view", str(swing), "--export", str(swing.parent)], capture_output=True, text=True,
                          timeout=60)
    assert here.returncode == 1 and os.path.exists(swing)
    page = tmp_path / "page"  # what an earlier export left: replaced
    (page / "data").mkdir(parents=True)
    (page / "index.html").write_text("an earlier export")
    ok = subprocess.run([EXE, "view", str(swing), "--export", str(page), "--every", "10"], capture_output=True,
                        text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert (page / "index.html").read_text() != "an earlier export" and (page / "data" / "meta.js").exists()
