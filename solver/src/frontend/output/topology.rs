//! Cell connectivity in the vertex orders that XDMF/VTK readers expect.
//!
//! hasse keeps only sorted vertex sets (rows of M_p), so cyclic and
//! VTK orders are rebuilt from the signed boundary matrices: a 2-cell's
//! oriented edges (columns of ∂_2 with ∂_1 giving each edge's tail and
//! head) chain into its boundary cycle, and a hexahedron is a bottom face
//! cycle plus, for each bottom vertex, its neighbour along a cell edge.
//! Signs of 3-cells are then checked against the geometry, because VTK
//! wants positive volumes whatever the complex's own orientation.

use super::OutputError;
use hasse_complex::Complex;
use nalgebra::Vector3;
use std::collections::HashMap;

/// XDMF topology type codes used in `Mixed` connectivity arrays.
pub(crate) mod code {
    pub const POLYLINE: i64 = 2;
    pub const POLYGON: i64 = 3;
    pub const TRIANGLE: i64 = 4;
    pub const QUADRILATERAL: i64 = 5;
    pub const TETRAHEDRON: i64 = 6;
    pub const HEXAHEDRON: i64 = 9;
}

/// One element of a grid, vertices in reader order.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Element {
    Line([usize; 2]),
    Triangle([usize; 3]),
    Quadrilateral([usize; 4]),
    Polygon(Vec<usize>),
    Tetrahedron([usize; 4]),
    Hexahedron([usize; 8]),
}

impl Element {
    fn vertices(&self) -> &[usize] {
        match self {
            Element::Line(v) => v,
            Element::Triangle(v) => v,
            Element::Quadrilateral(v) => v,
            Element::Polygon(v) => v,
            Element::Tetrahedron(v) => v,
            Element::Hexahedron(v) => v,
        }
    }

    /// XDMF name and node count when every element of a grid has this kind.
    fn uniform_type(&self) -> Option<(&'static str, usize)> {
        match self {
            Element::Line(_) => Some(("Polyline", 2)),
            Element::Triangle(_) => Some(("Triangle", 3)),
            Element::Quadrilateral(_) => Some(("Quadrilateral", 4)),
            Element::Polygon(_) => None,
            Element::Tetrahedron(_) => Some(("Tetrahedron", 4)),
            Element::Hexahedron(_) => Some(("Hexahedron", 8)),
        }
    }

    fn same_kind(&self, other: &Element) -> bool {
        std::mem::discriminant(self) == std::mem::discriminant(other)
    }

    /// Append this element to an XDMF `Mixed` array: code, (count,) vertices.
    fn push_mixed(&self, out: &mut Vec<i64>) {
        let v = self.vertices();
        match self {
            Element::Line(_) => out.extend([code::POLYLINE, 2]),
            Element::Polygon(_) => out.extend([code::POLYGON, v.len() as i64]),
            Element::Triangle(_) => out.push(code::TRIANGLE),
            Element::Quadrilateral(_) => out.push(code::QUADRILATERAL),
            Element::Tetrahedron(_) => out.push(code::TETRAHEDRON),
            Element::Hexahedron(_) => out.push(code::HEXAHEDRON),
        }
        out.extend(v.iter().map(|&x| x as i64));
    }
}

/// The XDMF topology of one grid: the cells of one degree p.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GridTopology {
    /// Degree p of the cells (and of the cell-centred cochains shown on it).
    pub degree: usize,
    /// `Some((name, nodes per element))` for a uniform grid, `None` for `Mixed`.
    pub uniform: Option<(&'static str, usize)>,
    /// Uniform: element-major vertex ids; Mixed: the XDMF mixed array.
    pub connectivity: Vec<i64>,
    pub element_count: usize,
    /// The p-cell each element comes from, when that is not the identity
    /// (general polyhedra are written as several tetrahedra).
    pub cell_ids: Option<Vec<u64>>,
}

impl GridTopology {
    fn from_elements(degree: usize, elements: Vec<(usize, Element)>) -> Self {
        let uniform = match elements.first() {
            Some((_, first)) if elements.iter().all(|(_, e)| e.same_kind(first)) => {
                first.uniform_type()
            }
            _ => None,
        };
        let mut connectivity = Vec::new();
        for (_, e) in &elements {
            match uniform {
                Some(_) => connectivity.extend(e.vertices().iter().map(|&x| x as i64)),
                None => e.push_mixed(&mut connectivity),
            }
        }
        let identity = elements.iter().enumerate().all(|(k, (cell, _))| k == *cell);
        let cell_ids = (!identity).then(|| elements.iter().map(|(c, _)| *c as u64).collect());
        GridTopology {
            degree,
            uniform,
            connectivity,
            element_count: elements.len(),
            cell_ids,
        }
    }
}

/// How a grid writes 2-cells of five or more vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Polygons {
    /// As XDMF `Polygon` cells: ParaView and VisIt read them, meshio does not.
    Keep,
    /// As triangles on the polygon's own vertices (no point added, so point
    /// data stays valid), which every reader reads, meshio included.
    Triangulate,
}

/// Build the grid of the p-cells of `complex` (1 ≤ p ≤ dim), with its
/// polygons of five or more vertices written as `polygons` says.
pub(crate) fn grid_topology(
    complex: &Complex,
    p: usize,
    polygons: Polygons,
) -> Result<GridTopology, OutputError> {
    let mut elements = Vec::with_capacity(complex.cell_count(p));
    match p {
        1 => {
            for e in 0..complex.cell_count(1) {
                let (tail, head) = edge_ends(complex, e)?;
                elements.push((e, Element::Line([tail, head])));
            }
        }
        2 => {
            for f in 0..complex.cell_count(2) {
                let cycle = face_cycle(complex, f)?;
                if polygons == Polygons::Triangulate && cycle.len() > 4 {
                    let triangles = fan_triangles(complex, &cycle);
                    if triangles.is_empty() {
                        return Err(topology_error(2, f, "polygon has zero area"));
                    }
                    elements.extend(triangles.into_iter().map(|t| (f, Element::Triangle(t))));
                } else {
                    elements.push((f, polygon_element(cycle)));
                }
            }
        }
        3 => {
            for c in 0..complex.cell_count(3) {
                for element in solid_elements(complex, c)? {
                    elements.push((c, element));
                }
            }
        }
        _ => {
            return Err(OutputError::Topology {
                message: format!("no XDMF grid for cells of dimension {p}"),
            })
        }
    }
    Ok(GridTopology::from_elements(p, elements))
}

fn polygon_element(cycle: Vec<usize>) -> Element {
    match cycle.len() {
        3 => Element::Triangle([cycle[0], cycle[1], cycle[2]]),
        4 => Element::Quadrilateral([cycle[0], cycle[1], cycle[2], cycle[3]]),
        _ => Element::Polygon(cycle),
    }
}

/// A convex polygon (its vertices in cyclic order) as a fan of triangles
/// in the same orientation. SPLIT leaves vertices in the middle of the
/// sides of a cut cell's neighbours (hanging vertices), and a fan from a
/// corner next to such a side has triangles of three collinear points; so
/// the apex is the first vertex whose fan has no such triangle, and when
/// every apex has one (hanging vertices on every side), the one with fewest,
/// its zero-area triangles left out (they cover nothing).
fn fan_triangles(complex: &Complex, cycle: &[usize]) -> Vec<[usize; 3]> {
    let k = cycle.len();
    let fan = |apex: usize| -> Vec<([usize; 3], bool)> {
        (1..k - 1)
            .map(|j| {
                let t = [
                    cycle[apex],
                    cycle[(apex + j) % k],
                    cycle[(apex + j + 1) % k],
                ];
                (t, is_flat(complex, t))
            })
            .collect()
    };
    let flat_count = |f: &[([usize; 3], bool)]| f.iter().filter(|(_, flat)| *flat).count();
    let mut best = fan(0);
    for apex in 1..k {
        if flat_count(&best) == 0 {
            break;
        }
        let candidate = fan(apex);
        if flat_count(&candidate) < flat_count(&best) {
            best = candidate;
        }
    }
    best.into_iter()
        .filter(|(_, flat)| !flat)
        .map(|(t, _)| t)
        .collect()
}

/// Whether the triangle's corners are collinear: the sine of its angle at
/// the first corner below 1e-10 (relative, so independent of the mesh size).
fn is_flat(complex: &Complex, t: [usize; 3]) -> bool {
    let [a, b, c] = t.map(|v| Vector3::from(point3(complex, v)));
    let (u, w) = (b - a, c - a);
    u.cross(&w).norm() <= 1e-10 * u.norm() * w.norm()
}

/// Tail and head of edge `e` as ∂_1 orients it.
fn edge_ends(complex: &Complex, e: usize) -> Result<(usize, usize), OutputError> {
    let column = complex
        .boundary_csc(1)
        .outer_view(e)
        .ok_or_else(|| topology_error(1, e, "edge missing from ∂_1"))?;
    let (mut tail, mut head) = (None, None);
    for (v, &s) in column.iter() {
        if s < 0 {
            tail = Some(v);
        } else if s > 0 {
            head = Some(v);
        }
    }
    match (tail, head) {
        (Some(t), Some(h)) => Ok((t, h)),
        _ => Err(topology_error(1, e, "edge has no tail and head in ∂_1")),
    }
}

/// Vertices of 2-cell `f` in the cyclic order of its orientation.
pub(crate) fn face_cycle(complex: &Complex, f: usize) -> Result<Vec<usize>, OutputError> {
    let column = complex
        .boundary_csc(2)
        .outer_view(f)
        .ok_or_else(|| topology_error(2, f, "face missing from ∂_2"))?;
    let mut next = HashMap::with_capacity(column.nnz());
    let mut start = None;
    for (e, &s) in column.iter() {
        let (t, h) = edge_ends(complex, e)?;
        let (from, to) = if s > 0 { (t, h) } else { (h, t) };
        if next.insert(from, to).is_some() {
            return Err(topology_error(2, f, "boundary edges do not form one cycle"));
        }
        start = Some(start.map_or(from, |s: usize| s.min(from)));
    }
    let start = start.ok_or_else(|| topology_error(2, f, "face has no edges"))?;
    let mut cycle = Vec::with_capacity(next.len());
    let mut v = start;
    for _ in 0..next.len() {
        cycle.push(v);
        v = *next
            .get(&v)
            .ok_or_else(|| topology_error(2, f, "boundary edges do not form one cycle"))?;
    }
    if v != start {
        return Err(topology_error(2, f, "boundary edges do not form one cycle"));
    }
    Ok(cycle)
}

fn point3(complex: &Complex, v: usize) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (a, x) in complex.vertices().point(v).iter().enumerate() {
        p[a] = *x;
    }
    p
}

/// Six times the signed volume of the tetrahedron (a, b, c, d).
pub(crate) fn tet_volume6(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let [a, b, c, d] = [a, b, c, d].map(Vector3::from);
    (b - a).cross(&(c - a)).dot(&(d - a))
}

fn positive_tet(complex: &Complex, mut t: [usize; 4]) -> [usize; 4] {
    let [a, b, c, d] = t.map(|v| point3(complex, v));
    if tet_volume6(a, b, c, d) < 0.0 {
        t.swap(1, 2);
    }
    t
}

/// The elements one 3-cell is written as: a tetrahedron, a hexahedron, or
/// (any other convex polyhedron) a fan of tetrahedra from its lowest vertex.
fn solid_elements(complex: &Complex, c: usize) -> Result<Vec<Element>, OutputError> {
    let vertices = complex.cell_vertices(3, c);
    let faces: Vec<usize> = complex
        .boundary_csc(3)
        .outer_view(c)
        .ok_or_else(|| topology_error(3, c, "cell missing from ∂_3"))?
        .indices()
        .to_vec();
    if vertices.len() == 4 && faces.len() == 4 {
        let t = [vertices[0], vertices[1], vertices[2], vertices[3]];
        return Ok(vec![Element::Tetrahedron(positive_tet(complex, t))]);
    }
    let cycles = faces
        .iter()
        .map(|&f| face_cycle(complex, f))
        .collect::<Result<Vec<_>, _>>()?;
    if vertices.len() == 8 && cycles.len() == 6 && cycles.iter().all(|f| f.len() == 4) {
        if let Some(hex) = hexahedron(complex, &cycles) {
            return Ok(vec![Element::Hexahedron(hex)]);
        }
    }
    // A convex polyhedron is the union of the cones from one of its vertices
    // over the faces that do not contain it; fanning those faces gives
    // tetrahedra without adding points, which every reader understands.
    let apex = vertices[0];
    let mut tets = Vec::new();
    for cycle in cycles.iter().filter(|f| !f.contains(&apex)) {
        for k in 1..cycle.len() - 1 {
            let t = [apex, cycle[0], cycle[k], cycle[k + 1]];
            tets.push(Element::Tetrahedron(positive_tet(complex, t)));
        }
    }
    if tets.is_empty() {
        return Err(topology_error(
            3,
            c,
            "polyhedron has no face opposite a vertex",
        ));
    }
    Ok(tets)
}

/// VTK hexahedron order: a bottom quad (0..4) whose right-hand normal points
/// into the cell, and above each bottom vertex its neighbour along a cell edge.
fn hexahedron(complex: &Complex, cycles: &[Vec<usize>]) -> Option<[usize; 8]> {
    let mut neighbours: HashMap<usize, Vec<usize>> = HashMap::new();
    for cycle in cycles {
        for k in 0..cycle.len() {
            let (a, b) = (cycle[k], cycle[(k + 1) % cycle.len()]);
            for (x, y) in [(a, b), (b, a)] {
                let list = neighbours.entry(x).or_default();
                if !list.contains(&y) {
                    list.push(y);
                }
            }
        }
    }
    let bottom = &cycles[0];
    let mut hex = [0usize; 8];
    for (k, &v) in bottom.iter().enumerate() {
        hex[k] = v;
        let up: Vec<usize> = neighbours
            .get(&v)?
            .iter()
            .copied()
            .filter(|w| !bottom.contains(w))
            .collect();
        if up.len() != 1 {
            return None;
        }
        hex[k + 4] = up[0];
    }
    let mut distinct = hex.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() != 8 {
        return None;
    }
    if hex_orientation(complex, &hex) < 0.0 {
        hex = [
            hex[0], hex[3], hex[2], hex[1], hex[4], hex[7], hex[6], hex[5],
        ];
    }
    Some(hex)
}

/// Sign of the VTK hexahedron: the bottom normal against the first rising edge.
fn hex_orientation(complex: &Complex, hex: &[usize; 8]) -> f64 {
    let p = |k: usize| point3(complex, hex[k]);
    tet_volume6(p(0), p(1), p(3), p(4))
}

fn topology_error(p: usize, cell: usize, what: &str) -> OutputError {
    OutputError::Topology {
        message: format!("{p}-cell {cell}: {what}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hasse_complex::{generate, TopCells, Vertices};

    fn shoelace(complex: &Complex, cycle: &[usize]) -> f64 {
        (0..cycle.len())
            .map(|k| {
                let a = point3(complex, cycle[k]);
                let b = point3(complex, cycle[(k + 1) % cycle.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum::<f64>()
            / 2.0
    }

    #[test]
    fn unit_quad_is_cyclic_with_positive_area() {
        let k = generate::rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let grid = grid_topology(&k, 2, Polygons::Keep).unwrap();
        assert_eq!(grid.uniform, Some(("Quadrilateral", 4)));
        let quad: Vec<usize> = grid.connectivity.iter().map(|&v| v as usize).collect();
        // Tensor order 0,1,2,3 = (0,0),(1,0),(0,1),(1,1); cyclic means the
        // diagonal pairs {0,3} and {1,2} sit at distance two in the cycle.
        let at = |v: usize| quad.iter().position(|&x| x == v).unwrap();
        assert_eq!((at(0) as i64 - at(3) as i64).abs(), 2);
        assert_eq!((at(1) as i64 - at(2) as i64).abs(), 2);
        assert!((shoelace(&k, &quad) - 1.0).abs() < 1e-12);
    }

    /// Volume of a VTK-ordered hexahedron split into the five tetrahedra of
    /// the corner decomposition, each in VTK orientation.
    fn vtk_hex_volume(p: &[[f64; 3]; 8]) -> f64 {
        let tets = [
            [0, 1, 3, 4],
            [1, 2, 3, 6],
            [1, 4, 5, 6],
            [3, 6, 7, 4],
            [1, 3, 4, 6],
        ];
        tets.iter()
            .map(|t| tet_volume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) / 6.0)
            .sum()
    }

    #[test]
    fn unit_hex_has_positive_vtk_volume() {
        let k = generate::box3(1, 1, 1, [0.0, 1.0], [0.0, 2.0], [0.0, 3.0]).unwrap();
        let grid = grid_topology(&k, 3, Polygons::Keep).unwrap();
        assert_eq!(grid.uniform, Some(("Hexahedron", 8)));
        let hex: Vec<usize> = grid.connectivity.iter().map(|&v| v as usize).collect();
        let p: [[f64; 3]; 8] = std::array::from_fn(|i| point3(&k, hex[i]));
        assert!((vtk_hex_volume(&p) - 6.0).abs() < 1e-12);
        // Each top vertex sits straight above its bottom vertex along one axis.
        for i in 0..4 {
            let d = Vector3::from(p[i + 4]) - Vector3::from(p[i]);
            assert_eq!(d.iter().filter(|x| x.abs() > 0.0).count(), 1);
        }
        // Bottom face is a cycle: consecutive vertices differ along one axis.
        for i in 0..4 {
            let d = Vector3::from(p[(i + 1) % 4]) - Vector3::from(p[i]);
            assert_eq!(d.iter().filter(|x| x.abs() > 0.0).count(), 1);
        }
    }

    #[test]
    fn mixed_polygons_use_polygon_codes() {
        // A pentagon and a triangle sharing the edge (1, 2).
        let v = Vertices::from_points(&[
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 2.0],
            [0.0, 1.0],
            [3.0, 0.5],
        ])
        .unwrap();
        let k =
            Complex::build(v, TopCells::polygons([vec![0, 1, 2, 3, 4], vec![1, 5, 2]])).unwrap();
        let grid = grid_topology(&k, 2, Polygons::Keep).unwrap();
        assert_eq!(grid.uniform, None);
        assert_eq!(grid.connectivity.len(), (2 + 5) + (1 + 3));
        let pentagon: Vec<usize> = grid.connectivity[2..7]
            .iter()
            .map(|&x| x as usize)
            .collect();
        assert_eq!(&grid.connectivity[..2], &[code::POLYGON, 5]);
        assert_eq!(grid.connectivity[7], code::TRIANGLE);
        assert!((shoelace(&k, &pentagon) - 3.0).abs() < 1e-12);
    }

    #[test]
    fn general_polyhedron_becomes_positive_tetrahedra() {
        // A triangular prism: 2 triangles, 3 quads.
        let v = Vertices::from_points(&[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
        ])
        .unwrap();
        let prism = vec![
            vec![0, 2, 1],
            vec![3, 4, 5],
            vec![0, 1, 4, 3],
            vec![1, 2, 5, 4],
            vec![2, 0, 3, 5],
        ];
        let k = Complex::build(v, TopCells::polyhedra([prism])).unwrap();
        let grid = grid_topology(&k, 3, Polygons::Keep).unwrap();
        assert_eq!(grid.uniform, Some(("Tetrahedron", 4)));
        let ids = grid.cell_ids.clone().unwrap();
        assert!(ids.iter().all(|&c| c == 0));
        let volume: f64 = grid
            .connectivity
            .chunks(4)
            .map(|t| {
                let [a, b, c, d] = [0, 1, 2, 3].map(|i| point3(&k, t[i] as usize));
                let v6 = tet_volume6(a, b, c, d);
                assert!(v6 > 0.0);
                v6 / 6.0
            })
            .sum();
        assert!((volume - 0.5).abs() < 1e-12);
    }

    #[test]
    fn hanging_vertices_are_triangulated_without_flat_triangles() {
        // The unit square with a hanging vertex in the middle of its bottom
        // and of its right side (a neighbour on each was cut): a hexagon
        // whose fan from the corner (0, 0) would hold two flat triangles.
        let v = Vertices::from_points(&[
            [0.0, 0.0],
            [0.5, 0.0],
            [1.0, 0.0],
            [1.0, 0.5],
            [1.0, 1.0],
            [0.0, 1.0],
            [2.0, 0.0],
        ])
        .unwrap();
        let k = Complex::build(
            v,
            TopCells::polygons([vec![0, 1, 2, 3, 4, 5], vec![2, 6, 3]]),
        )
        .unwrap();
        let kept = grid_topology(&k, 2, Polygons::Keep).unwrap();
        assert_eq!(&kept.connectivity[..2], &[code::POLYGON, 6]);
        assert_eq!(kept.cell_ids, None);

        let grid = grid_topology(&k, 2, Polygons::Triangulate).unwrap();
        assert_eq!(grid.uniform, Some(("Triangle", 3)));
        let ids = grid.cell_ids.clone().unwrap();
        // Four triangles for the hexagon (k − 2), one for the triangle.
        assert_eq!(ids, [0, 0, 0, 0, 1]);
        let mut used = Vec::new();
        let area: f64 = grid.connectivity[..12]
            .chunks(3)
            .map(|t| {
                let t: Vec<usize> = t.iter().map(|&v| v as usize).collect();
                let a = shoelace(&k, &t);
                assert!(a > 1e-3, "flat or clockwise triangle {t:?}: {a}");
                used.extend(t);
                a
            })
            .sum();
        assert!((area - 1.0).abs() < 1e-12);
        used.sort_unstable();
        used.dedup();
        assert_eq!(
            used,
            [0, 1, 2, 3, 4, 5],
            "every vertex of the hexagon is used"
        );
    }
}
