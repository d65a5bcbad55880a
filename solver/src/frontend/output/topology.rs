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
use rayon::prelude::*;
use sprs::{CsMat, CsVecView};
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

/// The element types a grid can have as its one XDMF type (a grid of
/// polygons is always `Mixed`: each polygon carries its vertex count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Line,
    Triangle,
    Quadrilateral,
    Tetrahedron,
    Hexahedron,
}

impl Kind {
    /// XDMF name and node count of a grid whose elements all have this kind.
    fn uniform_type(self) -> (&'static str, usize) {
        match self {
            Kind::Line => ("Polyline", 2),
            Kind::Triangle => ("Triangle", 3),
            Kind::Quadrilateral => ("Quadrilateral", 4),
            Kind::Tetrahedron => ("Tetrahedron", 4),
            Kind::Hexahedron => ("Hexahedron", 8),
        }
    }

    /// What precedes an element's vertices in an XDMF `Mixed` array: its
    /// code, and for a polyline its node count.
    fn mixed_header(self) -> &'static [i64] {
        match self {
            Kind::Line => &[code::POLYLINE, 2],
            Kind::Triangle => &[code::TRIANGLE],
            Kind::Quadrilateral => &[code::QUADRILATERAL],
            Kind::Tetrahedron => &[code::TETRAHEDRON],
            Kind::Hexahedron => &[code::HEXAHEDRON],
        }
    }
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

    /// Its kind, `None` for a polygon (which has no uniform XDMF type).
    fn kind(&self) -> Option<Kind> {
        match self {
            Element::Line(_) => Some(Kind::Line),
            Element::Triangle(_) => Some(Kind::Triangle),
            Element::Quadrilateral(_) => Some(Kind::Quadrilateral),
            Element::Polygon(_) => None,
            Element::Tetrahedron(_) => Some(Kind::Tetrahedron),
            Element::Hexahedron(_) => Some(Kind::Hexahedron),
        }
    }

    /// Append this element to an XDMF `Mixed` array: code, (count,) vertices.
    fn push_mixed(&self, out: &mut Vec<i64>) {
        let v = self.vertices();
        match self.kind() {
            Some(kind) => out.extend_from_slice(kind.mixed_header()),
            None => out.extend([code::POLYGON, v.len() as i64]),
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
    /// The grid of the elements of `runs`, consecutive runs of cells in
    /// increasing order: uniform when every element has the same kind.
    fn from_runs(degree: usize, mut runs: Vec<Elements>) -> Self {
        let mut kinds =
            runs.iter()
                .filter(|r| !r.cells.is_empty())
                .map(|r| if r.mixed { None } else { r.kind });
        let kind = match kinds.next() {
            Some(Some(first)) if kinds.all(|k| k == Some(first)) => Some(first),
            _ => None,
        };
        if kind.is_none() {
            for run in &mut runs {
                run.make_mixed();
            }
        }
        let element_count = runs.iter().map(|r| r.cells.len()).sum();
        let identity = runs
            .iter()
            .flat_map(|r| &r.cells)
            .enumerate()
            .all(|(k, &cell)| k as u64 == cell);
        let cell_ids =
            (!identity).then(|| runs.iter().flat_map(|r| r.cells.iter().copied()).collect());
        let mut connectivity = Vec::with_capacity(runs.iter().map(|r| r.connectivity.len()).sum());
        for run in runs {
            connectivity.extend_from_slice(&run.connectivity);
        }
        GridTopology {
            degree,
            uniform: kind.map(Kind::uniform_type),
            connectivity,
            element_count,
            cell_ids,
        }
    }
}

/// The elements of a run of consecutive cells, as one task builds them:
/// a uniform array while every element has one kind, a `Mixed` one after.
#[derive(Default)]
struct Elements {
    /// The kind of every element so far, while not `mixed`; `None` while empty.
    kind: Option<Kind>,
    /// Whether `connectivity` is an XDMF `Mixed` array.
    mixed: bool,
    connectivity: Vec<i64>,
    /// The cell of each element.
    cells: Vec<u64>,
}

impl Elements {
    fn push(&mut self, cell: usize, element: &Element) {
        if !self.mixed {
            match (self.kind, element.kind()) {
                (None, Some(kind)) if self.cells.is_empty() => self.kind = Some(kind),
                (Some(kind), Some(other)) if kind == other => {}
                _ => self.make_mixed(),
            }
        }
        self.cells.push(cell as u64);
        if self.mixed {
            element.push_mixed(&mut self.connectivity);
        } else {
            let v = element.vertices();
            self.connectivity.extend(v.iter().map(|&x| x as i64));
        }
    }

    /// Rewrite a uniform array as a `Mixed` one (once two kinds meet, in a
    /// run or between runs).
    fn make_mixed(&mut self) {
        if self.mixed {
            return;
        }
        self.mixed = true;
        let Some(kind) = self.kind else {
            return;
        };
        let (_, nodes) = kind.uniform_type();
        let header = kind.mixed_header();
        let mut mixed = Vec::with_capacity(self.cells.len() * (nodes + header.len()));
        for element in self.connectivity.chunks(nodes) {
            mixed.extend_from_slice(header);
            mixed.extend_from_slice(element);
        }
        self.connectivity = mixed;
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

/// Cells per parallel task: enough that a task's buffers and scheduling
/// cost nothing against its work, few enough that the tasks of a grid of
/// 10⁴ cells already spread over the cores.
const TASK_CELLS: usize = 1 << 11;

/// Build the grid of the p-cells of `complex` (1 ≤ p ≤ dim), with its
/// polygons of five or more vertices written as `polygons` says.
///
/// Each cell's elements depend on that cell alone, so runs of cells are
/// built in parallel (at 10⁶ hexahedra this is most of the output's work)
/// and joined in cell order; the error reported is that of the first bad
/// cell, as a serial pass would find it.
pub(crate) fn grid_topology(
    complex: &Complex,
    p: usize,
    polygons: Polygons,
) -> Result<GridTopology, OutputError> {
    if !(1..=3).contains(&p) {
        return Err(OutputError::Topology {
            message: format!("no XDMF grid for cells of dimension {p}"),
        });
    }
    let columns = Columns::of(complex);
    let count = complex.cell_count(p);
    let runs: Vec<Result<Elements, OutputError>> = (0..count.div_ceil(TASK_CELLS))
        .into_par_iter()
        .map(|task| {
            let mut run = Elements::default();
            let mut scratch = Scratch::default();
            for c in task * TASK_CELLS..count.min((task + 1) * TASK_CELLS) {
                columns.push_cell(p, c, polygons, &mut scratch, &mut run)?;
            }
            Ok(run)
        })
        .collect();
    let runs = runs.into_iter().collect::<Result<Vec<_>, _>>()?;
    Ok(GridTopology::from_runs(p, runs))
}

/// Buffers of one task, reused from cell to cell.
#[derive(Default)]
struct Scratch {
    /// A face's oriented edges, (tail, head).
    pairs: Vec<(usize, usize)>,
    /// A face's vertex cycle.
    cycle: Vec<usize>,
    /// The cycles of a 3-cell's faces, one after the other …
    cycles: Vec<usize>,
    /// … face k's being `cycles[starts[k]..starts[k + 1]]`.
    starts: Vec<usize>,
}

/// Faces with more edges than this chain them through a hash map; up to
/// it a scan of the (tail, head) pairs is faster and allocates nothing.
const LINEAR_EDGES: usize = 16;

/// The complex with its boundary matrices by columns (cell → facets),
/// looked up once per grid instead of once per cell.
struct Columns<'a> {
    complex: &'a Complex,
    /// ∂_1, ∂_2, ∂_3 in CSC, where the complex has them.
    d: [Option<&'a CsMat<i8>>; 3],
}

impl<'a> Columns<'a> {
    fn of(complex: &'a Complex) -> Self {
        let d = |p: usize| complex.try_boundary_csc(p).ok().map(|m| &**m);
        Columns {
            complex,
            d: [d(1), d(2), d(3)],
        }
    }

    /// The facets of p-cell `c` with their signs.
    fn column(&self, p: usize, c: usize, what: &str) -> Result<CsVecView<'a, i8>, OutputError> {
        self.d[p - 1]
            .and_then(|d| d.outer_view(c))
            .ok_or_else(|| topology_error(p, c, what))
    }

    /// Append the elements of p-cell `c` to `out`.
    fn push_cell(
        &self,
        p: usize,
        c: usize,
        polygons: Polygons,
        scratch: &mut Scratch,
        out: &mut Elements,
    ) -> Result<(), OutputError> {
        match p {
            1 => {
                let (tail, head) = self.edge_ends(c)?;
                out.push(c, &Element::Line([tail, head]));
            }
            2 => {
                self.face_cycle(c, &mut scratch.pairs, &mut scratch.cycle)?;
                let cycle = &scratch.cycle;
                if polygons == Polygons::Triangulate && cycle.len() > 4 {
                    let triangles = fan_triangles(self.complex, cycle);
                    if triangles.is_empty() {
                        return Err(topology_error(2, c, "polygon has zero area"));
                    }
                    for t in triangles {
                        out.push(c, &Element::Triangle(t));
                    }
                } else {
                    out.push(c, &polygon_element(cycle));
                }
            }
            _ => self.solid_elements(c, scratch, out)?,
        }
        Ok(())
    }

    /// Tail and head of edge `e` as ∂_1 orients it.
    fn edge_ends(&self, e: usize) -> Result<(usize, usize), OutputError> {
        let column = self.column(1, e, "edge missing from ∂_1")?;
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

    /// Vertices of 2-cell `f` into `cycle`, in the cyclic order of its
    /// orientation from its lowest vertex; `pairs` is scratch.
    fn face_cycle(
        &self,
        f: usize,
        pairs: &mut Vec<(usize, usize)>,
        cycle: &mut Vec<usize>,
    ) -> Result<(), OutputError> {
        let not_a_cycle = || topology_error(2, f, "boundary edges do not form one cycle");
        let column = self.column(2, f, "face missing from ∂_2")?;
        let mut next = (column.nnz() > LINEAR_EDGES).then(|| HashMap::with_capacity(column.nnz()));
        pairs.clear();
        let mut start = None;
        for (e, &s) in column.iter() {
            let (t, h) = self.edge_ends(e)?;
            let (from, to) = if s > 0 { (t, h) } else { (h, t) };
            let repeated = match &mut next {
                Some(next) => next.insert(from, to).is_some(),
                None => pairs.iter().any(|&(a, _)| a == from),
            };
            if repeated {
                return Err(not_a_cycle());
            }
            pairs.push((from, to));
            start = Some(start.map_or(from, |s: usize| s.min(from)));
        }
        let start = start.ok_or_else(|| topology_error(2, f, "face has no edges"))?;
        cycle.clear();
        let mut v = start;
        for _ in 0..pairs.len() {
            cycle.push(v);
            let to = match &next {
                Some(next) => next.get(&v).copied(),
                None => pairs.iter().find(|&&(a, _)| a == v).map(|&(_, b)| b),
            };
            v = to.ok_or_else(not_a_cycle)?;
        }
        if v != start {
            return Err(not_a_cycle());
        }
        Ok(())
    }

    /// The elements one 3-cell is written as: a tetrahedron, a hexahedron,
    /// or (any other convex polyhedron) a fan of tetrahedra from its lowest
    /// vertex.
    fn solid_elements(
        &self,
        c: usize,
        s: &mut Scratch,
        out: &mut Elements,
    ) -> Result<(), OutputError> {
        let complex = self.complex;
        let vertices = complex.cell_vertices(3, c);
        let column = self.column(3, c, "cell missing from ∂_3")?;
        let faces = column.indices();
        if vertices.len() == 4 && faces.len() == 4 {
            let t = [vertices[0], vertices[1], vertices[2], vertices[3]];
            out.push(c, &Element::Tetrahedron(positive_tet(complex, t)));
            return Ok(());
        }
        s.cycles.clear();
        s.starts.clear();
        for &f in faces {
            self.face_cycle(f, &mut s.pairs, &mut s.cycle)?;
            s.starts.push(s.cycles.len());
            s.cycles.extend_from_slice(&s.cycle);
        }
        s.starts.push(s.cycles.len());
        let cycle = |k: usize| &s.cycles[s.starts[k]..s.starts[k + 1]];
        let quads = faces.len() == 6 && (0..6).all(|k| cycle(k).len() == 4);
        if vertices.len() == 8 && quads {
            if let Some(hex) = hexahedron(complex, &s.cycles) {
                out.push(c, &Element::Hexahedron(hex));
                return Ok(());
            }
        }
        // A convex polyhedron is the union of the cones from one of its vertices
        // over the faces that do not contain it; fanning those faces gives
        // tetrahedra without adding points, which every reader understands.
        let apex = vertices[0];
        let before = out.cells.len();
        for k in 0..faces.len() {
            let face = cycle(k);
            if face.contains(&apex) {
                continue;
            }
            for j in 1..face.len().saturating_sub(1) {
                let t = [apex, face[0], face[j], face[j + 1]];
                out.push(c, &Element::Tetrahedron(positive_tet(complex, t)));
            }
        }
        if out.cells.len() == before {
            return Err(topology_error(
                3,
                c,
                "polyhedron has no face opposite a vertex",
            ));
        }
        Ok(())
    }
}

fn polygon_element(cycle: &[usize]) -> Element {
    match cycle.len() {
        3 => Element::Triangle([cycle[0], cycle[1], cycle[2]]),
        4 => Element::Quadrilateral([cycle[0], cycle[1], cycle[2], cycle[3]]),
        _ => Element::Polygon(cycle.to_vec()),
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

/// VTK hexahedron order from the vertex cycles of a hexahedron's six
/// quadrilateral faces (`quads`, four after four): a bottom quad (0..4)
/// whose right-hand normal points into the cell, and above each bottom
/// vertex its one neighbour along a cell edge that is not on the bottom.
fn hexahedron(complex: &Complex, quads: &[usize]) -> Option<[usize; 8]> {
    let bottom = &quads[..4];
    let mut hex = [0usize; 8];
    for (k, &v) in bottom.iter().enumerate() {
        hex[k] = v;
        let mut up = None;
        for quad in quads.chunks(4) {
            for i in 0..quad.len() {
                let (a, b) = (quad[i], quad[(i + 1) % quad.len()]);
                let w = match (a == v, b == v) {
                    (true, _) => b,
                    (_, true) => a,
                    _ => continue,
                };
                if bottom.contains(&w) {
                    continue;
                }
                match up {
                    None => up = Some(w),
                    Some(u) if u == w => {}
                    Some(_) => return None,
                }
            }
        }
        hex[k + 4] = up?;
    }
    let mut distinct = hex;
    distinct.sort_unstable();
    if distinct.windows(2).any(|w| w[0] == w[1]) {
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
mod tests;
