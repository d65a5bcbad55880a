//! Krylov methods for nonsymmetric systems: BiCGStab and restarted
//! GMRES(m), with an incomplete LU factorisation without fill (ILU(0)) as
//! the preconditioner.
//!
//! Conjugate gradients ([`crate::la::iterative`]) need a symmetric positive
//! definite matrix; an advection term makes M = Aᵀ Ω A + ∂ₙᵀ diag(F) U
//! nonsymmetric. Both methods here are right-preconditioned (they iterate
//! on M B y = b, x = B y), so the residual they watch is the true residual
//! b − M x, and they stop on the same figure as every other solver of the
//! project: ‖b − M x‖₂ ≤ tolerance · ‖b‖₂, recomputed at the end.
//!
//! ```
//! use hasse_solver::la::iterative::RowMatrix;
//! use hasse_solver::la::krylov::{bicgstab, gmres, Ilu0, KrylovOptions};
//! // A nonsymmetric tridiagonal matrix (upwinded 1D advection–diffusion)
//! // and a right-hand side made from a known solution x* = (1, 2, …, 8).
//! let n = 8;
//! let rows: Vec<Vec<(usize, f64)>> = (0..n)
//!     .map(|i| {
//!         let mut r = vec![(i, 3.0)];
//!         if i > 0 { r.insert(0, (i - 1, -2.0)); }
//!         if i + 1 < n { r.push((i + 1, -1.0)); }
//!         r
//!     })
//!     .collect();
//! let m = RowMatrix::from_rows(n, rows).unwrap();
//! let exact: Vec<f64> = (1..=n).map(|i| i as f64).collect();
//! let mut b = vec![0.0; n];
//! m.multiply(&exact, &mut b);
//! let ilu = Ilu0::new(&m).unwrap();
//! let options = KrylovOptions { tolerance: 1e-12, ..KrylovOptions::default() };
//! for (x, _) in [bicgstab(&m, &b, None, &options, &ilu).unwrap(), gmres(&m, &b, None, &options, &ilu).unwrap()] {
//!     assert!(x.iter().zip(&exact).all(|(a, e)| (a - e).abs() < 1e-9));
//! }
//! ```

use super::iterative::{CgReport, Preconditioner, RowMatrix};
use faer::sparse::SparseColMat;
use std::time::Instant;

/// Stopping rule and restart length of a Krylov solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KrylovOptions {
    /// Stop when ‖b − M x‖₂ ≤ tolerance · ‖b‖₂.
    pub tolerance: f64,
    /// Give up after this many iterations (matrix–vector products for
    /// GMRES, BiCGStab steps of two products each).
    pub max_iterations: usize,
    /// GMRES(m): the Krylov basis is rebuilt from the current residual
    /// after `restart` iterations (memory: `restart` vectors).
    pub restart: usize,
}

impl Default for KrylovOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 10_000,
            restart: 30,
        }
    }
}

/// Why a Krylov solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum KrylovError {
    /// The matrix is not square, or a vector has the wrong length.
    #[error("{method}: matrix is {rows}×{cols}, right-hand side has {rhs} entries, initial guess {guess}")]
    Size {
        /// The method.
        method: &'static str,
        /// Rows of the matrix.
        rows: usize,
        /// Columns of the matrix.
        cols: usize,
        /// Entries of the right-hand side.
        rhs: usize,
        /// Entries of the initial guess (`rhs` when there is none).
        guess: usize,
    },
    /// ILU(0) met a zero (or non-finite) pivot: the matrix has a zero
    /// diagonal entry, or elimination without fill produced one.
    #[error("ILU(0): pivot {value} at row {row}; the matrix needs a nonzero diagonal (use the direct solver)")]
    ZeroPivot {
        /// Row of the pivot.
        row: usize,
        /// Its value.
        value: f64,
    },
    /// BiCGStab met a vanishing inner product (ρ = r̂ᵀr or ω = 0): the
    /// iteration cannot continue from this residual.
    #[error("BiCGStab broke down at iteration {iteration} (relative residual {relative_residual:e}); try gmres or the direct solver")]
    Breakdown {
        /// Iteration at which it happened.
        iteration: usize,
        /// ‖b − M x‖₂ / ‖b‖₂ there.
        relative_residual: f64,
    },
    /// The iteration limit was reached before the tolerance.
    #[error("{method} did not converge: relative residual {relative_residual:e} after {iterations} iterations (tolerance {tolerance:e}); raise the iteration limit or use the direct solver")]
    NotConverged {
        /// The method.
        method: &'static str,
        /// Iterations made.
        iterations: usize,
        /// ‖b − M x‖₂ / ‖b‖₂ at the last iterate.
        relative_residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
}

/// Any square matrix (faer, column storage) as a [`RowMatrix`] with
/// sorted rows, for the Krylov methods and ILU(0).
pub fn rows_of(matrix: &SparseColMat<usize, f64>) -> Result<RowMatrix, KrylovError> {
    let n = matrix.nrows();
    if matrix.ncols() != n {
        return Err(KrylovError::Size {
            method: "sparse matrix",
            rows: n,
            cols: matrix.ncols(),
            rhs: n,
            guess: n,
        });
    }
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    // Columns in increasing order: every row comes out sorted.
    for j in 0..n {
        let range = matrix.col_range(j);
        for (&i, &v) in matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
        {
            rows[i].push((j, v));
        }
    }
    RowMatrix::from_rows(n, rows).map_err(|_| KrylovError::Size {
        method: "sparse matrix",
        rows: n,
        cols: n,
        rhs: n,
        guess: n,
    })
}

/// Incomplete LU factorisation on the pattern of M (no fill): L unit lower
/// and U upper triangular with L U = M on every stored entry of M.
///
/// For an M-matrix (upwind advection plus two-point diffusion is one) the
/// factorisation exists and B = (LU)⁻¹ is a good preconditioner; on a
/// tridiagonal matrix there is no fill and LU = M exactly.
///
/// ```
/// use hasse_solver::la::iterative::{Preconditioner, RowMatrix};
/// use hasse_solver::la::krylov::Ilu0;
/// // [[4, -1], [-2, 5]] has no fill: ILU(0) is its LU, B = M⁻¹.
/// let m = RowMatrix::from_rows(2, vec![vec![(0, 4.0), (1, -1.0)], vec![(0, -2.0), (1, 5.0)]]).unwrap();
/// let mut z = vec![0.0; 2];
/// Ilu0::new(&m).unwrap().apply(&[3.0, 3.0], &mut z); // M (1, 1) = (3, 3)
/// assert!((z[0] - 1.0).abs() < 1e-15 && (z[1] - 1.0).abs() < 1e-15);
/// ```
#[derive(Clone, Debug)]
pub struct Ilu0 {
    ptr: Vec<usize>,
    idx: Vec<usize>,
    /// L below the diagonal (unit diagonal not stored), U on and above.
    val: Vec<f64>,
    /// Position of the diagonal entry of every row.
    diagonal: Vec<usize>,
}

impl Ilu0 {
    /// Factorise `matrix` (rows sorted by column, as [`rows_of`] and
    /// [`RowMatrix::from_rows`] make them) in place of its values.
    pub fn new(matrix: &RowMatrix) -> Result<Self, KrylovError> {
        let n = matrix.nrows();
        let mut ptr = Vec::with_capacity(n + 1);
        let mut idx = Vec::with_capacity(matrix.nnz());
        let mut val = Vec::with_capacity(matrix.nnz());
        ptr.push(0);
        for i in 0..n {
            let (cols, values) = matrix.row(i);
            let mut row: Vec<(usize, f64)> = cols
                .iter()
                .map(|&c| c as usize)
                .zip(values.iter().copied())
                .collect();
            row.sort_by_key(|&(c, _)| c);
            for (c, v) in row {
                idx.push(c);
                val.push(v);
            }
            ptr.push(idx.len());
        }
        let mut diagonal = vec![usize::MAX; n];
        for i in 0..n {
            if let Some(k) = (ptr[i]..ptr[i + 1]).find(|&k| idx[k] == i) {
                diagonal[i] = k;
            } else {
                return Err(KrylovError::ZeroPivot { row: i, value: 0.0 });
            }
        }
        // IKJ elimination restricted to the pattern; `position[j]` finds
        // entry (i, j) of the current row.
        let mut position = vec![usize::MAX; n];
        for i in 0..n {
            for k in ptr[i]..ptr[i + 1] {
                position[idx[k]] = k;
            }
            for k in ptr[i]..diagonal[i] {
                let p = idx[k];
                let pivot = val[diagonal[p]];
                if !(pivot.is_finite() && pivot != 0.0) {
                    return Err(KrylovError::ZeroPivot {
                        row: p,
                        value: pivot,
                    });
                }
                val[k] /= pivot;
                let factor = val[k];
                for q in diagonal[p] + 1..ptr[p + 1] {
                    let at = position[idx[q]];
                    if at != usize::MAX {
                        val[at] -= factor * val[q];
                    }
                }
            }
            for k in ptr[i]..ptr[i + 1] {
                position[idx[k]] = usize::MAX;
            }
            let pivot = val[diagonal[i]];
            if !(pivot.is_finite() && pivot != 0.0) {
                return Err(KrylovError::ZeroPivot {
                    row: i,
                    value: pivot,
                });
            }
        }
        Ok(Self {
            ptr,
            idx,
            val,
            diagonal,
        })
    }
}

impl Preconditioner for Ilu0 {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let n = self.diagonal.len();
        // L y = r (unit diagonal), then U z = y.
        for i in 0..n {
            let mut s = r[i];
            for k in self.ptr[i]..self.diagonal[i] {
                s -= self.val[k] * z[self.idx[k]];
            }
            z[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = z[i];
            for k in self.diagonal[i] + 1..self.ptr[i + 1] {
                s -= self.val[k] * z[self.idx[k]];
            }
            z[i] = s / self.val[self.diagonal[i]];
        }
    }

    fn name(&self) -> &'static str {
        "ILU(0)"
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// ‖b − M x‖₂ / ‖b‖₂ (‖b − M x‖₂ when b = 0).
fn relative(matrix: &RowMatrix, rhs: &[f64], x: &[f64], norm_b: f64) -> f64 {
    let mut r = vec![0.0; rhs.len()];
    matrix.residual(rhs, x, &mut r);
    let nr = norm(&r);
    if norm_b == 0.0 {
        nr
    } else {
        nr / norm_b
    }
}

fn check(
    method: &'static str,
    matrix: &RowMatrix,
    rhs: &[f64],
    initial: Option<&[f64]>,
) -> Result<(), KrylovError> {
    let n = rhs.len();
    if matrix.nrows() != n || matrix.ncols() != n || initial.is_some_and(|x| x.len() != n) {
        return Err(KrylovError::Size {
            method,
            rows: matrix.nrows(),
            cols: matrix.ncols(),
            rhs: n,
            guess: initial.map_or(n, <[f64]>::len),
        });
    }
    Ok(())
}

/// Solve M x = b by right-preconditioned BiCGStab (van der Vorst 1992)
/// from `initial` (zero if `None`). Each iteration applies M and the
/// preconditioner twice; memory is a handful of vectors.
pub fn bicgstab(
    matrix: &RowMatrix,
    rhs: &[f64],
    initial: Option<&[f64]>,
    options: &KrylovOptions,
    preconditioner: &dyn Preconditioner,
) -> Result<(Vec<f64>, CgReport), KrylovError> {
    const METHOD: &str = "BiCGStab";
    check(METHOD, matrix, rhs, initial)?;
    let started = Instant::now();
    let n = rhs.len();
    let norm_b = norm(rhs);
    let mut x = initial.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
    let mut r = vec![0.0; n];
    matrix.residual(rhs, &x, &mut r);
    let initial_residual = if norm_b == 0.0 {
        norm(&r)
    } else {
        norm(&r) / norm_b
    };
    let goal = options.tolerance * if norm_b == 0.0 { 1.0 } else { norm_b };
    let done = |x: Vec<f64>, iterations: usize| {
        let relative_residual = relative(matrix, rhs, &x, norm_b);
        (
            x,
            CgReport {
                iterations,
                relative_residual,
                initial_residual,
                seconds: started.elapsed().as_secs_f64(),
            },
        )
    };
    if norm(&r) <= goal {
        return Ok(done(x, 0));
    }
    let shadow = r.clone();
    let (mut rho, mut alpha, mut omega) = (1.0, 1.0, 1.0);
    let mut p = vec![0.0; n];
    let mut v = vec![0.0; n];
    let mut p_hat = vec![0.0; n];
    let mut s_hat = vec![0.0; n];
    let mut t = vec![0.0; n];
    for iteration in 1..=options.max_iterations {
        let rho_new = dot(&shadow, &r);
        if rho_new == 0.0 || omega == 0.0 || !rho_new.is_finite() {
            return Err(KrylovError::Breakdown {
                iteration,
                relative_residual: relative(matrix, rhs, &x, norm_b),
            });
        }
        let beta = (rho_new / rho) * (alpha / omega);
        rho = rho_new;
        for i in 0..n {
            p[i] = r[i] + beta * (p[i] - omega * v[i]);
        }
        preconditioner.apply(&p, &mut p_hat);
        matrix.multiply(&p_hat, &mut v);
        let shadow_v = dot(&shadow, &v);
        if shadow_v == 0.0 || !shadow_v.is_finite() {
            return Err(KrylovError::Breakdown {
                iteration,
                relative_residual: relative(matrix, rhs, &x, norm_b),
            });
        }
        alpha = rho / shadow_v;
        // s = r − α v, kept in r.
        for i in 0..n {
            r[i] -= alpha * v[i];
        }
        if norm(&r) <= goal {
            for i in 0..n {
                x[i] += alpha * p_hat[i];
            }
            return Ok(done(x, iteration));
        }
        preconditioner.apply(&r, &mut s_hat);
        matrix.multiply(&s_hat, &mut t);
        let tt = dot(&t, &t);
        omega = if tt > 0.0 { dot(&t, &r) / tt } else { 0.0 };
        for i in 0..n {
            x[i] += alpha * p_hat[i] + omega * s_hat[i];
            r[i] -= omega * t[i];
        }
        if norm(&r) <= goal {
            return Ok(done(x, iteration));
        }
    }
    let relative_residual = relative(matrix, rhs, &x, norm_b);
    Err(KrylovError::NotConverged {
        method: METHOD,
        iterations: options.max_iterations,
        relative_residual,
        tolerance: options.tolerance,
    })
}

/// Solve M x = b by right-preconditioned restarted GMRES(m) (Saad &
/// Schultz 1986; modified Gram–Schmidt and Givens rotations) from
/// `initial` (zero if `None`). Within a cycle the residual norm never
/// grows; `options.restart` bounds the basis kept in memory.
pub fn gmres(
    matrix: &RowMatrix,
    rhs: &[f64],
    initial: Option<&[f64]>,
    options: &KrylovOptions,
    preconditioner: &dyn Preconditioner,
) -> Result<(Vec<f64>, CgReport), KrylovError> {
    const METHOD: &str = "GMRES";
    check(METHOD, matrix, rhs, initial)?;
    let started = Instant::now();
    let n = rhs.len();
    let m = options.restart.max(1);
    let norm_b = norm(rhs);
    let goal = options.tolerance * if norm_b == 0.0 { 1.0 } else { norm_b };
    let mut x = initial.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
    let mut r = vec![0.0; n];
    matrix.residual(rhs, &x, &mut r);
    let initial_residual = if norm_b == 0.0 {
        norm(&r)
    } else {
        norm(&r) / norm_b
    };
    let mut iterations = 0;
    let mut z = vec![0.0; n];
    let mut w = vec![0.0; n];
    loop {
        let beta = norm(&r);
        if beta <= goal || iterations >= options.max_iterations {
            break;
        }
        let mut basis: Vec<Vec<f64>> = vec![r.iter().map(|v| v / beta).collect()];
        // Hessenberg columns, rotated into R as they come.
        let mut h: Vec<Vec<f64>> = Vec::with_capacity(m);
        let (mut cs, mut sn): (Vec<f64>, Vec<f64>) = (Vec::with_capacity(m), Vec::with_capacity(m));
        let mut g = vec![beta];
        let mut residual = beta;
        while h.len() < m && iterations < options.max_iterations && residual > goal {
            iterations += 1;
            let j = h.len();
            preconditioner.apply(&basis[j], &mut z);
            matrix.multiply(&z, &mut w);
            let mut column = Vec::with_capacity(j + 2);
            for b in &basis {
                let hij = dot(&w, b);
                for (wi, bi) in w.iter_mut().zip(b) {
                    *wi -= hij * bi;
                }
                column.push(hij);
            }
            let next = norm(&w);
            column.push(next);
            for i in 0..j {
                let (a, b) = (column[i], column[i + 1]);
                column[i] = cs[i] * a + sn[i] * b;
                column[i + 1] = -sn[i] * a + cs[i] * b;
            }
            let (a, b) = (column[j], column[j + 1]);
            let d = a.hypot(b);
            let (c, s) = if d == 0.0 { (1.0, 0.0) } else { (a / d, b / d) };
            column[j] = d;
            column.truncate(j + 1);
            cs.push(c);
            sn.push(s);
            let gj = g[j];
            g[j] = c * gj;
            g.push(-s * gj);
            residual = g[j + 1].abs();
            h.push(column);
            if next == 0.0 {
                // Lucky breakdown: the solution lies in this space.
                break;
            }
            basis.push(w.iter().map(|v| v / next).collect());
        }
        // y = R⁻¹ g, x += B (V y).
        let k = h.len();
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let mut s = g[i];
            for (l, yl) in y.iter().enumerate().take(k).skip(i + 1) {
                s -= h[l][i] * yl;
            }
            y[i] = if h[i][i] == 0.0 { 0.0 } else { s / h[i][i] };
        }
        let mut update = vec![0.0; n];
        for (yi, b) in y.iter().zip(&basis) {
            for (u, bi) in update.iter_mut().zip(b) {
                *u += yi * bi;
            }
        }
        preconditioner.apply(&update, &mut z);
        for (xi, zi) in x.iter_mut().zip(&z) {
            *xi += zi;
        }
        matrix.residual(rhs, &x, &mut r);
        if k == 0 {
            break;
        }
    }
    let relative_residual = relative(matrix, rhs, &x, norm_b);
    // The loop above restarts until the recomputed residual meets the
    // goal, so only the iteration limit (or a breakdown) ends here above it.
    if relative_residual > options.tolerance || !relative_residual.is_finite() {
        return Err(KrylovError::NotConverged {
            method: METHOD,
            iterations,
            relative_residual,
            tolerance: options.tolerance,
        });
    }
    Ok((
        x,
        CgReport {
            iterations,
            relative_residual,
            initial_residual,
            seconds: started.elapsed().as_secs_f64(),
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 2D upwind advection–diffusion five-point matrix on an m×m grid
    /// (velocity (1, 1), cell Péclet `pe`), strongly nonsymmetric for
    /// large `pe`.
    fn advection_diffusion(m: usize, pe: f64) -> RowMatrix {
        let n = m * m;
        let rows = (0..n)
            .map(|k| {
                let (i, j) = (k % m, k / m);
                let mut row = Vec::new();
                if j > 0 {
                    row.push((k - m, -1.0 - pe));
                }
                if i > 0 {
                    row.push((k - 1, -1.0 - pe));
                }
                row.push((k, 4.0 + 2.0 * pe));
                if i + 1 < m {
                    row.push((k + 1, -1.0));
                }
                if j + 1 < m {
                    row.push((k + m, -1.0));
                }
                row
            })
            .collect();
        RowMatrix::from_rows(n, rows).expect("valid rows")
    }

    #[test]
    fn both_methods_recover_a_known_solution_in_bounded_iterations() {
        // b = M x* with x*_k = sin(k): the solvers must return x* to their
        // tolerance times the condition of M, well inside 1e-6 here.
        for pe in [0.5, 10.0] {
            let m = advection_diffusion(20, pe);
            let exact: Vec<f64> = (0..400).map(|k| (k as f64).sin()).collect();
            let mut b = vec![0.0; 400];
            m.multiply(&exact, &mut b);
            let ilu = Ilu0::new(&m).expect("M-matrix");
            let options = KrylovOptions {
                tolerance: 1e-10,
                max_iterations: 200,
                restart: 30,
            };
            for (name, result) in [
                ("bicgstab", bicgstab(&m, &b, None, &options, &ilu)),
                ("gmres", gmres(&m, &b, None, &options, &ilu)),
            ] {
                let (x, report) = result.expect("converges");
                let error = x
                    .iter()
                    .zip(&exact)
                    .fold(0.0f64, |e, (a, b)| e.max((a - b).abs()));
                assert!(error < 1e-7, "{name} pe {pe}: error {error:e}");
                assert!(report.relative_residual <= 1e-9, "{name}");
                // ILU(0) on a 400-unknown M-matrix: a few tens of products.
                assert!(report.iterations <= 60, "{name}: {}", report.iterations);
            }
        }
    }

    #[test]
    fn zero_diagonal_is_refused() {
        let m = RowMatrix::from_rows(2, vec![vec![(1, 1.0)], vec![(0, 1.0), (1, 1.0)]])
            .expect("valid rows");
        assert!(matches!(
            Ilu0::new(&m),
            Err(KrylovError::ZeroPivot { row: 0, .. })
        ));
    }

    #[test]
    fn iteration_limit_is_reported() {
        let m = advection_diffusion(20, 1.0);
        let b = vec![1.0; 400];
        let options = KrylovOptions {
            tolerance: 1e-14,
            max_iterations: 2,
            restart: 30,
        };
        let identity = Ilu0::new(
            &RowMatrix::from_rows(400, (0..400).map(|i| vec![(i, 1.0)]).collect())
                .expect("identity"),
        )
        .expect("identity");
        assert!(matches!(
            gmres(&m, &b, None, &options, &identity),
            Err(KrylovError::NotConverged { iterations: 2, .. })
        ));
    }
}
