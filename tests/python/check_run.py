"""Check a `hasse run` output with h5py and meshio only, against the numbers
the run printed.

Usage: check_run.py STEM L2 MAX

STEM.h5 / STEM.xdmf come from `hasse run cases/poisson-square.toml --set
problem.method=fv -o STEM` (cell-centred unknowns on a uniform quad grid of
the unit square). L2 and MAX are the errors printed in the run's summary
(7 significant digits). The script recomputes them from the arrays: cell
areas by the shoelace formula on the XDMF quads, the exact solution
sin(πx) sin(πy) at the cell centroids (the vertex mean of a parallelogram).
"""

import json
import sys

import h5py
import meshio
import numpy as np


def main():
    stem, l2_printed, max_printed = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    with h5py.File(stem + ".h5", "r") as f:
        points = f["mesh/vertices"][:, :2]
        quads = f["xdmf/2/topology"][:].reshape(-1, 4)
        u = f["steps/0/u"][:]
        u_exact = f["steps/0/u_exact"][:]
        assert f["steps/0/u"].attrs["dim"] == 2
        assert f["steps/0/u"].attrs["method"] == "fv"
        report = json.loads(f["provenance/report"][()].decode() if isinstance(f["provenance/report"][()], bytes) else f["provenance/report"][()])
        case_text = f["provenance/case_text"][()]
        case_text = case_text.decode() if isinstance(case_text, bytes) else case_text
    assert "sin(pi*x) * sin(pi*y)" in case_text, "the case text is stored"
    corners = points[quads]                       # (cells, 4, 2), cyclic order
    x, y = corners[..., 0], corners[..., 1]
    area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    assert np.all(area > 0), "quads are counter-clockwise"
    assert abs(area.sum() - 1.0) < 1e-12, area.sum()
    centre = corners.mean(axis=1)
    exact = np.sin(np.pi * centre[:, 0]) * np.sin(np.pi * centre[:, 1])
    assert np.allclose(u_exact, exact, rtol=0, atol=1e-14), "u_exact at centroids"
    l2 = np.sqrt(np.sum(area * (u - exact) ** 2))
    mx = np.max(np.abs(u - exact))
    assert abs(l2 - l2_printed) <= 1e-6 * l2_printed, (l2, l2_printed)
    assert abs(mx - max_printed) <= 1e-6 * max_printed, (mx, max_printed)
    assert abs(report["errors"]["l2_sampled"] - l2) <= 1e-12 * l2, (report["errors"], l2)
    assert report["unknowns"] == len(u)

    mesh = meshio.read(stem + ".xdmf")
    assert len(mesh.points) == len(points), len(mesh.points)
    cells = {block.type: len(block.data) for block in mesh.cells}
    assert cells == {"quad": len(u)}, cells
    assert np.array_equal(mesh.cell_data["u"][0], u), "meshio cell data u"
    print(f"check_run: {stem}: L2 {l2:.6e}, max {mx:.6e}, {len(u)} quads: ok")


if __name__ == "__main__":
    main()
