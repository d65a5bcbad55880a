//! Tensor-product grids and their Kuhn subdivision written down directly
//! from index arithmetic: every M_p and ∂_p of [`grid`](super::grid) and
//! [`kuhn`](super::kuhn), equal bit for bit to what [`Complex::build`]
//! (facet extraction, merging, filtered LAR products, geometric signs)
//! makes of the same top cells, without extracting or sorting anything.
//!
//! On a grid every p-cell is a translate of one of a few *kinds* (an
//! x-edge, a yz-face, one of the six Kuhn tetrahedra of a cube, …): its
//! vertices are its lowest vertex plus fixed offsets, each offset a set of
//! axes written as a bit mask. Three facts give the general path's results
//! in closed form:
//!
//! - Numbering. Vertex (i, j, k) is `i + s_y j + s_z k` with s_y = n_x ≥ 2
//!   and s_z = n_x n_y ≥ 2 n_x > n_x + 1: each stride exceeds the sum of the
//!   smaller ones, so offsets order like their masks and a cell's sorted
//!   vertex list is its lowest vertex followed by its masks in increasing
//!   order. The general path numbers the cells of each dimension by sorted
//!   vertex list, which therefore orders them by lowest vertex, then by
//!   kind (kinds sorted by mask list); the top cells it keeps in input
//!   order, which for both families is this same order. A cell's number is
//!   the first number of its x-line, plus `i` times the kinds that fit at
//!   an inner vertex of that line, plus the rank of its kind among those
//!   that fit at its own vertex (on the last index of an axis no cell
//!   extends along it).
//! - Signs. A simplex's facet without its k-th vertex has sign (−1)^k, as
//!   in the general path. A cuboid's frame (greedy over its sorted
//!   vertices) is e_{a_0}, …, e_{a_{p−1}} for its axes a_0 < … < a_{p−1};
//!   its facet on side s of axis a_k has the frame of the other axes, and
//!   the outward direction ±e_{a_k} (+ on the upper side) before it gives
//!   the determinant ±(−1)^k.
//! - Orientation. Top cells fill R^n and are oriented by the sign of their
//!   frame's determinant: +1 for a cuboid (the identity), the sign of the
//!   permutation for a Kuhn simplex (its edges from the lowest vertex are
//!   e_{π1}, e_{π1} + e_{π2}, …, scaled by positive spacings).
//!
//! The geometric signs of the general path are decided against a relative
//! tolerance of 1e-10; [`well_shaped`] keeps this path to grids whose
//! spacings are far above it, so that the two always agree.

use super::grid::Layout;
use crate::error::{ComplexError, Result};
use crate::frame;
use crate::lar::Lar;
use crate::tags::Tags;
use crate::Complex;
use rayon::prelude::*;
use sprs::CsMat;

/// Which cells fill a grid cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Family {
    /// One segment, quadrilateral or hexahedron.
    Cuboid,
    /// The Kuhn (Freudenthal) simplices: 2 triangles or 6 tetrahedra.
    Kuhn,
}

/// Smallest spacing, relative to the longest cell diagonal, for which the
/// direct builder is used. The general path's geometric signs and
/// degeneracy checks use 1e-10 (`frame`); four orders of magnitude above
/// it, the geometric sign of an axis-aligned facet cannot differ from the
/// combinatorial one, nor can a cell be called degenerate.
const THINNEST: f64 = 1e-6;

/// True when every cell is thick enough (see [`THINNEST`]) for the direct
/// builder to reproduce the general path; false sends the grid through
/// [`Complex::build`], which reports degenerate cells itself.
pub(super) fn well_shaped(layout: &Layout) -> bool {
    let mut smallest = f64::INFINITY;
    let mut diagonal_squared = 0.0;
    for axis in layout.axes {
        let (mut low, mut high) = (f64::INFINITY, 0.0f64);
        for w in axis.windows(2) {
            let h = w[1] - w[0];
            low = low.min(h);
            high = high.max(h);
        }
        smallest = smallest.min(low);
        diagonal_squared += high * high;
    }
    // An overflowing spacing makes the diagonal infinite: not well shaped.
    smallest > THINNEST * f64::sqrt(diagonal_squared)
}

/// Build the complex of [`grid`](super::grid) (`Cuboid`) or
/// [`kuhn`](super::kuhn) (`Kuhn`) on `layout`, tags included.
pub(super) fn build(layout: &Layout, family: Family) -> Result<Complex> {
    let grid = Grid::new(layout);
    let n = layout.dim();
    let levels: Vec<Level> = (0..=n)
        .map(|p| Level::new(&grid, kinds(family, n, p)))
        .collect();
    let top_signs: Vec<i8> = levels[n]
        .kinds
        .iter()
        .map(|kind| orientation(family, n, kind))
        .collect();
    let mut characteristic = Vec::with_capacity(n);
    let mut boundaries = Vec::with_capacity(n);
    for p in 1..=n {
        characteristic.push(characteristic_matrix(&grid, &levels[p])?);
        let signs = if p == n {
            top_signs.clone()
        } else {
            vec![1; levels[p].kinds.len()]
        };
        let cofaces = cofaces(family, &levels[p - 1].kinds, &levels[p].kinds, &signs)?;
        boundaries.push(boundary_matrix(
            &grid,
            &levels[p - 1],
            &levels[p],
            &cofaces,
        )?);
    }
    // Every top kind spans all axes, so every vertex that holds a top cell
    // holds one of each kind, in kind order.
    let top_orientation: Vec<i8> = (0..levels[n].count())
        .into_par_iter()
        .map(|c| top_signs[c % top_signs.len()])
        .collect();
    let lar = Lar::new(layout.vertices()?, characteristic)?;
    let mut complex = Complex::from_parts(lar, boundaries, top_orientation, Tags::default());
    layout.tag(&mut complex)?;
    Ok(complex)
}

/// The grid's index arithmetic, padded to three axes (a missing axis has
/// one coordinate, so nothing extends along it).
struct Grid {
    counts: [usize; 3],
    strides: [usize; 3],
    vertices: usize,
    /// Number of x-lines of vertices (one per (j, k)).
    lines: usize,
}

impl Grid {
    fn new(layout: &Layout) -> Self {
        let mut counts = [1; 3];
        counts[..layout.dim()].copy_from_slice(&layout.counts);
        Self {
            counts,
            strides: layout.strides,
            vertices: layout.vertex_count(),
            lines: counts[1] * counts[2],
        }
    }

    /// Bit a set when `at` is on the last index along axis a.
    fn class(&self, at: [usize; 3]) -> usize {
        (0..3)
            .filter(|&a| at[a] + 1 == self.counts[a])
            .fold(0, |class, a| class | 1 << a)
    }

    /// Where `at` lies on each axis: bit 2a set on the first index, bit
    /// 2a + 1 on the last (a one-coordinate axis has both). Which cofaces
    /// a cell has, and where they sit relative to it, depend on nothing
    /// else.
    fn position(&self, at: [usize; 3]) -> usize {
        (0..3).fold(0, |position, a| {
            position
                | usize::from(at[a] == 0) << (2 * a)
                | usize::from(at[a] + 1 == self.counts[a]) << (2 * a + 1)
        })
    }

    fn vertex(&self, at: [usize; 3]) -> usize {
        at[0] + at[1] * self.strides[1] + at[2] * self.strides[2]
    }

    /// Vertex-id offset of the axes in `mask`.
    fn offset(&self, mask: u8) -> usize {
        (0..3)
            .filter(|&a| mask >> a & 1 == 1)
            .map(|a| self.strides[a])
            .sum()
    }
}

/// One kind of p-cell: all its translates over the grid.
#[derive(Clone, Debug)]
struct Kind {
    /// Vertex offsets from the lowest vertex as axis bit masks, increasing.
    masks: Vec<u8>,
    /// The axes the cell extends along (union of its masks).
    span: u8,
}

/// The kinds of p-cell of a family in an n-dimensional grid, in numbering
/// order (lexicographic by mask list, which is sorted-vertex-list order).
fn kinds(family: Family, n: usize, p: usize) -> Vec<Kind> {
    let full: u8 = (1 << n) - 1;
    let mut lists: Vec<Vec<u8>> = match family {
        // All subsets of p axes, each with all its corners.
        Family::Cuboid => (0..=full)
            .filter(|s| s.count_ones() as usize == p)
            .map(|s| (0..=s).filter(|m| m & !s == 0).collect())
            .collect(),
        // Chains 0 ⊂ m_1 ⊂ … ⊂ m_p of axis sets: the vertices of a Kuhn
        // simplex walk up the cube, and every such chain is a face of one.
        Family::Kuhn => {
            let mut chains = vec![vec![0u8]];
            for _ in 0..p {
                chains = chains
                    .into_iter()
                    .flat_map(|chain| {
                        let last = chain.last().copied().unwrap_or(0);
                        (0..=full)
                            .filter(move |&m| m != last && m & last == last)
                            .map(move |m| {
                                let mut longer = chain.clone();
                                longer.push(m);
                                longer
                            })
                    })
                    .collect();
            }
            chains
        }
    };
    lists.sort_unstable();
    lists
        .into_iter()
        .map(|masks| Kind {
            span: masks.iter().fold(0, |span, m| span | m),
            masks,
        })
        .collect()
}

/// Orientation flag of a top kind: the sign of the determinant of the
/// frame its sorted vertices give (see the module documentation).
fn orientation(family: Family, n: usize, kind: &Kind) -> i8 {
    match family {
        Family::Cuboid => 1,
        Family::Kuhn => {
            let mut rows = [[0.0; 3]; 3];
            for (row, &m) in rows.iter_mut().zip(&kind.masks[1..]) {
                for (a, x) in row.iter_mut().enumerate().take(n) {
                    *x = f64::from(m >> a & 1);
                }
            }
            // A 0/1 matrix of order ≤ 3: its determinant is an exact integer.
            if frame::det(n, &rows) > 0.0 {
                1
            } else {
                -1
            }
        }
    }
}

/// The facets of a kind as (remaining masks, sign in ∂ before the top
/// orientation is applied).
fn facets(family: Family, kind: &Kind) -> Vec<(Vec<u8>, i8)> {
    let alternating = |k: usize| if k % 2 == 0 { 1 } else { -1 };
    match family {
        Family::Kuhn => (0..kind.masks.len())
            .map(|k| {
                let rest = kind
                    .masks
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != k)
                    .map(|(_, &m)| m)
                    .collect();
                (rest, alternating(k))
            })
            .collect(),
        Family::Cuboid => (0..8)
            .filter(|a| kind.span >> a & 1 == 1)
            .enumerate()
            .flat_map(|(k, a)| {
                (0..2u8).map(move |side| {
                    let rest = kind
                        .masks
                        .iter()
                        .copied()
                        .filter(|m| m >> a & 1 == side)
                        .collect();
                    let outward = if side == 1 { 1 } else { -1 };
                    (rest, outward * alternating(k))
                })
            })
            .collect(),
    }
}

/// A p-cell having a given (p−1)-cell as a facet, seen from the facet: the
/// p-cell's lowest vertex is the facet's minus the axes of `shift`.
#[derive(Clone, Copy, Debug)]
struct Coface {
    shift: u8,
    kind: usize,
    sign: i8,
}

/// For every lower kind, the cofaces of one of its cells: every facet of
/// every upper kind, moved so that its lowest vertex is the origin.
/// `signs[t]` multiplies the entries of upper kind t (the top orientation).
fn cofaces(
    family: Family,
    lower: &[Kind],
    upper: &[Kind],
    signs: &[i8],
) -> Result<Vec<Vec<Coface>>> {
    let mut out = vec![Vec::new(); lower.len()];
    for (t, kind) in upper.iter().enumerate() {
        for (rest, sign) in facets(family, kind) {
            // Every mask of the facet contains its lowest one (cube faces
            // and chains alike), so XOR subtracts it.
            let shift = rest.first().copied().unwrap_or(0);
            let relative: Vec<u8> = rest.iter().map(|m| m ^ shift).collect();
            let f = lower
                .iter()
                .position(|k| k.masks == relative)
                .ok_or_else(|| {
                    ComplexError::Invalid(format!(
                        "internal: facet {rest:?} of grid cell kind {:?} is no lower kind",
                        kind.masks
                    ))
                })?;
            out[f].push(Coface {
                shift,
                kind: t,
                sign: sign * signs[t],
            });
        }
    }
    Ok(out)
}

/// The p-cells of a grid: their kinds and where each x-line's cells start.
struct Level {
    kinds: Vec<Kind>,
    /// Per vertex class (see [`Grid::class`]): the kinds that fit there, in
    /// numbering order.
    fitting: [Vec<usize>; 8],
    /// `rank[class][kind]`: position of `kind` in `fitting[class]`.
    rank: [Vec<usize>; 8],
    /// Number of the first cell on each x-line; the total at the end.
    line_start: Vec<usize>,
}

impl Level {
    fn new(grid: &Grid, kinds: Vec<Kind>) -> Self {
        let mut fitting: [Vec<usize>; 8] = Default::default();
        let mut rank: [Vec<usize>; 8] = Default::default();
        for class in 0..8 {
            rank[class] = vec![usize::MAX; kinds.len()];
            for (t, kind) in kinds.iter().enumerate() {
                if usize::from(kind.span) & class == 0 {
                    rank[class][t] = fitting[class].len();
                    fitting[class].push(t);
                }
            }
        }
        let mut line_start = Vec::with_capacity(grid.lines + 1);
        let mut total = 0;
        for line in 0..grid.lines {
            line_start.push(total);
            // i = 0 is never the last index: an axis has 2 coordinates or more.
            let inner = grid.class([0, line % grid.counts[1], line / grid.counts[1]]);
            total += (grid.counts[0] - 1) * fitting[inner].len() + fitting[inner | 1].len();
        }
        line_start.push(total);
        Self {
            kinds,
            fitting,
            rank,
            line_start,
        }
    }

    fn count(&self) -> usize {
        self.line_start.last().copied().unwrap_or(0)
    }

    /// `visit(lowest vertex, kind)` for the cells of one x-line, in order.
    fn for_each_on_line(&self, grid: &Grid, line: usize, mut visit: impl FnMut([usize; 3], usize)) {
        let (j, k) = (line % grid.counts[1], line / grid.counts[1]);
        // Only the last i changes the class along the line.
        let inner = grid.class([0, j, k]);
        for i in 0..grid.counts[0] {
            let class = if i + 1 == grid.counts[0] {
                inner | 1
            } else {
                inner
            };
            for &kind in &self.fitting[class] {
                visit([i, j, k], kind);
            }
        }
    }
}

/// `data` cut at `bounds` (increasing, from 0 to `data.len()`): one slice
/// per consecutive pair, for writing the parts in parallel.
fn split_at_bounds<'a, T>(mut data: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(bounds.len().saturating_sub(1));
    for w in bounds.windows(2) {
        let (part, rest) = std::mem::take(&mut data).split_at_mut(w[1] - w[0]);
        parts.push(part);
        data = rest;
    }
    parts
}

fn internal(what: &str, e: sprs::errors::StructureError) -> ComplexError {
    ComplexError::Invalid(format!("internal: structured {what}: {e}"))
}

/// M_p: row c lists the vertices of p-cell c, increasing. Every row has
/// the same length, so each x-line's rows are one known slice of the
/// column indices, written in parallel.
fn characteristic_matrix(grid: &Grid, level: &Level) -> Result<CsMat<u8>> {
    let width = level.kinds.first().map_or(0, |k| k.masks.len());
    let offsets: Vec<Vec<usize>> = level
        .kinds
        .iter()
        .map(|k| k.masks.iter().map(|&m| grid.offset(m)).collect())
        .collect();
    let count = level.count();
    let mut indices = vec![0usize; count * width];
    let bounds: Vec<usize> = level.line_start.iter().map(|&s| s * width).collect();
    split_at_bounds(&mut indices, &bounds)
        .into_par_iter()
        .enumerate()
        .for_each(|(line, out)| {
            let mut rows = out.chunks_exact_mut(width);
            level.for_each_on_line(grid, line, |at, kind| {
                let origin = grid.vertex(at);
                if let Some(row) = rows.next() {
                    for (slot, offset) in row.iter_mut().zip(&offsets[kind]) {
                        *slot = origin + offset;
                    }
                }
            });
        });
    let indptr: Vec<usize> = (0..=count).into_par_iter().map(|c| c * width).collect();
    let data = vec![1u8; count * width];
    CsMat::try_new((count, grid.vertices), indptr, indices, data)
        .map_err(|e| internal("characteristic matrix", e.3))
}

/// One entry of a row of ∂_p, relative to the row's cell: the coface's
/// lowest vertex is `lines_back` x-lines and `steps_back` steps along x
/// before the cell's, where `per_vertex` upper cells start at each inner
/// vertex, and the coface is the `rank`-th cell at its vertex.
#[derive(Clone, Copy, Debug)]
struct Entry {
    lines_back: usize,
    steps_back: usize,
    per_vertex: usize,
    rank: usize,
    sign: i8,
}

/// For every [`Grid::position`] and lower kind, the entries of the row of
/// a cell of that kind there, in increasing column order. Columns grow
/// with the coface's x-line, then its x index, then its rank, so the order
/// is fixed by the stencil and no row needs sorting.
fn stencils(grid: &Grid, upper: &Level, cofaces: &[Vec<Coface>]) -> Vec<Vec<Vec<Entry>>> {
    (0..64)
        .map(|position: usize| {
            let first = |a: usize| position >> (2 * a) & 1 == 1;
            let last = |a: usize| position >> (2 * a + 1) & 1 == 1;
            cofaces
                .iter()
                .map(|list| {
                    let mut entries: Vec<Entry> = list
                        .iter()
                        .filter(|c| {
                            let span = upper.kinds[c.kind].span;
                            (0..3).all(|a| {
                                let shifted = c.shift >> a & 1 == 1;
                                // Stepping back needs room before; extending
                                // from the cell's own index needs room after.
                                !(shifted && first(a) || span >> a & 1 == 1 && !shifted && last(a))
                            })
                        })
                        .map(|c| {
                            let shifted = |a: usize| usize::from(c.shift >> a & 1);
                            // The coface's vertex is never last where it
                            // stepped back; elsewhere it is where the cell is.
                            let class = (0..3)
                                .filter(|&a| shifted(a) == 0 && last(a))
                                .fold(0, |class, a| class | 1 << a);
                            Entry {
                                lines_back: shifted(1) + shifted(2) * grid.counts[1],
                                steps_back: shifted(0),
                                per_vertex: upper.fitting[class & !1].len(),
                                rank: upper.rank[class][c.kind],
                                sign: c.sign,
                            }
                        })
                        .collect();
                    entries.sort_unstable_by_key(|e| {
                        (
                            std::cmp::Reverse(e.lines_back),
                            std::cmp::Reverse(e.steps_back),
                            e.rank,
                        )
                    });
                    entries
                })
                .collect()
        })
        .collect()
}

/// ∂_p: row r lists the p-cells having (p−1)-cell r as a facet, in
/// increasing order, with their signs. Two passes over the x-lines, both
/// in parallel: count each line's entries, then write each line's rows
/// into its slice of the arrays, each entry by the stencil of the row's
/// position.
fn boundary_matrix(
    grid: &Grid,
    lower: &Level,
    upper: &Level,
    cofaces: &[Vec<Coface>],
) -> Result<CsMat<i8>> {
    let stencils = stencils(grid, upper, cofaces);
    let class_of = |position: usize| (0..3).fold(0, |c, a| c | (position >> (2 * a + 1) & 1) << a);
    // Entries of all rows whose cells start at a vertex of each position.
    let vertex_entries: Vec<usize> = (0..64)
        .map(|position| {
            lower.fitting[class_of(position)]
                .iter()
                .map(|&kind| stencils[position][kind].len())
                .sum()
        })
        .collect();
    let line_entries: Vec<usize> = (0..grid.lines)
        .into_par_iter()
        .map(|line| {
            let (j, k) = (line % grid.counts[1], line / grid.counts[1]);
            (0..grid.counts[0])
                .map(|i| vertex_entries[grid.position([i, j, k])])
                .sum()
        })
        .collect();
    let mut entry_start = Vec::with_capacity(grid.lines + 1);
    let mut nnz = 0;
    for &e in &line_entries {
        entry_start.push(nnz);
        nnz += e;
    }
    entry_start.push(nnz);
    let rows = lower.count();
    let mut indptr = vec![0usize; rows + 1];
    let mut indices = vec![0usize; nnz];
    let mut data = vec![0i8; nnz];
    let pointers = split_at_bounds(&mut indptr[1..], &lower.line_start);
    let columns = split_at_bounds(&mut indices, &entry_start);
    let signs = split_at_bounds(&mut data, &entry_start);
    pointers
        .into_par_iter()
        .zip(columns)
        .zip(signs)
        .enumerate()
        .for_each(|(line, ((pointers, columns), signs))| {
            let (j, k) = (line % grid.counts[1], line / grid.counts[1]);
            let (mut written, mut row) = (0, 0);
            for i in 0..grid.counts[0] {
                let position = grid.position([i, j, k]);
                let row_stencils = &stencils[position];
                for &kind in &lower.fitting[class_of(position)] {
                    for e in &row_stencils[kind] {
                        let line_start = upper.line_start[line - e.lines_back];
                        columns[written] = line_start + (i - e.steps_back) * e.per_vertex + e.rank;
                        signs[written] = e.sign;
                        written += 1;
                    }
                    pointers[row] = entry_start[line] + written;
                    row += 1;
                }
            }
        });
    CsMat::try_new((rows, upper.count()), indptr, indices, data)
        .map_err(|e| internal("boundary matrix", e.3))
}

#[cfg(test)]
mod tests;
