//! Ω as a sum of dense blocks over rows of A: [`BlockMetric`].

use super::CanonicalError;
use rayon::prelude::*;
use sprs::CsMat;
use std::sync::{Arc, OnceLock};

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
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::fe;
/// use hasse_solver::operator::Canonical;
/// // Q1 on one unit square: one dense 4×4 block over the square's edges.
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let omega = fe::stiffness_metric(&k, &[1.0]).unwrap();
/// assert_eq!((omega.size(), omega.block_count()), (4, 1));
/// let (rows, cols, values) = omega.block(0);
/// assert_eq!((rows.len(), cols, values.len()), (4, rows, 16));
/// assert!(omega.is_symmetric(1e-14));
/// // δ⁰ᵀ Ω δ⁰ is the Q1 stiffness matrix: 2/3 on the diagonal, −1/6 along
/// // an edge, −1/3 across the diagonal.
/// let m = Canonical::new(k.coboundary(0), omega).unwrap().assemble().to_dense();
/// let mut row: Vec<f64> = (0..4).map(|j| m[(0, j)]).collect();
/// row.sort_by(f64::total_cmp);
/// for (a, b) in row.iter().zip([-1.0 / 3.0, -1.0 / 6.0, -1.0 / 6.0, 2.0 / 3.0]) {
///     assert!((a - b).abs() < 1e-14);
/// }
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
    pub(super) per_cell: bool,
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
    /// layout of blocks. [`Canonical`](super::Canonical) assembles such an
    /// Ω column by column, from A stored by columns.
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

    /// The metrics c_k Ω_k placed along the diagonal, the rows of each
    /// after those of the one before (see [`Canonical::sum`]); a list of
    /// diagonal metrics stays diagonal.
    ///
    /// [`Canonical::sum`]: super::Canonical::sum
    ///
    /// ```
    /// use hasse_solver::operator::BlockMetric;
    /// let mut dense = BlockMetric::new(2);
    /// dense.push_symmetric(&[0, 1], &[2.0, -1.0, -1.0, 2.0]);
    /// let both = BlockMetric::stacked(&[(2.0, &BlockMetric::diagonal(&[1.0])), (0.5, &dense)]);
    /// assert_eq!(both.to_dense(), vec![vec![2.0, 0.0, 0.0], vec![0.0, 1.0, -0.5], vec![0.0, -0.5, 1.0]]);
    /// ```
    pub fn stacked(parts: &[(f64, &BlockMetric)]) -> Self {
        let size = parts.iter().map(|(_, m)| m.size).sum();
        let diagonal: Option<Vec<f64>> = parts
            .iter()
            .map(|(c, m)| {
                let w = m.diagonal_weights().filter(|w| w.len() == m.size)?;
                Some(w.iter().map(|v| c * v).collect::<Vec<f64>>())
            })
            .collect::<Option<Vec<_>>>()
            .map(|pieces| pieces.concat());
        if let Some(weights) = diagonal {
            return Self::from_weights(weights);
        }
        let mut stacked = Self::new(size);
        let mut offset = 0;
        let (mut rows, mut cols, mut values) = (Vec::new(), Vec::new(), Vec::new());
        for (c, m) in parts {
            for b in 0..m.block_count() {
                let (r, s, w) = m.block(b);
                rows.clear();
                rows.extend(r.iter().map(|i| i + offset));
                cols.clear();
                cols.extend(s.iter().map(|i| i + offset));
                values.clear();
                values.extend(w.iter().map(|v| c * v));
                stacked.push_block(&rows, &cols, &values);
            }
            offset += m.size;
        }
        stacked
    }

    /// Ω from square blocks over the same rows and columns, laid out back
    /// to back: block b covers the rows `indices[ptr[b]..ptr[b + 1]]` and
    /// its values (m_b × m_b row-major, m_b = `ptr[b + 1] − ptr[b]`) are
    /// `values[value_ptr[b]..value_ptr[b + 1]]`, following those of block
    /// b − 1. Builders that know their block sizes in advance write them in
    /// place (and in parallel) this way. `per_cell` says that block b is
    /// over the edges of top cell b of a complex, for every b
    /// ([`Canonical::with_cell_blocks`](super::Canonical::with_cell_blocks)).
    ///
    /// The caller guarantees that every block is exactly symmetric and
    /// finite (the FE builders mirror each block and reject a cell with a
    /// non-finite one), so [`BlockMetric::is_symmetric`] and the finiteness
    /// check of [`Canonical`](super::Canonical) need not read the values;
    /// debug builds check it here.
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

    /// Rows, columns and values of block `b`, the values row-major
    /// (|rows| × |cols|).
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
    pub(super) fn rows_are_columns(&self, b: usize) -> bool {
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
    pub(crate) fn block_values_mut(&mut self, b: usize) -> &mut [f64] {
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

    pub(super) fn validate(&self) -> Result<(), CanonicalError> {
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

    pub(super) fn same_pattern(&self, other: &Self) -> bool {
        self.size == other.size
            && self.blocks == other.blocks
            && self.square == other.square
            && self.indices == other.indices
            // Diagonal layouts keep no indices: their lengths say it.
            && self.values.len() == other.values.len()
    }
}
