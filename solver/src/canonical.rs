//! The canonical form M = δ Ω ∂ = Aᵀ Ω A.
//!
//! A is an exact integer incidence matrix (rows: the cells that carry
//! fluxes, columns: the unknowns); Ω is the metric, a sum of small dense
//! blocks Σ_b E_{R_b}ᵀ W_b E_{S_b} over row sets R_b, S_b of A. A diagonal Ω
//! has one 1×1 block per row, a finite-element Ω one block per cell over the
//! cell's edges, a user-given sparse Ω one 1×1 block per entry.
//!
//! Assembly is split like a sparse factorisation: the sparsity pattern of
//! M and a scatter map from every entry of each block's local matrix
//! A_{R_b}ᵀ W_b A_{S_b} to its place in M are built once
//! ([`Canonical::new`]); numeric assembly ([`Canonical::assemble`]) is then
//! one pass over the blocks, and can be repeated with new values of the
//! same pattern ([`Canonical::set_metric`]).

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use sprs::CsMat;

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

/// The metric Ω as a sum of dense blocks over rows of A.
///
/// ```
/// use hasse_solver::canonical::BlockMetric;
/// let mut omega = BlockMetric::new(3);
/// omega.push_symmetric(&[0, 2], &[2.0, -1.0, -1.0, 2.0]);
/// omega.push_block(&[1], &[1], &[5.0]);
/// assert_eq!(omega.apply(&[1.0, 1.0, 1.0]), vec![1.0, 5.0, 1.0]);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BlockMetric {
    size: usize,
    blocks: Vec<Block>,
    indices: Vec<usize>,
    values: Vec<f64>,
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
        let mut m = Self::new(values.len());
        m.blocks.reserve(values.len());
        m.indices.reserve(values.len());
        m.values.reserve(values.len());
        for (r, &v) in values.iter().enumerate() {
            m.push_block(&[r], &[r], &[v]);
        }
        m
    }

    /// Ω from entries (row, column, value); repeated positions add up.
    pub fn from_triplets(size: usize, entries: &[(usize, usize, f64)]) -> Self {
        let mut m = Self::new(size);
        for &(r, s, v) in entries {
            m.push_block(&[r], &[s], &[v]);
        }
        m
    }

    /// Add the block W (|rows| × |cols|, row-major) at rows × cols.
    pub fn push_block(&mut self, rows: &[usize], cols: &[usize], values: &[f64]) {
        let r0 = self.indices.len();
        self.indices.extend_from_slice(rows);
        let c0 = self.indices.len();
        self.indices.extend_from_slice(cols);
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
        self.blocks.len()
    }

    /// Rows, columns and values of block `b`.
    pub fn block(&self, b: usize) -> (&[usize], &[usize], &[f64]) {
        let block = &self.blocks[b];
        let rows = &self.indices[block.rows.0..block.rows.0 + block.rows.1];
        let cols = &self.indices[block.cols.0..block.cols.0 + block.cols.1];
        let values = &self.values[block.values..block.values + block.rows.1 * block.cols.1];
        (rows, cols, values)
    }

    /// Mutable values of block `b` (row-major).
    pub fn block_values_mut(&mut self, b: usize) -> &mut [f64] {
        let block = &self.blocks[b];
        let len = block.rows.1 * block.cols.1;
        &mut self.values[block.values..block.values + len]
    }

    /// Ω x.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.size];
        for b in 0..self.blocks.len() {
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
        for b in 0..self.blocks.len() {
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
        (0..self.blocks.len()).all(|b| {
            let (rows, cols, w) = self.block(b);
            if rows != cols {
                return false;
            }
            let k = rows.len();
            let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            (0..k).all(|i| (0..i).all(|j| (w[i * k + j] - w[j * k + i]).abs() <= tolerance * scale))
        })
    }

    fn validate(&self) -> Result<(), CanonicalError> {
        for b in 0..self.blocks.len() {
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
        }
        Ok(())
    }

    fn same_pattern(&self, other: &Self) -> bool {
        self.size == other.size && self.blocks == other.blocks && self.indices == other.indices
    }
}

/// M = Aᵀ Ω A with its assembly pattern.
///
/// ```
/// use hasse_solver::canonical::{BlockMetric, Canonical};
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
    incidence: CsMat<i8>,
    metric: BlockMetric,
    symbolic: SymbolicSparseColMat<usize>,
    /// Where each block's local matrix goes in M (boxed: it is large and
    /// `Canonical` sits in enums next to small variants).
    local: Box<LocalPattern>,
}

/// Block b of Ω touches only the unknowns in the columns of A's rows R_b
/// (its row side) and S_b (its column side); its contribution
/// A_{R_b}ᵀ W_b A_{S_b} is a dense matrix over those two sets. Assembly
/// forms that small matrix and adds each of its entries once, so a dense
/// element block (a Q1 hexahedron: 12 edge rows, 8 vertices) costs 64
/// scatter entries, not the 576 products of every row pair with every
/// incidence pair.
#[derive(Clone, Debug)]
struct LocalPattern {
    /// Block b's row-side unknowns are `unknowns[ptr[b]..ptr[b] + rows[b]]`
    /// and its column-side unknowns the rest up to `ptr[b + 1]`, each
    /// sorted and distinct; when `shared[b]` (the block's row and column
    /// sets are the same rows of A, as in every symmetric metric) the one
    /// list `unknowns[ptr[b]..ptr[b + 1]]` is both.
    ptr: Vec<usize>,
    rows: Vec<usize>,
    shared: Vec<bool>,
    unknowns: Vec<usize>,
    /// Positions in M's value array of every local entry, block after
    /// block, each block row-major (row side × column side).
    scatter: Vec<usize>,
}

/// `0..count` cut into a few contiguous ranges per thread, in order. Few
/// large tasks keep the per-task output vectors few, since every fresh
/// page of them costs a page fault;
/// the results are concatenated in range order, so they do not depend on
/// the thread count.
fn ranges(count: usize) -> Vec<std::ops::Range<usize>> {
    let parts = (4 * rayon::current_num_threads()).clamp(1, count.max(1));
    let size = count.div_ceil(parts).max(1);
    (0..count)
        .step_by(size)
        .map(|first| first..(first + size).min(count))
        .collect()
}

impl LocalPattern {
    /// The local unknown sets of every block, in block order.
    fn new(incidence: &CsMat<i8>, metric: &BlockMetric) -> Self {
        let row = |r: usize| &incidence.indices()[incidence.indptr().outer_inds_sz(r)];
        type Chunk = (Vec<usize>, Vec<bool>, Vec<usize>, Vec<usize>);
        let chunks: Vec<Chunk> = ranges(metric.block_count())
            .into_par_iter()
            .map(|range| {
                let (first, last) = (range.start, range.end);
                let mut rows = Vec::with_capacity(last - first);
                let mut shared = Vec::with_capacity(last - first);
                let mut lengths = Vec::with_capacity(last - first);
                let mut unknowns = Vec::new();
                for b in first..last {
                    let (r, s, _) = metric.block(b);
                    let start = unknowns.len();
                    let same = r == s;
                    let sides: &[&[usize]] = if same { &[r] } else { &[r, s] };
                    for (k, side) in sides.iter().enumerate() {
                        let begin = unknowns.len();
                        for &x in *side {
                            unknowns.extend_from_slice(row(x));
                        }
                        unknowns[begin..].sort_unstable();
                        let distinct = dedup_tail(&mut unknowns, begin);
                        if k == 0 {
                            rows.push(distinct);
                        }
                    }
                    shared.push(same);
                    lengths.push(unknowns.len() - start);
                }
                (rows, shared, lengths, unknowns)
            })
            .collect();
        let mut pattern = Self {
            ptr: Vec::with_capacity(metric.block_count() + 1),
            rows: Vec::with_capacity(metric.block_count()),
            shared: Vec::with_capacity(metric.block_count()),
            unknowns: Vec::with_capacity(chunks.iter().map(|c| c.3.len()).sum()),
            scatter: Vec::new(),
        };
        pattern.ptr.push(0);
        for (rows, shared, lengths, unknowns) in chunks {
            pattern.rows.extend_from_slice(&rows);
            pattern.shared.extend_from_slice(&shared);
            for l in lengths {
                let end = pattern.ptr[pattern.ptr.len() - 1] + l;
                pattern.ptr.push(end);
            }
            pattern.unknowns.extend_from_slice(&unknowns);
        }
        pattern
    }

    fn block_count(&self) -> usize {
        self.rows.len()
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

    /// The sparsity pattern of M: column j holds every row-side unknown of
    /// every block with j on its column side. Returns (column pointers,
    /// row indices), rows sorted within each column.
    fn matrix_pattern(&self, n: usize) -> (Vec<usize>, Vec<usize>) {
        // Blocks by column-side unknown, in block order.
        let mut block_ptr = vec![0usize; n + 1];
        for b in 0..self.block_count() {
            for &j in self.sides(b).1 {
                block_ptr[j + 1] += 1;
            }
        }
        for j in 0..n {
            block_ptr[j + 1] += block_ptr[j];
        }
        let mut blocks_of = vec![0usize; block_ptr[n]];
        let mut next = block_ptr.clone();
        for b in 0..self.block_count() {
            for &j in self.sides(b).1 {
                blocks_of[next[j]] = b;
                next[j] += 1;
            }
        }
        drop(next);
        // A column's candidates are few (a vertex's cells times their
        // vertices), so sorting them beats an n-sized marker per task.
        let parts: Vec<(Vec<usize>, Vec<usize>)> = ranges(n)
            .into_par_iter()
            .map(|range| {
                let mut counts = Vec::with_capacity(range.len());
                let mut rows = Vec::new();
                for j in range {
                    let begin = rows.len();
                    for &b in &blocks_of[block_ptr[j]..block_ptr[j + 1]] {
                        rows.extend_from_slice(self.sides(b).0);
                    }
                    rows[begin..].sort_unstable();
                    counts.push(dedup_tail(&mut rows, begin));
                }
                (counts, rows)
            })
            .collect();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(parts.iter().map(|p| p.1.len()).sum());
        for (counts, rows) in parts {
            for c in counts {
                col_ptr.push(col_ptr[col_ptr.len() - 1] + c);
            }
            row_idx.extend_from_slice(&rows);
        }
        (col_ptr, row_idx)
    }

    /// Fill `scatter` for the pattern (col_ptr, row_idx).
    fn locate(&mut self, col_ptr: &[usize], row_idx: &[usize]) {
        let this = &*self;
        let chunks: Vec<Vec<usize>> = ranges(this.block_count())
            .into_par_iter()
            .map(|range| {
                let (first, last) = (range.start, range.end);
                let mut out = Vec::new();
                for b in first..last {
                    let (left, right) = this.sides(b);
                    for &i in left {
                        for &j in right {
                            let column = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                            // Present by construction of the pattern.
                            out.push(col_ptr[j] + column.binary_search(&i).unwrap_or(0));
                        }
                    }
                }
                out
            })
            .collect();
        self.scatter = chunks.concat();
    }
}

/// Remove repeated values from the sorted `v[begin..]`; returns how many
/// distinct values remain there.
fn dedup_tail(v: &mut Vec<usize>, begin: usize) -> usize {
    let mut write = begin;
    for read in begin..v.len() {
        if write == begin || v[read] != v[write - 1] {
            v[write] = v[read];
            write += 1;
        }
    }
    v.truncate(write);
    write - begin
}

impl Canonical {
    /// Build the operator and its assembly pattern. `incidence` is A
    /// (rows: metric rows, columns: unknowns), exact integers.
    pub fn new(incidence: CsMat<i8>, metric: BlockMetric) -> Result<Self, CanonicalError> {
        let incidence = if incidence.is_csr() {
            incidence
        } else {
            incidence.to_csr()
        };
        if metric.size() != incidence.rows() {
            return Err(CanonicalError::SizeMismatch {
                metric: metric.size(),
                rows: incidence.rows(),
            });
        }
        metric.validate()?;
        let n = incidence.cols();
        let mut local = LocalPattern::new(&incidence, &metric);
        let (col_ptr, row_idx) = local.matrix_pattern(n);
        local.locate(&col_ptr, &row_idx);
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Ok(Self {
            incidence,
            metric,
            symbolic,
            local: Box::new(local),
        })
    }

    /// Number of unknowns (columns of A).
    pub fn unknowns(&self) -> usize {
        self.incidence.cols()
    }

    /// The incidence matrix A.
    pub fn incidence(&self) -> &CsMat<i8> {
        &self.incidence
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
        self.symbolic.row_idx().len()
    }

    /// M = Aᵀ Ω A (full symmetric storage when Ω is symmetric).
    ///
    /// Each block's dense A_Rᵀ W A_S is formed first and then added to M,
    /// block after block, so the sums (and so the bits) are the same for
    /// any thread count.
    pub fn assemble(&self) -> SparseColMat<usize, f64> {
        let mut values = vec![0.0; self.nonzeros()];
        let a = &self.incidence;
        let row = |r: usize| {
            let range = a.indptr().outer_inds_sz(r);
            (&a.indices()[range.clone()], &a.data()[range])
        };
        let local = &self.local;
        // W A_S (|R| × |U_S|) and then A_Rᵀ (W A_S) (|U_R| × |U_S|).
        let mut half = Vec::new();
        let mut dense = Vec::new();
        let mut k = 0;
        for b in 0..self.metric.block_count() {
            let (rows, cols, w) = self.metric.block(b);
            let (left, right) = local.sides(b);
            let (p, q) = (left.len(), right.len());
            if let ([r], [s]) = (rows, cols) {
                // One row pair (a diagonal Ω, a face of a two-point flux):
                // when A's rows list their unknowns as the local lists do
                // (sorted, distinct), the local matrix is the outer
                // product a_r w a_sᵀ, with no position searches.
                let ((ur, ar), (us, as_)) = (row(*r), row(*s));
                if ur == left && us == right {
                    let places = &local.scatter[k..k + p * q];
                    for (i, &x) in ar.iter().enumerate() {
                        let wx = w[0] * f64::from(x);
                        for (j, &y) in as_.iter().enumerate() {
                            values[places[i * q + j]] += wx * f64::from(y);
                        }
                    }
                    k += p * q;
                    continue;
                }
            }
            half.clear();
            half.resize(rows.len() * q, 0.0);
            for (si, &s) in cols.iter().enumerate() {
                let (unknowns, signs) = row(s);
                for (&j, &sign) in unknowns.iter().zip(signs) {
                    let jl = position(right, j);
                    let sign = f64::from(sign);
                    for ri in 0..rows.len() {
                        half[ri * q + jl] += w[ri * cols.len() + si] * sign;
                    }
                }
            }
            dense.clear();
            dense.resize(p * q, 0.0);
            for (ri, &r) in rows.iter().enumerate() {
                let (unknowns, signs) = row(r);
                for (&i, &sign) in unknowns.iter().zip(signs) {
                    let il = position(left, i);
                    let sign = f64::from(sign);
                    for jl in 0..q {
                        dense[il * q + jl] += sign * half[ri * q + jl];
                    }
                }
            }
            for (&place, &v) in local.scatter[k..k + p * q].iter().zip(&dense) {
                values[place] += v;
            }
            k += p * q;
        }
        SparseColMat::new(self.symbolic.clone(), values)
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
        let mut out = vec![0.0; self.unknowns()];
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

/// Index of `x` in the short sorted list `list` (it is there).
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
