"""tools/energy_chart.py (the paper's Figure 8): its table against the run files read
directly, a failed run marked as such, and a clear stop on a file that is not a run."""
import csv
import os
import subprocess

import h5py
import numpy as np

from paths import EXE, SOURCE

TOOL = os.path.join(SOURCE, "tools", "energy_chart.py")
CUBE = os.path.join(SOURCE, "demos", "cube_collapse.toml")


def test_the_table_is_the_runs_own_energy_and_a_failed_run_says_so(tmp_path):
    exe = EXE
    ok, bad = tmp_path / "ok.h5", tmp_path / "bad.h5"
    base = [exe, "run", CUBE, "-q", "--set", "mesh.cells=2", "--set", "frames.duration=0.5",
            "--set", "integrator.kind=backward_euler", "--set", "integrator.linear_solver=reduced"]
    subprocess.run(base + ["-o", str(ok), "--set", "integrator.dt=0.008"], check=True, capture_output=True)
    # Plain Newton at 33 ms fails on this collapse (tests/test_optimisation_step.cpp).
    p = subprocess.run(base + ["-o", str(bad), "--set", "integrator.dt=0.033", "--set", "integrator.line_search=false"],
                       capture_output=True, text=True)
    assert p.returncode != 0
    png, table = tmp_path / "e.png", tmp_path / "e.csv"
    subprocess.run(["/usr/bin/python3", TOOL, "-o", str(png), "--csv", str(table), "--zoom-last", "0.2",
                    f"good={ok}", f"plain={bad}"], check=True, capture_output=True)
    assert png.stat().st_size > 10000
    rows = {r["run"]: r for r in csv.DictReader(open(table))}
    with h5py.File(ok, "r") as f:
        e = f["/frames/energy"][()]
        t = f["/frames/time"][()]
        potential = e[:, 1] + e[:, 2]
        last = t >= t[-1] - 0.2
        v = f["/frames/volume"][()][:, 0]
    assert rows["good"]["status"] == "finished"
    assert int(rows["good"]["frames"]) == len(t)
    assert np.isclose(float(rows["good"]["final_potential_J"]), potential[-1], rtol=1e-6)
    assert np.isclose(float(rows["good"]["swing_in_window_J"]), np.ptp(potential[last]), rtol=1e-3)
    assert np.isclose(float(rows["good"]["worst_volume_error"]), np.abs(v / v[0] - 1).max(), rtol=1e-3, atol=1e-15)
    assert rows["plain"]["status"] == "failed"
    assert "Newton did not converge" in rows["plain"]["reason"]
    assert int(rows["plain"]["frames"]) < len(t)


def test_a_file_that_is_no_run_stops_with_its_name(tmp_path):
    junk = tmp_path / "junk.h5"
    junk.write_text("not hdf5")
    p = subprocess.run(["/usr/bin/python3", TOOL, "-o", str(tmp_path / "x.png"), f"j={junk}"],
                       capture_output=True, text=True)
    assert p.returncode != 0
    assert str(junk) in p.stderr and "not a readable isochor run" in p.stderr
