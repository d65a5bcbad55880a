//! Krylov solvers for symmetric positive definite systems: conjugate
//! gradients with a preconditioner ([`Preconditioner`]): Jacobi (diagonal)
//! here, a multigrid V-cycle in [`crate::multigrid`].
//!
//! Used where an initial guess matters (re-solving on a refined mesh from
//! the transferred coarse solution) and where a factorisation would be too
//! big. Convergence is measured by the relative residual ‖b − Mx‖₂ / ‖b‖₂,
//! the same figure the direct solvers report.

use faer::sparse::SparseColMat;
use rayon::prelude::*;

/// Stopping rule of conjugate gradients.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::la::iterative::{CgError, CgOptions};
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::{Diffusion, DiffusionError, Iterative};
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// let mesh = rectangle(16, 16, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let mut problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
/// let options = CgOptions { tolerance: 1e-10, max_iterations: 3 };
/// problem.iterative = Some(Iterative { options, ..Default::default() });
/// // Three iterations are far too few for 256 unknowns.
/// match problem.solve(&mesh) {
///     Err(DiffusionError::Iterative(CgError::NotConverged { iterations, .. })) => assert_eq!(iterations, 3),
///     other => panic!("{:?}", other.map(|_| ())),
/// }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CgOptions {
    /// Stop when ‖b − Mx‖₂ ≤ tolerance · ‖b‖₂.
    pub tolerance: f64,
    /// Give up (with [`CgError::NotConverged`]) after this many iterations.
    pub max_iterations: usize,
}

impl Default for CgOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 10_000,
        }
    }
}

/// How an iterative solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CgReport {
    /// Conjugate-gradient iterations (one preconditioner application each).
    pub iterations: usize,
    /// ‖b − Mx‖₂ / ‖b‖₂ at the returned x (recomputed, not the recurrence's).
    pub relative_residual: f64,
    /// The relative residual of the initial guess.
    pub initial_residual: f64,
    /// Wall-clock seconds of the iteration (setup of a preconditioner not
    /// included).
    pub seconds: f64,
}

/// Why an iterative solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CgError {
    /// The matrix is not square, or the right-hand side or the initial
    /// guess does not have one entry per unknown.
    #[error("conjugate gradients: matrix is {rows}×{cols}, right-hand side has {rhs} entries, initial guess {guess}")]
    Size {
        /// Rows of the matrix.
        rows: usize,
        /// Columns of the matrix.
        cols: usize,
        /// Entries of the right-hand side.
        rhs: usize,
        /// Entries of the initial guess (`rhs` when there is none).
        guess: usize,
    },
    /// A diagonal entry is ≤ 0 or NaN, which no symmetric positive definite
    /// matrix has (found while building the Jacobi preconditioner).
    #[error("conjugate gradients: diagonal entry {index} is {value}, not positive: the matrix is not symmetric positive definite")]
    NotPositive {
        /// Row of the entry.
        index: usize,
        /// The entry.
        value: f64,
    },
    /// A search direction p has pᵀMp ≤ 0: M is not positive definite
    /// (e.g. singular on a floating part of the domain).
    #[error("conjugate gradients: direction {iteration} has pᵀMp = {curvature:e} ≤ 0: the matrix is not positive definite")]
    Breakdown {
        /// Iteration at which it happened.
        iteration: usize,
        /// pᵀMp.
        curvature: f64,
    },
    /// A residual r has rᵀBr ≤ 0 for the preconditioner B: B is not
    /// positive definite, and conjugate gradients need it to be.
    #[error("preconditioned conjugate gradients: rᵀBr = {value:e} at iteration {iteration}: the preconditioner is not positive definite")]
    Preconditioner {
        /// Iteration at which it happened.
        iteration: usize,
        /// rᵀBr.
        value: f64,
    },
    /// Row pointers or column indices of a [`RowMatrix`] are out of range,
    /// or there are more columns than 32-bit indices address.
    #[error("sparse matrix of {rows}×{cols}: row pointers or column indices out of range (at most 2³² columns)")]
    Layout {
        /// Rows of the matrix.
        rows: usize,
        /// Columns of the matrix.
        cols: usize,
    },
    /// The iteration limit ([`CgOptions::max_iterations`]) was reached
    /// before the tolerance.
    #[error("conjugate gradients did not converge: relative residual {relative_residual:e} after {iterations} iterations (tolerance {tolerance:e}); raise the iteration limit or use a direct solver")]
    NotConverged {
        /// Iterations made.
        iterations: usize,
        /// ‖b − Mx‖₂ / ‖b‖₂ at the last iterate.
        relative_residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
}

/// A sparse matrix stored by rows (CSR) with 32-bit column indices: the
/// layout of every matrix-vector product of the iterative solvers and the
/// multigrid hierarchy. Rows are independent, so products run in parallel
/// over rows with rayon and give the same bits for any thread count.
///
/// ```
/// use hasse_solver::la::iterative::RowMatrix;
/// // [[2, -1], [-1, 2]]
/// let m = RowMatrix::from_rows(2, vec![vec![(0, 2.0), (1, -1.0)], vec![(0, -1.0), (1, 2.0)]]).unwrap();
/// let mut y = vec![0.0; 2];
/// m.multiply(&[1.0, 1.0], &mut y);
/// assert_eq!(y, vec![1.0, 1.0]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RowMatrix {
    nrows: usize,
    ncols: usize,
    ptr: Vec<usize>,
    idx: Vec<u32>,
    val: Vec<f64>,
}

/// Rows per parallel task: large enough that scheduling costs nothing
/// next to the arithmetic, small enough to balance two to eight threads.
const ROW_CHUNK: usize = 4096;

impl RowMatrix {
    /// From raw CSR arrays; checked.
    pub fn new(
        nrows: usize,
        ncols: usize,
        ptr: Vec<usize>,
        idx: Vec<u32>,
        val: Vec<f64>,
    ) -> Result<Self, CgError> {
        let bad = ptr.len() != nrows + 1
            || ptr[0] != 0
            || ptr.windows(2).any(|w| w[0] > w[1])
            || ptr[nrows] != idx.len()
            || idx.len() != val.len()
            || idx.iter().any(|&j| j as usize >= ncols)
            || ncols > u32::MAX as usize;
        if bad {
            return Err(CgError::Layout {
                rows: nrows,
                cols: ncols,
            });
        }
        Ok(Self {
            nrows,
            ncols,
            ptr,
            idx,
            val,
        })
    }

    /// From lists of (column, value) per row (square, `n` × `n`).
    pub fn from_rows(n: usize, rows: Vec<Vec<(usize, f64)>>) -> Result<Self, CgError> {
        let mut ptr = vec![0];
        let (mut idx, mut val) = (Vec::new(), Vec::new());
        for row in &rows {
            for &(j, v) in row {
                idx.push(u32::try_from(j).map_err(|_| CgError::Layout { rows: n, cols: n })?);
                val.push(v);
            }
            ptr.push(idx.len());
        }
        Self::new(rows.len(), n, ptr, idx, val)
    }

    /// A symmetric faer matrix read by rows: its columns are its rows, so
    /// the CSC arrays are taken as CSR ones (for a non-symmetric matrix this
    /// is the transpose).
    pub fn from_symmetric(matrix: &SparseColMat<usize, f64>) -> Result<Self, CgError> {
        let n = matrix.ncols();
        let mut ptr = Vec::with_capacity(n + 1);
        let mut idx = Vec::with_capacity(matrix.compute_nnz());
        let mut val = Vec::with_capacity(matrix.compute_nnz());
        ptr.push(0);
        for j in 0..n {
            let range = matrix.col_range(j);
            for (&i, &v) in matrix.row_idx()[range.clone()]
                .iter()
                .zip(&matrix.val()[range])
            {
                idx.push(u32::try_from(i).map_err(|_| CgError::Layout { rows: n, cols: n })?);
                val.push(v);
            }
            ptr.push(idx.len());
        }
        Self::new(n, matrix.nrows(), ptr, idx, val)
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.val.len()
    }

    /// Stored entries of row `i`.
    pub(crate) fn row_len(&self, i: usize) -> usize {
        self.ptr[i + 1] - self.ptr[i]
    }

    /// Column indices and values of row `i`.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.ptr[i]..self.ptr[i + 1];
        (&self.idx[r.clone()], &self.val[r])
    }

    /// Row `i` times `x`, summed in storage order.
    pub(crate) fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        let (c, v) = self.row(i);
        c.iter().zip(v).map(|(&j, &a)| a * x[j as usize]).sum()
    }

    /// The sum of the stored diagonal entries of each row.
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.nrows)
            .into_par_iter()
            .with_min_len(ROW_CHUNK)
            .map(|i| {
                let (c, v) = self.row(i);
                c.iter()
                    .zip(v)
                    .filter(|(&j, _)| j as usize == i)
                    .map(|(_, &v)| v)
                    .sum()
            })
            .collect()
    }

    /// y = M x, in parallel over rows.
    pub fn multiply(&self, x: &[f64], y: &mut [f64]) {
        y.par_iter_mut()
            .with_min_len(ROW_CHUNK)
            .enumerate()
            .for_each(|(i, yi)| {
                *yi = self.row_dot(i, x);
            });
    }

    /// y = M x and xᵀy in one pass, the inner product summed as [`dot`]
    /// sums it (the same bits as `multiply` followed by `dot(x, y)`).
    pub(crate) fn multiply_dot(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let partial: Vec<f64> = y
            .par_chunks_mut(DOT_CHUNK)
            .enumerate()
            .map(|(chunk, ys)| {
                let base = chunk * DOT_CHUNK;
                for (k, yi) in ys.iter_mut().enumerate() {
                    *yi = self.row_dot(base + k, x);
                }
                x[base..base + ys.len()]
                    .iter()
                    .zip(ys.iter())
                    .map(|(p, q)| p * q)
                    .sum::<f64>()
            })
            .collect();
        partial.iter().sum()
    }

    /// r = b − M x, in parallel over rows.
    pub fn residual(&self, b: &[f64], x: &[f64], r: &mut [f64]) {
        r.par_iter_mut()
            .with_min_len(ROW_CHUNK)
            .enumerate()
            .for_each(|(i, ri)| {
                *ri = b[i] - self.row_dot(i, x);
            });
    }

    /// Mᵀ, by a counting sort over columns (rows of the result keep
    /// increasing column order).
    pub fn transpose(&self) -> RowMatrix {
        let mut count = vec![0usize; self.ncols + 1];
        for &j in &self.idx {
            count[j as usize + 1] += 1;
        }
        for j in 0..self.ncols {
            count[j + 1] += count[j];
        }
        let ptr = count.clone();
        let mut next = count;
        let mut idx = vec![0u32; self.nnz()];
        let mut val = vec![0.0; self.nnz()];
        for i in 0..self.nrows {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                let slot = &mut next[j as usize];
                idx[*slot] = i as u32;
                val[*slot] = a;
                *slot += 1;
            }
        }
        RowMatrix {
            nrows: self.ncols,
            ncols: self.nrows,
            ptr,
            idx,
            val,
        }
    }

    /// The product self · other (Gustavson's row-by-row algorithm), in
    /// parallel over rows. Each entry is summed in the order of this row's
    /// entries, whatever the thread count, so the bits do not depend on it.
    pub fn product(&self, other: &RowMatrix) -> RowMatrix {
        self.gustavson(other, None)
    }

    /// P − diag(scale) · (self · P): one Jacobi-type smoothing step applied
    /// to the columns of P (`scale` holds ω/a_ii per row), in one pass over
    /// the rows. Entry by entry the same numbers as forming self · P with
    /// [`RowMatrix::product`] and then subtracting: P's pattern joined with
    /// the product's, an entry of the product alone is 0 − s·(AP)_ij.
    pub(crate) fn smoothed(&self, p: &RowMatrix, scale: &[f64]) -> RowMatrix {
        self.gustavson(p, Some(scale))
    }

    /// self · other, or other − diag(scale)(self · other) with `scale`
    /// (then other has as many rows as self). Rows are computed in fixed
    /// chunks, each by one thread, and written to their place in the
    /// result in parallel.
    fn gustavson(&self, other: &RowMatrix, scale: Option<&[f64]>) -> RowMatrix {
        assert_eq!(
            self.ncols, other.nrows,
            "inner dimensions of a sparse product"
        );
        let width = other.ncols;
        let chunks: Vec<(Vec<u32>, Vec<u32>, Vec<f64>)> = (0..self.nrows.div_ceil(ROW_CHUNK))
            .into_par_iter()
            .map_init(
                || (vec![0.0f64; width], vec![usize::MAX; width]),
                |(acc, mark), chunk| {
                    let rows = chunk * ROW_CHUNK..((chunk + 1) * ROW_CHUNK).min(self.nrows);
                    let mut lengths = Vec::with_capacity(rows.len());
                    // An upper bound of the chunk's entries (up to 2²²),
                    // so that the buffers rarely grow by copying (pages of
                    // the bound that are never written are never touched).
                    let bound: usize = rows
                        .clone()
                        .map(|i| {
                            let extra = scale.map_or(0, |_| other.row_len(i));
                            self.row(i)
                                .0
                                .iter()
                                .map(|&k| other.row_len(k as usize))
                                .sum::<usize>()
                                + extra
                        })
                        .sum::<usize>()
                        .min(1 << 22);
                    let (mut idx, mut val) = (Vec::with_capacity(bound), Vec::with_capacity(bound));
                    for i in rows {
                        let tag = i;
                        let start = idx.len();
                        let (c, v) = self.row(i);
                        for (&k, &a) in c.iter().zip(v) {
                            let (ck, vk) = other.row(k as usize);
                            for (&j, &b) in ck.iter().zip(vk) {
                                let j = j as usize;
                                if mark[j] != tag {
                                    mark[j] = tag;
                                    acc[j] = 0.0;
                                    idx.push(j as u32);
                                }
                                acc[j] += a * b;
                            }
                        }
                        if let Some(scale) = scale {
                            let s = scale[i];
                            for &j in &idx[start..] {
                                let j = j as usize;
                                acc[j] = 0.0 - s * acc[j];
                            }
                            // pv + (0 − s·x) is pv − s·x exactly (P has no −0).
                            let (pc, pv) = other.row(i);
                            for (&j, &b) in pc.iter().zip(pv) {
                                let j = j as usize;
                                if mark[j] != tag {
                                    mark[j] = tag;
                                    acc[j] = b;
                                    idx.push(j as u32);
                                } else {
                                    acc[j] += b;
                                }
                            }
                        }
                        idx[start..].sort_unstable();
                        val.extend(idx[start..].iter().map(|&j| acc[j as usize]));
                        lengths.push((idx.len() - start) as u32);
                    }
                    (lengths, idx, val)
                },
            )
            .collect();
        let mut ptr = Vec::with_capacity(self.nrows + 1);
        ptr.push(0);
        let mut end = 0;
        for (lengths, _, _) in &chunks {
            for &l in lengths {
                end += l as usize;
                ptr.push(end);
            }
        }
        let mut idx = vec![0u32; end];
        let mut val = vec![0.0; end];
        let mut pieces = Vec::with_capacity(chunks.len());
        let (mut idx_rest, mut val_rest) = (idx.as_mut_slice(), val.as_mut_slice());
        for chunk in &chunks {
            let (i, r) = std::mem::take(&mut idx_rest).split_at_mut(chunk.1.len());
            let (v, s) = std::mem::take(&mut val_rest).split_at_mut(chunk.2.len());
            idx_rest = r;
            val_rest = s;
            pieces.push((i, v, chunk));
        }
        pieces.into_par_iter().for_each(|(i, v, chunk)| {
            i.copy_from_slice(&chunk.1);
            v.copy_from_slice(&chunk.2);
        });
        RowMatrix {
            nrows: self.nrows,
            ncols: width,
            ptr,
            idx,
            val,
        }
    }

    /// The matrix with rows and columns kept where `keep_rows` /
    /// `keep_cols` say so, renumbered in order.
    pub fn restrict(&self, keep_rows: &[bool], keep_cols: &[bool]) -> RowMatrix {
        let mut new_col = vec![u32::MAX; self.ncols];
        let mut k = 0u32;
        for (j, &keep) in keep_cols.iter().enumerate() {
            if keep {
                new_col[j] = k;
                k += 1;
            }
        }
        let mut ptr = vec![0];
        let (mut idx, mut val) = (Vec::new(), Vec::new());
        for i in (0..self.nrows).filter(|&i| keep_rows[i]) {
            let (c, v) = self.row(i);
            for (&j, &a) in c.iter().zip(v) {
                if new_col[j as usize] != u32::MAX {
                    idx.push(new_col[j as usize]);
                    val.push(a);
                }
            }
            ptr.push(idx.len());
        }
        RowMatrix {
            nrows: ptr.len() - 1,
            ncols: k as usize,
            ptr,
            idx,
            val,
        }
    }

    /// The matrix as faer CSC (for the direct solve on the coarsest level).
    pub fn to_faer(&self) -> SparseColMat<usize, f64> {
        let triplets: Vec<faer::sparse::Triplet<usize, usize, f64>> = (0..self.nrows)
            .flat_map(|i| {
                let (c, v) = self.row(i);
                c.iter()
                    .zip(v)
                    .map(move |(&j, &a)| faer::sparse::Triplet::new(i, j as usize, a))
            })
            .collect();
        // The rows and columns were checked on construction.
        SparseColMat::try_new_from_triplets(self.nrows, self.ncols, &triplets)
            .expect("in-range CSR entries")
    }
}

/// Entries per partial sum of [`dot`]: the summation order depends on this
/// constant only, never on the number of threads.
pub(crate) const DOT_CHUNK: usize = 8192;

/// aᵀb, summed in fixed chunks so the result is bit-identical for any
/// number of threads.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let partial: Vec<f64> = a
        .par_chunks(DOT_CHUNK)
        .zip(b.par_chunks(DOT_CHUNK))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum())
        .collect();
    partial.iter().sum()
}

/// A symmetric positive definite approximation B ≈ M⁻¹ applied to a
/// residual. For conjugate gradients B must be symmetric positive definite
/// and the same operator at every call.
///
/// ```
/// use hasse_solver::la::iterative::{Preconditioner, RowMatrix};
/// use hasse_solver::multigrid::{Multigrid, MultigridOptions};
/// // tridiag(−1, 2, −1) on 5 unknowns; no more than `coarse_size` unknowns
/// // make a single level, factorised, so the "cycle" is B = M⁻¹ exactly.
/// let n = 5;
/// let rows = (0..n)
///     .map(|i| {
///         let mut row = vec![(i, 2.0)];
///         if i > 0 { row.insert(0, (i - 1, -1.0)); }
///         if i + 1 < n { row.push((i + 1, -1.0)); }
///         row
///     })
///     .collect();
/// let m = RowMatrix::from_rows(n, rows).unwrap();
/// let b = Multigrid::algebraic(m.clone(), &MultigridOptions::default()).unwrap();
/// let x = [1.0, -2.0, 0.5, 3.0, 0.0];
/// let mut r = vec![0.0; n];
/// m.multiply(&x, &mut r);
/// let mut z = vec![0.0; n];
/// b.apply(&r, &mut z);
/// assert!(z.iter().zip(&x).all(|(z, x)| (z - x).abs() < 1e-12));
/// assert_eq!(b.name(), "multigrid V-cycle");
/// ```
pub trait Preconditioner: Sync {
    /// z = B r.
    fn apply(&self, r: &[f64], z: &mut [f64]);
    /// A short name for reports.
    fn name(&self) -> &'static str;
}

/// B = diag(M)⁻¹.
#[derive(Clone, Debug)]
pub struct Jacobi {
    inverse_diagonal: Vec<f64>,
}

impl Jacobi {
    /// The inverse diagonal of `matrix`; every diagonal entry must be positive.
    pub fn new(matrix: &RowMatrix) -> Result<Self, CgError> {
        let diagonal = matrix.diagonal();
        let mut inverse_diagonal = Vec::with_capacity(diagonal.len());
        for (index, &value) in diagonal.iter().enumerate() {
            // NaN fails too.
            if value.is_nan() || value <= 0.0 {
                return Err(CgError::NotPositive { index, value });
            }
            inverse_diagonal.push(1.0 / value);
        }
        Ok(Self { inverse_diagonal })
    }
}

impl Preconditioner for Jacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.par_iter_mut()
            .with_min_len(ROW_CHUNK)
            .zip(r)
            .zip(&self.inverse_diagonal)
            .for_each(|((z, r), d)| *z = r * d);
    }

    fn name(&self) -> &'static str {
        "Jacobi"
    }
}

/// Solve M x = b (M symmetric positive definite, both triangles stored)
/// by Jacobi-preconditioned conjugate gradients from `initial` (zero if
/// `None`).
pub fn conjugate_gradient(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    initial: Option<&[f64]>,
    options: &CgOptions,
) -> Result<(Vec<f64>, CgReport), CgError> {
    check_sizes(matrix.nrows(), matrix.ncols(), rhs, initial)?;
    let rows = RowMatrix::from_symmetric(matrix)?;
    let jacobi = Jacobi::new(&rows)?;
    preconditioned_cg(&rows, rhs, initial, options, &jacobi)
}

fn check_sizes(
    rows: usize,
    cols: usize,
    rhs: &[f64],
    initial: Option<&[f64]>,
) -> Result<(), CgError> {
    let n = rhs.len();
    if rows != n || cols != n || initial.is_some_and(|x| x.len() != n) {
        return Err(CgError::Size {
            rows,
            cols,
            rhs: n,
            guess: initial.map_or(n, <[f64]>::len),
        });
    }
    Ok(())
}

/// Solve M x = b (M symmetric positive definite, stored by rows) by
/// conjugate gradients preconditioned with `preconditioner`, from
/// `initial` (zero if `None`). Every vector operation is parallel over
/// entries and every inner product is summed in fixed chunks, so the
/// iterates do not depend on the number of threads.
pub fn preconditioned_cg(
    matrix: &RowMatrix,
    rhs: &[f64],
    initial: Option<&[f64]>,
    options: &CgOptions,
    preconditioner: &dyn Preconditioner,
) -> Result<(Vec<f64>, CgReport), CgError> {
    check_sizes(matrix.nrows(), matrix.ncols(), rhs, initial)?;
    let n = rhs.len();
    let mut x = initial.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
    let mut work = CgWork::default();
    let report = preconditioned_cg_in(matrix, rhs, &mut x, options, preconditioner, &mut work)?;
    Ok((x, report))
}

/// The vectors of a conjugate-gradient solve, kept between solves of the
/// same size so that a sequence of solves (the steps of a transient run)
/// allocates them once. After a solve, [`CgWork::residual`] is its true
/// residual b − M x.
///
/// ```
/// use hasse_solver::la::iterative::{preconditioned_cg_in, CgOptions, CgWork, Jacobi, RowMatrix};
/// let m = RowMatrix::from_rows(2, vec![vec![(0, 4.0), (1, 1.0)], vec![(0, 1.0), (1, 3.0)]]).unwrap();
/// let jacobi = Jacobi::new(&m).unwrap();
/// let mut work = CgWork::default();
/// // [4 1; 1 3] x = [1, 2] has x = [1/11, 7/11].
/// let mut x = vec![0.0; 2];
/// let report = preconditioned_cg_in(&m, &[1.0, 2.0], &mut x, &CgOptions::default(), &jacobi, &mut work).unwrap();
/// assert!((x[0] - 1.0 / 11.0).abs() < 1e-12 && (x[1] - 7.0 / 11.0).abs() < 1e-12);
/// assert!(work.residual().iter().all(|r| r.abs() <= 1e-10 * 5f64.sqrt()));
/// // Started from the answer, no iteration and no preconditioning is needed.
/// let again = preconditioned_cg_in(&m, &[1.0, 2.0], &mut x, &CgOptions::default(), &jacobi, &mut work).unwrap();
/// assert_eq!(again.iterations, 0);
/// # assert!(report.iterations <= 2);
/// ```
#[derive(Clone, Debug, Default)]
pub struct CgWork {
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    product: Vec<f64>,
}

impl CgWork {
    /// b − M x of the last solve (empty before any).
    pub fn residual(&self) -> &[f64] {
        &self.r
    }

    fn fit(&mut self, n: usize) {
        for v in [&mut self.r, &mut self.z, &mut self.p, &mut self.product] {
            v.resize(n, 0.0);
        }
    }
}

/// [`preconditioned_cg`] in place: `x` holds the initial guess on entry
/// and the solution on return, and the vectors come from `work` (resized
/// to the system once, then reused). When the initial guess already meets
/// the tolerance, nothing more is computed: no preconditioner application
/// and no second residual.
pub fn preconditioned_cg_in(
    matrix: &RowMatrix,
    rhs: &[f64],
    x: &mut [f64],
    options: &CgOptions,
    preconditioner: &dyn Preconditioner,
    work: &mut CgWork,
) -> Result<CgReport, CgError> {
    let started = std::time::Instant::now();
    let n = rhs.len();
    check_sizes(matrix.nrows(), matrix.ncols(), rhs, Some(x))?;
    work.fit(n);
    let CgWork { r, z, p, product } = work;
    let norm_b = dot(rhs, rhs).sqrt();
    if norm_b == 0.0 {
        x.iter_mut().for_each(|x| *x = 0.0);
        r.iter_mut().for_each(|r| *r = 0.0);
        let report = CgReport {
            iterations: 0,
            relative_residual: 0.0,
            initial_residual: 0.0,
            seconds: started.elapsed().as_secs_f64(),
        };
        return Ok(report);
    }
    matrix.residual(rhs, x, r);
    let initial_residual = dot(r, r).sqrt() / norm_b;
    let mut iterations = 0;
    let mut residual = initial_residual;
    if residual > options.tolerance {
        preconditioner.apply(r, z);
        p.copy_from_slice(z);
        let mut rz = dot(r, z);
        while residual > options.tolerance {
            if iterations == options.max_iterations {
                return Err(CgError::NotConverged {
                    iterations,
                    relative_residual: residual,
                    tolerance: options.tolerance,
                });
            }
            let curvature = matrix.multiply_dot(p, product);
            if curvature.is_nan() || curvature <= 0.0 {
                return Err(CgError::Breakdown {
                    iteration: iterations,
                    curvature,
                });
            }
            let alpha = rz / curvature;
            // x += αp, r −= αq and rᵀr in one pass, rᵀr summed as `dot` does.
            let partial: Vec<f64> = x
                .par_chunks_mut(DOT_CHUNK)
                .zip(r.par_chunks_mut(DOT_CHUNK))
                .zip(p.par_chunks(DOT_CHUNK))
                .zip(product.par_chunks(DOT_CHUNK))
                .map(|(((x, r), p), q)| {
                    x.iter_mut().zip(p).for_each(|(x, p)| *x += alpha * p);
                    r.iter_mut().zip(q).for_each(|(r, q)| *r -= alpha * q);
                    r.iter().map(|r| r * r).sum::<f64>()
                })
                .collect();
            let rr: f64 = partial.iter().sum();
            preconditioner.apply(r, z);
            let rz_next = dot(r, z);
            if rz_next.is_nan() || (rz_next <= 0.0 && rr > 0.0) {
                return Err(CgError::Preconditioner {
                    iteration: iterations,
                    value: rz_next,
                });
            }
            let beta = rz_next / rz;
            rz = rz_next;
            p.par_iter_mut()
                .with_min_len(ROW_CHUNK)
                .zip(&z[..])
                .for_each(|(p, z)| *p = z + beta * *p);
            iterations += 1;
            residual = rr.sqrt() / norm_b;
        }
        // The recurrence drifts from the true residual; report the true
        // one (with no iteration, r is already b − M x as computed).
        matrix.residual(rhs, x, r);
        residual = dot(r, r).sqrt() / norm_b;
    }
    let report = CgReport {
        iterations,
        relative_residual: residual,
        initial_residual,
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// The 1D Dirichlet Laplacian tridiag(−1, 2, −1) of size n.
    fn laplacian(n: usize) -> SparseColMat<usize, f64> {
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    #[test]
    fn exact_in_n_steps_in_exact_arithmetic() {
        // x_i = i(n+1−i)/2 solves tridiag(−1,2,−1) x = 1 (a discrete parabola).
        let n = 50;
        let m = laplacian(n);
        let (x, report) =
            conjugate_gradient(&m, &vec![1.0; n], None, &CgOptions::default()).unwrap();
        for (i, v) in x.iter().enumerate() {
            let k = (i + 1) as f64;
            let exact = k * (n as f64 + 1.0 - k) / 2.0;
            assert!((v - exact).abs() <= 1e-8 * exact, "{i}: {v} vs {exact}");
        }
        // CG on an n×n SPD system with distinct eigenvalues ends within n
        // steps up to rounding; the parabola needs about n/2 (symmetry).
        assert!(report.iterations <= n, "{}", report.iterations);
        assert!(report.relative_residual <= 1e-10);
    }

    #[test]
    fn a_good_initial_guess_saves_iterations() {
        // The guess is off by one eigenvector of tridiag(−1, 2, −1) (the
        // Jacobi scaling is the constant 1/2, so also of the preconditioned
        // operator): CG removes a single eigencomponent in one step, while
        // from zero it needs about n/2 = 100 (b = 1 excites the even modes).
        let n = 200;
        let m = laplacian(n);
        let b = vec![1.0; n];
        let (_, cold) = conjugate_gradient(&m, &b, None, &CgOptions::default()).unwrap();
        // The exact solution is the discrete parabola x_i = k(n+1−k)/2, k = i+1.
        let exact: Vec<f64> = (1..=n).map(|k| (k * (n + 1 - k)) as f64 / 2.0).collect();
        // The highest mode (λ ≈ 4): a step along the lowest one (λ ≈ 2.4e-4)
        // would multiply the rounding noise of the residual by 1/λ.
        let mode = |i: usize| (std::f64::consts::PI * (n * (i + 1)) as f64 / (n + 1) as f64).sin();
        let guess: Vec<f64> = exact
            .iter()
            .enumerate()
            .map(|(i, v)| v + 10.0 * mode(i))
            .collect();
        let (x, warm) = conjugate_gradient(&m, &b, Some(&guess), &CgOptions::default()).unwrap();
        assert!(cold.initial_residual == 1.0 && warm.initial_residual > 1e-4);
        assert_eq!(warm.iterations, 1);
        assert!(cold.iterations >= 90, "{}", cold.iterations);
        for (a, e) in x.iter().zip(&exact) {
            assert!((a - e).abs() <= 1e-8 * e.abs().max(1.0));
        }
    }

    #[test]
    fn indefinite_and_unconverged_systems_are_reported() {
        let t = [Triplet::new(0, 0, 1.0), Triplet::new(1, 1, -1.0)];
        let m = SparseColMat::try_new_from_triplets(2, 2, &t).unwrap();
        assert!(matches!(
            conjugate_gradient(&m, &[1.0, 1.0], None, &CgOptions::default()),
            Err(CgError::NotPositive { index: 1, .. })
        ));
        let options = CgOptions {
            tolerance: 1e-12,
            max_iterations: 3,
        };
        assert!(matches!(
            conjugate_gradient(&laplacian(100), &vec![1.0; 100], None, &options),
            Err(CgError::NotConverged { iterations: 3, .. })
        ));
    }

    #[test]
    fn jacobi_cg_solves_a_small_laplacian_in_at_most_n_steps() {
        // tridiag(−1, 2, −1) x = (1, 0, 1) has x = (1, 1, 1).
        let t = [
            (0, 0, 2.0),
            (1, 1, 2.0),
            (2, 2, 2.0),
            (0, 1, -1.0),
            (1, 0, -1.0),
            (1, 2, -1.0),
            (2, 1, -1.0),
        ];
        let triplets: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
        let m = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &triplets).unwrap();
        let (x, report) =
            conjugate_gradient(&m, &[1.0, 0.0, 1.0], None, &CgOptions::default()).unwrap();
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-10));
        assert!(report.iterations <= 3);
    }

    /// A preconditioner that counts its applications (Jacobi inside).
    struct Counting(Jacobi, std::sync::atomic::AtomicUsize);

    impl Preconditioner for Counting {
        fn apply(&self, r: &[f64], z: &mut [f64]) {
            self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            self.0.apply(r, z);
        }
        fn name(&self) -> &'static str {
            "counting"
        }
    }

    #[test]
    fn in_place_cg_skips_the_preconditioner_when_the_start_is_converged() {
        // [4 1; 1 3] x = [1, 2] has x = [1/11, 7/11] (Cramer's rule).
        let m = RowMatrix::from_rows(2, vec![vec![(0, 4.0), (1, 1.0)], vec![(0, 1.0), (1, 3.0)]])
            .unwrap();
        let counting = Counting(Jacobi::new(&m).unwrap(), Default::default());
        let mut work = CgWork::default();
        let options = CgOptions::default();
        // From x = [0.1, 0.6]: r = b − Mx = [1 − 1, 2 − 1.9] = [0, 0.1].
        let mut x = vec![0.1, 0.6];
        let report =
            preconditioned_cg_in(&m, &[1.0, 2.0], &mut x, &options, &counting, &mut work).unwrap();
        assert!((x[0] - 1.0 / 11.0).abs() < 1e-14 && (x[1] - 7.0 / 11.0).abs() < 1e-14);
        // One application per iteration plus the first.
        let applied = counting.1.load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(applied, report.iterations + 1);
        assert!((report.initial_residual - 0.1 / 5f64.sqrt()).abs() < 1e-15);
        // Started from the answer: the residual check alone, no application.
        let mut exact = vec![1.0 / 11.0, 7.0 / 11.0];
        let again =
            preconditioned_cg_in(&m, &[1.0, 2.0], &mut exact, &options, &counting, &mut work)
                .unwrap();
        assert_eq!(again.iterations, 0);
        assert_eq!(
            counting.1.load(std::sync::atomic::Ordering::Relaxed),
            applied
        );
        // The kept residual is b − Mx of the answer: rounding of values ≤ 3.
        assert!(work.residual().iter().all(|r| r.abs() < 1e-15));
    }

    #[test]
    fn preconditioned_cg_takes_any_preconditioner() {
        let m = RowMatrix::from_rows(2, vec![vec![(0, 4.0), (1, 1.0)], vec![(0, 1.0), (1, 3.0)]])
            .unwrap();
        let jacobi = Jacobi::new(&m).unwrap();
        let (x, report) =
            preconditioned_cg(&m, &[1.0, 2.0], None, &CgOptions::default(), &jacobi).unwrap();
        assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-12 && report.iterations <= 2);
    }
}
