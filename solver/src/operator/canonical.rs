//! The canonical form M = δ Ω ∂ = Aᵀ Ω A.
//!
//! A is an exact integer incidence matrix (rows: the cells that carry
//! fluxes, columns: the unknowns); Ω is the metric, a sum of small dense
//! blocks Σ_b E_{R_b}ᵀ W_b E_{S_b} over row sets R_b, S_b of A. A diagonal Ω
//! has one 1×1 block per row, a finite-element Ω one block per cell over the
//! cell's edges, a user-given sparse Ω one 1×1 block per entry.
//!
//! Assembly is split like a sparse factorisation: the sparsity pattern of
//! M, and how values reach it, are built once ([`Canonical::new`]);
//! numeric assembly ([`Canonical::assemble`]) can then be repeated with new
//! values of the same pattern ([`Canonical::set_metric`]). No map from
//! local entries to M is kept: M is formed column by column in parallel.
//! For a general Ω column j gathers column j of each local matrix
//! A_{R_b}ᵀ W_b A_{S_b} whose block touches j (blocks indexed by unknown
//! with the pattern); for a diagonal Ω (two-point fluxes, diagonal Hodge
//! stars) column j is Σ_r w_r a_rj A_r over the rows of A touching j,
//! from A stored by columns.

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use sprs::CsMat;
use std::sync::{Arc, OnceLock};

/// Errors in building a canonical operator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CanonicalError {
    #[error("metric has size {metric} but the incidence matrix has {rows} rows")]
    SizeMismatch { metric: usize, rows: usize },
    #[error("metric block {block} refers to row {row}, beyond the {size} rows of A")]
    RowOutOfRange {
        block: usize,
        row: usize,
        size: usize,
    },
    #[error("metric block {block} has {found} values for a {rows}×{cols} block")]
    BlockShape {
        block: usize,
        rows: usize,
        cols: usize,
        found: usize,
    },
    #[error("metric block {block} has a non-finite value")]
    NonFinite { block: usize },
    #[error("new metric values do not have the pattern the operator was built with")]
    PatternChanged,
}

#[derive(Clone, Debug, PartialEq)]
struct Block {
    rows: (usize, usize),
    cols: (usize, usize),
    values: usize,
}

/// Square blocks over their own rows, back to back (a builder that knew
/// the block sizes in advance): block b covers the rows `rows` gives it
/// and its values are `values[value_ptr[b]..value_ptr[b + 1]]`. Two
/// pointers a block instead of a 40-byte record: at 10⁶ Q1 cells, 16 MB
/// instead of 40 MB.
#[derive(Clone, Debug, PartialEq)]
struct SquareBlocks {
    rows: SquareRows,
    value_ptr: Vec<usize>,
}

/// Where square blocks keep their rows.
#[derive(Clone, Debug, PartialEq)]
enum SquareRows {
    /// Block b covers the metric's `indices[ptr[b]..ptr[b + 1]]`.
    Listed { ptr: Vec<usize> },
    /// Block b covers the rows of column b of this CSC matrix, shared with
    /// the complex (∂₂ by cells: a 2D cell's sorted edges, 40 MB at 10⁶
    /// cells that a copy would write again); the metric keeps no indices.
    Columns(Arc<CsMat<i8>>),
}

impl SquareBlocks {
    fn count(&self) -> usize {
        self.value_ptr.len().saturating_sub(1)
    }

    /// Rows of block b, `indices` being the metric's.
    fn rows<'a>(&'a self, indices: &'a [usize], b: usize) -> &'a [usize] {
        match &self.rows {
            SquareRows::Listed { ptr } => &indices[ptr[b]..ptr[b + 1]],
            SquareRows::Columns(by_column) => {
                &by_column.indices()[by_column.indptr().outer_inds_sz(b)]
            }
        }
    }

    /// Every block's rows in block order, one list.
    fn all_rows<'a>(&'a self, indices: &'a [usize]) -> &'a [usize] {
        match &self.rows {
            SquareRows::Listed { .. } => indices,
            SquareRows::Columns(by_column) => {
                let ptr = by_column.indptr();
                let ptr = ptr.raw_storage();
                &by_column.indices()[ptr[0]..ptr[ptr.len() - 1]]
            }
        }
    }

    /// The block holding entry k of [`SquareBlocks::all_rows`].
    fn block_of_entry(&self, k: usize) -> usize {
        match &self.rows {
            SquareRows::Listed { ptr } => ptr.partition_point(|&p| p <= k) - 1,
            SquareRows::Columns(by_column) => {
                let ptr = by_column.indptr();
                let ptr = ptr.raw_storage();
                ptr.partition_point(|&p| p - ptr[0] <= k) - 1
            }
        }
    }

    /// The same blocks as records over the metric's `indices`, for a
    /// metric that is pushed to (shared rows are copied there first).
    fn records(&self, indices: &mut Vec<usize>) -> Vec<Block> {
        if let SquareRows::Columns(_) = &self.rows {
            *indices = self.all_rows(&[]).to_vec();
        }
        let mut start = 0;
        (0..self.count())
            .map(|b| {
                let m = self.rows(indices, b).len();
                let block = Block {
                    rows: (start, m),
                    cols: (start, m),
                    values: self.value_ptr[b],
                };
                start += m;
                block
            })
            .collect()
    }
}

/// The metric Ω as a sum of dense blocks over rows of A.
///
/// ```
/// use hasse_solver::operator::BlockMetric;
/// let mut omega = BlockMetric::new(3);
/// omega.push_symmetric(&[0, 2], &[2.0, -1.0, -1.0, 2.0]);
/// omega.push_block(&[1], &[1], &[5.0]);
/// assert_eq!(omega.apply(&[1.0, 1.0, 1.0]), vec![1.0, 5.0, 1.0]);
/// ```
#[derive(Clone, Debug, Default)]
pub struct BlockMetric {
    size: usize,
    /// Empty while Ω is diagonal in row order, block b being the 1×1
    /// block (b, b) (two-point fluxes, diagonal Hodge stars): then
    /// `indices` is empty too and `values` holds the k weights, 8 bytes a
    /// row instead of 64 with a block record. The first block that breaks
    /// the pattern writes the records of the earlier ones. Empty too when
    /// the blocks are `square`.
    blocks: Vec<Block>,
    /// The blocks when a builder laid them out square and back to back;
    /// a push turns them into records.
    square: Option<SquareBlocks>,
    indices: Vec<usize>,
    values: Vec<f64>,
    /// 0..k, built only if a diagonal metric is read block by block
    /// ([`BlockMetric::block`] returns index slices); cleared by pushes.
    identity: OnceLock<Vec<usize>>,
    /// Block b is the block of top cell b over that cell's edges, for
    /// every b (a nodal element metric built so); cleared by pushes.
    per_cell: bool,
    /// Every block is exactly symmetric with finite values, as its builder
    /// made it ([`BlockMetric::from_symmetric_blocks`]): the symmetry and
    /// finiteness scans then read nothing (each is a pass over 128 MB of
    /// values at 10⁶ Q1 cells). Cleared by pushes and by mutable access.
    exact: bool,
}

impl PartialEq for BlockMetric {
    fn eq(&self, other: &Self) -> bool {
        self.size == other.size
            && self.blocks == other.blocks
            && self.square == other.square
            && self.indices == other.indices
            && self.values == other.values
    }
}

impl BlockMetric {
    /// An empty metric (Ω = 0) over `size` rows.
    pub fn new(size: usize) -> Self {
        Self {
            size,
            ..Self::default()
        }
    }

    /// Ω = diag(values).
    pub fn diagonal(values: &[f64]) -> Self {
        Self::from_weights(values.to_vec())
    }

    /// Ω = diag(weights), taking the vector.
    pub fn from_weights(weights: Vec<f64>) -> Self {
        Self {
            size: weights.len(),
            blocks: Vec::new(),
            square: None,
            indices: Vec::new(),
            values: weights,
            identity: OnceLock::new(),
            per_cell: false,
            exact: false,
        }
    }

    /// The weights w when Ω = diag(w) with block b the 1×1 block (b, b)
    /// for b < w.len() (rows beyond have no block); `None` for any other
    /// layout of blocks. [`Canonical`] assembles such an Ω column by
    /// column, from A stored by columns.
    ///
    /// ```
    /// use hasse_solver::operator::BlockMetric;
    /// let mut omega = BlockMetric::from_weights(vec![2.0, 3.0]);
    /// omega.add_rows(1);
    /// omega.push_block(&[2], &[2], &[4.0]);
    /// assert_eq!(omega.diagonal_weights(), Some(&[2.0, 3.0, 4.0][..]));
    /// // A block off the diagonal (or out of row order) ends the layout.
    /// omega.push_block(&[0], &[1], &[1.0]);
    /// assert_eq!(omega.diagonal_weights(), None);
    /// assert_eq!(omega.block(1), (&[1][..], &[1][..], &[3.0][..]));
    /// ```
    pub fn diagonal_weights(&self) -> Option<&[f64]> {
        (self.blocks.is_empty() && self.square.is_none()).then_some(&self.values[..])
    }

    /// Ω from entries (row, column, value); repeated positions add up.
    pub fn from_triplets(size: usize, entries: &[(usize, usize, f64)]) -> Self {
        let mut m = Self::new(size);
        for &(r, s, v) in entries {
            m.push_block(&[r], &[s], &[v]);
        }
        m
    }

    /// Ω from square blocks over the same rows and columns, laid out back
    /// to back: block b covers the rows `indices[ptr[b]..ptr[b + 1]]` and
    /// its values (m_b × m_b row-major, m_b = ptr[b + 1] − ptr[b]) are
    /// `values[value_ptr[b]..value_ptr[b + 1]]`, following those of block
    /// b − 1. Builders that know their block sizes in advance write them in
    /// place (and in parallel) this way. `per_cell` says that block b is
    /// over the edges of top cell b of a complex, for every b
    /// ([`Canonical::with_cell_blocks`]).
    ///
    /// The caller guarantees that every block is exactly symmetric and
    /// finite (the FE builders mirror each block and reject a cell with a
    /// non-finite one), so [`BlockMetric::is_symmetric`] and the finiteness
    /// check of [`Canonical`] need not read the values; debug builds check
    /// it here.
    pub(crate) fn from_symmetric_blocks(
        size: usize,
        ptr: Vec<usize>,
        value_ptr: Vec<usize>,
        indices: Vec<usize>,
        values: Vec<f64>,
        per_cell: bool,
    ) -> Self {
        debug_assert_eq!(ptr.len(), value_ptr.len());
        debug_assert_eq!(ptr.last().copied().unwrap_or(0), indices.len());
        let rows = SquareRows::Listed { ptr };
        Self::exact_square(size, rows, value_ptr, indices, values, per_cell)
    }

    /// [`BlockMetric::from_symmetric_blocks`] with block b over the rows
    /// of column b of `by_column` (CSC, shared, not copied), one block per
    /// column.
    pub(crate) fn from_symmetric_column_blocks(
        size: usize,
        by_column: Arc<CsMat<i8>>,
        value_ptr: Vec<usize>,
        values: Vec<f64>,
        per_cell: bool,
    ) -> Self {
        debug_assert!(by_column.is_csc());
        debug_assert_eq!(by_column.cols() + 1, value_ptr.len());
        let rows = SquareRows::Columns(by_column);
        Self::exact_square(size, rows, value_ptr, Vec::new(), values, per_cell)
    }

    fn exact_square(
        size: usize,
        rows: SquareRows,
        value_ptr: Vec<usize>,
        indices: Vec<usize>,
        values: Vec<f64>,
        per_cell: bool,
    ) -> Self {
        debug_assert_eq!(value_ptr.last().copied().unwrap_or(0), values.len());
        let metric = Self {
            size,
            blocks: Vec::new(),
            square: Some(SquareBlocks { rows, value_ptr }),
            indices,
            values,
            identity: OnceLock::new(),
            per_cell,
            exact: true,
        };
        debug_assert!((0..metric.block_count()).all(|b| {
            let (rows, _, w) = metric.block(b);
            let m = rows.len();
            w.len() == m * m
                && w.iter().all(|v| v.is_finite())
                && (0..m).all(|i| (0..i).all(|j| w[i * m + j] == w[j * m + i]))
        }));
        metric
    }

    /// Add the block W (|rows| × |cols|, row-major) at rows × cols.
    pub fn push_block(&mut self, rows: &[usize], cols: &[usize], values: &[f64]) {
        self.per_cell = false;
        self.exact = false;
        if let Some(square) = self.square.take() {
            self.blocks = square.records(&mut self.indices);
            if self.blocks.is_empty() {
                // No blocks at all: the empty diagonal layout.
                self.indices.clear();
            }
        }
        if self.blocks.is_empty() {
            let next = self.values.len();
            if let ([r], [c], [v]) = (rows, cols, values) {
                if *r == next && *c == next {
                    self.values.push(*v);
                    self.identity = OnceLock::new();
                    return;
                }
            }
            self.indices = (0..next).collect();
            self.identity = OnceLock::new();
            // Rows and columns of a diagonal block share its one index.
            self.blocks = (0..next)
                .map(|b| Block {
                    rows: (b, 1),
                    cols: (b, 1),
                    values: b,
                })
                .collect();
        }
        let r0 = self.indices.len();
        self.indices.extend_from_slice(rows);
        // A symmetric block's columns are its rows: stored once.
        let c0 = if rows == cols {
            r0
        } else {
            self.indices.extend_from_slice(cols);
            r0 + rows.len()
        };
        let v0 = self.values.len();
        self.values.extend_from_slice(values);
        self.blocks.push(Block {
            rows: (r0, rows.len()),
            cols: (c0, cols.len()),
            values: v0,
        });
    }

    /// Add a square block over the same rows and columns.
    pub fn push_symmetric(&mut self, rows: &[usize], values: &[f64]) {
        self.push_block(rows, rows, values);
    }

    /// Append `count` rows (and columns) with no blocks yet.
    pub fn add_rows(&mut self, count: usize) {
        self.size += count;
    }

    /// Number of rows (and columns) of Ω.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Number of blocks.
    pub fn block_count(&self) -> usize {
        match &self.square {
            Some(square) => square.count(),
            None if self.blocks.is_empty() => self.values.len(),
            None => self.blocks.len(),
        }
    }

    /// Rows, columns and values of block `b`.
    pub fn block(&self, b: usize) -> (&[usize], &[usize], &[f64]) {
        if let Some(square) = &self.square {
            let rows = square.rows(&self.indices, b);
            return (
                rows,
                rows,
                &self.values[square.value_ptr[b]..square.value_ptr[b + 1]],
            );
        }
        if self.blocks.is_empty() {
            let identity = self
                .identity
                .get_or_init(|| (0..self.values.len()).collect());
            let index = &identity[b..b + 1];
            return (index, index, &self.values[b..b + 1]);
        }
        let block = &self.blocks[b];
        let rows = &self.indices[block.rows.0..block.rows.0 + block.rows.1];
        let cols = &self.indices[block.cols.0..block.cols.0 + block.cols.1];
        let values = &self.values[block.values..block.values + block.rows.1 * block.cols.1];
        (rows, cols, values)
    }

    /// True when block `b`'s columns are its rows (a square block over
    /// one set of rows, as every symmetric metric block is).
    fn rows_are_columns(&self, b: usize) -> bool {
        if self.square.is_some() {
            return true;
        }
        match self.blocks.get(b) {
            // Stored once when pushed or built that way: no compare.
            Some(block) if block.rows == block.cols => true,
            Some(_) => {
                let (rows, cols, _) = self.block(b);
                rows == cols
            }
            None => true,
        }
    }

    /// Mutable values of block `b` (row-major).
    pub fn block_values_mut(&mut self, b: usize) -> &mut [f64] {
        self.exact = false;
        if let Some(square) = &self.square {
            return &mut self.values[square.value_ptr[b]..square.value_ptr[b + 1]];
        }
        if self.blocks.is_empty() {
            return &mut self.values[b..b + 1];
        }
        let block = &self.blocks[b];
        let len = block.rows.1 * block.cols.1;
        &mut self.values[block.values..block.values + len]
    }

    /// Ω x.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.size];
        if let Some(w) = self.diagonal_weights() {
            for ((y, w), x) in y.iter_mut().zip(w).zip(x) {
                *y = w * x;
            }
            return y;
        }
        for b in 0..self.block_count() {
            let (rows, cols, w) = self.block(b);
            for (i, &r) in rows.iter().enumerate() {
                y[r] += cols
                    .iter()
                    .enumerate()
                    .map(|(j, &s)| w[i * cols.len() + j] * x[s])
                    .sum::<f64>();
            }
        }
        y
    }

    /// Ω as a dense matrix (for tests and small problems).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.size]; self.size];
        for b in 0..self.block_count() {
            let (rows, cols, w) = self.block(b);
            for (i, &r) in rows.iter().enumerate() {
                for (j, &s) in cols.iter().enumerate() {
                    d[r][s] += w[i * cols.len() + j];
                }
            }
        }
        d
    }

    /// True when every block is square over equal row/column sets and
    /// symmetric to `tolerance` relative to its largest entry. This is a
    /// sufficient condition for Ω (and so Aᵀ Ω A) to be symmetric.
    pub fn is_symmetric(&self, tolerance: f64) -> bool {
        self.exact
            || self.diagonal_weights().is_some()
            || (0..self.block_count()).into_par_iter().all(|b| {
                let (rows, cols, w) = self.block(b);
                if rows != cols {
                    return false;
                }
                let k = rows.len();
                let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                (0..k).all(|i| {
                    (0..i).all(|j| (w[i * k + j] - w[j * k + i]).abs() <= tolerance * scale)
                })
            })
    }

    fn validate(&self) -> Result<(), CanonicalError> {
        if let Some(w) = self.diagonal_weights() {
            if w.len() > self.size {
                return Err(CanonicalError::RowOutOfRange {
                    block: self.size,
                    row: self.size,
                    size: self.size,
                });
            }
            return match w.iter().position(|v| !v.is_finite()) {
                Some(block) => Err(CanonicalError::NonFinite { block }),
                None => Ok(()),
            };
        }
        if let (true, Some(square)) = (self.exact, &self.square) {
            // Square, finite blocks by construction: only a row can be
            // wrong, and the rows are one list (columns of a matrix with
            // no more rows than Ω cannot be).
            if let SquareRows::Columns(by_column) = &square.rows {
                if by_column.rows() <= self.size {
                    return Ok(());
                }
            }
            let rows = square.all_rows(&self.indices);
            let largest = rows
                .par_chunks(1 << 16)
                .map(|chunk| chunk.iter().copied().max().unwrap_or(0))
                .max();
            if largest.is_none_or(|r| r < self.size) {
                return Ok(());
            }
            return match rows.iter().position(|&r| r >= self.size) {
                Some(k) => Err(CanonicalError::RowOutOfRange {
                    block: square.block_of_entry(k),
                    row: rows[k],
                    size: self.size,
                }),
                None => Ok(()),
            };
        }
        let check = |b: usize| {
            let (rows, cols, w) = self.block(b);
            if let Some(&row) = rows.iter().chain(cols).find(|&&r| r >= self.size) {
                return Err(CanonicalError::RowOutOfRange {
                    block: b,
                    row,
                    size: self.size,
                });
            }
            if w.len() != rows.len() * cols.len() {
                return Err(CanonicalError::BlockShape {
                    block: b,
                    rows: rows.len(),
                    cols: cols.len(),
                    found: w.len(),
                });
            }
            if w.iter().any(|v| !v.is_finite()) {
                return Err(CanonicalError::NonFinite { block: b });
            }
            Ok(())
        };
        // The first bad block in block order, whatever the threads did.
        match (0..self.block_count())
            .into_par_iter()
            .find_first(|&b| check(b).is_err())
        {
            Some(b) => check(b),
            None => Ok(()),
        }
    }

    fn same_pattern(&self, other: &Self) -> bool {
        self.size == other.size
            && self.blocks == other.blocks
            && self.square == other.square
            && self.indices == other.indices
            // Diagonal layouts keep no indices: their lengths say it.
            && self.values.len() == other.values.len()
    }
}

/// M = Aᵀ Ω A with its assembly pattern.
///
/// ```
/// use hasse_solver::operator::{BlockMetric, Canonical};
/// // A = ∂_1ᵀ of a path of 3 vertices (2 edges), Ω = identity:
/// // Aᵀ A is the graph Laplacian tridiag(−1, 2, −1) without the end rows.
/// let a = sprs::CsMat::new((2, 3), vec![0, 2, 4], vec![0, 1, 1, 2], vec![-1i8, 1, -1, 1]);
/// let op = Canonical::new(a, BlockMetric::diagonal(&[1.0, 1.0])).unwrap();
/// let m = op.assemble();
/// assert_eq!(m.to_dense()[(1, 1)], 2.0);
/// assert_eq!(m.to_dense()[(0, 1)], -1.0);
/// ```
#[derive(Clone, Debug)]
pub struct Canonical {
    /// Shared, so that a boundary matrix of the complex is used in place.
    incidence: Arc<CsMat<i8>>,
    metric: BlockMetric,
    /// The pattern of M, built with the operator; [`Canonical::assemble_owned`]
    /// hands it over to the matrix, and a later assembly builds it again.
    symbolic: OnceLock<SymbolicSparseColMat<usize>>,
    nonzeros: usize,
    /// How values reach M (boxed: it is large and `Canonical` sits in
    /// enums next to small variants).
    assembly: Box<Assembly>,
}

/// The two ways of forming M's values.
#[derive(Clone, Debug)]
enum Assembly {
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
enum Columns {
    Owned {
        ptr: Vec<usize>,
        rows: Vec<usize>,
        signs: Vec<i8>,
    },
    Shared(Arc<CsMat<i8>>),
}

impl Columns {
    /// Rows `0..rows` of the CSR matrix `a`, by columns.
    fn new(a: &CsMat<i8>, rows: usize) -> Self {
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
    fn column(&self, j: usize) -> (&[usize], &[i8]) {
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
enum LocalPattern {
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
struct GatheredPattern {
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
struct CellSides {
    vertices: Arc<CsMat<u8>>,
    star: Arc<CsMat<u8>>,
}

/// `len` zeros, written (in parallel when long) before anyone reads them.
/// A freshly allocated zeroed vector is not yet backed by memory: its
/// first read maps the shared zero page, and the write that follows faults
/// again and has every thread's TLB flushed. Accumulations (`v[i] += x`)
/// into such a vector cost two faults and a flush per page; writing the
/// zeros first costs one fault. On the 2D 1000² two-point assembly this
/// took the values pass from 0.10 s to 0.02 s.
pub(crate) fn zeroed<T: Copy + Default + Send + Sync>(len: usize) -> Vec<T> {
    let mut v = vec![T::default(); len];
    v.par_chunks_mut(1 << 15)
        .for_each(|chunk| chunk.fill(T::default()));
    v
}

/// `0..count` cut into a few contiguous ranges per thread, in order. Few
/// large tasks keep the per-task output vectors few, since every fresh
/// page of them costs a page fault;
/// the results are concatenated in range order, so they do not depend on
/// the thread count.
pub(crate) fn ranges(count: usize) -> Vec<std::ops::Range<usize>> {
    let parts = (4 * rayon::current_num_threads()).clamp(1, count.max(1));
    let size = count.div_ceil(parts).max(1);
    (0..count)
        .step_by(size)
        .map(|first| first..(first + size).min(count))
        .collect()
}

impl GatheredPattern {
    /// The local unknown sets of every block, in block order, written
    /// straight into one list by [`compressed_lists`], and the blocks
    /// indexed by column-side unknown (`n` unknowns).
    fn new(incidence: &CsMat<i8>, metric: &BlockMetric, n: usize) -> Self {
        // Append the distinct unknowns of the rows `list` of A, sorted.
        let side = |list: &[usize], out: &mut Vec<usize>| {
            let begin = out.len();
            for &x in list {
                out.extend_from_slice(&incidence.indices()[incidence.indptr().outer_inds_sz(x)]);
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
            .map(|b| metric.rows_are_columns(b))
            .collect();
        let (ptr, unknowns) = compressed_lists(metric.block_count(), |b, out| {
            let (r, s, _) = metric.block(b);
            side(r, out);
            if !shared[b] {
                side(s, out);
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
                    side(metric.block(b).0, scratch);
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
        gathered.index_blocks(n);
        gathered
    }

    /// Row-side and column-side unknowns of block b.
    fn sides(&self, b: usize) -> (&[usize], &[usize]) {
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
    fn index_blocks(&mut self, n: usize) {
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
    fn is_shared(&self, b: usize) -> bool {
        match self {
            Self::Gathered(gathered) => gathered.shared[b],
            Self::Cells(_) => true,
        }
    }

    /// Row-side and column-side unknowns of block b.
    fn sides(&self, b: usize) -> (&[usize], &[usize]) {
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
    fn blocks_of(&self, j: usize) -> &[usize] {
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
    fn matrix_pattern(&self, n: usize) -> (Vec<usize>, Vec<usize>) {
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
/// columns): the pattern [`Canonical`] gives such an operator, known from
/// topology before any weight is computed.
pub(crate) fn diagonal_pattern(
    incidence: &CsMat<i8>,
    by_columns: &Arc<CsMat<i8>>,
) -> SymbolicSparseColMat<usize> {
    debug_assert!(incidence.is_csr() && by_columns.is_csc());
    debug_assert_eq!(incidence.shape(), by_columns.shape());
    matrix_pattern(
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

/// The pattern of M = Aᵀ Ω A for the way its values are formed.
fn matrix_pattern(incidence: &CsMat<i8>, assembly: &Assembly) -> SymbolicSparseColMat<usize> {
    let n = incidence.cols();
    let (col_ptr, row_idx) = match assembly {
        Assembly::Diagonal(columns) => pattern_by_columns(n, |j, out| {
            for &r in columns.column(j).0 {
                out.extend_from_slice(&incidence.indices()[incidence.indptr().outer_inds_sz(r)]);
            }
        }),
        Assembly::Blocks(local) => local.matrix_pattern(n),
    };
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

/// The pattern (column pointers, row indices) of an n-column matrix whose
/// column j holds the rows `candidates(j, out)` appends to `out` (repeats
/// allowed), sorted within each column. A column's candidates are few (a
/// vertex's cells times their vertices), so sorting them in a small
/// scratch vector beats an n-sized marker per task.
fn pattern_by_columns(
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

/// `data` cut at `offset(range.start)` of each of the consecutive `parts`
/// (offsets relative to the first part's start), one piece per part, so
/// that parts can be filled in parallel.
pub(crate) fn split_at_ranges<'a, T>(
    data: &'a mut [T],
    parts: &[std::ops::Range<usize>],
    offset: impl Fn(usize) -> usize,
) -> Vec<&'a mut [T]> {
    let mut pieces = Vec::with_capacity(parts.len());
    let mut rest = data;
    for range in parts {
        let (head, tail) = rest.split_at_mut(offset(range.end) - offset(range.start));
        pieces.push(head);
        rest = tail;
    }
    pieces
}

/// Ω fits A's rows and holds finite values inside them.
fn check_sizes(incidence: &CsMat<i8>, metric: &BlockMetric) -> Result<(), CanonicalError> {
    if metric.size() != incidence.rows() {
        return Err(CanonicalError::SizeMismatch {
            metric: metric.size(),
            rows: incidence.rows(),
        });
    }
    metric.validate()
}

impl Canonical {
    /// Build the operator and its assembly pattern. `incidence` is A
    /// (rows: metric rows, columns: unknowns), exact integers.
    pub fn new(
        incidence: impl Into<Arc<CsMat<i8>>>,
        metric: BlockMetric,
    ) -> Result<Self, CanonicalError> {
        Self::build(incidence.into(), None, metric)
    }

    /// [`Canonical::new`] with A also given in CSC storage, `by_columns`,
    /// which must be the same matrix (a complex keeps ∂ₙ both ways: see
    /// `Complex::shared_boundary_csc`). A diagonal Ω over every row of A is
    /// then assembled from it in place instead of from a copy of A by
    /// columns. Only the shapes are checked, so this stays in the crate.
    pub(crate) fn with_columns(
        incidence: Arc<CsMat<i8>>,
        by_columns: Arc<CsMat<i8>>,
        metric: BlockMetric,
    ) -> Result<Self, CanonicalError> {
        debug_assert_eq!(by_columns.nnz(), incidence.nnz());
        Self::build(incidence, Some(by_columns), metric)
    }

    /// [`Canonical::new`] for a metric with one block per top cell of
    /// `complex`, block b over the edges of cell b (a nodal element
    /// metric: A = δ⁰, Ω from [`crate::metric::fe::stiffness_metric`]):
    /// the blocks' unknowns are read from the complex's characteristic
    /// matrix M_n and vertex star (its transpose) instead of being
    /// gathered from A's rows, which at 10⁶ Q1 cells is half the pattern's
    /// time and 80 MB. The same M to the bit; falls back to
    /// [`Canonical::new`] unless Ω was built with one block per cell and
    /// the shapes fit.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::operator::Canonical;
    /// use hasse_solver::metric::fe;
    /// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let omega = fe::stiffness_metric(&k, &[1.0; 4]).unwrap();
    /// let m = Canonical::with_cell_blocks(k.coboundary(0), omega.clone(), &k).unwrap().assemble();
    /// let plain = Canonical::new(k.coboundary(0), omega).unwrap().assemble();
    /// assert_eq!(m.val(), plain.val());
    /// ```
    pub fn with_cell_blocks(
        incidence: impl Into<Arc<CsMat<i8>>>,
        metric: BlockMetric,
        complex: &hasse_complex::Complex,
    ) -> Result<Self, CanonicalError> {
        let incidence = incidence.into();
        let n = complex.dim();
        let Ok(vertices) = complex.lar().shared_characteristic(n) else {
            return Self::new(incidence, metric);
        };
        let star = complex.shared_vertex_star(n);
        let fits = incidence.is_csr()
            && metric.per_cell
            && metric.diagonal_weights().is_none()
            && metric.block_count() == vertices.rows()
            && vertices.is_csr()
            && star.is_csr()
            && vertices.cols() == incidence.cols()
            && star.rows() == incidence.cols()
            && star.cols() == vertices.rows()
            && (0..metric.block_count())
                .into_par_iter()
                .all(|b| metric.rows_are_columns(b));
        if !fits {
            return Self::new(incidence, metric);
        }
        check_sizes(&incidence, &metric)?;
        let local = LocalPattern::Cells(CellSides { vertices, star });
        debug_assert!(
            {
                let gathered = GatheredPattern::new(&incidence, &metric, incidence.cols());
                (0..metric.block_count()).all(|b| gathered.sides(b) == local.sides(b))
            },
            "a block's edges do not touch exactly its cell's vertices"
        );
        Self::finish(incidence, metric, Assembly::Blocks(local))
    }

    fn build(
        incidence: Arc<CsMat<i8>>,
        by_columns: Option<Arc<CsMat<i8>>>,
        metric: BlockMetric,
    ) -> Result<Self, CanonicalError> {
        let incidence = if incidence.is_csr() {
            incidence
        } else {
            Arc::new(incidence.to_csr())
        };
        check_sizes(&incidence, &metric)?;
        let n = incidence.cols();
        let assembly = match metric.diagonal_weights() {
            Some(weights) => {
                let columns = match by_columns {
                    Some(by_columns)
                        if weights.len() == incidence.rows()
                            && by_columns.is_csc()
                            && by_columns.shape() == incidence.shape() =>
                    {
                        Columns::Shared(by_columns)
                    }
                    _ => Columns::new(&incidence, weights.len()),
                };
                Assembly::Diagonal(columns)
            }
            None => Assembly::Blocks(LocalPattern::Gathered(GatheredPattern::new(
                &incidence, &metric, n,
            ))),
        };
        Self::finish(incidence, metric, assembly)
    }

    fn finish(
        incidence: Arc<CsMat<i8>>,
        metric: BlockMetric,
        assembly: Assembly,
    ) -> Result<Self, CanonicalError> {
        let symbolic = matrix_pattern(&incidence, &assembly);
        Ok(Self {
            incidence,
            metric,
            nonzeros: symbolic.row_idx().len(),
            symbolic: OnceLock::from(symbolic),
            assembly: Box::new(assembly),
        })
    }

    /// The pattern of M, built again if [`Canonical::assemble_owned`] gave
    /// it away.
    fn pattern(&self) -> &SymbolicSparseColMat<usize> {
        self.symbolic
            .get_or_init(|| matrix_pattern(&self.incidence, &self.assembly))
    }

    /// Number of unknowns (columns of A).
    pub fn unknowns(&self) -> usize {
        self.incidence.cols()
    }

    /// The incidence matrix A.
    pub fn incidence(&self) -> &CsMat<i8> {
        &self.incidence
    }

    /// The incidence matrix A, shared.
    pub fn shared_incidence(&self) -> Arc<CsMat<i8>> {
        Arc::clone(&self.incidence)
    }

    /// The metric Ω.
    pub fn metric(&self) -> &BlockMetric {
        &self.metric
    }

    /// Replace Ω by one with the same blocks and new values; the assembly
    /// pattern is kept.
    pub fn set_metric(&mut self, metric: BlockMetric) -> Result<(), CanonicalError> {
        if !metric.same_pattern(&self.metric) {
            return Err(CanonicalError::PatternChanged);
        }
        metric.validate()?;
        self.metric = metric;
        Ok(())
    }

    /// Number of stored entries of M.
    pub fn nonzeros(&self) -> usize {
        self.nonzeros
    }

    /// M = Aᵀ Ω A (full symmetric storage when Ω is symmetric).
    ///
    /// Each block's dense A_Rᵀ W A_S is formed first and then added to M,
    /// block after block, so the sums (and so the bits) are the same for
    /// any thread count.
    pub fn assemble(&self) -> SparseColMat<usize, f64> {
        SparseColMat::new(self.pattern().clone(), self.values())
    }

    /// [`Canonical::assemble`] for the last (or only) assembly: the matrix
    /// takes the operator's copy of the pattern instead of a new one (at
    /// 10⁶ cells, 50–80 MB of fresh memory and its page faults). A later
    /// `assemble` builds the pattern again.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::operator::{BlockMetric, Canonical};
    /// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let faces = k.cell_count(1);
    /// let mut op = Canonical::new(k.shared_boundary(2), BlockMetric::diagonal(&vec![1.0; faces])).unwrap();
    /// let last = op.assemble_owned();
    /// // A later assembly builds the same pattern again.
    /// let again = op.assemble();
    /// assert_eq!(last.symbolic().row_idx(), again.symbolic().row_idx());
    /// assert_eq!(last.val(), again.val());
    /// ```
    pub fn assemble_owned(&mut self) -> SparseColMat<usize, f64> {
        let values = self.values();
        let symbolic = match self.symbolic.take() {
            Some(symbolic) => symbolic,
            None => matrix_pattern(&self.incidence, &self.assembly),
        };
        SparseColMat::new(symbolic, values)
    }

    /// M's values in the order of its pattern.
    fn values(&self) -> Vec<f64> {
        match (&*self.assembly, self.metric.diagonal_weights()) {
            (Assembly::Diagonal(columns), Some(weights)) => self.diagonal_values(columns, weights),
            (Assembly::Blocks(local), _) => self.block_values(local),
            // `set_metric` keeps the block layout, and with it the variant.
            (Assembly::Diagonal(_), None) => unreachable!("a diagonal pattern with a block metric"),
        }
    }

    /// Row r of A: its unknowns and signs.
    fn row(&self, r: usize) -> (&[usize], &[i8]) {
        let a = &*self.incidence;
        let range = a.indptr().outer_inds_sz(r);
        (&a.indices()[range.clone()], &a.data()[range])
    }

    /// M's values for Ω = diag(w), column after column in parallel; entry
    /// (i, j) sums w_r a_ri a_rj over r in increasing order, whatever the
    /// thread count.
    fn diagonal_values(&self, columns: &Columns, weights: &[f64]) -> Vec<f64> {
        let mut values = vec![0.0; self.nonzeros()];
        let pattern = self.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let parts = ranges(self.unknowns());
        let slices = split_at_ranges(&mut values, &parts, |j| col_ptr[j]);
        parts.into_par_iter().zip(slices).for_each(|(range, out)| {
            // Written before the sums read it (see `zeroed`): one page
            // fault per fresh page instead of two and a TLB flush.
            out.fill(0.0);
            let base = col_ptr[range.start];
            for j in range {
                let (first, last) = (col_ptr[j], col_ptr[j + 1]);
                let column = &row_idx[first..last];
                let column_values = &mut out[first - base..last - base];
                let (rows, signs) = columns.column(j);
                for (&r, &sign) in rows.iter().zip(signs) {
                    let weight = weights[r] * f64::from(sign);
                    let (unknowns, row_signs) = self.row(r);
                    for (&i, &x) in unknowns.iter().zip(row_signs) {
                        column_values[position(column, i)] += weight * f64::from(x);
                    }
                }
            }
        });
        values
    }

    /// M's values in parallel over ranges of columns: entry (i, j) adds the
    /// blocks' (A_Rᵀ W A_S)_ij in block order, each formed as
    /// Σ_r a_ri (Σ_s W_rs a_sj) with r and s in the block's order, whatever
    /// the thread count. Each range's thread walks the blocks that touch
    /// its columns in block order and reads each block's local incidence
    /// (A_R and A_S in the block's own unknown lists) once, for all of
    /// the block's columns in the range.
    fn block_values(&self, local: &LocalPattern) -> Vec<f64> {
        let mut values = vec![0.0; self.nonzeros()];
        let pattern = self.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let parts = ranges(self.unknowns());
        let slices = split_at_ranges(&mut values, &parts, |j| col_ptr[j]);
        parts.into_par_iter().zip(slices).for_each_init(
            BlockScratch::default,
            |scratch, (range, out)| {
                // Written before the sums read it (see `zeroed`).
                out.fill(0.0);
                let base = col_ptr[range.start];
                let touching = || {
                    range
                        .clone()
                        .flat_map(|j| local.blocks_of(j).iter().copied())
                };
                let (first, last, count) = touching().fold((usize::MAX, 0, 0), |(lo, hi, k), b| {
                    (lo.min(b), hi.max(b + 1), k + 1)
                });
                // Blocks numbered like their unknowns (cells and vertices of
                // a generated grid) touch a range in a short run of block
                // numbers: walk the run. Otherwise sort the touching blocks.
                let scattered;
                let blocks: &mut dyn Iterator<Item = usize> =
                    if last.saturating_sub(first) <= 2 * count {
                        &mut (first..last.max(first))
                    } else {
                        let mut list: Vec<usize> = touching().collect();
                        list.sort_unstable();
                        list.dedup();
                        scattered = list;
                        &mut scattered.iter().copied()
                    };
                for b in blocks {
                    let (_, right) = local.sides(b);
                    let in_range = right.partition_point(|&j| j < range.start)
                        ..right.partition_point(|&j| j < range.end);
                    if in_range.is_empty() {
                        continue;
                    }
                    self.add_block_columns(
                        local,
                        b,
                        in_range,
                        scratch,
                        |j, rows, column_values| {
                            // Both row lists are sorted and the block's are in
                            // M's column: one walk finds them all.
                            let column = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                            let target = &mut out[col_ptr[j] - base..col_ptr[j + 1] - base];
                            let mut k = 0;
                            for (&i, &v) in rows.iter().zip(column_values) {
                                while column[k] < i {
                                    k += 1;
                                }
                                target[k] += v;
                            }
                        },
                    );
                }
            },
        );
        values
    }

    /// Columns `columns` (positions in the block's column-side unknowns)
    /// of block b's A_Rᵀ W A_S, handed to `add(j, rows, values)` column
    /// by column, `rows` the block's row-side unknowns (sorted).
    fn add_block_columns(
        &self,
        local: &LocalPattern,
        b: usize,
        columns: std::ops::Range<usize>,
        scratch: &mut BlockScratch,
        mut add: impl FnMut(usize, &[usize], &[f64]),
    ) {
        let (rows, cols, w) = self.metric.block(b);
        let (left, right) = local.sides(b);
        // The Q1 cells' shapes (4 edges over 4 vertices, 12 over 8) in
        // fixed-size arrays.
        if local.is_shared(b) {
            match (rows.len(), left.len()) {
                (4, 4) => return self.square_block_columns::<4, 4>(rows, w, left, columns, add),
                (12, 8) => return self.square_block_columns::<12, 8>(rows, w, left, columns, add),
                _ => {}
            }
        }
        // A_S and A_R over the block's own unknowns: (local row, local
        // unknown, sign), in row order and each row's order; one list when
        // the block's rows are its columns.
        let BlockScratch {
            column_side,
            row_side,
            half,
            dense,
        } = scratch;
        let local_incidence = |a_rows: &[usize], unknowns: &[usize], out: &mut Vec<_>| {
            out.clear();
            for (k, &r) in a_rows.iter().enumerate() {
                let (row_unknowns, signs) = self.row(r);
                for (&u, &sign) in row_unknowns.iter().zip(signs) {
                    out.push((k, position(unknowns, u), f64::from(sign)));
                }
            }
        };
        local_incidence(cols, right, column_side);
        let row_side: &[(usize, usize, f64)] = if local.is_shared(b) {
            column_side
        } else {
            local_incidence(rows, left, row_side);
            row_side
        };
        // A_Rᵀ (W A_S)_{·j} on the stack when the block is small (every
        // FE cell), else in the scratch.
        let mut stack = [0.0; 16];
        let dense: &mut [f64] = if left.len() <= stack.len() {
            &mut stack[..left.len()]
        } else {
            dense.resize(left.len(), 0.0);
            dense
        };
        for jl in columns {
            // (W A_S)_{·j}, then A_Rᵀ (W A_S)_{·j}.
            half.clear();
            half.resize(rows.len(), 0.0);
            for &(si, _, sign) in column_side.iter().filter(|e| e.1 == jl) {
                for (ri, h) in half.iter_mut().enumerate() {
                    *h += w[ri * cols.len() + si] * sign;
                }
            }
            dense.fill(0.0);
            for &(ri, il, sign) in row_side {
                dense[il] += sign * half[ri];
            }
            add(right[jl], left, dense);
        }
    }

    /// [`Canonical::add_block_columns`] for a block over the same K rows
    /// on both sides, touching M unknowns (`unknowns`, sorted), in arrays
    /// of those sizes: A_c as a dense K × M matrix of signs, then
    /// (W A_c)_{·j} and A_cᵀ (W A_c)_{·j}. Every sum adds its nonzero
    /// terms in the order of the general path (rows in block order), and
    /// the zero terms in between leave a sum as it is, so the values are
    /// the general path's.
    fn square_block_columns<const K: usize, const M: usize>(
        &self,
        rows: &[usize],
        w: &[f64],
        unknowns: &[usize],
        columns: std::ops::Range<usize>,
        mut add: impl FnMut(usize, &[usize], &[f64]),
    ) {
        let mut signs = [[0.0; M]; K];
        for (signs_row, &r) in signs.iter_mut().zip(rows) {
            let (row_unknowns, row_signs) = self.row(r);
            for (&u, &sign) in row_unknowns.iter().zip(row_signs) {
                signs_row[position(unknowns, u)] = f64::from(sign);
            }
        }
        for jl in columns {
            let mut half = [0.0; K];
            for (h, w_row) in half.iter_mut().zip(w.chunks_exact(K)) {
                for (&weight, signs_row) in w_row.iter().zip(&signs) {
                    *h += weight * signs_row[jl];
                }
            }
            let mut column = [0.0; M];
            for (signs_row, &h) in signs.iter().zip(&half) {
                for (c, &sign) in column.iter_mut().zip(signs_row) {
                    *c += sign * h;
                }
            }
            add(unknowns[jl], unknowns, &column);
        }
    }

    /// A u: the differences of `u` across every metric row.
    pub fn difference(&self, u: &[f64]) -> Vec<f64> {
        let a = &self.incidence;
        a.outer_iterator()
            .map(|r| r.iter().map(|(j, &x)| f64::from(x) * u[j]).sum())
            .collect()
    }

    /// Aᵀ g for a cochain g on the metric rows.
    pub fn sum_transpose(&self, g: &[f64]) -> Vec<f64> {
        let mut out = zeroed(self.unknowns());
        for (r, row) in self.incidence.outer_iterator().enumerate() {
            for (j, &x) in row.iter() {
                out[j] += f64::from(x) * g[r];
            }
        }
        out
    }

    /// The flux cochain Ω A u.
    pub fn flux(&self, u: &[f64]) -> Vec<f64> {
        self.metric.apply(&self.difference(u))
    }

    /// M u computed as Aᵀ (Ω (A u)), without the assembled matrix.
    pub fn apply(&self, u: &[f64]) -> Vec<f64> {
        self.sum_transpose(&self.flux(u))
    }
}

/// Scratch of [`Canonical::add_block_columns`], reused from block to block.
#[derive(Default)]
struct BlockScratch {
    column_side: Vec<(usize, usize, f64)>,
    row_side: Vec<(usize, usize, f64)>,
    half: Vec<f64>,
    dense: Vec<f64>,
}

/// Index of `x` in the short list `list` (it is there).
fn position(list: &[usize], x: usize) -> usize {
    list.iter().position(|&y| y == x).unwrap_or(0)
}

/// Theorem 1 of the thesis: when A has trivial kernel, any matrix M of the
/// same unknowns is Aᵀ Ω A with Ω = Cᵀ M C for a left inverse C of A; here
/// C = (AᵀA)⁻¹Aᵀ. Returns the dense Ω, or `None` when A has a kernel.
pub fn metric_from_matrix(
    incidence: &nalgebra::DMatrix<f64>,
    matrix: &nalgebra::DMatrix<f64>,
) -> Option<nalgebra::DMatrix<f64>> {
    let gram = incidence.transpose() * incidence;
    let left_inverse = gram.try_inverse()? * incidence.transpose();
    Some(left_inverse.transpose() * matrix * left_inverse)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn square_blocks_read_like_records_and_turn_into_them_on_a_push() {
        // Two square blocks, over rows {0, 2} and {1, 2, 3}, back to back.
        let first = [2.0, -1.0, -1.0, 2.0];
        let second = [3.0, 0.5, 0.0, 0.5, 4.0, 1.0, 0.0, 1.0, 5.0];
        let values: Vec<f64> = first.iter().chain(&second).copied().collect();
        let square = BlockMetric::from_symmetric_blocks(
            5,
            vec![0, 2, 5],
            vec![0, 4, 13],
            vec![0, 2, 1, 2, 3],
            values,
            false,
        );
        let mut pushed = BlockMetric::new(5);
        pushed.push_symmetric(&[0, 2], &first);
        pushed.push_symmetric(&[1, 2, 3], &second);
        assert_eq!(square.block_count(), 2);
        assert_eq!(square.diagonal_weights(), None);
        for b in 0..2 {
            assert_eq!(square.block(b), pushed.block(b));
        }
        assert_eq!(square.to_dense(), pushed.to_dense());
        assert!(square.is_symmetric(0.0));
        // A push turns the square layout into records of the same blocks.
        let mut more = square.clone();
        more.push_block(&[4], &[4], &[7.0]);
        pushed.push_block(&[4], &[4], &[7.0]);
        assert_eq!(more, pushed);
        assert_eq!(more.apply(&[1.0; 5]), vec![1.0, 3.5, 6.5, 6.0, 7.0]);
    }

    /// The error of a five-row Ω whose block 1 lists row 7.
    fn assert_row_7_of_block_1(built: Result<Canonical, CanonicalError>) {
        let error = built.unwrap_err();
        assert!(
            matches!(
                error,
                CanonicalError::RowOutOfRange {
                    block: 1,
                    row: 7,
                    size: 5
                }
            ),
            "{error:?}"
        );
    }

    #[test]
    fn square_blocks_skip_the_value_scans_until_their_values_are_changed() {
        let square = |indices: Vec<usize>| {
            let values = [
                2.0, -1.0, -1.0, 2.0, 3.0, 0.5, 0.0, 0.5, 4.0, 1.0, 0.0, 1.0, 5.0,
            ];
            BlockMetric::from_symmetric_blocks(
                5,
                vec![0, 2, 5],
                vec![0, 4, 13],
                indices,
                values.to_vec(),
                false,
            )
        };
        let identity = || CsMat::<i8>::eye(5);
        assert!(Canonical::new(identity(), square(vec![0, 2, 1, 2, 3])).is_ok());
        // A row past Ω's size is still found, in the block that holds it.
        assert_row_7_of_block_1(Canonical::new(identity(), square(vec![0, 2, 1, 2, 7])));
        // Changed values are scanned again.
        let mut changed = square(vec![0, 2, 1, 2, 3]);
        assert!(changed.is_symmetric(0.0));
        changed.block_values_mut(1)[1] = 9.0;
        assert!(!changed.is_symmetric(1e-12));
        changed.block_values_mut(0)[3] = f64::NAN;
        let error = Canonical::new(identity(), changed).unwrap_err();
        assert!(
            matches!(error, CanonicalError::NonFinite { block: 0 }),
            "{error:?}"
        );
    }

    #[test]
    fn blocks_over_shared_columns_read_like_listed_rows() {
        // The two blocks of the test above, their rows {0, 2} and
        // {1, 2, 3} as the columns of a 5 × 2 CSC matrix.
        let values = vec![
            2.0, -1.0, -1.0, 2.0, 3.0, 0.5, 0.0, 0.5, 4.0, 1.0, 0.0, 1.0, 5.0,
        ];
        let columns = |rows: usize, last: usize| {
            Arc::new(CsMat::new_csc(
                (rows, 2),
                vec![0, 2, 5],
                vec![0, 2, 1, 2, last],
                vec![1i8; 5],
            ))
        };
        let listed = |last: usize| {
            BlockMetric::from_symmetric_blocks(
                5,
                vec![0, 2, 5],
                vec![0, 4, 13],
                vec![0, 2, 1, 2, last],
                values.clone(),
                true,
            )
        };
        let shared = |rows: usize, last: usize| {
            BlockMetric::from_symmetric_column_blocks(
                5,
                columns(rows, last),
                vec![0, 4, 13],
                values.clone(),
                true,
            )
        };
        let metric = shared(5, 3);
        assert_eq!(metric.block_count(), 2);
        for b in 0..2 {
            assert_eq!(metric.block(b), listed(3).block(b));
        }
        assert_eq!(metric.to_dense(), listed(3).to_dense());
        let identity = || CsMat::<i8>::eye(5);
        assert!(Canonical::new(identity(), metric.clone()).is_ok());
        // A row past Ω's size, in a matrix with more rows than Ω: named
        // with its block, as for listed rows.
        assert_row_7_of_block_1(Canonical::new(identity(), shared(8, 7)));
        // A push copies the rows out and continues as records.
        let mut pushed = metric;
        pushed.push_block(&[4], &[4], &[7.0]);
        let mut expected = listed(3);
        expected.push_block(&[4], &[4], &[7.0]);
        assert_eq!(pushed, expected);
        assert_eq!(pushed.apply(&[1.0; 5]), vec![1.0, 3.5, 6.5, 6.0, 7.0]);
    }

    /// M of `omega` on the nodal operator of `k`, through the blocks'
    /// own pattern and through the complex's cell lists.
    fn both_ways(
        k: &hasse_complex::Complex,
        omega: BlockMetric,
    ) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
        let gathered = Canonical::new(k.shared_coboundary(0), omega.clone()).unwrap();
        let from_cells = Canonical::with_cell_blocks(k.shared_coboundary(0), omega, k).unwrap();
        (gathered.assemble(), from_cells.assemble())
    }

    #[test]
    fn cell_blocks_give_the_nine_point_stencil_of_the_unit_grid() {
        // Q1 on a 3 × 3 grid of unit squares (h = 1): from the element
        // matrix (4, −1, −2 over 6 on the diagonal, along an edge, across
        // a diagonal), vertex (i, j) gets 4/6 from each of its cells, and
        // a neighbour −1/6 from each shared cell along an edge (two inside,
        // one on the boundary) or −2/6 across a diagonal (one cell).
        let k = hasse_complex::generate::rectangle(3, 3, [0.0, 3.0], [0.0, 3.0]).unwrap();
        let omega = crate::metric::fe::stiffness_metric(&k, &[1.0; 9]).unwrap();
        let (gathered, from_cells) = both_ways(&k, omega);
        assert_eq!(
            gathered.symbolic().col_ptr(),
            from_cells.symbolic().col_ptr()
        );
        assert_eq!(
            gathered.symbolic().row_idx(),
            from_cells.symbolic().row_idx()
        );
        assert_eq!(gathered.val(), from_cells.val());
        let dense = from_cells.to_dense();
        let at = |v: usize| {
            let p = k.vertices().point(v);
            (p[0].round() as i64, p[1].round() as i64)
        };
        let cells_of = |(x, y): (i64, i64)| {
            let side = |t: i64| if t == 0 || t == 3 { 1 } else { 2 };
            side(x) * side(y)
        };
        for u in 0..16 {
            for v in 0..16 {
                let ((xu, yu), (xv, yv)) = (at(u), at(v));
                let (dx, dy) = ((xu - xv).abs(), (yu - yv).abs());
                let expected = match (dx, dy) {
                    (0, 0) => 4.0 / 6.0 * f64::from(cells_of((xu, yu))),
                    (1, 0) | (0, 1) => {
                        // Cells on the edge: 2, or 1 when it is on the boundary.
                        let boundary = if dx == 1 {
                            yu == 0 || yu == 3
                        } else {
                            xu == 0 || xu == 3
                        };
                        -1.0 / 6.0 * if boundary { 1.0 } else { 2.0 }
                    }
                    (1, 1) => -2.0 / 6.0,
                    _ => 0.0,
                };
                assert!(
                    (dense[(u, v)] - expected).abs() < 1e-14,
                    "({u}, {v}): {} against {expected}",
                    dense[(u, v)]
                );
            }
        }
    }

    #[test]
    fn cell_blocks_assemble_like_the_gathered_pattern_on_hexahedra_and_polygons() {
        // Moved vertices: no two blocks are alike.
        let hexes =
            hasse_complex::generate::box3(3, 2, 2, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
        let moved: Vec<[f64; 3]> = (0..hexes.cell_count(0))
            .map(|v| {
                let p = hexes.vertices().point(v);
                let t = v as f64;
                [
                    p[0] + 0.02 * (1.3 * t).sin(),
                    p[1] + 0.02 * (0.7 * t).cos(),
                    p[2],
                ]
            })
            .collect();
        let hexes = hexes
            .with_vertices(hasse_complex::Vertices::from_points(&moved).unwrap())
            .unwrap();
        let tensors = vec![1.5; hexes.cell_count(3)];
        let omega = crate::metric::fe::stiffness_metric(&hexes, &tensors).unwrap();
        let (gathered, from_cells) = both_ways(&hexes, omega);
        assert_eq!(
            gathered.symbolic().row_idx(),
            from_cells.symbolic().row_idx()
        );
        assert_eq!(gathered.val(), from_cells.val());
        // Virtual elements on quadrilaterals.
        let quads = hasse_complex::generate::rectangle(4, 3, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let omega = crate::metric::fe::vem_stiffness_metric(&quads, &[1.0; 12]).unwrap();
        let (gathered, from_cells) = both_ways(&quads, omega);
        assert_eq!(gathered.val(), from_cells.val());
        // Constants are the kernel: every row of M sums to zero.
        let dense = from_cells.to_dense();
        for i in 0..dense.nrows() {
            let sum: f64 = (0..dense.ncols()).map(|j| dense[(i, j)]).sum();
            assert!(sum.abs() < 1e-13, "row {i} sums to {sum}");
        }
    }

    #[test]
    fn a_metric_pushed_to_after_it_was_built_per_cell_uses_its_own_pattern() {
        let k = hasse_complex::generate::rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let mut omega = crate::metric::fe::stiffness_metric(&k, &[1.0; 4]).unwrap();
        assert!(omega.per_cell);
        // One block more than cells: not one block per cell any longer.
        omega.push_symmetric(&[0], &[7.0]);
        assert!(!omega.per_cell);
        let (gathered, from_cells) = both_ways(&k, omega);
        assert_eq!(gathered.val(), from_cells.val());
        // Edge 0's extra weight 7 lands on its two ends a, b: +7 on (a, a),
        // −7 on (a, b).
        let (tail, head) = (k.cell_vertices(1, 0)[0], k.cell_vertices(1, 0)[1]);
        let plain = Canonical::new(
            k.shared_coboundary(0),
            crate::metric::fe::stiffness_metric(&k, &[1.0; 4]).unwrap(),
        )
        .unwrap()
        .assemble()
        .to_dense();
        let dense = from_cells.to_dense();
        assert!((dense[(tail, tail)] - plain[(tail, tail)] - 7.0).abs() < 1e-14);
        assert!((dense[(tail, head)] - plain[(tail, head)] + 7.0).abs() < 1e-14);
    }

    #[test]
    fn the_diagonal_pattern_is_the_cells_coupled_through_faces() {
        // Three cells in a row, four faces: ∂ by faces has rows (1), (−1, 1),
        // (−1, 1), (−1); ∂ᵀ∂ is tridiagonal whatever the face weights.
        let rows = CsMat::new(
            (4, 3),
            vec![0, 1, 3, 5, 6],
            vec![0, 0, 1, 1, 2, 2],
            vec![1i8, -1, 1, -1, 1, -1],
        );
        let by_columns = Arc::new(rows.to_csc());
        let pattern = diagonal_pattern(&rows, &by_columns);
        assert_eq!(pattern.col_ptr(), &[0, 2, 5, 7]);
        assert_eq!(pattern.row_idx(), &[0, 1, 0, 1, 2, 1, 2]);
        // The operator with real weights has that pattern too.
        let metric = BlockMetric::diagonal(&[2.0, 0.5, 3.0, 1.0]);
        let m = Canonical::new(rows, metric).unwrap().assemble();
        assert_eq!(m.symbolic().col_ptr(), pattern.col_ptr());
        assert_eq!(m.symbolic().row_idx(), pattern.row_idx());
    }

    #[test]
    fn theorem_one_reproduces_any_matrix_when_the_kernel_is_trivial() {
        // A = ∂_1 of a path of 6 edges with all 7 vertices kept (7 × 6, full
        // column rank); M = tridiag(−1, 3, −1), the thesis's implicit heat matrix.
        let mut a = DMatrix::zeros(7, 6);
        for e in 0..6 {
            a[(e, e)] = -1.0;
            a[(e + 1, e)] = 1.0;
        }
        let m = DMatrix::from_fn(6, 6, |i, j| match i.abs_diff(j) {
            0 => 3.0,
            1 => -1.0,
            _ => 0.0,
        });
        let omega = metric_from_matrix(&a, &m).unwrap();
        let back = a.transpose() * &omega * &a;
        assert!((back - &m).abs().max() < 1e-12);
        // A with a kernel (the closed cycle of 3 edges) has no left inverse.
        let mut cycle = DMatrix::zeros(3, 3);
        for e in 0..3 {
            cycle[(e, e)] = -1.0;
            cycle[((e + 1) % 3, e)] = 1.0;
        }
        assert!(metric_from_matrix(&cycle, &DMatrix::identity(3, 3)).is_none());
    }

    #[test]
    fn one_dimensional_identity_metric_gives_the_fe_stiffness() {
        // A = ∂_1ᵀ... thesis: A = ∂_1 ((n+1) × n, boundary vertices kept), Ω = I:
        // AᵀA = tridiag(−1, 2, −1).
        let n = 5;
        let mut tri = sprs::TriMat::new((n + 1, n));
        for e in 0..n {
            tri.add_triplet(e, e, -1i8);
            tri.add_triplet(e + 1, e, 1i8);
        }
        let op = Canonical::new(tri.to_csr(), BlockMetric::diagonal(&vec![1.0; n + 1])).unwrap();
        let m = op.assemble().to_dense();
        for i in 0..n {
            for j in 0..n {
                let expected = match i.abs_diff(j) {
                    0 => 2.0,
                    1 => -1.0,
                    _ => 0.0,
                };
                assert_eq!(m[(i, j)], expected);
            }
        }
    }

    #[test]
    fn dense_blocks_assemble_like_the_dense_triple_product() {
        // A: 4 rows × 3 unknowns; Ω: one 2×2 symmetric block + a diagonal entry
        // + an off-diagonal triplet pair (symmetric).
        let a = CsMat::new(
            (4, 3),
            vec![0, 2, 4, 5, 7],
            vec![0, 1, 1, 2, 0, 0, 2],
            vec![1i8, -1, 1, -1, 1, -1, 1],
        );
        let mut omega = BlockMetric::new(4);
        omega.push_symmetric(&[0, 1], &[2.0, 0.5, 0.5, 3.0]);
        omega.push_block(&[2], &[2], &[1.5]);
        omega.push_block(&[3], &[0], &[0.25]);
        omega.push_block(&[0], &[3], &[0.25]);
        let op = Canonical::new(a.clone(), omega.clone()).unwrap();
        let m = op.assemble().to_dense();
        let ad = DMatrix::from_fn(4, 3, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
        let od = DMatrix::from_fn(4, 4, |i, j| omega.to_dense()[i][j]);
        let expected = ad.transpose() * od * ad;
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[(i, j)] - expected[(i, j)]).abs() < 1e-15, "({i},{j})");
            }
        }
        // Matrix-free application agrees with the assembled matrix.
        let u = [0.3, -1.0, 2.0];
        let mu = op.apply(&u);
        for i in 0..3 {
            let row: f64 = (0..3).map(|j| expected[(i, j)] * u[j]).sum();
            assert!((mu[i] - row).abs() < 1e-14);
        }
        assert!(!omega.is_symmetric(0.0));
    }

    #[test]
    fn the_clique_pattern_couples_the_kept_vertices_of_each_cell() {
        // Two quadrilaterals side by side: bottom vertices 0 1 2, top 3 4
        // 5; cell 0 = {0, 1, 3, 4}, cell 1 = {1, 2, 4, 5}. Vertex 0 is
        // dropped, so vertices 1..5 become 0..4.
        let cells = [vec![0, 1, 3, 4], vec![1, 2, 4, 5]];
        let star = CsMat::new(
            (6, 2),
            vec![0, 1, 3, 4, 5, 7, 8],
            vec![0, 0, 1, 1, 0, 0, 1, 1],
            vec![1u8; 8],
        );
        let keep = [false, true, true, true, true, true];
        let pattern = clique_pattern(&star, |c| &cells[c][..], &keep);
        assert_eq!((pattern.nrows(), pattern.ncols()), (5, 5));
        assert_eq!(pattern.col_ptr(), &[0, 5, 9, 12, 17, 21]);
        assert_eq!(
            pattern.row_idx(),
            &[0, 1, 2, 3, 4, 0, 1, 3, 4, 0, 2, 3, 0, 1, 2, 3, 4, 0, 1, 3, 4]
        );
    }

    #[test]
    fn blocks_numbered_apart_from_their_unknowns_assemble_like_the_dense_product() {
        // A cycle of 240 unknowns numbered by a stride permutation, one row
        // (edge) per consecutive pair; blocks of three rows picked by
        // another stride, some symmetric, some with different row and
        // column sets, then a 1×1 block per row. A column range's blocks
        // are spread over the whole block range, so each range sorts them
        // (the nodal tests on generated grids take the run path).
        let n = 240;
        let label = |k: usize| (k * 7) % n;
        let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
        for r in 0..n {
            let (a, b) = (label(r), label((r + 1) % n));
            let (lo, hi, sign) = if a < b { (a, b, -1i8) } else { (b, a, 1i8) };
            indices.extend([lo, hi]);
            data.extend([sign, -sign]);
            indptr.push(indices.len());
        }
        let a = CsMat::new((n, n), indptr, indices, data);
        let mut omega = BlockMetric::new(n);
        let value = |b: usize, k: usize| 0.1 + ((b * 31 + k * 17) % 23) as f64 / 7.0;
        for b in 0..60 {
            let rows = [(b * 11) % n, (b * 11 + 97) % n, (b * 11 + 181) % n];
            let mut w = [0.0; 9];
            for i in 0..3 {
                for j in 0..=i {
                    let v = value(b, i * 3 + j) + if i == j { 5.0 } else { 0.0 };
                    w[i * 3 + j] = v;
                    w[j * 3 + i] = v;
                }
            }
            if b % 4 == 0 {
                let cols = [(b * 13 + 5) % n, (b * 13 + 50) % n, (b * 13 + 120) % n];
                omega.push_block(&rows, &cols, &w);
            } else {
                omega.push_symmetric(&rows, &w);
            }
        }
        for r in 0..n {
            omega.push_block(&[r], &[r], &[1.0 + r as f64 / n as f64]);
        }
        let m = Canonical::new(a.clone(), omega.clone())
            .unwrap()
            .assemble()
            .to_dense();
        let ad = DMatrix::from_fn(n, n, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
        let omega_dense = omega.to_dense();
        let od = DMatrix::from_fn(n, n, |i, j| omega_dense[i][j]);
        let expected = ad.transpose() * od * ad;
        // Entries are sums of a few products of values below 10: the two
        // orders of summation agree to a few ulps of 100.
        for i in 0..n {
            for j in 0..n {
                assert!((m[(i, j)] - expected[(i, j)]).abs() < 1e-12, "({i},{j})");
            }
        }
    }

    #[test]
    fn a_diagonal_metric_stays_compact_until_a_block_breaks_the_pattern() {
        let mut omega = BlockMetric::new(3);
        omega.push_block(&[0], &[0], &[2.0]);
        omega.push_block(&[1], &[1], &[3.0]);
        assert_eq!(omega.diagonal_weights(), Some(&[2.0, 3.0][..]));
        assert_eq!(omega.block_count(), 2);
        assert_eq!(omega.block(1), (&[1][..], &[1][..], &[3.0][..]));
        // An off-diagonal block: the earlier blocks get records and keep
        // their rows, columns and values.
        omega.push_block(&[2], &[0], &[5.0]);
        assert_eq!(omega.diagonal_weights(), None);
        assert_eq!(omega.block_count(), 3);
        assert_eq!(omega.block(0), (&[0][..], &[0][..], &[2.0][..]));
        assert_eq!(omega.block(2), (&[2][..], &[0][..], &[5.0][..]));
        let dense = omega.to_dense();
        assert_eq!(dense[0], vec![2.0, 0.0, 0.0]);
        assert_eq!(dense[1], vec![0.0, 3.0, 0.0]);
        assert_eq!(dense[2], vec![5.0, 0.0, 0.0]);
        // A block out of row order also ends the compact layout.
        let mut skipped = BlockMetric::new(3);
        skipped.push_block(&[1], &[1], &[1.0]);
        assert_eq!(skipped.diagonal_weights(), None);
        assert_eq!(skipped.apply(&[1.0, 4.0, 9.0]), vec![0.0, 4.0, 0.0]);
        // Out-of-range and non-finite diagonal entries are refused by number.
        let a = CsMat::new((2, 2), vec![0, 1, 3], vec![0, 0, 1], vec![1i8, -1, 1]);
        let mut long = BlockMetric::diagonal(&[1.0, 1.0]);
        long.push_block(&[2], &[2], &[1.0]);
        assert_eq!(
            Canonical::new(a.clone(), long).err(),
            Some(CanonicalError::RowOutOfRange {
                block: 2,
                row: 2,
                size: 2
            })
        );
        let mut beyond = BlockMetric::diagonal(&[1.0]);
        beyond.push_block(&[1], &[1], &[1.0]);
        beyond.push_block(&[2], &[2], &[1.0]);
        assert_eq!(beyond.diagonal_weights().map(<[f64]>::len), Some(3));
        assert_eq!(beyond.size(), 1);
        assert!(matches!(
            beyond.validate(),
            Err(CanonicalError::RowOutOfRange {
                block: 1,
                row: 1,
                size: 1
            })
        ));
        assert_eq!(
            Canonical::new(a, BlockMetric::diagonal(&[1.0, f64::NAN])).err(),
            Some(CanonicalError::NonFinite { block: 1 })
        );
    }

    #[test]
    fn diagonal_metrics_assemble_like_the_dense_triple_product_and_the_block_path() {
        // A = ∂_2 of a 3×2 grid of squares (17 edges × 6 cells): the
        // two-point flux operator. Dyadic weights make every sum exact, so
        // the column-wise diagonal assembly, the block-wise assembly and
        // the dense product must agree to the last bit.
        let grid = hasse_complex::generate::rectangle(3, 2, [0.0, 3.0], [0.0, 2.0]).unwrap();
        let a = grid.boundary(2).clone();
        let rows = a.rows();
        let weights: Vec<f64> = (0..rows).map(|r| 0.25 * (r % 5 + 1) as f64).collect();
        let dense_a = DMatrix::from_fn(rows, 6, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
        for blocks in [rows, rows - 4] {
            // Only the first `blocks` rows carry a weight; the rest have no
            // block at all and must not enter the pattern.
            let mut diagonal = BlockMetric::diagonal(&weights[..blocks]);
            diagonal.add_rows(rows - blocks);
            assert!(diagonal.diagonal_weights().is_some());
            let mut by_blocks = BlockMetric::new(rows);
            for r in (0..blocks).rev() {
                by_blocks.push_block(&[r], &[r], &[weights[r]]);
            }
            assert!(by_blocks.diagonal_weights().is_none());
            // With A's CSC form from the complex (used only when every
            // row has its weight) the result is the same.
            let shared = Canonical::with_columns(
                grid.shared_boundary(2),
                grid.shared_boundary_csc(2),
                diagonal.clone(),
            )
            .unwrap()
            .assemble();
            let fast = Canonical::new(a.clone(), diagonal).unwrap().assemble();
            let general = Canonical::new(a.clone(), by_blocks).unwrap().assemble();
            for other in [&general, &shared] {
                assert_eq!(fast.symbolic().col_ptr(), other.symbolic().col_ptr());
                assert_eq!(fast.symbolic().row_idx(), other.symbolic().row_idx());
                assert_eq!(fast.val(), other.val());
            }
            let w = DMatrix::from_fn(rows, rows, |i, j| {
                if i == j && i < blocks {
                    weights[i]
                } else {
                    0.0
                }
            });
            let expected = dense_a.transpose() * w * &dense_a;
            let m = fast.to_dense();
            for i in 0..6 {
                for j in 0..6 {
                    assert_eq!(
                        m[(i, j)],
                        expected[(i, j)],
                        "({i},{j}) with {blocks} blocks"
                    );
                }
            }
        }
        // Cells 0 and 5 (opposite corners) share no edge: no stored entry.
        let op = Canonical::new(a, BlockMetric::diagonal(&weights)).unwrap();
        let m = op.assemble();
        let column = &m.symbolic().row_idx()[m.symbolic().col_ptr()[0]..m.symbolic().col_ptr()[1]];
        assert!(!column.contains(&5));
    }

    #[test]
    fn the_last_assembly_takes_the_pattern_and_a_later_one_rebuilds_it() {
        // Q1 blocks on a 3×2 grid (block path) and two-point weights
        // (diagonal path): the owned assembly and the assemblies before and
        // after it, which rebuild the pattern, agree to the last bit.
        let grid = hasse_complex::generate::rectangle(3, 2, [0.0, 3.0], [0.0, 2.0]).unwrap();
        let q1 = crate::metric::fe::stiffness_metric(&grid, &[1.0; 6]).unwrap();
        let tpfa = crate::metric::fv::two_point(&grid, &[1.0; 6]).unwrap();
        for (a, metric) in [
            (Arc::new(grid.coboundary(0)), q1),
            (grid.shared_boundary(2), tpfa),
        ] {
            let mut op = Canonical::new(a, metric).unwrap();
            let before = op.assemble();
            let owned = op.assemble_owned();
            let after = op.assemble();
            for m in [&owned, &after] {
                assert_eq!(m.symbolic().col_ptr(), before.symbolic().col_ptr());
                assert_eq!(m.symbolic().row_idx(), before.symbolic().row_idx());
                assert_eq!(m.val(), before.val());
            }
            assert_eq!(op.nonzeros(), before.val().len());
        }
    }

    #[test]
    fn metric_values_can_change_without_a_new_pattern() {
        let a = CsMat::new((2, 2), vec![0, 1, 3], vec![0, 0, 1], vec![1i8, -1, 1]);
        let mut op = Canonical::new(a, BlockMetric::diagonal(&[1.0, 1.0])).unwrap();
        op.set_metric(BlockMetric::diagonal(&[2.0, 3.0])).unwrap();
        let m = op.assemble().to_dense();
        assert_eq!((m[(0, 0)], m[(0, 1)], m[(1, 1)]), (5.0, -3.0, 3.0));
        assert_eq!(
            op.set_metric(BlockMetric::from_triplets(2, &[(0, 1, 1.0)])),
            Err(CanonicalError::PatternChanged)
        );
    }
}
