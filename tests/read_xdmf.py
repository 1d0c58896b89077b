"""Reads an isochor XDMF time series with meshio (a reader written elsewhere) and checks it.

usage: read_xdmf.py FILE.xdmf NODES TETS FRAMES
The writer test moves frame k by 0.01 k (1, 2, 3) after scaling z by 1 + 0.1 k.
"""
import sys

import meshio
import numpy as np

path, nodes, tets, frames = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
with meshio.xdmf.TimeSeriesReader(path) as reader:
    points, cells = reader.read_points_cells()
    assert points.shape == (nodes, 3), points.shape
    assert len(cells) == 1 and cells[0].type == "tetra", cells
    assert cells[0].data.shape == (tets, 4), cells[0].data.shape
    assert reader.num_steps == frames, reader.num_steps
    rest = points.copy()
    for k in range(reader.num_steps):
        t, point_data, cell_data = reader.read_data(k)
        assert abs(t - 0.5 * k) < 1e-15, t
        expected = rest.copy()
        expected[:, 2] *= 1.0 + 0.1 * k
        expected += 0.01 * k * np.array([1.0, 2.0, 3.0])
        err = np.abs(point_data["position"] - expected).max()
        assert err < 1e-12, (k, err)
        load = point_data["load"]
        expected_load = np.stack([0.001 * np.arange(nodes), np.zeros(nodes), np.full(nodes, float(k))], axis=1)
        assert np.abs(load - expected_load).max() == 0.0, k
        pressure = cell_data["pressure"][0]
        assert pressure.shape == (tets,) and np.all(pressure == 10.0 * k), pressure[:3]
print("meshio read", nodes, "nodes,", tets, "tets,", frames, "frames: ok")
