"""`python3 -m isochor ARGS` (and the `isochor` command of an installed package): the command line,
the same program as build/apps/isochor, with ARGS as they are."""
import os
import sys


def _command() -> str:
    """The isochor program: bin/isochor beside this package (pip install), else the one the
    compiled part was built with (a build tree)."""
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bin", "isochor")
    if os.access(here, os.X_OK):
        return here
    from . import _api  # the build tree's module knows its program
    return _api._core().executable


def main() -> None:
    """Replaces this process with the isochor program (its exit status is the command's)."""
    try:
        exe = _command()
    except Exception as e:  # isochor.Error: the compiled part is not built
        sys.exit(f"isochor: {e}")
    os.execv(exe, ["isochor", *sys.argv[1:]])


if __name__ == "__main__":
    main()
