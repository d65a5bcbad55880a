"""Read hasse output files with h5py and meshio only, as a user would.

Usage: check_output.py MANIFEST.json

The manifest (written by tests/output/output_python.rs) lists output files and the
values expected in them, computed in Rust from analytic formulas. Every
check raises AssertionError with a message; the script prints one line per
case (and one per edges file read) and exits non-zero on the first failure.

A case with "edges" also has an edge cochain: its main <stem>.xdmf must
still be readable by meshio (top cells only), and <stem>.edges.xdmf must be
readable too, with one line cell per edge, in edge-id order, carrying the
edge values.

A "mesh_series" case is a series whose mesh changes (write_mesh_series):
h5py reads step k's mesh and fields from /steps/<k> with the recipe of
cases/OUTPUT.md, xml.etree checks that grid k of every XDMF file points at
step k's mesh with the right element counts, meshio.read opens the files of
each level alone (<stem>.level-<k>.xdmf, <stem>.level-<k>.edges.xdmf) with
that level's mesh and fields, and meshio's TimeSeriesReader, which would
pair every step's fields with the first step's mesh, refuses the series.
"""

import json
import xml.etree.ElementTree as ET
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


def read_step(f, k):
    """The recipe of cases/OUTPUT.md: step k's mesh and fields of a file
    whose mesh changes (root attribute mesh_changes == 1)."""
    step = f[f"steps/{k}"]
    mesh = step["mesh"]
    points = mesh["vertices"][()]
    cells = {}
    for p, g in mesh["cells"].items():
        indptr, indices = g["indptr"][()], g["indices"][()]
        cells[int(p)] = [indices[indptr[i] : indptr[i + 1]] for i in range(len(indptr) - 1)]
    fields = {name: (int(ds.attrs["dim"]), ds[()]) for name, ds in step.items() if name != "mesh"}
    return float(step.attrs["time"]), points, cells, fields


def check_mesh_series_h5(case):
    with h5py.File(case["h5"], "r") as f:
        assert int(f.attrs["mesh_changes"]) == 1, "mesh_changes"
        assert int(f.attrs["format_version"]) == 2, "format_version"
        assert int(f.attrs["step_count"]) == len(case["steps"]), "step_count"
        equal(f.attrs["times"], case["times"], "times")
        assert "mesh" not in f and "xdmf" not in f, f"shared mesh groups in {list(f)}"
        assert f["provenance"].attrs["hasse_version"] == case["hasse_version"]
        for k, expected in enumerate(case["steps"]):
            t, points, cells, fields = read_step(f, k)
            assert t == case["times"][k], f"step {k}: time {t}"
            equal(points, expected["vertices"], f"step {k} vertices")
            counts = [len(cells[p]) for p in range(len(cells))]
            assert counts == expected["cell_counts"], f"step {k}: cell counts {counts}"
            assert int(f[f"steps/{k}/mesh"].attrs["dim"]) == case["dim"]
            for p, (rows, cols) in expected["boundary_shapes"].items():
                g = f[f"steps/{k}/mesh/boundary/{p}"]
                equal(g.attrs["shape"], [rows, cols], f"step {k} shape of boundary {p}")
                assert len(g["indptr"]) == rows + 1, f"step {k} boundary {p}: indptr"
            # Every edge of cells[1] is two vertices of this step's mesh.
            assert all(len(e) == 2 and e.max() < len(points) for e in cells[1]), f"step {k} edges"
            assert set(fields) == set(expected["fields"]), f"step {k} fields {list(fields)}"
            for name, values in expected["fields"].items():
                dim, got = fields[name]
                assert dim == expected["field_dims"][name], f"step {k} {name}: dim {dim}"
                assert len(got) == counts[dim], f"step {k} {name}: {len(got)} values"
                equal(got, values, f"step {k} {name}")


def check_mesh_series_xdmf(case, path, degree, grid_name):
    """Grid k of the temporal collection takes topology and geometry from
    /steps/<k>/mesh, with NumberOfElements the count of step k's cells."""
    h5_name = Path(case["h5"]).name
    root = ET.parse(path).getroot()
    (domain,) = list(root)
    (collection,) = list(domain)
    assert collection.get("CollectionType") == "Temporal", f"{path}: not temporal"
    grids = list(collection)
    assert len(grids) == len(case["steps"]), f"{path}: {len(grids)} grids"
    with h5py.File(case["h5"], "r") as f:
        for k, (grid, expected) in enumerate(zip(grids, case["steps"])):
            # GridType is left at its default, Uniform (see check_mesh_series_meshio).
            assert grid.get("Name") == grid_name and grid.get("GridType") is None
            assert float(grid.find("Time").get("Value")) == case["times"][k], f"grid {k} time"
            count = expected["cell_counts"][degree]
            nv = len(expected["vertices"])
            top = grid.find("Topology")
            assert int(top.get("NumberOfElements")) == count, f"{path} grid {k}: elements"
            nodes = 2 if degree == 1 else expected["top_nodes"]
            kind = "Polyline" if degree == 1 else expected["top_type"]
            assert top.get("TopologyType") == kind, f"{path} grid {k}: {top.get('TopologyType')}"
            item = top.find("DataItem")
            assert item.text == f"{h5_name}:/steps/{k}/mesh/xdmf/{degree}/topology", item.text
            assert item.get("Dimensions") == f"{count} {nodes}", item.get("Dimensions")
            conn = f[item.text.split(":", 1)[1]][()]
            assert conn.shape == (count, nodes), f"grid {k}: topology shape {conn.shape}"
            assert conn.min() >= 0 and conn.max() < nv, f"grid {k}: vertex ids out of range"
            geo = grid.find("Geometry").find("DataItem")
            assert geo.text == f"{h5_name}:/steps/{k}/mesh/vertices", geo.text
            assert geo.get("Dimensions") == f"{nv} 3", geo.get("Dimensions")
            equal(f[geo.text.split(":", 1)[1]][()], expected["vertices"], f"grid {k} geometry")
            # The attributes read step k's values, sized for step k's mesh.
            shown = {}
            for attr in grid.findall("Attribute"):
                item = attr.find("DataItem")
                name = attr.get("Name")
                assert item.text == f"{h5_name}:/steps/{k}/{name}", item.text
                size = nv if attr.get("Center") == "Node" else count
                assert item.get("Dimensions") == str(size), f"grid {k} {name}"
                shown[name] = f[item.text.split(":", 1)[1]][()]
            wanted = {
                n: v
                for n, v in expected["fields"].items()
                if expected["field_dims"][n] == degree
                or (degree == case["dim"] and expected["field_dims"][n] == 0)
            }
            assert set(shown) == set(wanted), f"{path} grid {k}: attributes {list(shown)}"
            for name, values in wanted.items():
                equal(shown[name], values, f"{path} grid {k} {name}")


def check_mesh_series_meshio(case):
    """meshio's TimeSeriesReader takes points and cells from one grid only,
    so it must refuse the series (its grids do not name their type, and it
    finds no "mesh grid") rather than give step 0's mesh with every step's
    fields; each level's own files open with meshio.read instead."""
    steps = case["steps"]
    try:
        meshio.xdmf.TimeSeriesReader(case["xdmf"])
    except meshio.ReadError as e:
        assert "mesh grid" in str(e), str(e)
    else:
        raise AssertionError("meshio's TimeSeriesReader opened a series whose mesh changes")
    assert len(case["levels"]) == len(steps), f"{len(case['levels'])} level file sets"
    for k, (files, expected) in enumerate(zip(case["levels"], steps)):
        top, edges = files
        fields = expected["fields"]
        mesh = meshio.read(top)
        equal(mesh.points, expected["vertices"], f"{top} points")
        kind = {"Quadrilateral": "quad", "Triangle": "triangle"}[expected["top_type"]]
        assert [b.type for b in mesh.cells] == [kind], f"{top}: {mesh.cells}"
        assert len(mesh.cells[0].data) == expected["cell_counts"][case["dim"]], f"{top} cells"
        equal(mesh.point_data["u"], fields["u"], f"{top} u")
        equal(mesh.cell_data["c"][0], fields["c"], f"{top} c")
        assert set(mesh.point_data) == {"u"} and set(mesh.cell_data) == {"c"}, top
        lines = meshio.read(edges)
        assert [b.type for b in lines.cells] == ["line"], f"{edges}: {lines.cells}"
        assert len(lines.cells[0].data) == expected["cell_counts"][1], f"{edges} edges"
        equal(lines.cell_data["q"][0], fields["q"], f"{edges} q")


def main():
    manifest = json.loads(Path(sys.argv[1]).read_text())
    for case in manifest.get("mesh_series", []):
        name = case["name"]
        check_mesh_series_h5(case)
        print(f"ok mesh series {name}: h5py reads {len(case['steps'])} steps' meshes and fields")
        check_mesh_series_xdmf(case, case["xdmf"], case["dim"], "cells")
        print(f"ok mesh series {name}: {Path(case['xdmf']).name} grid k points at /steps/k/mesh")
        check_mesh_series_xdmf(case, case["edges_xdmf"], 1, "edges")
        print(f"ok mesh series {name}: {Path(case['edges_xdmf']).name} grid k points at /steps/k/mesh")
        check_mesh_series_meshio(case)
        print(f"ok mesh series {name}: meshio.read opens each level's files, TimeSeriesReader refuses the series")
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
