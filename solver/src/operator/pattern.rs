//! The sparsity pattern of M = Aᵀ Ω A, built once per operator, and the
//! local unknown sets of Ω's blocks that the value pass reads.

use super::BlockMetric;
use crate::la::parallel::{ranges, split_at_ranges, zeroed};
use faer::sparse::SymbolicSparseColMat;
use rayon::prelude::*;
use sprs::CsMat;
use std::sync::Arc;

/// The two ways of forming M's values.
#[derive(Clone, Debug)]
pub(super) enum Assembly {
    /// Ω diagonal in row order: column j of M is Σ_r w_r a_rj A_r over
    /// the rows r of A that touch j, each column formed on its own.
    Diagonal(Columns),
    /// Any blocks: column j of M gathered from the blocks touching j.
    Blocks(LocalPattern),
}

/// A by columns: the rows of A (with a metric block) that touch each
/// unknown, in increasing order, and their signs; either built here or
/// A's CSC form shared with the complex that owns it.
#[derive(Clone, Debug)]
pub(super) enum Columns {
    Owned {
        ptr: Vec<usize>,
        rows: Vec<usize>,
        signs: Vec<i8>,
    },
    Shared(Arc<CsMat<i8>>),
}

impl Columns {
    /// Rows `0..rows` of the CSR matrix `a`, by columns.
    pub(super) fn new(a: &CsMat<i8>, rows: usize) -> Self {
        let n = a.cols();
        let end = a.indptr().index(rows) - a.indptr().index(0);
        let mut ptr = zeroed(n + 1);
        for &j in &a.indices()[..end] {
            ptr[j + 1] += 1;
        }
        for j in 0..n {
            ptr[j + 1] += ptr[j];
        }
        let mut next = ptr[..n].to_vec();
        let mut by_column = vec![0usize; end];
        let mut signs = vec![0i8; end];
        for r in 0..rows {
            let range = a.indptr().outer_inds_sz(r);
            for (&j, &sign) in a.indices()[range.clone()].iter().zip(&a.data()[range]) {
                by_column[next[j]] = r;
                signs[next[j]] = sign;
                next[j] += 1;
            }
        }
        Self::Owned {
            ptr,
            rows: by_column,
            signs,
        }
    }

    /// The rows touching unknown j and their signs.
    pub(super) fn column(&self, j: usize) -> (&[usize], &[i8]) {
        match self {
            Self::Owned { ptr, rows, signs } => {
                let range = ptr[j]..ptr[j + 1];
                (&rows[range.clone()], &signs[range])
            }
            Self::Shared(a) => {
                let range = a.indptr().outer_inds_sz(j);
                (&a.indices()[range.clone()], &a.data()[range])
            }
        }
    }
}

/// Block b of Ω touches only the unknowns in the columns of A's rows R_b
/// (its row side) and S_b (its column side); its contribution
/// A_{R_b}ᵀ W_b A_{S_b} is a dense matrix over those two sets. Assembly
/// forms M column by column: column j gathers, from every block with j on
/// its column side, that block's column j of A_{R_b}ᵀ W_b A_{S_b}, so a
/// dense element block (a Q1 hexahedron: 12 edge rows, 8 vertices) costs a
/// few products per entry and no map from local entries to M is stored.
#[derive(Clone, Debug)]
pub(super) enum LocalPattern {
    /// Gathered from A's rows, for any blocks.
    Gathered(GatheredPattern),
    /// Block b is top cell b of a complex over the cell's edges (a nodal
    /// element metric): both sides of block b are the cell's vertices, row
    /// b of the characteristic matrix M_n, and the blocks of unknown j are
    /// row j of the vertex star M_nᵀ, both shared with the complex instead
    /// of rebuilt.
    Cells(CellSides),
}

#[derive(Clone, Debug)]
pub(super) struct GatheredPattern {
    /// Block b's row-side unknowns are `unknowns[ptr[b]..ptr[b] + rows[b]]`
    /// and its column-side unknowns the rest up to `ptr[b + 1]`, each
    /// sorted and distinct; when `shared[b]` (the block's row and column
    /// sets are the same rows of A, as in every symmetric metric) the one
    /// list `unknowns[ptr[b]..ptr[b + 1]]` is both.
    ptr: Vec<usize>,
    rows: Vec<usize>,
    shared: Vec<bool>,
    unknowns: Vec<usize>,
    /// The blocks with unknown j on their column side are
    /// `blocks_of[block_ptr[j]..block_ptr[j + 1]]`, in block order.
    block_ptr: Vec<usize>,
    blocks_of: Vec<usize>,
}

#[derive(Clone, Debug)]
pub(super) struct CellSides {
    pub(super) vertices: Arc<CsMat<u8>>,
    pub(super) star: Arc<CsMat<u8>>,
}

impl GatheredPattern {
    /// The local unknown sets of every block, in block order, written
    /// straight into one list by [`compressed_lists`], and the blocks
    /// indexed by column-side unknown. A block's row side is read from A
    /// (`left`), its column side from B (`right`, A itself when `None`).
    pub(super) fn new(left: &CsMat<i8>, right: Option<&CsMat<i8>>, metric: &BlockMetric) -> Self {
        let same = right.is_none();
        let right = right.unwrap_or(left);
        // Append the distinct unknowns of the rows `list` of `a`, sorted.
        let side = |a: &CsMat<i8>, list: &[usize], out: &mut Vec<usize>| {
            let begin = out.len();
            for &x in list {
                out.extend_from_slice(&a.indices()[a.indptr().outer_inds_sz(x)]);
            }
            out[begin..].sort_unstable();
            let mut end = begin;
            for k in begin..out.len() {
                if end == begin || out[k] != out[end - 1] {
                    out[end] = out[k];
                    end += 1;
                }
            }
            out.truncate(end);
        };
        let shared: Vec<bool> = (0..metric.block_count())
            .into_par_iter()
            .map(|b| same && metric.rows_are_columns(b))
            .collect();
        let (ptr, unknowns) = compressed_lists(metric.block_count(), |b, out| {
            let (r, s, _) = metric.block(b);
            side(left, r, out);
            if !shared[b] {
                side(right, s, out);
            }
        });
        // The row side's length: the whole list when shared, else counted
        // again (unsymmetric blocks are the rare case).
        let rows = (0..metric.block_count())
            .into_par_iter()
            .map_init(Vec::new, |scratch, b| {
                if shared[b] {
                    ptr[b + 1] - ptr[b]
                } else {
                    scratch.clear();
                    side(left, metric.block(b).0, scratch);
                    scratch.len()
                }
            })
            .collect();
        let mut gathered = Self {
            ptr,
            rows,
            shared,
            unknowns,
            block_ptr: Vec::new(),
            blocks_of: Vec::new(),
        };
        gathered.index_blocks(right.cols());
        gathered
    }

    /// Row-side and column-side unknowns of block b.
    pub(super) fn sides(&self, b: usize) -> (&[usize], &[usize]) {
        let start = self.ptr[b];
        if self.shared[b] {
            let both = &self.unknowns[start..self.ptr[b + 1]];
            return (both, both);
        }
        let middle = start + self.rows[b];
        (
            &self.unknowns[start..middle],
            &self.unknowns[middle..self.ptr[b + 1]],
        )
    }

    /// Index the blocks by column-side unknown (n unknowns).
    pub(super) fn index_blocks(&mut self, n: usize) {
        let mut block_ptr = zeroed(n + 1);
        for b in 0..self.rows.len() {
            for &j in self.sides(b).1 {
                block_ptr[j + 1] += 1;
            }
        }
        for j in 0..n {
            block_ptr[j + 1] += block_ptr[j];
        }
        let mut blocks_of = vec![0usize; block_ptr[n]];
        let mut next = block_ptr.clone();
        for b in 0..self.rows.len() {
            for &j in self.sides(b).1 {
                blocks_of[next[j]] = b;
                next[j] += 1;
            }
        }
        drop(next);
        self.block_ptr = block_ptr;
        self.blocks_of = blocks_of;
    }
}

impl LocalPattern {
    /// Whether block b's row side is its column side.
    pub(super) fn is_shared(&self, b: usize) -> bool {
        match self {
            Self::Gathered(gathered) => gathered.shared[b],
            Self::Cells(_) => true,
        }
    }

    /// Row-side and column-side unknowns of block b.
    pub(super) fn sides(&self, b: usize) -> (&[usize], &[usize]) {
        match self {
            Self::Gathered(gathered) => gathered.sides(b),
            Self::Cells(cells) => {
                let m = &cells.vertices;
                let both = &m.indices()[m.indptr().outer_inds_sz(b)];
                (both, both)
            }
        }
    }

    /// The blocks with unknown j on their column side, in block order.
    pub(super) fn blocks_of(&self, j: usize) -> &[usize] {
        match self {
            Self::Gathered(g) => &g.blocks_of[g.block_ptr[j]..g.block_ptr[j + 1]],
            Self::Cells(cells) => {
                let m = &cells.star;
                &m.indices()[m.indptr().outer_inds_sz(j)]
            }
        }
    }

    /// The sparsity pattern of M: column j holds every row-side unknown of
    /// every block with j on its column side. Returns (column pointers, row
    /// indices), rows sorted within each column.
    pub(super) fn matrix_pattern(&self, n: usize) -> (Vec<usize>, Vec<usize>) {
        pattern_by_columns(n, |j, rows| {
            for &b in self.blocks_of(j) {
                // A block's unknowns are few (a cell's vertices): a copy
                // loop beats a call to memcpy per block.
                for &i in self.sides(b).0 {
                    rows.push(i);
                }
            }
        })
    }
}

/// The pattern of M = Aᵀ W A for every diagonal W with a weight on each
/// row of A (`incidence` by rows, `by_columns` the same matrix by
/// columns): the pattern [`Canonical`](super::Canonical) gives such an operator, known from
/// topology before any weight is computed.
pub(crate) fn diagonal_pattern(
    incidence: &CsMat<i8>,
    by_columns: &Arc<CsMat<i8>>,
) -> SymbolicSparseColMat<usize> {
    debug_assert!(incidence.is_csr() && by_columns.is_csc());
    debug_assert_eq!(incidence.shape(), by_columns.shape());
    matrix_pattern(
        incidence,
        incidence,
        &Assembly::Diagonal(Columns::Shared(Arc::clone(by_columns))),
    )
}

/// The pattern of a nodal operator whose every top cell couples all its
/// vertices (a dense block per cell, or P1 weights on a simplex's edges),
/// restricted to the vertices with `keep[v]` and renumbered in increasing
/// order: column k, the k-th kept vertex, holds the kept vertices that
/// share a top cell with it. `cells_by_vertex` is the vertex star (vertex
/// × top cell) and `cell_vertices(c)` a top cell's vertices.
pub(crate) fn clique_pattern<'a>(
    cells_by_vertex: &CsMat<u8>,
    cell_vertices: impl Fn(usize) -> &'a [usize] + Sync,
    keep: &[bool],
) -> SymbolicSparseColMat<usize> {
    let mut new_index = vec![usize::MAX; keep.len()];
    let mut kept = Vec::new();
    for (v, _) in keep.iter().enumerate().filter(|(_, &k)| k) {
        new_index[v] = kept.len();
        kept.push(v);
    }
    let (col_ptr, row_idx) = pattern_by_columns(kept.len(), |k, out| {
        let star = cells_by_vertex.indptr().outer_inds_sz(kept[k]);
        for &c in &cells_by_vertex.indices()[star] {
            out.extend(
                cell_vertices(c)
                    .iter()
                    .map(|&u| new_index[u])
                    .filter(|&i| i != usize::MAX),
            );
        }
    });
    SymbolicSparseColMat::new_checked(kept.len(), kept.len(), col_ptr, None, row_idx)
}

/// The pattern of M = Aᵀ Ω B (B = A for a square operator) for the way
/// its values are formed: column j holds the unknowns of A's rows that
/// meet column j of B through Ω.
pub(super) fn matrix_pattern(
    left: &CsMat<i8>,
    right: &CsMat<i8>,
    assembly: &Assembly,
) -> SymbolicSparseColMat<usize> {
    let n = right.cols();
    let (col_ptr, row_idx) = match assembly {
        Assembly::Diagonal(columns) => pattern_by_columns(n, |j, out| {
            for &r in columns.column(j).0 {
                out.extend_from_slice(&left.indices()[left.indptr().outer_inds_sz(r)]);
            }
        }),
        Assembly::Blocks(local) => local.matrix_pattern(n),
    };
    SymbolicSparseColMat::new_checked(left.cols(), n, col_ptr, None, row_idx)
}

/// The pattern (column pointers, row indices) of an n-column matrix whose
/// column j holds the rows `candidates(j, out)` appends to `out` (repeats
/// allowed), sorted within each column. A column's candidates are few (a
/// vertex's cells times their vertices), so sorting them in a small
/// scratch vector beats an n-sized marker per task.
pub(super) fn pattern_by_columns(
    n: usize,
    candidates: impl Fn(usize, &mut Vec<usize>) + Sync,
) -> (Vec<usize>, Vec<usize>) {
    compressed_lists(n, |j, out| {
        candidates(j, out);
        out.sort_unstable();
        out.dedup();
    })
}

/// n lists in one array (pointers, items): list j is what `fill(j, out)`
/// leaves in the cleared `out`. Each list is formed once, in parallel over
/// a few ranges of j, into its range's own buffer; the buffers are then
/// copied into place.
fn compressed_lists(
    n: usize,
    fill: impl Fn(usize, &mut Vec<usize>) + Sync,
) -> (Vec<usize>, Vec<usize>) {
    let parts = ranges(n);
    let mut ptr = vec![0usize; n + 1];
    let counts = split_at_ranges(&mut ptr[1..], &parts, |j| j);
    let buffers: Vec<Vec<usize>> = parts
        .par_iter()
        .zip(counts)
        .map_init(Vec::new, |scratch, (range, counts)| {
            let mut buffer = Vec::new();
            for (j, count) in range.clone().zip(counts) {
                scratch.clear();
                fill(j, scratch);
                *count = scratch.len();
                if buffer.is_empty() {
                    // The first list's length times the range's: one
                    // allocation for lists of even length.
                    buffer.reserve(scratch.len() * range.len() * 5 / 4);
                }
                buffer.extend_from_slice(scratch);
            }
            buffer
        })
        .collect();
    for j in 0..n {
        ptr[j + 1] += ptr[j];
    }
    let mut items = vec![0usize; ptr[n]];
    let pieces = split_at_ranges(&mut items, &parts, |j| ptr[j]);
    pieces
        .into_par_iter()
        .zip(buffers)
        .for_each(|(out, buffer)| out.copy_from_slice(&buffer));
    (ptr, items)
}
