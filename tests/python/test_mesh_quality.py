"""tools/mesh_quality.py: on the sliver box its extremes are the ones geometry gives, and a
file that is not a run stops with one line naming it."""
import math
import os
import re
import subprocess

import pytest

from paths import EXE, SOURCE

TOOL = os.path.join(SOURCE, "tools", "mesh_quality.py")
SCRAMBLE = os.path.join(SOURCE, "demos", "scramble.toml")


def test_sliver_box_extremes_and_counts(tmp_path):
    exe = EXE
    run = tmp_path / "q.h5"
    subprocess.run([exe, "run", SCRAMBLE, "-q", "--set", "mesh.cells=5", "--set", "frames.duration=0", "-o", str(run)],
                   check=True, capture_output=True)
    png = tmp_path / "q.png"
    out = subprocess.run(["/usr/bin/python3", TOOL, str(run), "-o", str(png)], check=True, capture_output=True,
                         text=True).stdout
    assert png.stat().st_size > 5000
    # Thin layers 60 times thinner: the flattest face is a right triangle with legs sqrt(2) w and
    # w/60, the longest edge ratio sqrt(2 * 60^2 + 1).
    smallest = float(re.search(r"smallest face angle: min ([0-9.e+-]+) deg", out).group(1))
    assert smallest == pytest.approx(math.degrees(math.atan(1 / (math.sqrt(2) * 60))), rel=2e-3)
    ratio = float(re.search(r"edge ratio: max ([0-9.e+-]+)", out).group(1))
    assert ratio == pytest.approx(math.sqrt(2 * 60 ** 2 + 1), rel=2e-3)
    # Every Kuhn tet has one edge along each axis and a right angle between consecutive ones, so
    # every tet of a cell that is thin along some axes and thick along others has a face below 1
    # degree; of the 5^3 cells, 3^3 are thick and 2^3 thin along all three axes (regular), 6 tets each.
    below = int(re.search(r"; (\d+) tets below 1 deg", out).group(1))
    assert below == 6 * (5 ** 3 - 3 ** 3 - 2 ** 3)


def test_not_a_run_is_one_line_naming_the_file(tmp_path):
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    p = subprocess.run(["/usr/bin/python3", TOOL, str(junk)], capture_output=True, text=True)
    assert p.returncode != 0
    assert str(junk) in p.stderr and len(p.stderr.strip().splitlines()) == 1
