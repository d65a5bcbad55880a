"""Writes the small broken Gmsh meshes of tests/bad-input/meshes/ (run from
this directory: python3 make_meshes.py). Each is the smallest mesh showing
one defect; the case files next door say which message it must produce."""

import math


def msh(name, nodes, top, lines=(), groups=None):
    """nodes: list of (x, y, z); top: (gmsh type, [node lists]) of the
    2-cells; lines: boundary segments in physical group 1 (named by
    groups[1]); node and element tags are 1-based."""
    groups = groups or {}
    out = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat"]
    if groups:
        out += ["$PhysicalNames", str(len(groups))]
        out += [f'1 {tag} "{name}"' for tag, name in groups.items()]
        out += ["$EndPhysicalNames"]
        out += ["$Entities", "0 1 1 0"]
        out += ["1 -9 -9 -9 9 9 9 1 1 0"]
        out += ["1 -9 -9 -9 9 9 9 0 1 1"]
        out += ["$EndEntities"]
    n = len(nodes)
    out += ["$Nodes", f"1 {n} 1 {n}", f"2 1 0 {n}"]
    out += [str(i + 1) for i in range(n)]
    out += [" ".join(repr(float(c)) for c in p) for p in nodes]
    out += ["$EndNodes"]
    kind, cells = top
    blocks = [(2, 1, kind, cells)]
    if lines:
        blocks.append((1, 1, 1, list(lines)))
    total = sum(len(b[3]) for b in blocks)
    out += ["$Elements", f"{len(blocks)} {total} 1 {total}"]
    tag = 1
    for dim, entity, kind, cells in blocks:
        out.append(f"{dim} {entity} {kind} {len(cells)}")
        for c in cells:
            out.append(" ".join(str(v) for v in [tag, *c]))
            tag += 1
    out += ["$EndElements"]
    with open(name, "w") as f:
        f.write("\n".join(out) + "\n")


square = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]

# Node 5 repeats node 3's position: the two triangles do not share their
# diagonal, so the mesh has a crack along it.
msh("duplicate-vertices.msh", square + [(1, 1, 0)], (2, [[1, 2, 3], [1, 5, 4]]))

# The second triangle's nodes are collinear: zero area.
msh("degenerate.msh", square + [(2, 0, 0)], (2, [[1, 2, 3], [1, 2, 5]]))

# Both triangles lie above their common edge 1-2: the second is folded
# over the first (it is "inverted" with respect to its neighbour).
msh("inverted.msh", square, (2, [[1, 2, 3], [2, 1, 4]]))

# Three triangles share the edge 1-2: not a manifold.
msh(
    "non-manifold.msh",
    [(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -1, 0), (0.5, 0, 1)],
    (2, [[1, 2, 3], [1, 2, 4], [1, 2, 5]]),
)

# A Möbius strip of 8 quads: no consistent orientation.
k = 8
nodes = []
for i in range(k):
    a = 2 * math.pi * i / k
    for s in (-0.3, 0.3):
        r = 1 + s * math.cos(a / 2)
        nodes.append((r * math.cos(a), r * math.sin(a), s * math.sin(a / 2)))
quads = []
for i in range(k):
    j = (i + 1) % k
    a, b = 2 * i + 1, 2 * i + 2
    c, d = (2 * j + 1, 2 * j + 2) if j else (2, 1)  # the half twist
    quads.append([a, c, d, b])
msh("mobius.msh", nodes, (3, quads))

# Two unit squares 1 apart; only the left one's left side is tagged.
two = square + [(2, 0, 0), (3, 0, 0), (3, 1, 0), (2, 1, 0)]
msh(
    "disconnected.msh",
    two,
    (3, [[1, 2, 3, 4], [5, 6, 7, 8]]),
    lines=[[4, 1]],
    groups={1: "left"},
)

# Three triangles of the plane on one edge: two of them overlap.
msh(
    "overlap.msh",
    [(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -1, 0), (0.5, 2, 0)],
    (2, [[1, 2, 3], [1, 2, 4], [1, 2, 5]]),
)

# Node 3's x coordinate is not a number: the message names the node, not
# the cells.
msh("nonfinite-vertex.msh", [(0, 0, 0), (1, 0, 0), (math.nan, 1, 0), (0, 1, 0)], (2, [[1, 2, 3], [1, 3, 4]]))

# Element 3 repeats element 1 (same nodes): a duplicate, not an overlap.
msh("duplicate-element.msh", square, (2, [[1, 2, 3], [1, 3, 4], [1, 2, 3]]))

