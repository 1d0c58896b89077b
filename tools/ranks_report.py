#!/usr/bin/python3
"""The table, cost model and chart of bench/mpi_ranks.sh: for each scene of the CSV files (one or
more; scene,ranks,part,seconds_or_mb,steps,newton,cg) the medians on 1 and 2 ranks, the speedup
of the solver's wall time, and Amdahl's law fitted to it:

    T(P) = T(1) (f + (1 - f) / P),   f = 2 T(2) / T(1) - 1,

where f lumps the work every rank repeats (the replicated state) with what P = 2 spent in MPI
calls. Its prediction at 16, 64 and 256 ranks is an upper bound: the volume each rank receives
per residual and per Jacobian does not shrink with P (docs/scale.md), so f grows with P.

    /usr/bin/python3 tools/ranks_report.py OUT_DIR CSV [CSV ...]   (writes OUT_DIR/distributed.md, .png)

A hand-written section that starts with "## Reading" in an existing OUT_DIR/distributed.md is kept.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PREDICT = (16, 64, 256)


def serial_fraction(t1, t2):
    """Amdahl's serial fraction f from the times on one and two ranks.

    >>> serial_fraction(10.0, 5.0)
    0.0
    >>> serial_fraction(10.0, 10.0)
    1.0
    >>> round(serial_fraction(10.0, 6.0), 12)
    0.2
    """
    return 2.0 * t2 / t1 - 1.0


def efficiency(f, p):
    """Parallel efficiency T(1) / (P T(P)) on P ranks under Amdahl's law with serial fraction f.

    >>> efficiency(0.0, 64)
    1.0
    >>> round(efficiency(0.2, 2), 12)   # T(2) = 0.6 T(1): speedup 1.667 on 2
    0.833333333333
    >>> round(efficiency(1 / 45, 16), 3)
    0.75
    """
    return 1.0 / (p * f + 1.0 - f)


def read(paths):
    """{scene: {ranks: {part: value, "counts": (steps, newton, cg)}}} from the bench's CSV files."""
    table = {}
    for path in paths:
        try:
            rows = list(csv.DictReader(open(path)))
        except OSError as e:
            sys.exit(f"{path}: {e.strerror}")
        for r in rows:
            entry = table.setdefault(r["scene"], {}).setdefault(r["ranks"], {})
            entry[r["part"]] = float(r["seconds_or_mb"])
            entry["counts"] = (int(r["steps"]), int(r["newton"]), int(r["cg"]))
    return table


def rows_of(table):
    lines = ["| scene | ranks | process (s) | solver (s) | assembly (s) | CG solves (s) | in MPI calls, rank 0 (s) | "
             "peak memory, rank 0 (MB) | steps / Newton / CG |", "|---|---|---|---|---|---|---|---|---|"]
    for scene, by_ranks in table.items():
        for ranks, e in by_ranks.items():
            s, n, c = e["counts"]
            lines.append(f"| {scene} | {ranks} | {e['process']:.2f} | {e['solver']:.2f} | {e['assembly']:.2f} | "
                         f"{e['solve']:.2f} | {e['mpi']:.2f} | {e['peak_memory_mb']:.0f} | {s:,} / {n:,} / {c:,} |")
    return lines


def model_of(table):
    lines = ["| scene | speedup on 2 (solver) | speedup on 2 (process) | f | limit 1/f | "
             + " | ".join(f"efficiency at {p} (bound)" for p in PREDICT) + " |", "|---" * (5 + len(PREDICT)) + "|"]
    fits = {}
    for scene, by_ranks in table.items():
        if "1" not in by_ranks or "2" not in by_ranks:
            continue
        one, two = by_ranks["1"], by_ranks["2"]
        f = serial_fraction(one["solver"], two["solver"])
        fits[scene] = (one["solver"], f)
        lines.append(f"| {scene} | {one['solver'] / two['solver']:.2f} | {one['process'] / two['process']:.2f} | "
                     f"{f:.3f} | {1 / f:.1f} | " + " | ".join(f"{100 * efficiency(f, p):.0f}%" for p in PREDICT) + " |")
    return lines, fits


def chart(table, fits, path):
    fig, ax = plt.subplots(figsize=(8.8, 4.4))
    ps = [2 ** k for k in range(9)]
    for scene, (t1, f) in fits.items():
        measured = [(int(r), e["solver"]) for r, e in table[scene].items() if r.isdigit()]
        line = ax.loglog(*zip(*sorted(measured)), "o", label=f"{scene}: measured")[0]
        ax.loglog(ps, [t1 * (f + (1 - f) / p) for p in ps], "-", color=line.get_color(),
                  label=f"{scene}: Amdahl, f = {f:.3f}")
        ax.loglog(ps, [t1 / p for p in ps], ":", color=line.get_color(), alpha=0.5)
    ax.set_xlabel("MPI ranks P")
    ax.set_ylabel("solver wall time (s)")
    ax.set_title("one scene on P ranks (dotted: T(1)/P)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: ranks_report.py OUT_DIR CSV [CSV ...]")
    out, paths = sys.argv[1], sys.argv[2:]
    table = read(paths)
    model, fits = model_of(table)
    md = os.path.join(out, "distributed.md")
    reading = ""
    if os.path.exists(md):
        text = open(md).read()
        if "## Reading" in text:
            reading = text[text.index("## Reading"):]
    lines = ["# One scene on 1 and 2 MPI ranks (`bench/mpi_ranks.sh`)", "",
             "Each scene on one process without `mpirun` and on `mpirun -n 2`, one OpenMP thread per rank, the "
             "settings interleaved in every round, medians over the rounds (" + ", ".join(f"`{p}`" for p in paths)
             + "). \"1 (base build)\" is a build without MPI ranks in the same rounds.", ""]
    lines += rows_of(table)
    lines += ["", "Amdahl's law fitted to the solver's wall time on 1 and 2 ranks (`tools/ranks_report.py`); the "
              "efficiencies are upper bounds (the shared volume per rank does not shrink with P):", ""]
    lines += model
    chart(table, fits, os.path.join(out, "distributed.png"))
    lines += ["", "![solver time against ranks, log-log](distributed.png)", ""]
    with open(md, "w") as f:
        f.write("\n".join(lines) + "\n" + reading)
    print(f"wrote {md} and distributed.png ({len(table)} scenes)")


if __name__ == "__main__":
    main()
