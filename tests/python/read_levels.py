"""Read the XDMF files of a 2D run the way a user would and print what was
found as JSON, for tests/output/refine_series.rs to compare with counts
that do not come from the XDMF writer (`hasse info`, the run's report, the
h5 file's own mesh datasets).

    python read_levels.py STEM LEVELS

reads STEM.level-<k>.xdmf for k < LEVELS with `meshio.read` (LEVELS = 0:
none), parses STEM.xdmf with xml.etree (every grid of its collection, or
its one grid), reads STEM.xdmf with `meshio.read` when it holds one grid,
and tries `meshio.xdmf.TimeSeriesReader` on it.
"""

import json
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np


def shoelace(points, cell):
    xy = points[cell][:, :2]
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def read_mesh(path):
    """Counts, areas and fields of the one mesh meshio reads from `path`."""
    mesh = meshio.read(path)
    areas = [shoelace(mesh.points, cell) for block in mesh.cells for cell in block.data]
    used = np.unique(np.concatenate([block.data.ravel() for block in mesh.cells]))
    return {
        "points": len(mesh.points),
        "elements": sum(len(block.data) for block in mesh.cells),
        "types": sorted({block.type for block in mesh.cells}),
        "area": sum(areas),
        "min_area": min(areas),
        "unused_points": len(mesh.points) - len(used),
        "point_data": {name: len(values) for name, values in mesh.point_data.items()},
        "cell_data": {
            name: np.concatenate(blocks).tolist() for name, blocks in mesh.cell_data.items()
        },
    }


def grids(path):
    """Each uniform grid of `path` as the file lists it, in order."""
    (domain,) = list(ET.parse(path).getroot())
    (top,) = list(domain)
    listed = list(top) if top.get("GridType") == "Collection" else [top]
    out = []
    for grid in listed:
        time = grid.find("Time")
        topology = grid.find("Topology")
        geometry = grid.find("Geometry").find("DataItem")
        out.append(
            {
                "grid_type": grid.get("GridType"),
                "time": None if time is None else float(time.get("Value")),
                "elements": int(topology.get("NumberOfElements")),
                "topology": topology.find("DataItem").text,
                "geometry": geometry.text,
                "geometry_rows": int(geometry.get("Dimensions").split()[0]),
            }
        )
    return {
        "collection": top.get("CollectionType"),
        "grids": out,
    }


def main():
    stem, count = sys.argv[1], int(sys.argv[2])
    found = {
        "meshio": meshio.__version__,
        "levels": [read_mesh(f"{stem}.level-{k}.xdmf") for k in range(count)],
        "series": grids(f"{stem}.xdmf"),
    }
    if found["series"]["collection"] is None:
        found["main"] = read_mesh(f"{stem}.xdmf")
    try:
        with meshio.xdmf.TimeSeriesReader(f"{stem}.xdmf") as reader:
            points, _ = reader.read_points_cells()
            found["time_series_reader"] = {"points": len(points), "steps": reader.num_steps}
    except Exception as e:  # noqa: BLE001 -- the test wants to see any refusal
        found["time_series_reader"] = {"error": f"{type(e).__name__}: {e}"}
    print(json.dumps(found))


if __name__ == "__main__":
    main()
