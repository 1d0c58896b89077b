"""Reading a run's HDF5 file (docs/output.md) as NumPy arrays: isochor.open(PATH).

Pure Python (h5py and NumPy): the scripts of tools/ read run files through it without the
compiled module, and none of them indexes the file's layout or parses the scene's text itself.
"""
from __future__ import annotations

import dataclasses
import functools
import os
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

from ._errors import Error


def _text(v: object) -> object:
    return v.decode() if isinstance(v, bytes) else v


@dataclasses.dataclass
class Bone:
    """A bone of the scene's skeleton as the run recorded it (/bones): its name, its parent's index
    (-1: none) and its capsule in the rest pose (from, to, radius; m, world coordinates). Where it
    is at frame k: Run.bone_pose(k, index)."""
    index: int             # its row in /frames/bone_pose (the skeleton's order)
    name: str
    parent: int
    start: np.ndarray      # the capsule's axis from (3,), rest pose
    end: np.ndarray        # and to (3,)
    radius: float


@dataclasses.dataclass
class Collider:
    """A collider as the run recorded it (/colliders): its shape and dimensions (m) in its own
    frame (axis z; a mesh: its file's, scaled), its rest pose, and a mesh collider's surface.
    Where it is at frame k: Run.collider_pose(k, index)."""
    index: int                    # its column in /frames/collider_pose (the scene's order)
    name: str                     # "contact.ground", "contact.plane[0]", "collider[2]"
    shape: str                    # plane, sphere, capsule, box, cylinder, mesh
    dimensions: Dict[str, float]  # radius, length, size_x/y/z, wall, rounding: what the shape has
    rest_pose: np.ndarray         # (12,) local -> world x = A l + b: A row-major, then b
    vertices: Optional[np.ndarray] = None   # (V,3) a mesh's surface in its frame
    triangles: Optional[np.ndarray] = None  # (T,3)

    @property
    def is_ground(self) -> bool:
        """Whether it is the scene's [contact] ground plane."""
        return self.name == "contact.ground"


class Run:
    """A run file: its mesh, zones, frames and statistics as NumPy arrays.

    Small things (mesh, zones, times, volumes, energies, statistics) are read at open; the
    per-frame node arrays (positions, velocities, pressure, loads) when first asked for, whole
    (`run.positions`, (F,N,3)) or one frame at a time (`run.frame_positions(k)`).
    """

    def __init__(self, path: Union[str, os.PathLike]):
        try:
            import h5py  # Debian's python3-h5py
        except ImportError as e:
            raise Error(f"reading run files needs h5py ({e}; Debian: apt-get install python3-h5py, and a "
                        "virtual environment made with --system-site-packages)") from None

        self.path = os.fspath(path)
        if not os.path.exists(self.path):
            raise Error(f"{self.path}: no such file (expected a run's .h5 file)")
        if not os.path.isfile(self.path):  # a directory, FIFO or device is not read (docs/reliability.md)
            raise Error(f"{self.path}: is not a regular file (expected a run's .h5 file)")
        try:
            # HDF5's default locking, as h5py and meshio open files (one process cannot open a
            # file with two settings); the writer takes no HDF5 lock, so a run still being
            # written is read as far as it is.
            self._h5 = h5py.File(self.path, "r")
        except OSError as e:
            raise Error(f"{self.path}: cannot be read as HDF5 ({e}; expected a run's .h5 file)") from None
        h = self._h5
        if "mesh" not in h or "frames" not in h:
            h.close()
            raise Error(f"{self.path}: has no /mesh and /frames (expected a file written by isochor run)")
        try:
            self._read(h)
        except (KeyError, ValueError, TypeError) as e:
            h.close()
            reason = e.args[0] if e.args else type(e).__name__
            raise Error(f"{self.path}: is not a whole run ({reason}; expected a file written by isochor run)") from None

    def _read(self, h) -> None:
        attr = {k: _text(v) for k, v in h.attrs.items()}
        self.attributes: Dict[str, object] = attr
        self.status: str = str(attr.get("status", ""))
        self.scene: str = str(attr.get("scene", ""))
        m = h["mesh"]
        self.rest_positions: np.ndarray = m["rest_positions"][()]
        self.tets: np.ndarray = m["tets"][()]
        self.surface: np.ndarray = m["surface"][()]
        self.rest_volumes: np.ndarray = m["rest_volumes"][()]
        self.node_sets: Dict[str, np.ndarray] = {k: v[()] for k, v in m.get("node_sets", {}).items()}
        self.zones: Dict[str, np.ndarray] = {k: v[()] for k, v in h.get("zones", {}).items()}
        # Each tet's smallest zone, as an index into volume_columns[1:] (-1: in none), for viewers.
        self.tet_zone: np.ndarray = m["zone"][()] if "zone" in m else np.full(len(self.tets), -1)
        self._check_mesh()
        f = h["frames"]
        # A run killed while writing a frame may hold one series a frame longer: the shortest
        # series is what is complete (as `isochor run --resume` cuts it).
        self.num_frames: int = min(f[name].shape[0] for name in ("time", "positions", "volume", "energy")
                                   if name in f)
        n = self.num_frames
        self.times: np.ndarray = f["time"][:n]
        vol = f["volume"]
        cols = vol.attrs.get("columns")
        if isinstance(cols, bytes):
            cols = cols.decode()
        # The columns' names, "total,zone,...": zone names hold no comma.
        self.volume_columns: List[str] = (cols.split(",") if isinstance(cols, str)
                                          else ["total", *self.zones.keys()])
        self.volumes: np.ndarray = vol[:n]
        self.energy: np.ndarray = f["energy"][:n]
        st = h.get("stats")
        self.totals: Dict[str, object] = {k: _text(v) for k, v in st.attrs.items()} if st is not None else {}
        self.stats: Dict[str, np.ndarray] = ({k: v[:n] for k, v in st.items() if hasattr(v, "shape")}
                                             if st is not None else {})
        self._read_scene_record(h, attr)

    def _check_mesh(self) -> None:
        """Shapes and node indices as isochor writes them: a file edited by hand or written by
        another program is refused here rather than indexed out of range by a tool."""
        nodes = len(self.rest_positions)
        if self.rest_positions.ndim != 2 or self.rest_positions.shape[1] != 3:
            raise ValueError(f"/mesh/rest_positions has shape {self.rest_positions.shape}, not (nodes, 3)")
        for name, cells, width in (("/mesh/tets", self.tets, 4), ("/mesh/surface", self.surface, 3)):
            if cells.ndim != 2 or cells.shape[1] != width:
                raise ValueError(f"{name} has shape {cells.shape}, not (rows, {width})")
            if cells.size and (cells.min() < 0 or cells.max() >= nodes):
                raise ValueError(f"{name} refers to node {cells.max() if cells.max() >= nodes else cells.min()} "
                                 f"of {nodes}")

    def _read_scene_record(self, h, attr: Dict[str, object]) -> None:
        """The up direction and the colliders that the run recorded (absent in a file written
        before they were: up z, no colliders)."""
        up = np.asarray(attr.get("up", (0.0, 0.0, 1.0)), float)
        self.up: np.ndarray = up / np.linalg.norm(up) if up.shape == (3,) and np.linalg.norm(up) > 0 else np.array([0.0, 0.0, 1.0])
        self.up_source: str = str(attr.get("up_source", "z (the file records no up direction)"))
        self.scene_directory: str = str(attr.get("scene_directory", "") or os.path.dirname(str(attr.get("scene_file", ""))))
        self.colliders: List[Collider] = []
        g = h.get("colliders")
        for key in sorted(g.keys() if g is not None else [], key=int):
            c = g[key]
            a = {k: _text(v) for k, v in c.attrs.items()}
            dims = {k: float(v) for k, v in a.items() if k not in ("name", "shape", "rest_pose")}
            self.colliders.append(Collider(int(key), str(a.get("name", "")), str(a.get("shape", "")), dims,
                                           np.asarray(a.get("rest_pose", np.r_[np.eye(3).ravel(), 0, 0, 0]), float),
                                           c["vertices"][()] if "vertices" in c else None,
                                           c["triangles"][()] if "triangles" in c else None))
        self.bones: List[Bone] = []
        g = h.get("bones")
        for key in sorted(g.keys() if g is not None else [], key=int):
            a = {k: _text(v) for k, v in g[key].attrs.items()}
            self.bones.append(Bone(int(key), str(a.get("name", "")), int(a.get("parent", -1)),
                                   np.asarray(a.get("from", np.zeros(3)), float), np.asarray(a.get("to", np.zeros(3)), float),
                                   float(a.get("radius", 0.0))))
        # Muscles: their names (the columns of activation), each tet's muscle (-1: none) and fibre.
        mu = h.get("muscles")
        names = _text(mu.attrs.get("names", "")) if mu is not None else ""
        self.muscles: List[str] = str(names).split(",") if names else []
        self.tet_muscle: np.ndarray = mu["tet_muscle"][()] if mu is not None else np.full(len(self.tets), -1)
        self.tet_fibre: np.ndarray = mu["tet_fibre"][()] if mu is not None else np.zeros((len(self.tets), 3))
        # A character's render mesh (/render): its vertices at rest, triangles, and each vertex's
        # tet and barycentric weights, which carry it with the tets (render_positions).
        r = h.get("render")
        self.render_source: str = str(_text(r.attrs.get("source", ""))) if r is not None else ""
        self.render_rest: Optional[np.ndarray] = r["rest"][()] if r is not None else None
        self.render_triangles: Optional[np.ndarray] = r["triangles"][()] if r is not None else None
        self._render_tet = r["tet"][()] if r is not None else None
        self._render_weights = r["weights"][()] if r is not None else None
        self._skin = (r["skin_bones"][()], r["skin_weights"][()]) if r is not None and "skin_bones" in r else None

    # The per-frame node arrays, read when first asked for.
    def _series(self, name: str) -> Optional[np.ndarray]:
        f = self._h5["frames"]
        return f[name][: self.num_frames] if name in f else None

    @functools.cached_property
    def positions(self) -> np.ndarray:
        """(F,N,3) every node at every frame (m)."""
        return self._series("positions")

    @functools.cached_property
    def velocities(self) -> Optional[np.ndarray]:
        """(F,N,3) m/s."""
        return self._series("velocities")

    @functools.cached_property
    def pressure(self) -> Optional[np.ndarray]:
        """(F,T) per-tet pressure (Pa), when the scene had output.pressure = true."""
        return self._series("pressure")

    @functools.cached_property
    def loads(self) -> Optional[np.ndarray]:
        """(F,N,3) applied loads (N), when the scene had [[load]]."""
        return self._series("load")

    @functools.cached_property
    def multipliers(self) -> Optional[np.ndarray]:
        """(F,M) the constraints' multipliers."""
        return self._series("multipliers")

    @functools.cached_property
    def contact(self) -> Optional[np.ndarray]:
        """(F,N,3) the colliders' force on every node (N), when the scene had colliders."""
        return self._series("contact")

    @functools.cached_property
    def activation(self) -> Optional[np.ndarray]:
        """(F,K) each muscle's activation (0..1) at every frame, in the order of `muscles`."""
        return self._series("activation")

    def has(self, name: str) -> bool:
        """Whether the run has the per-frame series /frames/NAME (load, contact, pressure, ...)."""
        return name in self._h5["frames"]

    def _frame_index(self, k: int) -> int:
        if k < 0:
            k += self.num_frames
        if not 0 <= k < self.num_frames:
            raise IndexError(f"{self.path}: frame {k} (it has {self.num_frames})")
        return k

    def frame(self, name: str, k: int) -> np.ndarray:
        """One frame of the series /frames/NAME ("positions", "load", "contact", "pressure", ...),
        read alone (negative k counts from the end)."""
        if not self.has(name):
            raise KeyError(f"{self.path}: no /frames/{name}")
        return self._h5["frames"][name][self._frame_index(k)]

    def frame_range(self, name: str, start: int, stop: int) -> np.ndarray:
        """Frames start..stop-1 of /frames/NAME, read together (a long run read in blocks)."""
        if not self.has(name):
            raise KeyError(f"{self.path}: no /frames/{name}")
        return self._h5["frames"][name][max(start, 0):min(stop, self.num_frames)]

    def frame_positions(self, k: int) -> np.ndarray:
        """(N,3) node positions at frame k (negative k counts from the end)."""
        return self.frame("positions", k)

    def render_positions(self, positions: np.ndarray) -> np.ndarray:
        """The render mesh's vertices (V,3) carried by node positions (N,3), or (F,V,3) by (F,N,3):
        each vertex the weighted sum of its tet's corners."""
        if self.render_rest is None:
            raise Error(f"{self.path}: has no render mesh (expected a run of a scene with a [character])")
        corners = self.tets[self._render_tet]  # (V,4)
        return np.einsum("...vkd,vk->...vd", positions[..., corners, :], self._render_weights)

    def collider_scale(self, k: int, c: int) -> float:
        """Collider c's factor on its radius at frame k (a band that tightens; 1: its own)."""
        f = self._h5["frames"]
        k = self._frame_index(k)
        return float(f["collider_scale"][k][c]) if "collider_scale" in f and f["collider_scale"].shape[0] > k else 1.0

    def collider_pose(self, k: int, c: int) -> Tuple[np.ndarray, np.ndarray]:
        """Collider c's pose at frame k: (A (3,3), b (3,)), its local point l at A l + b. The rest
        pose where the run did not write poses (an integrator that moves no collider)."""
        f = self._h5["frames"]
        k = self._frame_index(k)
        p = f["collider_pose"][k][c] if "collider_pose" in f and f["collider_pose"].shape[0] > k else self.colliders[c].rest_pose
        return np.asarray(p[:9], float).reshape(3, 3), np.asarray(p[9:], float)

    def bone_pose(self, k: int, b: int) -> Tuple[np.ndarray, np.ndarray]:
        """Bone b's pose at frame k: (A (3,3), b (3,)), a rest point X of the bone at A X + b (the
        nodes bound to it are exactly there)."""
        f = self._h5["frames"]
        k = self._frame_index(k)
        if "bone_pose" not in f or not 0 <= b < f["bone_pose"].shape[1]:
            raise KeyError(f"{self.path}: no bone {b} (bones: {len(self.bones)})")
        p = f["bone_pose"][k][b]
        return np.asarray(p[:9], float).reshape(3, 3), np.asarray(p[9:], float)

    def render_skinned(self, k: int) -> np.ndarray:
        """(V,3) the render mesh at frame k as linear blend skinning puts it: each vertex moved by
        its four bones' poses (/frames/bone_pose), weighted; the tissue's simulation without the
        tissue, to compare render_positions with."""
        if self._skin is None or "bone_pose" not in self._h5["frames"]:
            raise Error(f"{self.path}: has no skinned render mesh (expected a run of a scene with a [character])")
        poses = np.asarray(self._h5["frames"]["bone_pose"][self._frame_index(k)], float)  # (B,12)
        A, b = poses[:, :9].reshape(-1, 3, 3), poses[:, 9:]
        bones, weights = self._skin
        moved = np.einsum("vkij,vj->vki", A[bones], self.render_rest) + b[bones]  # (V,4,3)
        return np.einsum("vki,vk->vi", moved, weights)

    def zone_volume(self, name: str) -> np.ndarray:
        """(F,) the volume of a zone ("total": the whole body) at every frame."""
        if name not in self.volume_columns:
            raise KeyError(f"{self.path}: no zone {name!r} (zones: {', '.join(self.volume_columns[1:]) or 'none'})")
        return self.volumes[:, self.volume_columns.index(name)]

    def volume_error(self) -> float:
        """The worst relative zone-volume error over all frames and zones, against frame 0."""
        if self.num_frames == 0:
            return float("nan")
        return float(np.max(np.abs(self.volumes / self.volumes[0] - 1)))

    def close(self) -> None:
        """Closes the file (a `with isochor.open(...) as run:` block does it on leaving)."""
        self._h5.close()

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"<isochor.Run {self.path!r}: {len(self.rest_positions)} nodes, {len(self.tets)} tets, "
                f"{self.num_frames} frames, zones {list(self.zones)}, {len(self.colliders)} colliders, "
                f"{len(self.bones)} bones, {self.status}>")


def open(path: Union[str, os.PathLike]) -> Run:  # noqa: A001
    """Opens a run's .h5 file (docs/output.md)."""
    return Run(path)

