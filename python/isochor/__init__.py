"""isochor from Python: scenes, runs with a per-frame callback, run files, studies.

    import isochor
    scene = isochor.load("demos/swing.toml", {"material.mu": 3e4})
    result = isochor.run(scene, "out/swing.h5", overwrite=True,
                         on_frame=lambda f: print(f.time, f.volumes[0]))
    run = isochor.open(result.output)
    run.positions.shape          # (frames, nodes, 3)

Every error of isochor's (a bad key, a mesh it refuses, a solver failure) is raised as
isochor.Error with the one-line message the command line prints. docs/python.md has the whole
interface and an example study; `python3 -m isochor` (or the `isochor` command that `pip install`
puts in an environment) is the command line.
"""
from ._errors import Error, SceneNote
from ._runfile import Bone, Collider, Run, open  # noqa: A001 (isochor.open is the name users expect)
from ._api import Frame, RunResult, load, run, scene, study, study_cases
from . import _api

__all__ = ["Error", "SceneNote", "Scene", "Frame", "RunResult", "Run", "Collider", "Bone", "load", "scene", "run", "open",
           "study", "study_cases", "executable"]
__version__ = "0.1.0"


def __getattr__(name: str):
    """Scene and executable come from the compiled part: without it, an Error saying how to build it."""
    if name in ("Scene", "executable"):
        return getattr(_api, name)
    raise AttributeError(f"module 'isochor' has no attribute {name!r}")


for _public in (Frame, RunResult, Run, Collider, Bone, open):
    _public.__module__ = __name__  # shown as isochor.Run, and so on
del _public

if _api._isochor is not None:
    Scene = _api.Scene
    executable: str = _api.executable
    """The isochor command line this module runs studies with (bin/isochor of an installed package)."""
