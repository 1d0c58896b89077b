"""Sweep the shear modulus of the swinging block (demos/swing.toml) from Python: run each case,
with its zone kept and with it only measured, and plot the volume error and the tip's lowest
height against mu.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/sweep_mu.py [OUT_DIR]
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import isochor  # noqa: E402

here = os.path.dirname(os.path.abspath(__file__))
scene_file = os.path.join(here, "..", "..", "demos", "swing.toml")
out = sys.argv[1] if len(sys.argv) > 1 else "out/sweep_mu"
os.makedirs(out, exist_ok=True)

mus = [5e3, 1e4, 2e4, 4e4, 8e4]  # Pa
rows = []
for keep in (True, False):
    for mu in mus:
        # The block's lowest point over the run, watched frame by frame as it is computed.
        lowest = [np.inf]

        def watch(frame):
            lowest[0] = min(lowest[0], frame.positions[:, 2].min())

        path = os.path.join(out, f"mu{mu:g}_{'kept' if keep else 'measured'}.h5")
        result = isochor.run(scene_file, path, overwrite=True, on_frame=watch,
                             overrides={"material.mu": mu, "zones.keep": keep})
        with isochor.open(result.output) as run:
            rows.append((keep, mu, run.volume_error(), lowest[0], result.steps, result.wall_seconds))
        print(f"mu = {mu:8g} Pa, zone {'kept    ' if keep else 'measured'}: volume error {rows[-1][2]:.2e}, "
              f"lowest point {100 * lowest[0]:6.2f} cm, {result.steps} steps, {result.wall_seconds:.2f} s")

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.6))
for keep, style in ((True, "o-"), (False, "s--")):
    r = [row for row in rows if row[0] == keep]
    label = "global zone kept (CNH)" if keep else "zone measured only (CNH's local penalty)"
    ax1.loglog([x[1] for x in r], [max(x[2], 1e-16) for x in r], style, label=label)
    ax2.semilogx([x[1] for x in r], [100 * x[3] for x in r], style, label=label)
ax1.set_xlabel("shear modulus mu (Pa)")
ax1.set_ylabel("worst relative volume error")
ax2.set_xlabel("shear modulus mu (Pa)")
ax2.set_ylabel("lowest point of the block (cm)")
ax1.legend(fontsize=7)
ax1.grid(True, which="both", alpha=0.3)
ax2.grid(True, which="both", alpha=0.3)
fig.suptitle("The swinging block (demos/swing.toml), swept from Python")
fig.tight_layout()
fig.savefig(os.path.join(out, "sweep_mu.png"), dpi=110)
print("wrote", os.path.join(out, "sweep_mu.png"))
