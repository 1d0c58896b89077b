"""The run-file reader of the isochor package (python/isochor/_runfile.py) for the scripts of
tools/: pure Python (h5py, NumPy), no compiled module needed. No script indexes the file's
layout or parses the scene's text itself."""
import os
import stat
import sys


def _package_root():
    """The folder holding the isochor package: a source tree's python/ beside tools/, or the
    site-packages of an installed package whose isochor/tools/ this file is in."""
    here = os.path.dirname(os.path.abspath(__file__))
    for root in (os.path.join(here, os.pardir, "python"), os.path.join(here, os.pardir, os.pardir)):
        if os.path.isfile(os.path.join(root, "isochor", "__init__.py")):
            return os.path.abspath(root)
    sys.exit(f"{here}: no isochor package beside these tools (expected ../python/isochor or ../../isochor)")


sys.path.insert(0, _package_root())
from isochor import Collider, Error, Run  # noqa: E402,F401


_INPUTS = []  # the files this process read (open_run, note_input): no output replaces one


def note_input(path):
    """Records `path` as read: write_whole refuses to write over it."""
    _INPUTS.append(path)


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def check_output(path, what="the output"):
    """One line and exit 1 where `path` holds something other than a regular file (a directory, a
    FIFO, a device: a rename would replace it) or is a file this process read (the words of the
    command line's check_output_file, core/input_file.hpp)."""
    if not os.path.exists(path):
        return
    mode = os.stat(path).st_mode
    for is_kind, kind in _KINDS:
        if is_kind(mode):
            sys.exit(f"{path}: is {kind}, not a regular file (expected a path for {what})")
    for p in _INPUTS:
        if os.path.exists(p) and os.path.samefile(p, path):
            sys.exit(f"{path}: is the input {p} (writing {what} there would destroy it; expected another path)")


def write_whole(path, write, mode="w"):
    """Writes `path` through write(file) into PATH.part and renames it into place: a failed
    write (a full disk) leaves neither a partial file nor a traceback, one line and exit 1.
    Never over a directory, a device or a file this process read (check_output)."""
    check_output(path)
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
    note_input(path)
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
