"""isochor.Error: every error of isochor's, from the compiled part (a bad key, a mesh it refuses,
a solver failure) or from reading a run file, with the one-line message the command line prints.
Pure Python, so that reading run files needs no compiled module."""


class Error(RuntimeError):
    """An error of isochor's: its message names the file, key or element and what was expected."""


Error.__module__ = "isochor"  # shown as isochor.Error


class SceneNote(UserWarning):
    """What to know about a scene as written (patches too coarse for the body, a locking lambda):
    isochor.run warns with it, as `isochor run` prints it."""


SceneNote.__module__ = "isochor"
