"""The run-file reader of the isochor package (python/isochor/runfile.py) for the scripts of
tools/: pure Python (h5py, NumPy), no compiled module needed. No script indexes the file's
layout or parses the scene's text itself."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "python"))
from isochor.errors import Error  # noqa: E402
from isochor.runfile import Collider, Run  # noqa: E402,F401


def write_whole(path, write, mode="w"):
    """Writes `path` through write(file) into PATH.part and renames it into place: a failed
    write (a full disk) leaves neither a partial file nor a traceback, one line and exit 1."""
    part = path + ".part"
    try:
        with open(part, mode) as f:
            write(f)
        os.replace(part, path)
    except OSError as e:
        if os.path.exists(part):
            os.remove(part)
        sys.exit(f"{path}: cannot be written ({e.strerror or e})")


def write_png(path, fig, dpi=110):
    """Saves a matplotlib figure as PNG through write_whole, and says so."""
    write_whole(path, lambda f: fig.savefig(f, dpi=dpi, format="png"), "wb")
    print(f"wrote {path}")


def open_run(path, tool=""):
    """The run at `path`; one line naming the file and exit 1 when it is missing or not a run."""
    if not os.path.exists(path):
        sys.exit(f"{tool + ': ' if tool else ''}{path}: no such file")
    try:
        return Run(path)
    except Error as e:
        sys.exit(f"{tool + ': ' if tool else ''}{e}")


def labelled_runs(args, tool):
    """(label, path) for each LABEL=RUN.h5 argument; one line and exit 1 for one without a label."""
    runs = []
    for r in args:
        label, eq, path = r.rpartition("=")  # a label may hold "=", a path seldom does
        if not eq or not label or not path:
            sys.exit(f"{tool}: {r}: expected LABEL=RUN.h5")
        runs.append((label, path))
    return runs
