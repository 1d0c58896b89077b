#!/usr/bin/python3
"""Charts, results.h5 and report.md of a study directory written by `isochor study`.

    /usr/bin/python3 tools/study_report.py out/studies/NAME

Reads results.csv and the cases' HDF5 files (cases/<label>.h5); writes
  results.h5            the table, one dataset per column
  work_precision.png/svg  error against CPU seconds, log-log, one curve per method
  volume_error.png/svg    worst relative zone-volume error against time, every case
  energy.png/svg          total energy against time, every case
  stability.png/svg       for methods swept over one or two keys: each cell stable, failed (and
                          why), or ran with more than 10% of its volume lost or gained
  resolution.png/svg      for methods swept over mesh.target_tets: centre height, height/width
  convergence.png/svg     with an [observable] (observable.toml): its value per case against the
                          mesh size h = (volume / tets)^(1/3), the error against its reference
                          value (or the next finer case's) log-log, and the observed orders
                          (also convergence.csv, the fitted order per method in
                          convergence_fit.csv; printed)
  report.md             the charts and the table
"""
import csv
import math
import os
import sys
import tomllib

import h5py
import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from run_file import Error, Run  # noqa: E402


def number(s):
    try:
        return float(s)
    except ValueError:
        return math.nan


def load(d):
    with open(os.path.join(d, "results.csv")) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in ("frames", "frames_expected", "cpu_seconds", "wall_seconds", "steps", "error_l2", "volume_error",
                  "error_centroid", "shape_error", "inverted_tets"):
            r[k] = number(r.get(k) or "nan")
        r["sweep_pairs"] = [p.split("=", 1) for p in r["sweep"].split(";") if p]
    return rows


def save(fig, d, name):
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(d, f"{name}.{ext}"), dpi=120, bbox_inches="tight")
    plt.close(fig)
    return f"{name}.png"


def cost(r):
    """The integrator's own time (one thread), else the whole process's CPU time."""
    return r["wall_seconds"] if r["wall_seconds"] > 0 else r["cpu_seconds"]


def method_colours(rows):
    """One colour per method (table order), the same in every chart."""
    methods = [m for m in dict.fromkeys(r["method"] for r in rows) if m != "reference"]
    return {m: plt.cm.tab10(i % 10) for i, m in enumerate(methods)}


def work_precision(rows, d):
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    methods = sorted({r["method"] for r in rows if r["method"] != "reference"})
    colour = method_colours(rows)
    for ax, key, what in ((axes[0], "error_l2", "relative L2 error of all positions, all frames"),
                          (axes[1], "error_centroid", "relative L2 error of the centroid's path")):
        for m in methods:
            # In sweep order (the table's), each point labelled with its swept value(s).
            ok = [r for r in rows if r["method"] == m and r["status"] == "ok" and r[key] > 0]
            if ok:
                ax.loglog([cost(r) for r in ok], [r[key] for r in ok], "o-", color=colour[m], label=m)
                for r in ok:
                    text = ",".join(f"{number(v):g}" if not math.isnan(number(v)) else v for _, v in r["sweep_pairs"])
                    ax.annotate(text, (cost(r), r[key]), textcoords="offset points", xytext=(4, 3), fontsize=6,
                                color=colour[m])
            bad = [r for r in rows if r["method"] == m and r["status"] != "ok"]
            if bad:
                ax.plot([], [], "x", color="gray", label=f"{m}: {len(bad)} failed")
        ax.set_xlabel("integration seconds (one thread; meshing and start-up excluded)")
        ax.set_ylabel(what)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("work-precision (lower left is better)")
    return save(fig, d, "work_precision")


def cost_at_error(points, target):
    """The cost at which a method reaches an error: points are (cost, error) of its finished cases.

    On the method's Pareto front (no case both cheaper and more accurate), the cheapest case at or
    below the target, interpolated log-log from the next cheaper case when that one is above it;
    None when no case reaches the target.
    >>> cost_at_error([(1, 1e-2), (10, 1e-4)], 1e-3)  # halfway in log-log: 10^(1/2)
    3.162...
    >>> cost_at_error([(1, 1e-2), (10, 1e-4), (5, 1e-5)], 1e-3)  # (10, 1e-4) is dominated: 5^(1/3)
    1.709...
    >>> cost_at_error([(1, 1e-4)], 1e-3), cost_at_error([(1, 1e-2)], 1e-3)
    (1, None)
    """
    front = []
    for c, e in sorted(points):
        if e > 0 and (not front or e < front[-1][1]):
            front.append((c, e))
    for i, (c, e) in enumerate(front):
        if e <= target:
            if i == 0:
                return c
            c0, e0 = front[i - 1]
            w = math.log(e0 / target) / math.log(e0 / e)
            return math.exp(math.log(c0) + w * math.log(c / c0))
    return None


def equal_error_table(rows, targets=(1e-2, 1e-3, 1e-4, 1e-5)):
    """Markdown: each method's cost (integration seconds) at equal error, both error measures."""
    methods = sorted({r["method"] for r in rows if r["method"] != "reference"})
    lines = []
    for key, what in (("error_l2", "error of all positions"), ("error_centroid", "error of the centroid's path")):
        lines += [f"Integration seconds to reach a given {what} (log-log interpolation on each method's "
                  "Pareto front; — where no case gets there):", "",
                  "| method | " + " | ".join(f"{t:g}" for t in targets) + " |",
                  "|---|" + "---|" * len(targets)]
        for m in methods:
            pts = [(cost(r), r[key]) for r in rows if r["method"] == m and r["status"] == "ok" and cost(r) > 0]
            cells = [cost_at_error(pts, t) for t in targets]
            lines.append(f"| {m} | " + " | ".join("—" if c is None else f"{c:.3g}" for c in cells) + " |")
        lines.append("")
    return lines


def series(d, rows):
    for r in rows:
        p = os.path.join(d, "cases", r["label"] + ".h5")
        if not os.path.exists(p):
            continue
        try:
            with Run(p) as run:
                t, V, E = run.times, run.volumes, run.energy
        except (Error, OSError, KeyError):
            continue
        if len(t) == 0:  # failed before its first frame
            continue
        yield r, t, np.max(np.abs(V / V[0] - 1), axis=1), E.sum(axis=1)


def over_time(rows, d):
    """Volume error and energy against time: one colour per method, its cases from light (first in
    the sweep) to dark (last), the reference in black."""
    figv, axv = plt.subplots(figsize=(8.5, 4.5))
    fige, axe = plt.subplots(figsize=(8.5, 4.5))
    colour = method_colours(rows)
    count = {m: sum(1 for r in rows if r["method"] == m) for m in colour}
    seen = {}  # method -> index of its last case drawn
    for r, t, dv, e in series(d, rows):
        m = r["method"]
        if m == "reference":
            kw = dict(color="k", lw=1.2, label="reference")
        else:
            k = seen[m] = seen.get(m, -1) + 1
            kw = dict(color=colour[m], lw=0.8, alpha=0.35 + 0.65 * (k + 1) / count[m],
                      label=f"{m} ({count[m]} cases, light to dark in sweep order)" if k == 0 else None)
        axv.semilogy(t, np.maximum(dv, 1e-16), **kw)
        axe.plot(t, e, **kw)
    axv.set_xlabel("time (s)")
    axv.set_ylabel("worst |V - V0| / V0 over zones")
    axv.set_title("volume error")
    axe.set_xlabel("time (s)")
    axe.set_ylabel("kinetic + elastic + external energy (J)")
    axe.set_title("energy")
    for ax in (axv, axe):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    return save(figv, d, "volume_error"), save(fige, d, "energy")


def short_reason(reason):
    """A failure reason in a few words for a map cell, with the time it happened."""
    import re
    tm = re.search(r"failed at t = ([0-9.eE+-]+) s", reason)
    at = f"\nat {float(tm.group(1)):.3g} s" if tm else ""
    for key, tag in (("no progress", "no progress\n(steps stalled)"), ("does not descend", "no descent\n(inertia x1e6)"),
                     ("not finite", "inverted /\nexploded"), ("singular", "singular\nmatrix"), ("Newton", "Newton\ndiverged"),
                     ("IDA_CONV_FAIL", "IDA corrector\nfailed"), ("IDA_ERR_FAIL", "IDA error\ntest failed"),
                     ("steps", "too many\nsteps"), ("PCG", "linear solve\nfailed"),
                     ("line search", "no descent\n(line search)")):
        if key in reason:
            return tag + at
    return (reason.split(": ")[-1][:20] or "failed") + at


def stability(rows, d):
    methods = [m for m in sorted({r["method"] for r in rows}) if m != "reference"
               and all(len(r["sweep_pairs"]) in (1, 2) for r in rows if r["method"] == m)]
    if not methods:
        return None
    cols = min(3, len(methods))
    nrows = (len(methods) + cols - 1) // cols
    shape_study = any(r["method"].startswith(("scramble", "unfold")) for r in rows)  # scrambled starts
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 3.6 * nrows), squeeze=False)
    for ax in axes.flat[len(methods):]:
        ax.set_axis_off()
    for ax, m in zip(axes.flat, methods):
        mine = [r for r in rows if r["method"] == m]
        two = len(mine[0]["sweep_pairs"]) == 2  # one key: a single row
        kx, ky = mine[0]["sweep_pairs"][0][0], (mine[0]["sweep_pairs"][1][0] if two else "")
        xs = sorted({number(r["sweep_pairs"][0][1]) for r in mine})
        ys = sorted({number(r["sweep_pairs"][1][1]) for r in mine}) if two else [0.0]
        for r in mine:
            i, j = xs.index(number(r["sweep_pairs"][0][1])), (ys.index(number(r["sweep_pairs"][1][1])) if two else 0)
            ok = r["status"] == "ok"
            vol = number(r["volume_error"])
            # A run that ends but has lost or gained a tenth of its volume did not stand either.
            lost = ok and np.isfinite(vol) and vol > 0.1
            colour = "#fdc086" if lost else ("#7fc97f" if ok else "#f0027f")
            ax.add_patch(plt.Rectangle((i - 0.5, j - 0.5), 1, 1, color=colour, alpha=0.8))
            if ok:
                text = f"{'ran, volume off' if lost else 'ok'}\nvolume error\n{vol:.1e}" if np.isfinite(vol) else "ok"
            else:
                text = short_reason(r["reason"])
            if shape_study:  # how far from the rest shape and how tangled the last frame is
                text += f"\nshape {r['shape_error']:.2g}, inv {r['inverted_tets']:.0f}" if r["frames"] > 0 else ""
            ax.text(i, j, text, ha="center", va="center", fontsize=7)
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs])
        ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys] if two else [""])
        ax.set_xlim(-0.5, len(xs) - 0.5)
        ax.set_ylim(-0.5, len(ys) - 0.5)
        ax.set_xlabel(kx)
        ax.set_ylabel(ky)
        ax.set_title(m)
    fig.tight_layout()
    return save(fig, d, "stability")


def resolution(rows, d):
    """For methods swept over mesh.target_tets: the ball's centre height and height/width ratio."""
    cases = [r for r in rows if any(k == "mesh.target_tets" for k, _ in r["sweep_pairs"])]
    if not cases:
        return None
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    for r in cases:
        p = os.path.join(d, "cases", r["label"] + ".h5")
        if not os.path.exists(p):
            continue
        with Run(p) as run:
            t = run.times
            x = [run.frame_positions(k) for k in range(len(t))]
            c = np.array([xk[:, 2].mean() for xk in x])
            hw = np.array([np.ptp(xk[:, 2]) / np.ptp(xk[:, 0]) for xk in x])
        tets = dict(r["sweep_pairs"])["mesh.target_tets"]
        a1.plot(t, c, label=f"{r['method']} {float(tets):.0f} tets")
        a2.plot(t, hw, label=f"{r['method']} {float(tets):.0f} tets")
    a1.set_ylabel("centre height (m)")
    a2.set_ylabel("height / width")
    for a in (a1, a2):
        a.set_xlabel("time (s)")
        a.grid(True, alpha=0.3)
        a.legend(fontsize=7)
    return save(fig, d, "resolution")


def observable_value(run, spec):
    """The study's [observable] on one run: a node's (nearest the point at rest) or a node set's
    mean displacement at the frame, one component or its norm."""
    X = run.rest_positions
    if spec["kind"] == "point":
        nodes = [int(np.argmin(((X - np.array(spec["point"])) ** 2).sum(axis=1)))]
    else:
        if spec["set"] not in run.node_sets:
            raise Error(f"{run.path}: has no node set {spec['set']!r} (observable.set)")
        nodes = run.node_sets[spec["set"]]
    u = (run.frame_positions(spec.get("frame", -1)) - X)[nodes].mean(axis=0)
    c = spec.get("component", "norm")
    return float(np.linalg.norm(u)) if c == "norm" else float(u["xyz".index(c)])


def observed_orders(h, q, reference):
    """Per consecutive pair of meshes (coarse to fine): the error against the reference value and
    the observed order log(e_k / e_k+1) / log(h_k / h_k+1); without a reference, Richardson's
    from three meshes: log(|q_k - q_k+1| / |q_k+1 - q_k+2|) / log(h_k / h_k+1)."""
    out = []
    for k in range(len(h)):
        e = abs(q[k] - reference) if reference is not None else (abs(q[k] - q[k + 1]) if k + 1 < len(h) else math.nan)
        p = math.nan
        if reference is not None and k + 1 < len(h):
            e1 = abs(q[k + 1] - reference)
            if e > 0 and e1 > 0:
                p = math.log(e / e1) / math.log(h[k] / h[k + 1])
        elif reference is None and k + 2 < len(h):
            d0, d1 = abs(q[k] - q[k + 1]), abs(q[k + 1] - q[k + 2])
            if d0 > 0 and d1 > 0:
                p = math.log(d0 / d1) / math.log(h[k] / h[k + 1])
        out.append((e, p))
    return out


def convergence(rows, d):
    """With observable.toml: the observable per case against its mesh size, and observed orders."""
    path = os.path.join(d, "observable.toml")
    if not os.path.exists(path):
        return None, []
    with open(path, "rb") as f:
        spec = tomllib.load(f)
    reference = spec.get("reference")
    colours = method_colours(rows)
    table = []
    for method in colours:
        pts = []
        for r in rows:
            p = os.path.join(d, "cases", r["label"] + ".h5")
            if r["method"] != method or r["status"] != "ok" or not os.path.exists(p):
                continue
            with Run(p) as run:
                h = (float(run.rest_volumes.sum()) / len(run.tets)) ** (1.0 / 3.0)
                pts.append((h, len(run.tets), observable_value(run, spec), r["label"]))
        pts.sort(key=lambda t: -t[0])
        orders = observed_orders([t[0] for t in pts], [t[2] for t in pts], reference)
        table += [(method, h, tets, q, label, e, p) for (h, tets, q, label), (e, p) in zip(pts, orders)]
    if not table:
        return None, []
    with open(os.path.join(d, "convergence.csv"), "w") as f:
        f.write("method,label,h,tets,value,error,order\n")
        for m, h, tets, q, label, e, p in table:
            f.write(f"{m},{label},{h:.6g},{tets},{q:.10g},{e:.6g},{p:.4g}\n")
    name = spec.get("name", "observable")
    against = f"the reference {reference:g}" if reference is not None else "the next finer mesh"
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    for method, c in colours.items():
        t = [r for r in table if r[0] == method]
        if not t:
            continue
        a1.plot([r[1] for r in t], [r[3] for r in t], "o-", color=c, label=method)
        good = [r for r in t if r[5] > 0]
        a2.loglog([r[1] for r in good], [r[5] for r in good], "o-", color=c, label=method)
        for r in good:
            if not math.isnan(r[6]):
                a2.annotate(f"{r[6]:.2f}", (r[1], r[5]), textcoords="offset points", xytext=(4, 4), fontsize=7)
    if reference is not None:
        a1.axhline(reference, color="k", lw=0.8, ls="--", label=f"reference {reference:g}")
    a1.set_ylabel(name)
    a2.set_ylabel(f"|error| against {against}")
    sizes = sorted({r[1] for r in table})
    for a in (a1, a2):
        a.set_xscale("log")
        a.set_xticks(sizes, [f"{h:.3g}" for h in sizes])
        a.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        a.set_xlabel("mesh size h = (volume / tets)^(1/3)")
        a.invert_xaxis()
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
    a2.set_title("observed orders beside the points", fontsize=8)
    lines = [f"## Convergence of {name}", "",
             f"Errors against {against}; the order between a mesh and the next finer one "
             f"{'from the two errors' if reference is not None else 'by Richardson, from three meshes'}.", "",
             "| method | case | h | tets | value | error | observed order |", "|---|---|---|---|---|---|---|"]
    for m, h, tets, q, label, e, p in table:
        lines.append(f"| {m} | {label} | {h:.4g} | {tets} | {q:.6g} | {e:.3g} | {p:.2f} |")
    lines += ["", "Fitted order (least squares of log error against log h over the meshes; unstructured meshes "
              "are not nested, so single pairs scatter):", ""]
    fitted = {}
    for method in colours:
        t = [r for r in table if r[0] == method and r[5] > 0]
        if len(t) >= 2:
            fitted[method] = float(np.polyfit(np.log([r[1] for r in t]), np.log([r[5] for r in t]), 1)[0])
            lines.append(f"- {method}: {fitted[method]:.2f}")
    with open(os.path.join(d, "convergence_fit.csv"), "w") as f:
        f.write("method,fitted_order\n" + "".join(f"{m},{p:.4g}\n" for m, p in fitted.items()))
    print("\n".join(lines[4:]))
    return save(fig, d, "convergence"), lines + [""]


def write_h5(rows, d):
    """results.h5: the study's table as columns (its own file, not a run's)."""
    with h5py.File(os.path.join(d, "results.h5"), "w") as f:
        for k in ("method", "label", "sweep", "status", "reason"):
            f[k] = np.array([r[k] for r in rows], dtype=h5py.string_dtype())
        for k in ("frames", "frames_expected", "cpu_seconds", "wall_seconds", "steps", "error_l2", "volume_error",
                  "error_centroid", "shape_error", "inverted_tets"):
            f[k] = np.array([r[k] for r in rows], dtype=float)


def report(rows, d, images, extra=()):
    lines = [f"# Study `{os.path.basename(os.path.normpath(d))}`", "",
             "Every case ran in its own process on one thread; errors are measured against the reference "
             "case (relative L2 of all node positions over all frames; worst relative volume error over "
             "frames and zones).", ""]
    for img in images:
        if img:
            lines += [f"![{img[:-4]}]({img})", ""]
    lines += list(extra)
    lines += equal_error_table(rows)
    lines += ["| method | case | status | frames | CPU s | error (L2) | centroid error | volume error | shape error | "
              "inverted | reason |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['method']} | {r['label']} | {r['status']} | {r['frames']:.0f}/{r['frames_expected']:.0f} | "
                     f"{r['cpu_seconds']:.3g} | {r['error_l2']:.3g} | {r['error_centroid']:.3g} | {r['volume_error']:.3g} | "
                     f"{r['shape_error']:.3g} | {r['inverted_tets']:.0f} | {r['reason'].replace('|', '/')} |")
    with open(os.path.join(d, "report.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    d = sys.argv[1]
    rows = load(d)
    write_h5(rows, d)
    conv_image, conv_lines = convergence(rows, d)
    if conv_image:  # meshes compared with each other: no run-to-run errors, energies or maps
        images = [conv_image]
    else:
        images = [work_precision(rows, d), *over_time(rows, d), stability(rows, d), resolution(rows, d)]
    report(rows, d, images, conv_lines)
    print(f"wrote {d}/results.h5, charts and report.md")


if __name__ == "__main__":
    main()
