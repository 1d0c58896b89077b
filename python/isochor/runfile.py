"""Reading a run's HDF5 file (docs/output.md) as NumPy arrays: isochor.open(PATH)."""
from __future__ import annotations

import functools
import os
from typing import Dict, List, Optional, Union

import numpy as np

from ._isochor import Error


class Run:
    """A run file: its mesh, zones, frames and statistics as NumPy arrays.

    Small things (mesh, zones, times, volumes, energies, statistics) are read at open; the
    per-frame node arrays (positions, velocities, pressure, loads) when first asked for, whole
    (`run.positions`, (F,N,3)) or one frame at a time (`run.frame_positions(k)`).
    """

    def __init__(self, path: Union[str, os.PathLike]):
        import h5py  # Debian's python3-h5py

        self.path = os.fspath(path)
        if not os.path.exists(self.path):
            raise Error(f"{self.path}: no such file (expected a run's .h5 file)")
        try:
            self._h5 = h5py.File(self.path, "r")
        except OSError as e:
            raise Error(f"{self.path}: cannot be read as HDF5 ({e}; expected a run's .h5 file)") from None
        h = self._h5
        if "mesh" not in h or "frames" not in h:
            h.close()
            raise Error(f"{self.path}: has no /mesh and /frames (expected a file written by isochor run)")
        attr = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in h.attrs.items()}
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
        self.totals: Dict[str, object] = ({k: (v.decode() if isinstance(v, bytes) else v) for k, v in st.attrs.items()}
                                          if st is not None else {})
        self.stats: Dict[str, np.ndarray] = ({k: v[:n] for k, v in st.items() if hasattr(v, "shape")}
                                             if st is not None else {})

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

    def frame_positions(self, k: int) -> np.ndarray:
        """(N,3) node positions at frame k (negative k counts from the end)."""
        if k < 0:
            k += self.num_frames
        if not 0 <= k < self.num_frames:
            raise IndexError(f"{self.path}: frame {k} (it has {self.num_frames})")
        return self._h5["frames"]["positions"][k]

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
        self._h5.close()

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return (f"<isochor.Run {self.path!r}: {len(self.rest_positions)} nodes, {len(self.tets)} tets, "
                f"{self.num_frames} frames, zones {list(self.zones)}, {self.status}>")


def open(path: Union[str, os.PathLike]) -> Run:  # noqa: A001
    """Opens a run's .h5 file (docs/output.md)."""
    return Run(path)

