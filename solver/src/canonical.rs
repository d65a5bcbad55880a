//! The canonical form M = δ Ω ∂ = Aᵀ Ω A.
//!
//! A is an exact integer incidence matrix (rows: the cells that carry
//! fluxes, columns: the unknowns); Ω is the metric, a sum of small dense
//! blocks Σ_b E_{R_b}ᵀ W_b E_{S_b} over row sets R_b, S_b of A. A diagonal Ω
//! has one 1×1 block per row, a finite-element Ω one block per cell over the
//! cell's edges, a user-given sparse Ω one 1×1 block per entry.
//!
//! Assembly is split like a sparse factorisation: the sparsity pattern of
//! M and a scatter map from every block entry to its place in M are built
//! once ([`Canonical::new`]); numeric assembly ([`Canonical::assemble`]) is
//! then one pass over the block values, and can be repeated with new values
//! of the same pattern ([`Canonical::set_metric`]).

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
    /// Per block, the target positions in M's value array of every
    /// (row pair, incidence pair) product, in the order `assemble` visits them.
    scatter: Vec<usize>,
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
        let row =
            |r: usize| -> &[usize] { &incidence.indices()[incidence.indptr().outer_inds_sz(r)] };

        // Every (i, j) position M receives, bucketed by column j.
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for b in 0..metric.block_count() {
            let (rows, cols, _) = metric.block(b);
            for &r in rows {
                for &s in cols {
                    for &i in row(r) {
                        for &j in row(s) {
                            pairs.push((j, i));
                        }
                    }
                }
            }
        }
        let mut col_ptr = vec![0usize; n + 1];
        for &(j, _) in &pairs {
            col_ptr[j + 1] += 1;
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let mut bucketed = vec![0usize; pairs.len()];
        let mut next = col_ptr.clone();
        for &(j, i) in &pairs {
            bucketed[next[j]] = i;
            next[j] += 1;
        }
        let columns: Vec<Vec<usize>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let mut c = bucketed[col_ptr[j]..col_ptr[j + 1]].to_vec();
                c.sort_unstable();
                c.dedup();
                c
            })
            .collect();
        let mut final_ptr = Vec::with_capacity(n + 1);
        final_ptr.push(0);
        let mut row_idx = Vec::with_capacity(columns.iter().map(Vec::len).sum());
        for c in &columns {
            row_idx.extend_from_slice(c);
            final_ptr.push(row_idx.len());
        }
        let scatter: Vec<usize> = pairs
            .par_iter()
            .map(|&(j, i)| {
                let col = &row_idx[final_ptr[j]..final_ptr[j + 1]];
                // Present by construction.
                final_ptr[j] + col.binary_search(&i).unwrap_or(0)
            })
            .collect();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, final_ptr, None, row_idx);
        Ok(Self {
            incidence,
            metric,
            symbolic,
            scatter,
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
    pub fn assemble(&self) -> SparseColMat<usize, f64> {
        let mut values = vec![0.0; self.nonzeros()];
        let a = &self.incidence;
        let row = |r: usize| {
            let range = a.indptr().outer_inds_sz(r);
            (&a.indices()[range.clone()], &a.data()[range])
        };
        let mut k = 0;
        for b in 0..self.metric.block_count() {
            let (rows, cols, w) = self.metric.block(b);
            for (ri, &r) in rows.iter().enumerate() {
                let (_, ar) = row(r);
                for (si, &s) in cols.iter().enumerate() {
                    let weight = w[ri * cols.len() + si];
                    let (_, as_) = row(s);
                    for &x in ar {
                        for &y in as_ {
                            values[self.scatter[k]] += f64::from(x) * weight * f64::from(y);
                            k += 1;
                        }
                    }
                }
            }
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
