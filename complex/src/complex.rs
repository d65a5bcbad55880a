//! The oriented cell complex: LAR characteristic matrices plus the signed
//! boundary matrices ∂_p, with the topological queries built on them.

use crate::cells::{extract_facets, top_characteristic, TopCells, Vertices};
use crate::error::{ComplexError, Result};
use crate::frame;
use crate::homology::{self, Field};
use crate::lar::{characteristic_matrix, Lar};
use crate::tags::{CellTag, Tags};
use rayon::prelude::*;
use sprs::{CsMat, TriMat};
use std::collections::VecDeque;
use std::sync::{Arc, OnceLock};

mod incidence;

/// An oriented cell complex of dimension n embedded in R^d (n ≤ d ≤ 3).
///
/// Built from top cells only; every lower cell is extracted, merged and
/// numbered by its sorted vertex list. Each level answers directly:
/// `cell_count(p)`, `boundary(p)`, `coboundary(p)`, and (in the geometry
/// module) `measure(p)`, `centroid(p)`.
///
/// ```
/// use hasse_complex::{Complex, TopCells, Vertices};
/// // Two triangles forming the unit square.
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
/// let k = Complex::build(v, TopCells::simplices([[0, 1, 2], [1, 3, 2]])).unwrap();
/// assert_eq!(k.cell_counts(), vec![4, 5, 2]);
/// assert_eq!(k.euler_characteristic(), 1);
/// // ∂1 ∂2 = 0, exactly.
/// let dd = &**k.boundary(1) * &**k.boundary(2);
/// assert!(dd.data().iter().all(|&x| x == 0));
/// ```
#[derive(Clone, Debug)]
pub struct Complex {
    lar: Lar,
    /// Shared, so that operators built on ∂_p use it in place.
    boundaries: Vec<Arc<CsMat<i8>>>,
    top_orientation: Vec<i8>,
    tags: Tags,
    stars: Vec<OnceLock<Arc<CsMat<u8>>>>,
    pub(crate) geometry: crate::geometry::GeometryCache,
    pub(crate) dual: crate::dual::DualCache,
}

impl PartialEq for Complex {
    /// Two complexes are equal when their vertices, cells, orientations and
    /// tags are; cached geometry does not take part.
    fn eq(&self, other: &Self) -> bool {
        self.lar == other.lar
            && self.boundaries == other.boundaries
            && self.top_orientation == other.top_orientation
            && self.tags == other.tags
    }
}

impl Complex {
    /// Build a complex from its top cells: extract and number every lower
    /// cell, compute ∂_p from the filtered LAR products and orient them.
    pub fn build(vertices: Vertices, cells: TopCells) -> Result<Self> {
        let n = cells.validate(vertices.len())?;
        if n > vertices.dim() {
            return Err(ComplexError::DimensionTooHigh {
                cell_dim: n,
                embedding_dim: vertices.dim(),
            });
        }
        let k0 = vertices.len();
        let mut matrices = vec![top_characteristic(&cells, k0)];
        let mut current = cells;
        for p in (2..=n).rev() {
            // The edges (p = 2) need no facets of their own.
            let level = extract_facets(&current, p > 2);
            matrices.push(characteristic_matrix(level.sets, k0));
            current = level.cells;
        }
        matrices.reverse();
        let lar = Lar::new(vertices, matrices)?;
        Self::from_lar(lar)
    }

    /// Orient a LAR whose characteristic matrices are all given (every cell
    /// convex). Use [`Complex::build`] when only top cells are known.
    pub fn from_lar(lar: Lar) -> Result<Self> {
        let n = lar.dim();
        if n > lar.vertices().dim() {
            return Err(ComplexError::DimensionTooHigh {
                cell_dim: n,
                embedding_dim: lar.vertices().dim(),
            });
        }
        let mut boundaries = Vec::with_capacity(n);
        // Frames of the top cells, when ∂_n needed them (non-simplices).
        let mut top_frames = None;
        for p in 1..=n {
            let (boundary, frames) = signed_boundary(&lar, p)?;
            boundaries.push(boundary);
            if p == n {
                top_frames = frames;
            }
        }
        // One pass over the top cells: degeneracy, and the ambient orientation
        // (only used when n = d).
        let vertices = lar.vertices();
        let ambient: Vec<i8> = (0..lar.cell_count(n))
            .into_par_iter()
            .map(|j| {
                let cell = lar.cell_vertices(n, j);
                let f = match &top_frames {
                    Some(frames) => frames.get(j),
                    None => frame::frame(vertices, cell, n),
                };
                let f = f.ok_or_else(|| ComplexError::DegenerateCell {
                    dim: n,
                    cell: j,
                    vertices: cell.to_vec(),
                })?;
                Ok(if frame::det(n, &f.basis) > 0.0 { 1 } else { -1 })
            })
            .collect::<Result<_>>()?;
        drop(top_frames);
        crate::nonconvex::orient_by_cycles(&lar, &mut boundaries)?;
        check_closed(&lar, &boundaries)?;
        let top_orientation = orient_top_cells(&lar, &boundaries[n - 1], ambient)?;
        let top = &mut boundaries[n - 1];
        for mut row in top.outer_iterator_mut() {
            for (col, value) in row.iter_mut() {
                *value *= top_orientation[col];
            }
        }
        check_coherence(&boundaries[n - 1], n == lar.vertices().dim())?;
        Ok(Self {
            stars: (0..=n).map(|_| OnceLock::new()).collect(),
            lar,
            boundaries: boundaries.into_iter().map(Arc::new).collect(),
            top_orientation,
            tags: Tags::default(),
            geometry: Default::default(),
            dual: Default::default(),
        })
    }

    /// A complex from parts that are already consistent (used by SPLIT,
    /// which assembles ∂_p and the orientation flags cell by cell instead of
    /// recomputing them from geometry).
    pub(crate) fn from_parts(
        lar: Lar,
        boundaries: Vec<CsMat<i8>>,
        top_orientation: Vec<i8>,
        tags: Tags,
    ) -> Self {
        Self {
            stars: (0..=lar.dim()).map(|_| OnceLock::new()).collect(),
            lar,
            boundaries: boundaries.into_iter().map(Arc::new).collect(),
            top_orientation,
            tags,
            geometry: Default::default(),
            dual: Default::default(),
        }
    }

    /// The same cells on moved vertices (e.g. a perturbed grid): orientation
    /// and geometry are recomputed, tags are kept.
    pub fn with_vertices(&self, vertices: Vertices) -> Result<Self> {
        if vertices.len() != self.cell_count(0) {
            return Err(ComplexError::Invalid(format!(
                "{} vertices given for a complex with {}",
                vertices.len(),
                self.cell_count(0)
            )));
        }
        let matrices = (1..=self.dim())
            .map(|p| self.lar.characteristic(p).cloned())
            .collect::<Result<Vec<_>>>()?;
        let mut moved = Self::from_lar(Lar::new(vertices, matrices)?)?;
        moved.tags = self.tags.clone();
        Ok(moved)
    }

    /// The LAR representation (vertices and characteristic matrices).
    pub fn lar(&self) -> &Lar {
        &self.lar
    }

    /// Topological dimension n (dimension of the top cells).
    pub fn dim(&self) -> usize {
        self.lar.dim()
    }

    /// Dimension d of the space the vertices live in.
    pub fn embedding_dim(&self) -> usize {
        self.lar.vertices().dim()
    }

    /// The vertices.
    pub fn vertices(&self) -> &Vertices {
        self.lar.vertices()
    }

    /// Number of p-cells |K_p| (0 for p > n).
    pub fn cell_count(&self, p: usize) -> usize {
        self.lar.cell_count(p)
    }

    /// (|K_0|, …, |K_n|).
    pub fn cell_counts(&self) -> Vec<usize> {
        (0..=self.dim()).map(|p| self.cell_count(p)).collect()
    }

    /// Sorted vertex indices of p-cell `i` (row i of M_p).
    pub fn cell_vertices(&self, p: usize, i: usize) -> &[usize] {
        self.lar.cell_vertices(p, i)
    }

    /// Orientation of each top cell relative to the frame of its sorted
    /// vertex list (+1 same, −1 reversed). In R^n every top cell ends up
    /// positively oriented; on embedded manifolds the orientation is
    /// propagated coherently, with closed surfaces oriented outward.
    pub fn top_orientation(&self) -> &[i8] {
        &self.top_orientation
    }

    /// Euler characteristic Σ (−1)^p |K_p|.
    pub fn euler_characteristic(&self) -> i64 {
        homology::euler_characteristic(&self.cell_counts())
    }

    /// Betti numbers β_0 … β_n over the rationals.
    pub fn betti_numbers(&self) -> Vec<usize> {
        self.betti_numbers_over(Field::Rationals)
    }

    /// Betti numbers over the chosen field.
    pub fn betti_numbers_over(&self, field: Field) -> Vec<usize> {
        // The reduction costs far more than this copy of ∂_p.
        let boundaries: Vec<CsMat<i8>> = self.boundaries.iter().map(|b| (**b).clone()).collect();
        homology::betti_numbers(&self.cell_counts(), &boundaries, field)
    }

    /// The Hasse matrix H(K): one block-bidiagonal sparse matrix holding
    /// every incidence. Rows are the odd-dimensional cells (K_1, K_3, …),
    /// columns the even-dimensional ones (K_0, K_2, …); the block of row
    /// dimension 2i+1 holds δ^{2i} against K_{2i} and ∂_{2i+2} against
    /// K_{2i+2}. Its shape r × c gives χ(K) = c − r.
    pub fn hasse_matrix(&self) -> CsMat<i8> {
        let n = self.dim();
        let offset = |parity: usize| -> Vec<usize> {
            let mut off = vec![0; n + 2];
            let mut acc = 0;
            for p in (parity..=n).step_by(2) {
                off[p] = acc;
                acc += self.cell_count(p);
            }
            off[n + 1] = acc;
            off
        };
        let (row_off, col_off) = (offset(1), offset(0));
        let rows: usize = (1..=n).step_by(2).map(|p| self.cell_count(p)).sum();
        let cols: usize = (0..=n).step_by(2).map(|p| self.cell_count(p)).sum();
        let mut tri = TriMat::new((rows, cols));
        for p in 1..=n {
            // ∂_p relates (p-1)-cells to p-cells; whichever is odd is the row.
            for (value, (i, j)) in self.boundary(p).iter() {
                if p % 2 == 1 {
                    tri.add_triplet(row_off[p] + j, col_off[p - 1] + i, *value);
                } else {
                    tri.add_triplet(row_off[p - 1] + i, col_off[p] + j, *value);
                }
            }
        }
        tri.to_csr()
    }

    /// Vertex → p-cells incidence (M_pᵀ as CSR; for p = n the vertex star).
    pub fn vertex_star(&self, p: usize) -> &CsMat<u8> {
        self.star(p)
    }

    /// [`Complex::vertex_star`], shared.
    pub fn shared_vertex_star(&self, p: usize) -> Arc<CsMat<u8>> {
        Arc::clone(self.star(p))
    }

    fn star(&self, p: usize) -> &Arc<CsMat<u8>> {
        self.stars[p].get_or_init(|| {
            Arc::new(if p == 0 {
                CsMat::eye(self.cell_count(0))
            } else {
                self.lar.cells_by_vertex(p)
            })
        })
    }

    /// Adjacency of p-cells through shared (p−1)-faces: entry (i, j), i ≠ j,
    /// is the number of faces they share (|∂_p|ᵀ|∂_p| without its diagonal).
    pub fn cell_adjacency(&self, p: usize) -> CsMat<u32> {
        let abs = self.boundary(p).map(|x| u32::from(x.unsigned_abs()));
        let product = &abs.transpose_view().to_csr() * &abs;
        let mut tri = TriMat::new(product.shape());
        for (v, (i, j)) in product.iter() {
            if i != j {
                tri.add_triplet(i, j, *v);
            }
        }
        tri.to_csr()
    }

    /// The p-cell with exactly these vertices, if there is one.
    pub fn find_cell(&self, p: usize, vertices: &[usize]) -> Option<usize> {
        if p > self.dim() {
            return None;
        }
        let mut sorted = vertices.to_vec();
        sorted.sort_unstable();
        let first = *sorted.first()?;
        if first >= self.cell_count(0) {
            return None;
        }
        let star = self.vertex_star(p);
        star.outer_view(first)?
            .indices()
            .iter()
            .copied()
            .find(|&j| self.cell_vertices(p, j) == sorted.as_slice())
    }

    /// The boundary subcomplex ∂K: the (n−1)-cells with exactly one top
    /// cell on them, and all their faces.
    pub fn boundary_subcomplex(&self) -> Subcomplex {
        let n = self.dim();
        let mut member: Vec<Vec<bool>> = (0..n).map(|p| vec![false; self.cell_count(p)]).collect();
        let top = self.boundary(n);
        for (i, row) in top.outer_iterator().enumerate() {
            member[n - 1][i] = row.nnz() == 1;
        }
        for p in (1..n).rev() {
            // Row i of ∂_p lists the p-cells that (p−1)-cell i bounds.
            for (i, row) in self.boundary(p).outer_iterator().enumerate() {
                if row.indices().iter().any(|&j| member[p][j]) {
                    member[p - 1][i] = true;
                }
            }
        }
        Subcomplex {
            cells: member
                .into_iter()
                .map(|m| {
                    m.iter()
                        .enumerate()
                        .filter(|(_, &b)| b)
                        .map(|(i, _)| i)
                        .collect()
                })
                .collect(),
        }
    }

    /// Named cell sets (boundary regions, materials).
    pub fn tags(&self) -> &Tags {
        &self.tags
    }

    /// The tag called `name`, if present.
    pub fn tag(&self, name: &str) -> Option<&CellTag> {
        self.tags.get(name)
    }

    /// Name a set of p-cells; ids are checked against the cell count.
    pub fn set_tag(&mut self, name: &str, dim: usize, cells: Vec<usize>) -> Result<()> {
        if dim > self.dim() {
            return Err(ComplexError::DimensionOutOfRange {
                p: dim,
                dim: self.dim(),
            });
        }
        if let Some(&bad) = cells.iter().find(|&&c| c >= self.cell_count(dim)) {
            return Err(ComplexError::Invalid(format!(
                "tag '{name}': {dim}-cell {bad} does not exist (there are {})",
                self.cell_count(dim)
            )));
        }
        self.tags.insert(name, CellTag::new(dim, cells));
        Ok(())
    }

    /// Tag the boundary (n−1)-cells whose vertex average satisfies `inside`.
    /// Returns how many cells were tagged.
    pub fn tag_boundary_where(&mut self, name: &str, inside: impl Fn(&[f64]) -> bool) -> usize {
        let n = self.dim();
        let d = self.embedding_dim();
        let boundary = self.boundary_subcomplex();
        let cells: Vec<usize> = boundary
            .cells(n - 1)
            .iter()
            .copied()
            .filter(|&f| {
                let verts = self.cell_vertices(n - 1, f);
                let mut centre = vec![0.0; d];
                for &v in verts {
                    for (c, x) in centre.iter_mut().zip(self.vertices().point(v)) {
                        *c += x / verts.len() as f64;
                    }
                }
                inside(&centre)
            })
            .collect();
        let count = cells.len();
        self.tags.insert(name, CellTag::new(n - 1, cells));
        count
    }

    /// Replace all tags (used by readers).
    pub(crate) fn replace_tags(&mut self, tags: Tags) {
        self.tags = tags;
    }
}

/// A set of cells of every dimension closed under taking faces.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Subcomplex {
    cells: Vec<Vec<usize>>,
}

impl Subcomplex {
    /// Sorted ids of the member p-cells (empty beyond the top dimension).
    pub fn cells(&self, p: usize) -> &[usize] {
        self.cells.get(p).map_or(&[], Vec::as_slice)
    }

    /// Number of member p-cells for every p.
    pub fn cell_counts(&self) -> Vec<usize> {
        self.cells.iter().map(Vec::len).collect()
    }

    /// True when p-cell `i` belongs to the subcomplex.
    pub fn contains(&self, p: usize, i: usize) -> bool {
        self.cells(p).binary_search(&i).is_ok()
    }
}

/// ∂_p with signs: exact (−1)^k between simplices, the geometric induced
/// orientation otherwise. Frames are computed on the fly (once per facet,
/// once per incident cell) rather than stored: at 10^6 cells stored frames
/// cost more in memory traffic than recomputing them. Top cells are not
/// yet oriented. The frames of the p-cells are returned when they were
/// computed (some p-cell is not a simplex), for the top level's orientation.
fn signed_boundary(lar: &Lar, p: usize) -> Result<(CsMat<i8>, Option<frame::PackedFrames>)> {
    let rows = lar.cell_count(p - 1);
    let vertices = lar.vertices();
    let degenerate = |dim: usize, cell: usize, verts: &[usize]| ComplexError::DegenerateCell {
        dim,
        cell,
        vertices: verts.to_vec(),
    };
    // Frames of the upper cells are needed by every facet of a non-simplex
    // cell: compute them once per cell (a hex is met by six faces). Facet
    // frames are computed once per row, so they are never stored.
    let upper_frames: Option<frame::PackedFrames> = (0..lar.cell_count(p))
        .into_par_iter()
        .any(|j| lar.cell_vertices(p, j).len() != p + 1)
        .then(|| {
            frame::PackedFrames::new(p, lar.cell_count(p), |j| {
                frame::frame(vertices, lar.cell_vertices(p, j), p)
            })
        });
    let row_signs = |i: usize, columns: &[u32], out: &mut Vec<i8>| -> Result<()> {
        let facet = lar.cell_vertices(p - 1, i);
        let mut facet_frame = None;
        for &j in columns {
            let j = j as usize;
            let cell = lar.cell_vertices(p, j);
            if cell.len() == p + 1 && facet.len() == p {
                let k = facet
                    .iter()
                    .zip(cell)
                    .position(|(a, b)| a != b)
                    .unwrap_or(p);
                out.push(if k % 2 == 0 { 1 } else { -1 });
                continue;
            }
            if facet_frame.is_none() {
                facet_frame = Some(
                    frame::frame(vertices, facet, p - 1)
                        .ok_or_else(|| degenerate(p - 1, i, facet))?,
                );
            }
            let cell_frame = upper_frames
                .as_ref()
                .and_then(|frames| frames.get(j))
                .ok_or_else(|| degenerate(p, j, cell))?;
            let sign = facet_frame.as_ref().and_then(|f| {
                // On a flat torus the facet is seen from the cell's image.
                let mut f = *f;
                f.centre = vertices.nearest(&f.centre, &cell_frame.centre);
                frame::induced_sign(&cell_frame, &f, cell_frame.diameter)
            });
            // A polygon's undecided sign (0) is settled by its boundary
            // cycle (`nonconvex`); other cells must be convex.
            out.push(match sign {
                Some(sign) => sign,
                None if p == 2 => 0,
                None => return Err(ComplexError::Invalid(format!(
                    "{}-cell {i} (vertices {facet:?}) does not bound {p}-cell {j} (vertices {cell:?}) from outside: the cell is not convex or is degenerate",
                    p - 1
                ))),
            });
        }
        Ok(())
    };
    let (indptr, indices, data) = lar.boundary_pattern_with(p, row_signs)?;
    let shape = (rows, lar.cell_count(p));
    let matrix = CsMat::try_new(shape, indptr, indices, data)
        .map_err(|e| ComplexError::Invalid(format!("internal: boundary matrix ∂_{p}: {}", e.3)))?;
    Ok((matrix, upper_frames))
}

/// Orientation flags of the top cells: the ambient orientation when n = d,
/// otherwise propagated across shared faces, each closed surface oriented
/// by its outward normal.
fn orient_top_cells(lar: &Lar, top: &CsMat<i8>, ambient: Vec<i8>) -> Result<Vec<i8>> {
    let n = lar.dim();
    let d = lar.vertices().dim();
    let cells = lar.cell_count(n);
    if n == d {
        return Ok(ambient);
    }
    let by_cell = top.to_csc();
    let mut flags = vec![0i8; cells];
    for start in 0..cells {
        if flags[start] != 0 {
            continue;
        }
        flags[start] = 1;
        let mut component = vec![start];
        let mut closed = true;
        let mut queue = VecDeque::from([start]);
        while let Some(c) = queue.pop_front() {
            let Some(col) = by_cell.outer_view(c) else {
                continue;
            };
            for (face, &s) in col.iter() {
                let Some(row) = top.outer_view(face) else {
                    continue;
                };
                if row.nnz() == 1 {
                    closed = false;
                }
                if row.nnz() != 2 {
                    continue;
                }
                for (other, &t) in row.iter() {
                    if other == c {
                        continue;
                    }
                    let wanted = -flags[c] * s * t;
                    if flags[other] == 0 {
                        flags[other] = wanted;
                        component.push(other);
                        queue.push_back(other);
                    } else if flags[other] != wanted {
                        return Err(ComplexError::NonOrientable {
                            cell: other,
                            face,
                            face_dim: n - 1,
                        });
                    }
                }
            }
        }
        if closed
            && n == 2
            && d == 3
            && crate::nonconvex::enclosed_volume(lar, &by_cell, &flags, &component) < 0.0
        {
            for &c in &component {
                flags[c] = -flags[c];
            }
        }
    }
    Ok(flags)
}

/// ∂_{p−1} ∂_p = 0, column by column. The signs of a simplex's facets are
/// combinatorial and always close up; those of other cells come from
/// geometry, and on a twisted or self-intersecting cell (a "bow-tie" face of
/// a hexahedron whose nodes are out of order) they need not: report the
/// cell rather than hand out a complex that breaks ∂∂ = 0.
///
/// The product is formed row by row (row v of ∂_{p−1} ∂_p gathers the rows
/// of ∂_p of v's cofaces), in parallel and with no transposed copy; only when
/// some row does not cancel is the column-wise search run, to name the first
/// open cell.
fn check_closed(lar: &Lar, boundaries: &[CsMat<i8>]) -> Result<()> {
    const CHUNK: usize = 8192;
    for p in 2..=boundaries.len() {
        if (0..lar.cell_count(p))
            .into_par_iter()
            .all(|j| lar.cell_vertices(p, j).len() == p + 1)
        {
            continue;
        }
        let (lower, upper) = (&boundaries[p - 2], &boundaries[p - 1]);
        let rows = lower.rows();
        let closed = (0..rows.div_ceil(CHUNK)).into_par_iter().all(|chunk| {
            let mut terms: Vec<(usize, i32)> = Vec::new();
            (chunk * CHUNK..((chunk + 1) * CHUNK).min(rows)).all(|v| {
                terms.clear();
                let Some(row) = lower.outer_view(v) else {
                    return true;
                };
                for (facet, &s) in row.iter() {
                    if let Some(cells) = upper.outer_view(facet) {
                        terms.extend(cells.iter().map(|(j, &t)| (j, i32::from(s) * i32::from(t))));
                    }
                }
                terms.sort_unstable_by_key(|&(j, _)| j);
                terms
                    .chunk_by(|a, b| a.0 == b.0)
                    .all(|run| run.iter().map(|&(_, t)| t).sum::<i32>() == 0)
            })
        });
        if !closed {
            first_open_cell(lar, lower, upper, p)?;
        }
    }
    Ok(())
}

/// The column-wise form of [`check_closed`] for one level: the error names
/// the lowest-numbered p-cell whose faces do not close up.
fn first_open_cell(lar: &Lar, lower: &CsMat<i8>, upper: &CsMat<i8>, p: usize) -> Result<()> {
    let upper = upper.to_csc();
    let lower = lower.to_csc();
    let mut terms: Vec<(usize, i32)> = Vec::new();
    for (cell, column) in upper.outer_iterator().enumerate() {
        terms.clear();
        for (facet, &s) in column.iter() {
            if let Some(edges) = lower.outer_view(facet) {
                terms.extend(edges.iter().map(|(v, &t)| (v, i32::from(s) * i32::from(t))));
            }
        }
        terms.sort_unstable_by_key(|&(v, _)| v);
        let open = terms
            .chunk_by(|a, b| a.0 == b.0)
            .any(|run| run.iter().map(|&(_, t)| t).sum::<i32>() != 0);
        if open {
            return Err(ComplexError::Invalid(format!(
                    "{p}-cell {cell} (vertices {:?}) is twisted or self-intersecting: its {}-faces do not close up around it (∂∂ ≠ 0); check the order of its vertices",
                    lar.cell_vertices(p, cell),
                    p - 1
                )));
        }
    }
    Ok(())
}

/// Every (n−1)-cell shared by two top cells must appear with opposite signs;
/// when the cells fill R^n (`fills`), no face may bound more than two.
fn check_coherence(top: &CsMat<i8>, fills: bool) -> Result<()> {
    for (face, row) in top.outer_iterator().enumerate() {
        // Surfaces in R³ may branch (a T-junction of sheets is a valid
        // complex); cells that fill their space can only overlap there.
        if fills && row.nnz() > 2 {
            return Err(ComplexError::Invalid(format!(
                "face {face} bounds {} top cells ({:?}); in a mesh that fills its space a face bounds at most two: the cells overlap",
                row.nnz(),
                row.indices()
            )));
        }
        if row.nnz() == 2 && row.data()[0] == row.data()[1] {
            let cells: Vec<usize> = row.indices().to_vec();
            return Err(ComplexError::Invalid(format!(
                "top cells {} and {} lie on the same side of their shared face {face}: the cells overlap or one is inverted",
                cells[0], cells[1]
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(m: &CsMat<i8>) -> Vec<Vec<i8>> {
        let d = m.to_dense();
        d.rows().into_iter().map(|r| r.to_vec()).collect()
    }

    #[test]
    fn the_edge_coboundary_is_the_transpose_of_the_edge_boundary() {
        // δ⁰ is built from M₁ for n ≥ 2: it must be ∂₁ᵀ entry for entry,
        // on grids, simplices, polygons and an embedded surface; a curve
        // (n = 1, whose edges the top orientation may flip) transposes ∂₁.
        let complexes = [
            crate::generate::rectangle(3, 2, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            crate::generate::box3(2, 2, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
            crate::generate::kuhn(&[vec![0.0, 0.5, 1.0], vec![0.0, 1.0], vec![0.0, 1.0]]).unwrap(),
            crate::generate::voronoi(12, [0.0, 1.0], [0.0, 1.0], 7, 1).unwrap(),
            crate::generate::sphere(1.0, 1).unwrap(),
            crate::generate::interval(4, 0.0, 1.0).unwrap(),
        ];
        for k in &complexes {
            let transposed: CsMat<i8> = k.boundary(1).transpose_view().to_csr();
            assert_eq!(**k.coboundary(0), transposed, "dimension {}", k.dim());
        }
    }

    #[test]
    fn single_triangle_matches_hand_computed_boundaries() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        // Edges numbered by vertex sets: e0 = {0,1}, e1 = {0,2}, e2 = {1,2}.
        assert_eq!(
            dense(k.boundary(1)),
            vec![vec![-1, -1, 0], vec![1, 0, -1], vec![0, 1, 1]]
        );
        // Counter-clockwise triangle: ∂ = e0 − e1 + e2.
        assert_eq!(dense(k.boundary(2)), vec![vec![1], vec![-1], vec![1]]);
    }

    #[test]
    fn clockwise_input_is_reoriented_positively() {
        let v = Vertices::from_points(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        assert_eq!(k.top_orientation(), &[-1]);
        // Edges {0,1} (up the y axis), {0,2}, {1,2}; counter-clockwise
        // boundary runs 0→2→1→0: −e0 + e1 − e2.
        assert_eq!(dense(k.boundary(2)), vec![vec![-1], vec![1], vec![-1]]);
    }

    #[test]
    fn unit_square_quad_is_counter_clockwise() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
        // e0={0,1} bottom (→), e1={0,2} left (↑), e2={1,3} right (↑), e3={2,3} top (→).
        assert_eq!(
            dense(k.boundary(2)),
            vec![vec![1], vec![-1], vec![1], vec![-1]]
        );
    }

    #[test]
    fn degenerate_and_overlapping_cells_are_reported() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0]]).unwrap();
        let err = Complex::build(v.clone(), TopCells::simplices([[0, 1, 2]])).unwrap_err();
        assert_eq!(
            err,
            ComplexError::DegenerateCell {
                dim: 2,
                cell: 0,
                vertices: vec![0, 1, 2]
            }
        );
        // Both triangles lie above edge {0,1}.
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 2.0]]).unwrap();
        let err = Complex::build(v, TopCells::simplices([[0, 1, 2], [0, 1, 3]])).unwrap_err();
        assert!(err.to_string().contains("overlap"), "{err}");
    }

    #[test]
    fn combinatorial_simplex_signs_agree_with_the_geometric_orientation() {
        // Deterministic pseudo-random simplices in R^2 and R^3: for every facet
        // (vertex k dropped from the sorted list) the geometric induced sign
        // equals (−1)^k.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for d in 2..=3 {
            for _ in 0..200 {
                let coords: Vec<f64> = (0..(d + 1) * d).map(|_| next()).collect();
                let v = Vertices::new(d, coords).unwrap();
                let cell: Vec<usize> = (0..=d).collect();
                let Some(frame) = frame::frame(&v, &cell, d) else {
                    continue;
                };
                for k in 0..=d {
                    let facet: Vec<usize> = cell.iter().copied().filter(|&i| i != k).collect();
                    let f = frame::frame(&v, &facet, d - 1).unwrap();
                    if let Some(sign) = frame::induced_sign(&frame, &f, 1.0) {
                        assert_eq!(sign, if k % 2 == 0 { 1 } else { -1 }, "d = {d}, facet {k}");
                    }
                }
            }
        }
    }

    #[test]
    fn boundary_subcomplex_of_two_squares() {
        // Two unit squares side by side: 6 boundary edges, all 6 vertices.
        let v = Vertices::from_points(&[
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [2.0, 1.0],
        ])
        .unwrap();
        let k = Complex::build(v, TopCells::cuboids([[0, 1, 3, 4], [1, 2, 4, 5]])).unwrap();
        let b = k.boundary_subcomplex();
        assert_eq!(b.cell_counts(), vec![6, 6]);
        // The shared edge {1,4} is interior.
        let shared = k.find_cell(1, &[4, 1]).unwrap();
        assert!(!b.contains(1, shared));
    }

    #[test]
    fn hasse_matrix_of_a_triangle() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        let h = k.hasse_matrix();
        // d = 2: H = [δ0 | δ1ᵀ], 3 × (3 + 1), χ = 4 − 3 = 1.
        assert_eq!(h.shape(), (3, 4));
        assert_eq!(
            dense(&h),
            vec![vec![-1, 1, 0, 1], vec![-1, 0, 1, -1], vec![0, -1, 1, 1]]
        );
    }
}
