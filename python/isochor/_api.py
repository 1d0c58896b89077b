"""The functions of the isochor package over its compiled part (_isochor); `import isochor` gives
them, and only the names of isochor.__all__."""
from __future__ import annotations

import builtins
import csv
import dataclasses
import os
import subprocess
import warnings
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np

from ._errors import Error, SceneNote

try:
    from . import _isochor
except ImportError as _why:  # run files are read without the compiled part (tools/ do so)
    _isochor = None
    _built = any(n.startswith("_isochor") for n in os.listdir(os.path.dirname(os.path.abspath(__file__))))
    _missing = f"it does not load: {_why}" if _built else "it is not built there"

def _core():
    """The compiled part, or an Error saying that it is not importable here."""
    if _isochor is None:
        raise Error(f"isochor's compiled part (_isochor) is not importable from {os.path.dirname(__file__)} "
                    f"({_missing}): build it (make build) and put build/python on PYTHONPATH; "
                    "isochor.open reads run files without it")
    return _isochor


if _isochor is not None:
    Scene = _isochor.Scene
    Scene.__module__ = "isochor"
    executable: str = _isochor.executable
    """The isochor command line this module was built with (studies run their cases with it)."""


def __getattr__(name: str) -> Any:  # Scene and executable without the compiled part
    if name in ("Scene", "executable"):
        return getattr(_core(), name)
    raise AttributeError(f"module 'isochor' has no attribute {name!r}")

Overrides = Union[None, str, Sequence[str], Mapping[str, Any]]


def load(path: Union[str, os.PathLike], overrides: Overrides = None) -> Scene:
    """A scene file with overrides: a dict of dotted keys to values ({"material.mu": 3e4};
    a nested dict stands for its keys) or `--set` strings ("material.mu=3e4")."""
    return _core().load_scene(os.fspath(path), overrides)


def scene(table: Mapping[str, Any], overrides: Overrides = None, *, name: str = "<dict>",
          directory: Union[str, os.PathLike] = ".") -> Scene:
    """A scene from a dict shaped like the TOML file (what tomllib.load returns); relative file
    names in it are resolved against `directory`."""
    if not isinstance(table, Mapping):
        raise TypeError(f"scene(): expected a dict of the scene's tables (as tomllib.load returns), "
                        f"got a {type(table).__name__}")
    return _core().scene_from_dict(dict(table), overrides, name, os.fspath(directory))


@dataclasses.dataclass
class Frame:
    """One frame as the run writes it, handed to the on_frame callback (copies: keep them)."""
    index: int            # frame index in the file
    time: float           # s
    positions: np.ndarray   # (N,3) every node, m
    velocities: np.ndarray  # (N,3) m/s
    volumes: np.ndarray     # total volume, then each zone (zone_names), m^3
    zone_names: list
    energy: np.ndarray      # kinetic, elastic, external potential (J)
    pressure: Optional[np.ndarray]  # (T,) per-tet pressure, Pa (None without tets)
    multipliers: np.ndarray  # the constraints' multipliers
    loads: Optional[np.ndarray]  # (N,3) applied loads (N), when the scene has [[load]]
    activation: Optional[np.ndarray]  # each muscle's activation (Scene.muscles' order), with [[muscle]]s
    stats: dict              # the per-frame series (steps, newton_iterations, step_size, ...)

    def zone_volume(self, name: str) -> float:
        """The volume (m^3) of the zone `name` at this frame."""
        return float(self.volumes[1 + self.zone_names.index(name)])


@dataclasses.dataclass
class RunResult:
    """What run() did: the file, the frames in it, and the cost (a stopped run: until the stop)."""
    output: str
    frames: int
    stopped: bool             # the callback returned False (the file says "interrupted")
    stop_reason: str
    resumed_from: int
    already_finished: bool
    steps: int
    newton_iterations: int
    jacobian_evaluations: int
    rejected_steps_newton: int
    rejected_steps_error_test: int
    wall_seconds: float
    assembly_seconds: float
    factorisation_seconds: float
    solve_seconds: float
    simbody_seconds: float


def _as_scene(s: Union[Scene, str, os.PathLike, Mapping[str, Any]], overrides: Overrides) -> Scene:
    if isinstance(s, _core().Scene):
        if overrides:
            raise TypeError("run(): overrides go with a scene file or dict, not a loaded Scene "
                            "(isochor.load(path, overrides) applies them)")
        return s
    if isinstance(s, Mapping):
        return scene(s, overrides)
    return load(s, overrides)


def run(s: Union[Scene, str, os.PathLike, Mapping[str, Any]], output: Union[str, os.PathLike, None] = None, *,
        overrides: Overrides = None, overwrite: bool = False, resume: bool = False, progress: bool = False,
        on_frame: Optional[Callable[[Frame], Optional[bool]]] = None,
        activation: Optional[Callable[[float], Any]] = None) -> RunResult:
    """Runs a scene (a Scene, a scene file or a dict) into `output` (default: the scene's
    output.path), as `isochor run` does. An existing output is an error unless `overwrite`
    (replace it) or `resume` (continue it from its last complete frame).

    on_frame(frame) is called after each frame is written; returning False stops the run there
    (the file keeps the frames, status "interrupted"; the result says stopped). An exception in
    the callback, or Ctrl-C, stops the run the same way and is raised again.

    activation(t) replaces the scene's muscle activations: it returns a mapping from muscle names
    to activations in [0, 1] (muscles it leaves out keep the scene's curve) or a sequence with one
    per muscle (Scene.muscles' order). It is called at every new time the solver evaluates, so a
    value that on_frame sets between frames (kept where activation reads it) acts from that frame
    on. An exception it raises stops the run there and is raised again.
    """
    if overwrite and resume:
        raise ValueError("run(): overwrite excludes resume")
    # Checked before the scene is built or a file is made (an int as on_frame had failed at the
    # first frame, after the output was created).
    for what, f in (("on_frame", on_frame), ("activation", activation)):
        if f is not None and not callable(f):
            raise TypeError(f"run(): {what} must be a function or None, got a {type(f).__name__}")
    sc = _as_scene(s, overrides)
    for note in sc.notes:  # as `isochor run` prints them
        warnings.warn(f"{sc.name}: {note}", SceneNote, stacklevel=2)
    zone_names = list(sc.zones.keys())
    callback = None
    if on_frame is not None:
        def callback(d):
            return on_frame(Frame(zone_names=zone_names, **d))
    mode = "resume" if resume else "overwrite" if overwrite else "create"
    out = "" if output is None else os.fspath(output)
    return RunResult(**_core().run(sc, out, mode, progress, callback, _activation_list(sc, activation)))


def _activation_list(sc, activation):
    """activation(t) as the core takes it: a list with one value per muscle."""
    if activation is None:
        return None
    names = list(sc.muscles)
    if not names:
        raise Error(f"{sc.name}: an activation function, but the scene has no [[muscle]]")

    def listed(t):
        a = activation(t)
        if isinstance(a, Mapping):
            unknown = [k for k in a if k not in names]
            if unknown:
                raise KeyError(f"activation: no muscle {unknown[0]!r} (muscles: {', '.join(names)})")
            scene_values = sc.activations(t)
            return [float(a.get(n, scene_values[i])) for i, n in enumerate(names)]
        return [float(v) for v in a]
    return listed


def study_cases(path: Union[str, os.PathLike], overrides: Overrides = None) -> list:
    """The cases of a study file (the reference first): method, label, overrides, sweep."""
    return _core().study_cases(os.fspath(path), overrides)[1]


def study(path: Union[str, os.PathLike], overrides: Overrides = None, *, resume: bool = False,
          progress: bool = False, report: bool = False) -> list:
    """Runs a study as `isochor study` does (each case in its own process, `study.jobs` at once)
    and returns its results.csv as a list of dicts (numbers as floats, failed cases with their
    reason). `report` also writes the charts and report.md (tools/study_report.py)."""
    out, _failed = _core().run_study(os.fspath(path), overrides, resume, progress)
    if report:
        subprocess.run(["/usr/bin/python3", os.path.join(_core().tools_dir, "study_report.py"), out], check=True)
    rows = []
    with builtins.open(os.path.join(out, "results.csv"), newline="") as f:
        for row in csv.DictReader(f):
            for k, v in row.items():
                if k not in ("method", "label", "sweep", "status", "reason"):
                    try:
                        row[k] = float(v)
                    except ValueError:
                        pass
            rows.append(row)
    return rows

