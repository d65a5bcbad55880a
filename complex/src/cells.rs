//! Input of a complex: vertex coordinates and top cells, and the facet
//! extraction that turns top cells into every lower-dimensional cell.
//!
//! A top cell is a vertex list read according to its [`Shape`]:
//! simplices (any order; orientation comes from sorted vertex order),
//! cuboids (vertices in tensor order: local vertex `i` sits at offset
//! `bit a of i` along local axis `a`, as in LAR's cuboidal grids), convex
//! polygons (cyclic order) and convex polyhedra (a list of cyclic faces).
//! Facets of each shape are generated combinatorially; identical facets
//! coming from neighbouring cells are merged by their vertex sets.

use crate::error::{ComplexError, Result};
use crate::lar::{characteristic_matrix, widen};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sprs::CsMat;

/// Vertex coordinates: `len()` points in R^`dim()`, stored row by row.
///
/// ```
/// use hasse_complex::Vertices;
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
/// assert_eq!((v.len(), v.dim()), (3, 2));
/// assert_eq!(v.point(1), &[1.0, 0.0]);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Vertices {
    dim: usize,
    coords: Vec<f64>,
    /// Periods of a flat torus, per axis (0: not periodic); `None` for
    /// the ordinary, non-periodic embedding. See [`Vertices::with_period`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) period: Option<[f64; 3]>,
}

impl Vertices {
    /// Points of dimension `dim` (1, 2 or 3) from a flat row-major array.
    /// Non-finite coordinates are rejected with the vertex and axis named.
    pub fn new(dim: usize, coords: Vec<f64>) -> Result<Self> {
        if !(1..=3).contains(&dim) {
            return Err(ComplexError::UnsupportedEmbedding(dim));
        }
        if coords.is_empty() {
            return Err(ComplexError::NoVertices);
        }
        if coords.len() % dim != 0 {
            return Err(ComplexError::CoordinateShape {
                len: coords.len(),
                dim,
            });
        }
        if let Some(i) = coords.iter().position(|c| !c.is_finite()) {
            return Err(ComplexError::NonFiniteCoordinate {
                vertex: i / dim,
                axis: i % dim,
                value: coords[i],
            });
        }
        Ok(Self {
            dim,
            coords,
            period: None,
        })
    }

    /// Points from fixed-size arrays.
    pub fn from_points<const D: usize>(points: &[[f64; D]]) -> Result<Self> {
        Self::new(D, points.iter().flatten().copied().collect())
    }

    /// Dimension of the space the vertices live in.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.coords.len() / self.dim
    }

    /// Always false for a constructed value (at least one vertex is required).
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// Coordinates of vertex `i`.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.coords[i * self.dim..(i + 1) * self.dim]
    }

    /// All coordinates, row-major.
    pub fn as_slice(&self) -> &[f64] {
        &self.coords
    }

    /// Mutable coordinates (row-major); used by mesh perturbation.
    pub(crate) fn as_mut_slice(&mut self) -> &mut [f64] {
        &mut self.coords
    }
}

/// How the vertex list of a cell is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Shape {
    /// p+1 vertices in any order.
    Simplex,
    /// 2^p vertices in tensor order (bit `a` of the local index = side along axis `a`).
    Cuboid,
    /// A convex polygon, vertices in cyclic order.
    Polygon,
    /// A convex polyhedron; its vertex list encodes faces as
    /// `[face_count, len_0, v.., len_1, v.., ...]`, each face cyclic.
    Polyhedron,
}

/// Cells of one dimension given by shape and vertex list, stored flat.
///
/// ```
/// use hasse_complex::TopCells;
/// let mut cells = TopCells::default();
/// cells.push_simplex(&[0, 1, 2]);
/// cells.push_polygon(&[1, 3, 4, 2]);
/// assert_eq!(cells.len(), 2);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TopCells {
    shapes: Vec<Shape>,
    offsets: Vec<usize>,
    vertices: Vec<u32>,
}

impl TopCells {
    /// Simplices, each a list of p+1 vertex indices.
    pub fn simplices<C: AsRef<[usize]>>(cells: impl IntoIterator<Item = C>) -> Self {
        Self::collect(cells, Self::push_simplex)
    }

    /// Cuboids (segments, quads, hexes), each 2^p vertices in tensor order.
    pub fn cuboids<C: AsRef<[usize]>>(cells: impl IntoIterator<Item = C>) -> Self {
        Self::collect(cells, Self::push_cuboid)
    }

    /// Convex polygons in cyclic vertex order.
    pub fn polygons<C: AsRef<[usize]>>(cells: impl IntoIterator<Item = C>) -> Self {
        Self::collect(cells, Self::push_polygon)
    }

    /// Convex polyhedra, each a list of faces in cyclic vertex order.
    pub fn polyhedra<F: AsRef<[Vec<usize>]>>(cells: impl IntoIterator<Item = F>) -> Self {
        let mut out = Self::default();
        for c in cells {
            out.push_polyhedron(c.as_ref());
        }
        out
    }

    /// Cells pushed one by one, the lists reserved from the iterator's
    /// length hint and the first cell's size.
    fn collect<C: AsRef<[usize]>>(
        cells: impl IntoIterator<Item = C>,
        push: fn(&mut Self, &[usize]),
    ) -> Self {
        let mut out = Self::default();
        let cells = cells.into_iter();
        let count = cells.size_hint().0;
        out.shapes.reserve(count);
        out.offsets.reserve(count + 1);
        for (k, c) in cells.enumerate() {
            if k == 0 {
                out.vertices.reserve(count.saturating_mul(c.as_ref().len()));
            }
            push(&mut out, c.as_ref());
        }
        out
    }

    fn push_raw(&mut self, shape: Shape, vertices: impl IntoIterator<Item = u32>) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.shapes.push(shape);
        self.vertices.extend(vertices);
        self.offsets.push(self.vertices.len());
    }

    fn push_vertices(&mut self, shape: Shape, vertices: &[usize]) {
        // Indices beyond u32 are clamped to u32::MAX, which validation reports
        // as out of range (no mesh here has 4 billion vertices).
        self.push_raw(
            shape,
            vertices
                .iter()
                .map(|&v| u32::try_from(v).unwrap_or(u32::MAX)),
        );
    }

    /// Append a simplex.
    pub fn push_simplex(&mut self, vertices: &[usize]) {
        self.push_vertices(Shape::Simplex, vertices);
    }

    /// Append a cuboid (tensor vertex order).
    pub fn push_cuboid(&mut self, vertices: &[usize]) {
        self.push_vertices(Shape::Cuboid, vertices);
    }

    /// Append a convex polygon (cyclic vertex order).
    pub fn push_polygon(&mut self, vertices: &[usize]) {
        self.push_vertices(Shape::Polygon, vertices);
    }

    /// Append a convex polyhedron given by its faces (each cyclic).
    pub fn push_polyhedron(&mut self, faces: &[Vec<usize>]) {
        let clamp = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        let mut encoded = vec![clamp(faces.len())];
        for f in faces {
            encoded.push(clamp(f.len()));
            encoded.extend(f.iter().map(|&v| clamp(v)));
        }
        self.push_raw(Shape::Polyhedron, encoded);
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// True when no cell has been added.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Shape of cell `i`.
    pub fn shape(&self, i: usize) -> Shape {
        self.shapes[i]
    }

    /// Raw vertex list of cell `i` (for polyhedra, the face encoding).
    pub fn raw_vertices(&self, i: usize) -> &[u32] {
        &self.vertices[self.offsets[i]..self.offsets[i + 1]]
    }

    /// The distinct vertices of cell `i`, sorted: row `i` of the characteristic matrix.
    pub fn vertex_set(&self, i: usize) -> Vec<u32> {
        let mut set = match self.shapes[i] {
            Shape::Polyhedron => polyhedron_faces(self.raw_vertices(i))
                .into_iter()
                .flatten()
                .copied()
                .collect(),
            _ => self.raw_vertices(i).to_vec(),
        };
        set.sort_unstable();
        set.dedup();
        set
    }

    /// Check every cell against the vertex count and its shape, and return the
    /// common cell dimension.
    pub(crate) fn validate(&self, vertex_count: usize) -> Result<usize> {
        if let Some(dim) = self.quick_validate(vertex_count) {
            return Ok(dim);
        }
        if self.is_empty() {
            return Err(ComplexError::NoCells);
        }
        let mut dim = None;
        for i in 0..self.len() {
            let raw = self.raw_vertices(i);
            let listed: Vec<u32> = match self.shapes[i] {
                Shape::Polyhedron => {
                    let faces = checked_polyhedron_faces(raw).ok_or_else(|| {
                        ComplexError::Invalid(format!(
                            "top cell {i}: polyhedron face list is malformed (face lengths do not add up)"
                        ))
                    })?;
                    if faces.len() < 4 || faces.iter().any(|f| f.len() < 3) {
                        return Err(ComplexError::WrongVertexCount {
                            cell: i,
                            shape: "polyhedron",
                            expected: "at least 4 faces of at least 3 vertices".into(),
                            found: faces.len(),
                        });
                    }
                    for f in &faces {
                        check_repeats(i, f)?;
                    }
                    faces.into_iter().flatten().copied().collect()
                }
                _ => {
                    check_repeats(i, raw)?;
                    raw.to_vec()
                }
            };
            if let Some(&v) = listed.iter().find(|&&v| v as usize >= vertex_count) {
                return Err(ComplexError::VertexOutOfRange {
                    cell: i,
                    vertex: v as usize,
                    vertex_count,
                });
            }
            let n = raw.len();
            let cell_dim = match self.shapes[i] {
                Shape::Simplex => {
                    if n < 2 {
                        return Err(ComplexError::WrongVertexCount {
                            cell: i,
                            shape: "simplex",
                            expected: "at least 2 (an edge)".into(),
                            found: n,
                        });
                    }
                    n - 1
                }
                Shape::Cuboid => {
                    if !matches!(n, 2 | 4 | 8) {
                        return Err(ComplexError::WrongVertexCount {
                            cell: i,
                            shape: "cuboid",
                            expected: "2, 4 or 8".into(),
                            found: n,
                        });
                    }
                    n.trailing_zeros() as usize
                }
                Shape::Polygon => {
                    if n < 3 {
                        return Err(ComplexError::WrongVertexCount {
                            cell: i,
                            shape: "polygon",
                            expected: "at least 3".into(),
                            found: n,
                        });
                    }
                    2
                }
                Shape::Polyhedron => 3,
            };
            match dim {
                None => dim = Some(cell_dim),
                Some(d) if d != cell_dim => {
                    return Err(ComplexError::MixedDimension {
                        cell: i,
                        expected: d,
                        found: cell_dim,
                    })
                }
                _ => {}
            }
        }
        dim.ok_or(ComplexError::NoCells)
    }

    /// The common dimension when every cell is valid and no cell is a
    /// polyhedron or has more than 8 vertices: checked in parallel and
    /// without allocating. `None` sends [`TopCells::validate`] to the full
    /// check, which names the first offending cell.
    fn quick_validate(&self, vertex_count: usize) -> Option<usize> {
        if self.is_empty() || self.shapes.contains(&Shape::Polyhedron) {
            return None;
        }
        let dim_of = |i: usize| -> Option<usize> {
            let raw = self.raw_vertices(i);
            let n = raw.len();
            if n > 8 || raw.iter().any(|&v| v as usize >= vertex_count) {
                return None;
            }
            let mut buffer = [0u32; 8];
            let sorted = &mut buffer[..n];
            sorted.copy_from_slice(raw);
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[0] == w[1]) {
                return None;
            }
            match self.shapes[i] {
                Shape::Simplex if n >= 2 => Some(n - 1),
                Shape::Cuboid if matches!(n, 2 | 4 | 8) => Some(n.trailing_zeros() as usize),
                Shape::Polygon if n >= 3 => Some(2),
                _ => None,
            }
        };
        let dim = dim_of(0)?;
        (0..self.len())
            .into_par_iter()
            .with_min_len(4096)
            .all(|i| dim_of(i) == Some(dim))
            .then_some(dim)
    }

    /// The common length of the facets of cell `i` (`None` for polyhedra,
    /// whose faces may differ).
    fn facet_len(&self, i: usize) -> Option<usize> {
        let n = self.raw_vertices(i).len();
        match self.shapes[i] {
            Shape::Simplex => Some(n.saturating_sub(1)),
            Shape::Cuboid => Some(n / 2),
            Shape::Polygon => Some(2),
            Shape::Polyhedron => None,
        }
    }

    /// Number of facets of cell `i` and the total length of their vertex
    /// lists, as [`TopCells::push_facets`] writes them.
    fn facet_sizes(&self, i: usize) -> (usize, usize) {
        let n = self.raw_vertices(i).len();
        match self.shapes[i] {
            Shape::Simplex => (n, n * n.saturating_sub(1)),
            // 2p facets of 2^(p−1) vertices each.
            Shape::Cuboid => {
                let p = n.trailing_zeros() as usize;
                (2 * p, p * n)
            }
            Shape::Polygon => (n, 2 * n),
            Shape::Polyhedron => {
                let faces = polyhedron_faces(self.raw_vertices(i));
                (faces.len(), faces.iter().map(|f| f.len()).sum())
            }
        }
    }

    /// Facets of cell `i`, appended to `out` as cells one dimension lower.
    fn push_facets(&self, i: usize, out: &mut TopCells) {
        let raw = self.raw_vertices(i);
        match self.shapes[i] {
            Shape::Simplex => {
                // At most 4 vertices below the top of a 3-complex; the stack
                // copy avoids an allocation per cell.
                let mut buffer = [0u32; 8];
                let mut heap;
                let sorted: &mut [u32] = if raw.len() <= buffer.len() {
                    buffer[..raw.len()].copy_from_slice(raw);
                    &mut buffer[..raw.len()]
                } else {
                    heap = raw.to_vec();
                    &mut heap
                };
                sorted.sort_unstable();
                let sorted = &*sorted;
                for skip in 0..sorted.len() {
                    out.push_raw(
                        Shape::Simplex,
                        sorted
                            .iter()
                            .enumerate()
                            .filter(|&(k, _)| k != skip)
                            .map(|(_, &v)| v),
                    );
                }
            }
            Shape::Cuboid => {
                let p = raw.len().trailing_zeros() as usize;
                let shape = if p == 2 {
                    Shape::Simplex
                } else {
                    Shape::Cuboid
                };
                for axis in 0..p {
                    for side in 0..2 {
                        out.push_raw(
                            shape,
                            (0..raw.len())
                                .filter(|local| (local >> axis) & 1 == side)
                                .map(|local| raw[local]),
                        );
                    }
                }
            }
            Shape::Polygon => {
                for k in 0..raw.len() {
                    let (a, b) = (raw[k], raw[(k + 1) % raw.len()]);
                    out.push_raw(Shape::Simplex, [a.min(b), a.max(b)]);
                }
            }
            Shape::Polyhedron => {
                for face in polyhedron_faces(raw) {
                    let shape = if face.len() == 3 {
                        Shape::Simplex
                    } else {
                        Shape::Polygon
                    };
                    out.push_raw(shape, face.iter().copied());
                }
            }
        }
    }
}

fn check_repeats(cell: usize, vertices: &[u32]) -> Result<()> {
    let mut sorted = vertices.to_vec();
    sorted.sort_unstable();
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return Err(ComplexError::RepeatedVertex {
            cell,
            vertex: w[0] as usize,
        });
    }
    Ok(())
}

/// Decode the face lists of a polyhedron, or `None` when the encoding is inconsistent.
fn checked_polyhedron_faces(raw: &[u32]) -> Option<Vec<&[u32]>> {
    let (&count, mut rest) = raw.split_first()?;
    let mut faces = Vec::with_capacity(count as usize);
    for _ in 0..count {
        let (&len, tail) = rest.split_first()?;
        let len = len as usize;
        if tail.len() < len {
            return None;
        }
        faces.push(&tail[..len]);
        rest = &tail[len..];
    }
    rest.is_empty().then_some(faces)
}

fn polyhedron_faces(raw: &[u32]) -> Vec<&[u32]> {
    // Only called on validated cells.
    checked_polyhedron_faces(raw).unwrap_or_default()
}

/// Cells of one dimension after merging: the sorted vertex set of each
/// (one row of the characteristic matrix) and the description it was first
/// produced with (needed to extract its own facets).
pub(crate) struct ExtractedLevel {
    pub cells: TopCells,
    pub sets: FlatSets,
}

/// Sorted vertex sets stored flat: set i is `vertices[offsets[i]..offsets[i + 1]]`.
#[derive(Default)]
pub(crate) struct FlatSets {
    pub offsets: Vec<usize>,
    pub vertices: Vec<u32>,
}

impl FlatSets {
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    #[cfg(test)]
    pub fn get(&self, i: usize) -> &[u32] {
        &self.vertices[self.offsets[i]..self.offsets[i + 1]]
    }
}

/// The characteristic matrix M_p of the cells themselves (their sorted
/// vertex sets as rows), sorted and widened in one parallel pass.
pub(crate) fn top_characteristic(cells: &TopCells, vertex_count: usize) -> CsMat<u8> {
    if cells.shapes.contains(&Shape::Polyhedron) || cells.offsets.is_empty() {
        return characteristic_matrix(vertex_sets(cells), vertex_count);
    }
    let indices = widen(&cells.offsets, &cells.vertices, true);
    let nnz = indices.len();
    // Rows are sorted by `widen` and in range after validation.
    CsMat::new(
        (cells.len(), vertex_count),
        cells.offsets.clone(),
        indices,
        vec![1u8; nnz],
    )
}

/// The sorted vertex sets of every cell, without a heap allocation per
/// cell (polyhedra, whose lists encode faces, are the exception).
pub(crate) fn vertex_sets(cells: &TopCells) -> FlatSets {
    if cells.shapes.contains(&Shape::Polyhedron) {
        let mut sets = FlatSets {
            offsets: vec![0],
            vertices: Vec::new(),
        };
        for i in 0..cells.len() {
            sets.vertices.extend(cells.vertex_set(i));
            sets.offsets.push(sets.vertices.len());
        }
        return sets;
    }
    let mut vertices = cells.vertices.clone();
    let offsets = if cells.offsets.is_empty() {
        vec![0]
    } else {
        cells.offsets.clone()
    };
    // Cells are small; sorting each in place is cheaper than spawning tasks.
    for w in offsets.windows(2) {
        vertices[w[0]..w[1]].sort_unstable();
    }
    FlatSets { offsets, vertices }
}

/// Orders vertex sets lexicographically, a proper prefix after its
/// extensions (as if padded with `u32::MAX`); this fixes the numbering of
/// every extracted cell independently of how cells were traversed.
fn compare_sets(a: &[u32], b: &[u32]) -> std::cmp::Ordering {
    for (x, y) in a.iter().zip(b) {
        match x.cmp(y) {
            std::cmp::Ordering::Equal => {}
            other => return other,
        }
    }
    b.len().cmp(&a.len())
}

/// Extract, merge and number the facets of `cells` (all of dimension p ≥ 2).
/// With `keep_cells` false only the vertex sets are produced (`cells` of
/// the result is empty): the lowest extracted level needs no facets of its
/// own.
///
/// The facets of every cell are written, chunk by chunk in parallel, into
/// one flat candidate list (raw vertices, sorted vertex set, shape), sized
/// beforehand so nothing is concatenated or regrown. Candidates are then
/// bucketed by their smallest vertex (counting sort, stable) and each bucket
/// is sorted by vertex set, ties by candidate number, which is the order of
/// [`compare_sets`] over the whole list; the first candidate of each run of
/// equal sets is the extracted cell. Buckets are independent, so sorting,
/// counting and writing the unique cells run in parallel over groups of
/// buckets.
pub(crate) fn extract_facets(cells: &TopCells, keep_cells: bool) -> ExtractedLevel {
    const CHUNK: usize = 4096;
    let chunks = cells.len().div_ceil(CHUNK);
    let chunk_range = |c: usize| c * CHUNK..((c + 1) * CHUNK).min(cells.len());
    // Facet and vertex-slot counts per chunk, then their prefix sums.
    let sizes: Vec<(usize, usize)> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            chunk_range(c)
                .map(|i| cells.facet_sizes(i))
                .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
        })
        .collect();
    let facet_total: usize = sizes.iter().map(|s| s.0).sum();
    let slot_total: usize = sizes.iter().map(|s| s.1).sum();
    // When every facet has the same length (simplices, cuboids, polygons:
    // the usual meshes) candidate c sits at c·len and no offsets are kept.
    let first_len = (!cells.is_empty()).then(|| cells.facet_len(0)).flatten();
    let fixed = first_len.filter(|&len| {
        (0..cells.len())
            .into_par_iter()
            .with_min_len(4096)
            .all(|i| cells.facet_len(i) == Some(len))
    });
    let offset_count = if fixed.is_some() { 0 } else { facet_total };
    let mut offsets = vec![0usize; if fixed.is_some() { 0 } else { facet_total + 1 }];
    let mut sorted = vec![0u32; slot_total];
    let mut shapes = vec![Shape::Simplex; if keep_cells { facet_total } else { 0 }];
    let mut raw = vec![0u32; if keep_cells { slot_total } else { 0 }];
    {
        let mut jobs = Vec::with_capacity(chunks);
        let (mut o_rest, mut s_rest) = (&mut offsets[..offset_count], sorted.as_mut_slice());
        let (mut h_rest, mut r_rest) = (shapes.as_mut_slice(), raw.as_mut_slice());
        let mut slot_base = 0;
        for (c, &(nf, nv)) in sizes.iter().enumerate() {
            let (o, o_tail) = o_rest.split_at_mut(if fixed.is_some() { 0 } else { nf });
            let (s, s_tail) = s_rest.split_at_mut(nv);
            let (h, h_tail) = h_rest.split_at_mut(if keep_cells { nf } else { 0 });
            let (r, r_tail) = r_rest.split_at_mut(if keep_cells { nv } else { 0 });
            (o_rest, s_rest, h_rest, r_rest) = (o_tail, s_tail, h_tail, r_tail);
            jobs.push((c, slot_base, o, s, h, r));
            slot_base += nv;
        }
        jobs.into_par_iter().for_each_init(
            TopCells::default,
            |out, (c, slot_base, offsets, sorted, shapes, raw)| {
                out.shapes.clear();
                out.offsets.clear();
                out.vertices.clear();
                for i in chunk_range(c) {
                    cells.push_facets(i, out);
                }
                for (f, w) in out.offsets.windows(2).enumerate() {
                    if fixed.is_none() {
                        offsets[f] = slot_base + w[0];
                    }
                    let set = &mut sorted[w[0]..w[1]];
                    set.copy_from_slice(&out.vertices[w[0]..w[1]]);
                    set.sort_unstable();
                }
                if keep_cells {
                    shapes.copy_from_slice(&out.shapes);
                    raw.copy_from_slice(&out.vertices);
                }
            },
        );
    }
    if fixed.is_none() {
        offsets[facet_total] = slot_total;
    }
    let span = |c: usize| match fixed {
        Some(len) => c * len..(c + 1) * len,
        None => offsets[c]..offsets[c + 1],
    };
    let set = |c: usize| &sorted[span(c)];

    // Counting sort by smallest vertex.
    let bound = sorted
        .par_iter()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let mut start = vec![0usize; bound + 1];
    for c in 0..facet_total {
        start[set(c)[0] as usize + 1] += 1;
    }
    for v in 0..bound {
        start[v + 1] += start[v];
    }
    let mut order = vec![0u32; facet_total];
    {
        let mut next = start.clone();
        for c in 0..facet_total {
            let v = set(c)[0] as usize;
            order[next[v]] = c as u32;
            next[v] += 1;
        }
    }

    // Groups of consecutive buckets: sort each bucket, count unique sets.
    const GROUP: usize = 2048;
    let groups = bound.div_ceil(GROUP);
    let group_buckets = |g: usize| g * GROUP..((g + 1) * GROUP).min(bound);
    let same = |a: u32, b: u32| set(a as usize) == set(b as usize);
    let mut group_slices: Vec<(usize, &mut [u32])> = Vec::with_capacity(groups);
    let mut rest = order.as_mut_slice();
    for g in 0..groups {
        let r = group_buckets(g);
        let (slice, tail) = rest.split_at_mut(start[r.end] - start[r.start]);
        group_slices.push((g, slice));
        rest = tail;
    }
    let unique_sizes: Vec<(usize, usize)> = group_slices
        .into_par_iter()
        .map(|(g, slice)| {
            let first = start[group_buckets(g).start];
            let mut count = (0, 0);
            for v in group_buckets(g) {
                let bucket = &mut slice[start[v] - first..start[v + 1] - first];
                // Already in candidate order (the counting sort is stable):
                // a stable sort by set alone breaks ties by candidate number.
                bucket.sort_by(|&a, &b| compare_sets(set(a as usize), set(b as usize)));
                for (k, &c) in bucket.iter().enumerate() {
                    if k == 0 || !same(bucket[k - 1], c) {
                        count.0 += 1;
                        count.1 += set(c as usize).len();
                    }
                }
            }
            count
        })
        .collect();

    // Write the unique cells, group by group.
    let unique_total: usize = unique_sizes.iter().map(|s| s.0).sum();
    let unique_slots: usize = unique_sizes.iter().map(|s| s.1).sum();
    let mut unique = FlatSets {
        offsets: vec![0usize; unique_total + 1],
        vertices: vec![0u32; unique_slots],
    };
    let mut level = TopCells::default();
    if keep_cells {
        level.shapes = vec![Shape::Simplex; unique_total];
        level.vertices = vec![0u32; unique_slots];
    }
    {
        let mut jobs = Vec::with_capacity(groups);
        let (mut o_rest, mut v_rest) = (&mut unique.offsets[1..], unique.vertices.as_mut_slice());
        let (mut h_rest, mut r_rest) = (level.shapes.as_mut_slice(), level.vertices.as_mut_slice());
        let mut slot_base = 0;
        for (g, &(nf, nv)) in unique_sizes.iter().enumerate() {
            let (o, o_tail) = o_rest.split_at_mut(nf);
            let (v, v_tail) = v_rest.split_at_mut(nv);
            let (h, h_tail) = h_rest.split_at_mut(if keep_cells { nf } else { 0 });
            let (r, r_tail) = r_rest.split_at_mut(if keep_cells { nv } else { 0 });
            (o_rest, v_rest, h_rest, r_rest) = (o_tail, v_tail, h_tail, r_tail);
            jobs.push((g, slot_base, o, v, h, r));
            slot_base += nv;
        }
        let order = &order;
        jobs.into_par_iter()
            .for_each(|(g, slot_base, ends, vertices, shapes_out, raw_out)| {
                let buckets = group_buckets(g);
                let slice = &order[start[buckets.start]..start[buckets.end]];
                let (mut k, mut at) = (0, 0);
                for (idx, &c) in slice.iter().enumerate() {
                    // Equal sets share their smallest vertex, hence a bucket.
                    if idx > 0 && same(slice[idx - 1], c) {
                        continue;
                    }
                    let c = c as usize;
                    let s = set(c);
                    vertices[at..at + s.len()].copy_from_slice(s);
                    if keep_cells {
                        shapes_out[k] = shapes[c];
                        raw_out[at..at + s.len()].copy_from_slice(&raw[span(c)]);
                    }
                    at += s.len();
                    ends[k] = slot_base + at;
                    k += 1;
                }
            });
    }
    if keep_cells {
        level.offsets = unique.offsets.clone();
    }
    ExtractedLevel {
        cells: level,
        sets: unique,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuboid_facets_follow_tensor_order() {
        let quad = TopCells::cuboids([[0usize, 1, 2, 3]]);
        let mut out = TopCells::default();
        quad.push_facets(0, &mut out);
        let facets: Vec<Vec<u32>> = (0..out.len()).map(|i| out.vertex_set(i)).collect();
        // axis 0: side 0 = {0,2}, side 1 = {1,3}; axis 1: side 0 = {0,1}, side 1 = {2,3}.
        assert_eq!(facets, vec![vec![0, 2], vec![1, 3], vec![0, 1], vec![2, 3]]);
    }

    #[test]
    fn shared_facets_are_merged_and_numbered_by_vertex_set() {
        let tris = TopCells::simplices([[2usize, 1, 0], [1, 2, 3]]);
        let edges = extract_facets(&tris, true);
        let sets: Vec<&[u32]> = (0..edges.sets.len()).map(|i| edges.sets.get(i)).collect();
        assert_eq!(sets, vec![&[0, 1][..], &[0, 2], &[1, 2], &[1, 3], &[2, 3]]);
    }

    #[test]
    fn validation_names_the_bad_cell() {
        let cells = TopCells::simplices([vec![0usize, 1, 2], vec![0, 1, 1]]);
        assert_eq!(
            cells.validate(3),
            Err(ComplexError::RepeatedVertex { cell: 1, vertex: 1 })
        );
        let cells = TopCells::simplices([vec![0usize, 1, 7]]);
        assert_eq!(
            cells.validate(3),
            Err(ComplexError::VertexOutOfRange {
                cell: 0,
                vertex: 7,
                vertex_count: 3
            })
        );
        let cells = TopCells::cuboids([vec![0usize, 1, 2]]);
        assert!(matches!(
            cells.validate(3),
            Err(ComplexError::WrongVertexCount { cell: 0, .. })
        ));
        let mut mixed = TopCells::simplices([vec![0usize, 1, 2]]);
        mixed.push_simplex(&[0, 1]);
        assert_eq!(
            mixed.validate(3),
            Err(ComplexError::MixedDimension {
                cell: 1,
                expected: 2,
                found: 1
            })
        );
    }

    #[test]
    fn non_finite_coordinates_are_rejected() {
        let err = Vertices::new(2, vec![0.0, 1.0, f64::NAN, 0.0]);
        assert!(matches!(
            err,
            Err(ComplexError::NonFiniteCoordinate { vertex: 1, axis: 0, value }) if value.is_nan()
        ));
    }
}
