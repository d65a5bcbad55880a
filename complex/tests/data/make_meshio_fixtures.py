"""Regenerate the meshio-written fixtures (run once; the tests do not need Python).

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install meshio
    /tmp/venv/bin/python complex/tests/data/make_meshio_fixtures.py

Writes, next to this script, mixed_3d_binary.msh and mixed_3d_ascii.msh (the
same mesh, Gmsh 4.1 binary and ASCII), and ../../../cases/l-shape.msh.
"""
import os

import meshio
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def mixed_3d():
    # A unit hexahedron with a pyramid on top, a prism against its x = 1 face
    # and a tetrahedron against the pyramid's x + z = 2 face.
    points = np.array(
        [
            [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],  # 0-3 hex bottom
            [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],  # 4-7 hex top
            [0.5, 0.5, 1.5],  # 8 pyramid apex
            [2, 0, 0], [2, 1, 0],  # 9, 10 prism
            [1.5, 0.5, 1.5],  # 11 tetrahedron tip
        ],
        dtype=float,
    )
    cells = [
        ("vertex", [[8]]),
        ("line", [[9, 10]]),
        ("quad", [[0, 1, 2, 3], [1, 9, 10, 2]]),
        ("hexahedron", [[0, 1, 2, 3, 4, 5, 6, 7]]),
        ("pyramid", [[4, 5, 6, 7, 8]]),
        ("wedge", [[1, 9, 5, 2, 10, 6]]),
        ("tetra", [[5, 6, 8, 11]]),
    ]
    physical = [[1], [2], [3, 3], [4], [4], [4], [4]]
    geometrical = [[1], [1], [1, 1], [1], [2], [3], [4]]
    # meshio builds $Entities from the nodes' entities, so every element
    # block's entity owns at least one node. The grouping also lists the
    # nodes out of tag order (tags 9, 10, 11, 1, 4, ...), which the reader
    # must handle.
    dim_tags = np.array(
        [
            [2, 1], [3, 1], [3, 1], [2, 1],
            [3, 1], [3, 2], [3, 3], [3, 1],
            [0, 1],
            [1, 1], [1, 1],
            [3, 4],
        ]
    )
    return meshio.Mesh(
        points,
        cells,
        point_data={"gmsh:dim_tags": dim_tags},
        cell_data={
            "gmsh:physical": [np.array(p) for p in physical],
            "gmsh:geometrical": [np.array(g) for g in geometrical],
        },
        field_data={
            "apex": np.array([1, 0]),
            "ridge": np.array([2, 1]),
            "bottom": np.array([3, 2]),
            "solid": np.array([4, 3]),
        },
    )


def l_shape(m=8):
    # [0,1]^2 without (0.5,1]x(0.5,1], h = 1/m, each square cut along its
    # (i,j)-(i+1,j+1) diagonal into two counter-clockwise triangles.
    half = m // 2
    inside = lambda i, j: not (i > half and j > half)
    index = {}
    points = []
    for j in range(m + 1):
        for i in range(m + 1):
            if inside(i, j):
                index[i, j] = len(points)
                points.append([i / m, j / m, 0.0])
    triangles = []
    for j in range(m):
        for i in range(m):
            if i >= half and j >= half:
                continue
            a, b = index[i, j], index[i + 1, j]
            c, d = index[i, j + 1], index[i + 1, j + 1]
            triangles += [[a, b, d], [a, d, c]]
    count = {}
    for t in triangles:
        for k in range(3):
            e = tuple(sorted((t[k], t[(k + 1) % 3])))
            count[e] = count.get(e, 0) + 1
    lines = sorted(e for e, c in count.items() if c == 1)
    on_boundary = {v for e in lines for v in e}
    dim_tags = np.array([[1, 1] if v in on_boundary else [2, 1] for v in range(len(points))])
    return meshio.Mesh(
        np.array(points),
        [("line", lines), ("triangle", triangles)],
        point_data={"gmsh:dim_tags": dim_tags},
        cell_data={
            "gmsh:physical": [np.full(len(lines), 1), np.full(len(triangles), 2)],
            "gmsh:geometrical": [np.full(len(lines), 1), np.full(len(triangles), 1)],
        },
        field_data={"dirichlet": np.array([1, 1]), "domain": np.array([2, 2])},
    )


if __name__ == "__main__":
    mesh = mixed_3d()
    meshio.write(os.path.join(HERE, "mixed_3d_binary.msh"), mesh, file_format="gmsh", binary=True)
    meshio.write(os.path.join(HERE, "mixed_3d_ascii.msh"), mesh, file_format="gmsh", binary=False)
    cases = os.path.join(HERE, "..", "..", "..", "cases", "l-shape.msh")
    meshio.write(os.path.normpath(cases), l_shape(), file_format="gmsh", binary=False)
