"""tools/muscle_report.py on a free bundle of muscle (a bar on three symmetry planes, fibres along
x, activated): the bar shortens homogeneously to a stretch l, so the tool's mean fibre stretch must
be l (the end face's position), its mid-length cross-section the rest area over l (volume kept),
and its bulge the lateral growth 0.5 (l^-1/2 - 1) of a corner edge's distance from the x axis."""
import os
import subprocess

import numpy as np

import isochor
from paths import SOURCE
from scenes import BUNDLE

TOOL = os.path.join(SOURCE, "tools", "muscle_report.py")

def test_the_report_of_a_free_bundle_is_its_homogeneous_shortening(tmp_path):
    out = tmp_path / "bundle.h5"
    isochor.run(isochor.scene(BUNDLE), out)
    with isochor.open(out) as r:
        l = r.positions[-1][r.node_sets["xmax"], 0].mean()
    p = subprocess.run(["/usr/bin/python3", TOOL, str(out), "--muscle", "bundle", "--axis", "0,0,0,1,0,0"],
                       check=True, capture_output=True, text=True)
    last = [float(v) for v in p.stdout.strip().splitlines()[-1].split()]
    t, activation, area_cm2, outward_mm, stretch, drift = last
    assert l < 0.9 and t == 1.0 and activation == 0.8
    assert abs(stretch - l) < 1e-3  # the report prints 3 decimals
    assert abs(area_cm2 - 1e4 * 0.25 / l) < 1e-3 * 1e4 * 0.25 / l
    # The farthest surface node from the x axis is a corner edge at distance 0.5 sqrt(2) at rest.
    assert abs(outward_mm - 1e3 * 0.5 * np.sqrt(2) * (l ** -0.5 - 1)) < 0.01
    assert drift < 1e-9
    missing = subprocess.run(["/usr/bin/python3", TOOL, str(out), "--muscle", "biceps"], capture_output=True, text=True)
    assert missing.returncode != 0 and "no muscle \"biceps\" (muscles: bundle)" in missing.stderr
