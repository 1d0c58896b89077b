#!/usr/bin/python3
"""How a scrambled body comes back to its rest shape (demos/dragon_unfold.toml, scramble.toml).

    /usr/bin/python3 tools/recovery.py LABEL=RUN.h5 [LABEL=RUN.h5 ...] [--tolerance 0.01]
        [--markdown FILE.md] [--chart FILE.png]

At every frame: the surface's distance from its rest shape up to a rigid motion, the distances of
its nodes from their rest positions after the best rigid fit of the surface (Kabsch, no
reflection), over the rest shape's size (its bounding box's diagonal): their root mean square
(the surface as a whole) and their largest (the worst spot: a claw left through the body). The
time to recover is the first frame from which the root mean square stays within --tolerance to
the end. Also each run's status, its
volume at the end, the most tets inverted in one frame and at the end (where the run records
them), and its wall time.
"""
import argparse
import sys

import numpy as np

from render import rigid_fit
from run_file import labelled_runs, open_run, write_png, write_whole


def shape_errors(run):
    """(F,2) the surface nodes' rigid-fit distances from rest over the rest diagonal, per frame:
    their root mean square and their largest."""
    nodes = np.unique(run.surface)
    X = run.rest_positions[nodes]
    diag = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    w = np.ones(len(nodes))
    out = np.empty((run.num_frames, 2))
    for k in range(run.num_frames):
        x = run.frame_positions(k)[nodes]
        R, Xc, xc = rigid_fit(X, x, w)
        d = np.linalg.norm(x - ((X - Xc) @ R.T + xc), axis=1) / diag
        out[k] = np.sqrt(np.mean(d * d)), d.max()
    return out


def recovery_time(times, err, tol):
    """The first time from which err stays within tol to the end (None: it does not).

    >>> recovery_time([0.0, 1.0, 2.0, 3.0], np.array([0.5, 0.005, 0.02, 0.001]), 0.01)  # dips, rises, recovers
    3.0
    >>> recovery_time([0.0, 1.0], np.array([0.001, 0.002]), 0.01)
    0.0
    >>> recovery_time([0.0, 1.0], np.array([0.001, 0.2]), 0.01) is None
    True
    """
    above = np.nonzero(err > tol)[0]
    if len(above) == 0:
        return float(times[0])
    k = above[-1] + 1
    return float(times[k]) if k < len(times) else None


def measure(path, tol):
    run = open_run(path, "recovery.py")
    err = shape_errors(run)
    inv = run.stats.get("inverted_tets")
    V = run.volumes[:, 0]
    return {"times": run.times, "err": err, "status": run.status, "end": float(run.times[-1]),
            "recovered": recovery_time(run.times, err[:, 0], tol),
            "failure": str(run.totals.get("failure", "")),
            "volume": float(V[-1] / np.abs(run.rest_volumes).sum() - 1),
            "inverted": (int(np.max(inv)), int(inv[-1])) if inv is not None and len(inv) else None,
            "wall": float(run.totals.get("wall_seconds", np.nan))}


def table(runs, tol):
    lines = ["| | " + " | ".join(label for label, _ in runs) + " |", "|---" * (len(runs) + 1) + "|"]

    def row(name, fmt):
        lines.append(f"| {name} | " + " | ".join(fmt(m) for _, m in runs) + " |")

    row("status (last frame)", lambda m: f"{m['status']}, {m['end']:.2f} s")
    row(f"time to recover (rms within {100 * tol:g}% of the size)",
        lambda m: f"{m['recovered']:.2f} s" if m["recovered"] is not None else "not recovered")
    row("distance from the rest shape at the end, rms / largest (of the size)",
        lambda m: f"{m['err'][-1, 0]:.3g} / {m['err'][-1, 1]:.3g}")
    row("volume change at the end", lambda m: f"{100 * m['volume']:+.3g}%")
    row("inverted tets: most in a frame / at the end",
        lambda m: f"{m['inverted'][0]} / {m['inverted'][1]}" if m["inverted"] else "–")
    row("wall time (s)", lambda m: f"{m['wall']:.1f}" if np.isfinite(m["wall"]) else "—")
    fails = [(label, m["failure"]) for label, m in runs if m["failure"]]
    text = "\n".join(lines)
    for label, f in fails:
        text += f"\n\n{label}: {f}"
    return text


def chart(runs, out, tol):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for label, m in runs:
        line, = ax.semilogy(m["times"], np.maximum(m["err"][:, 0], 1e-6), label=f"{label} (rms)")
        ax.semilogy(m["times"], np.maximum(m["err"][:, 1], 1e-6), color=line.get_color(), ls=":", lw=1,
                    label=f"{label} (largest)")
    ax.axhline(tol, color="0.5", ls="--", lw=0.8)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("surface's distance from its rest shape\n(after the best rigid fit, of its size)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    write_png(out, fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", help="LABEL=RUN.h5")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--markdown", default="")
    ap.add_argument("--chart", default="")
    a = ap.parse_args()
    runs = [(label, measure(path, a.tolerance)) for label, path in labelled_runs(a.runs, "recovery.py")]
    text = table(runs, a.tolerance)
    print(text)
    if a.markdown:
        write_whole(a.markdown, lambda f: f.write(text + "\n"))
    if a.chart:
        chart(runs, a.chart, a.tolerance)


if __name__ == "__main__":
    main()
