"""Read hasse output files with h5py and meshio only, as a user would.

Usage: check_output.py MANIFEST.json

The manifest (written by tests/output_python.rs) lists output files and the
values expected in them, computed in Rust from analytic formulas. Every
check raises AssertionError with a message; the script prints one line per
case (and one per edges file read) and exits non-zero on the first failure.

A case with "edges" also has an edge cochain: its main <stem>.xdmf must
still be readable by meshio (top cells only), and <stem>.edges.xdmf must be
readable too, with one line cell per edge, in edge-id order, carrying the
edge values.
"""

import json
import sys
from pathlib import Path

import h5py
import meshio
import numpy as np


def equal(got, expected, what):
    got = np.asarray(got)
    expected = np.asarray(expected, dtype=got.dtype if got.dtype.kind == "f" else None)
    assert got.shape == expected.shape, f"{what}: shape {got.shape} != {expected.shape}"
    assert np.array_equal(got, expected), f"{what}: {got} != {expected}"


def check_h5(case):
    with h5py.File(case["h5"], "r") as f:
        n = int(f["mesh"].attrs["dim"])
        assert n == case["dim"], f"dim {n}"
        equal(f["mesh/vertices"][()], case["vertices"], "vertices")
        for p, (rows, cols) in case["boundary_shapes"].items():
            g = f[f"mesh/boundary/{p}"]
            equal(g.attrs["shape"], [rows, cols], f"shape of boundary {p}")
            indptr, indices, data = g["indptr"][()], g["indices"][()], g["data"][()]
            assert len(indptr) == rows + 1, f"boundary {p}: indptr length"
            assert indptr[-1] == len(indices) == len(data), f"boundary {p}: nnz"
            assert indices.max() < cols, f"boundary {p}: column out of range"
            assert set(np.unique(data)) <= {-1, 1}, f"boundary {p}: entries"
            # Every p-cell has at least p + 1 facets (a simplex has exactly p + 1).
            facets = np.bincount(indices, minlength=cols)
            assert facets.min() >= int(p) + 1, f"boundary {p}: facet counts"
        for path, values in case["datasets"].items():
            equal(f[path][()], values, path)
        equal(f.attrs["times"], case["times"], "times")
        assert f["provenance"].attrs["hasse_version"] == case["hasse_version"]
        report = json.loads(f["provenance/report"].asstr()[()])
        assert report == case["report"], f"report {report}"
        return {p: cell_sets(f, p) for p in range(n + 1)}


def cell_sets(f, p):
    g = f[f"mesh/cells/{p}"]
    indptr, indices = g["indptr"][()], g["indices"][()]
    return [frozenset(indices[indptr[i] : indptr[i + 1]]) for i in range(len(indptr) - 1)]


def signed_area(points, cell):
    xy = points[cell][:, :2]
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


def check_mesh_cells(points, cells, case):
    counts = {}
    for block in cells:
        counts[block.type] = counts.get(block.type, 0) + len(block.data)
        if block.type in ("triangle", "quad") and case["dim"] == 2:
            areas = [signed_area(points, c) for c in block.data]
            assert min(areas) > 0, f"{block.type}: non-positive area {min(areas)}"
        if block.type == "tetra":
            a, b, c, d = (points[block.data[:, i]] for i in range(4))
            vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
            assert vol.min() > 0, "tetra: non-positive volume"
    assert counts == case["cell_counts"], f"cell counts {counts} != {case['cell_counts']}"


def check_meshio(case, sets):
    mesh = meshio.read(case["xdmf"])
    equal(mesh.points, case["vertices"], "meshio points")
    check_mesh_cells(mesh.points, mesh.cells, case)
    for name, values in case["point_data"].items():
        equal(mesh.point_data[name], values, f"meshio point_data {name}")
    for name, values in case["cell_data"].items():
        got = np.concatenate(mesh.cell_data[name])
        if "cells_of" in case:
            # Cells split for the reader: each element carries its cell's value.
            top = sets[case["dim"]]
            owners = [
                next(i for i, s in enumerate(top) if set(c) <= s)
                for block in mesh.cells
                for c in block.data
            ]
            values = [values[i] for i in owners]
        equal(got, values, f"meshio cell_data {name}")


def check_edge_cells(points, cells, case, sets):
    """One 'line' block with the edges in edge-id order: line i joins the two
    vertices of row i of /mesh/cells/1, so cell data i is the value of edge i."""
    edges = case["edges"]
    assert [b.type for b in cells] == ["line"], f"edge blocks {[b.type for b in cells]}"
    lines = cells[0].data
    assert len(lines) == edges["count"], f"{len(lines)} lines != {edges['count']} edges"
    assert len(sets[1]) == edges["count"], f"h5 has {len(sets[1])} edges"
    for i, line in enumerate(lines):
        assert frozenset(line) == sets[1][i], f"line {i} {line} is not edge {set(sets[1][i])}"
        assert np.linalg.norm(points[line[1]] - points[line[0]]) > 0, f"line {i} has length 0"


def check_edges_meshio(case, sets):
    edges = case["edges"]
    mesh = meshio.read(edges["xdmf"])
    equal(mesh.points, case["vertices"], "edges file points")
    check_edge_cells(mesh.points, mesh.cells, case, sets)
    assert not mesh.point_data, f"edges file point data {list(mesh.point_data)}"
    assert set(mesh.cell_data) == set(edges["steps"][0]), f"edges cell data {list(mesh.cell_data)}"
    for name, values in edges["steps"][0].items():
        equal(np.concatenate(mesh.cell_data[name]), values, f"edges file cell_data {name}")


def check_edges_series(case, sets):
    edges = case["edges"]
    with meshio.xdmf.TimeSeriesReader(edges["xdmf"]) as reader:
        points, cells = reader.read_points_cells()
        equal(points, case["vertices"], "edges series points")
        check_edge_cells(points, cells, case, sets)
        assert reader.num_steps == len(case["times"]), f"edge steps {reader.num_steps}"
        for k, t in enumerate(case["times"]):
            time, point_data, cell_data = reader.read_data(k)
            assert time == t, f"edges step {k}: time {time} != {t}"
            assert not point_data, f"edges step {k}: point data {list(point_data)}"
            for name, values in edges["steps"][k].items():
                equal(np.concatenate(cell_data[name]), values, f"edges step {k} cell_data {name}")


def check_series(case):
    with meshio.xdmf.TimeSeriesReader(case["xdmf"]) as reader:
        points, cells = reader.read_points_cells()
        equal(points, case["vertices"], "series points")
        check_mesh_cells(points, cells, case)
        assert reader.num_steps == len(case["times"]), f"steps {reader.num_steps}"
        for k, t in enumerate(case["times"]):
            time, point_data, cell_data = reader.read_data(k)
            assert time == t, f"step {k}: time {time} != {t}"
            for name, values in case["steps"][k]["point_data"].items():
                equal(point_data[name], values, f"step {k} point_data {name}")
            for name, values in case["steps"][k]["cell_data"].items():
                equal(np.concatenate(cell_data[name]), values, f"step {k} cell_data {name}")


def main():
    manifest = json.loads(Path(sys.argv[1]).read_text())
    for case in manifest["cases"]:
        sets = check_h5(case)
        if len(case["times"]) > 1:
            check_series(case)
        else:
            check_meshio(case, sets)
        print(f"ok {case['name']} (h5py {h5py.__version__}, meshio {meshio.__version__})")
        if "edges" in case:
            if len(case["times"]) > 1:
                check_edges_series(case, sets)
            else:
                check_edges_meshio(case, sets)
            print(f"ok {case['name']} edges file ({case['edges']['count']} edges)")


if __name__ == "__main__":
    main()
