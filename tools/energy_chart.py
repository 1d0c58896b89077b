#!/usr/bin/env python3
"""Potential energy against time of several runs, as the CNH paper's Figure 8 draws it: the
whole run on top, and below a magnified window (the last seconds) where oscillations and drift
show. Potential energy is elastic plus external (gravity, loads, contact) from /frames/energy.

    tools/energy_chart.py -o energy.png [--csv runs.csv] [--zoom-last SECONDS] NAME=RUN.h5 ...

A run that stopped early (status "failed") is drawn as far as it went and marked with a cross at
its last frame; the CSV lists per run: status, frames, end time, final and extreme potential
energy, the largest oscillation of the potential energy over the zoom window (max - min), worst
relative volume error of the total volume, most inverted tets in a frame, wall seconds, and the
failure's reason.
"""
import argparse
import csv
import sys

import numpy as np

from run_file import Error, Run


def read(path):
    with Run(path) as run:
        n = run.num_frames
        e, vol = run.energy, run.volumes[:, 0]
        return {
            "t": run.times,
            "potential": e[:, 1] + e[:, 2],
            "volume_error": np.abs(vol / vol[0] - 1.0) if n else np.array([]),
            "inverted": run.stats.get("inverted_tets", np.zeros(n)),
            "status": run.status or "unknown",
            "wall": run.totals.get("wall_seconds", float("nan")),
            "reason": run.totals.get("failure", ""),
        }


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("runs", nargs="+", help="NAME=RUN.h5")
    p.add_argument("-o", "--output", required=True, help="the chart (PNG)")
    p.add_argument("--csv", help="one line per run")
    p.add_argument("--zoom-last", type=float, default=1.0, help="the magnified window: the last SECONDS of the longest run")
    p.add_argument("--title", default="potential energy")
    a = p.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = []
    for spec in a.runs:
        if "=" not in spec:
            sys.exit(f"energy_chart.py: {spec}: expected NAME=RUN.h5")
        name, path = spec.split("=", 1)
        try:
            data.append((name, read(path)))
        except (Error, OSError, KeyError) as e:
            sys.exit(f"energy_chart.py: {path}: not a readable isochor run ({e})")
    end = max(d["t"][-1] for _, d in data if len(d["t"]))
    lo = end - a.zoom_last
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 7), gridspec_kw={"height_ratios": [3, 2]})
    rows = []
    for k, (name, d) in enumerate(data):
        colour = f"C{k % 10}"
        failed = d["status"] != "finished"
        label = name + (" (failed)" if failed else "")
        top.plot(d["t"], d["potential"], colour, lw=0.9, label=label)
        if failed and len(d["t"]):
            top.plot(d["t"][-1], d["potential"][-1], "x", color=colour, ms=8)
        w = d["t"] >= lo
        if w.any():
            bottom.plot(d["t"][w], d["potential"][w], colour, lw=0.9)
        swing = float(np.ptp(d["potential"][w])) if w.any() else float("nan")
        rows.append({
            "run": name, "status": d["status"], "frames": len(d["t"]),
            "end_s": f"{d['t'][-1]:.4g}" if len(d["t"]) else "",
            "final_potential_J": f"{d['potential'][-1]:.6e}" if len(d["t"]) else "",
            "min_potential_J": f"{d['potential'].min():.6e}" if len(d["t"]) else "",
            "max_potential_J": f"{d['potential'].max():.6e}" if len(d["t"]) else "",
            "swing_in_window_J": f"{swing:.3e}",
            "worst_volume_error": f"{d['volume_error'].max():.3e}" if len(d["t"]) else "",
            "most_inverted_tets": int(np.max(d["inverted"])) if len(d["inverted"]) else 0,
            "wall_s": f"{d['wall']:.1f}",
            "reason": str(d["reason"]),
        })
    top.set_title(a.title)
    top.set_xlabel("time (s)")
    top.set_ylabel("elastic + gravity (J)")
    top.axvspan(lo, end, color="0.9", zorder=0)
    top.legend(fontsize=7)
    top.grid(alpha=0.3)
    bottom.set_title(f"magnified: the last {a.zoom_last:g} s", fontsize=9)
    bottom.set_xlabel("time (s)")
    bottom.set_ylabel("elastic + gravity (J)")
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
