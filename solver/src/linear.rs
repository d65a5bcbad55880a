//! Sparse direct solves through faer: LLᵀ for symmetric positive definite
//! systems, LDLᵀ for symmetric quasi-definite ones, LBLᵀ (Bunch–Kaufman
//! pivoting) for symmetric indefinite ones, LU for the rest.
//!
//! As in faer, the symbolic analysis (ordering, elimination tree, pattern
//! of the factor) is a value of its own ([`DirectSolver`]) that is kept and
//! reused when only the values of the matrix change; the numeric
//! factorisation ([`Factor`]) solves any number of right-hand sides.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, IntranodeLbltRef, LdltRef,
    SymbolicCholesky, SymbolicCholeskyRaw,
};
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::{Conj, Mat, Par, Side};
use std::sync::Arc;
use std::time::Instant;

/// Which factorisation to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Factorization {
    /// Cholesky LLᵀ: symmetric positive definite matrices.
    Llt,
    /// LDLᵀ without pivoting: symmetric matrices whose leading minors are
    /// nonsingular (quasi-definite systems).
    Ldlt,
    /// LBLᵀ with Bunch–Kaufman pivoting (1×1 and 2×2 blocks in B) inside
    /// each supernode: symmetric indefinite matrices such as saddle-point
    /// systems [[A, B], [Bᵀ, 0]], where LDLᵀ without pivoting can meet a
    /// zero pivot. Pivots are only exchanged within a supernode (faer's
    /// intranodal variant), so the fill-reducing ordering is kept.
    Lblt,
    /// LU with partial pivoting: any nonsingular matrix.
    Lu,
}

impl std::fmt::Display for Factorization {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Factorization::Llt => "sparse LLᵀ (faer)",
            Factorization::Ldlt => "sparse LDLᵀ (faer)",
            Factorization::Lblt => "sparse LBLᵀ, Bunch–Kaufman (faer)",
            Factorization::Lu => "sparse LU (faer)",
        })
    }
}

/// Why a solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error("the matrix is {rows}×{cols}; a direct solve needs a square matrix")]
    NotSquare { rows: usize, cols: usize },
    #[error("right-hand side has {found} entries for {expected} unknowns")]
    RhsSize { expected: usize, found: usize },
    #[error("LLᵀ failed: the matrix is not positive definite (a pivot was ≤ 0). The system is singular or indefinite: check that every connected part of the domain has a Dirichlet or Robin boundary, or that the coefficients are positive")]
    NotPositiveDefinite,
    #[error("{method} factorisation failed: the matrix is singular (a zero pivot). Check the boundary conditions and coefficients")]
    Singular { method: &'static str },
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    #[error("out of memory while factorising")]
    OutOfMemory,
}

enum Analysis {
    Llt(SymbolicLlt<usize>),
    Ldlt(Arc<SymbolicCholesky<usize>>),
    Lblt(Arc<SymbolicCholesky<usize>>),
    Lu(SymbolicLu<usize>),
}

/// The symbolic phase of a factorisation, reusable for every matrix with
/// the same sparsity pattern.
pub struct DirectSolver {
    kind: Factorization,
    analysis: Analysis,
    size: usize,
    /// Seconds spent in the symbolic analysis.
    pub symbolic_seconds: f64,
}

/// A numeric factorisation, ready to solve.
pub struct Factor {
    kind: Factorization,
    inner: Numeric,
    size: usize,
    /// Seconds spent in the numeric factorisation.
    pub numeric_seconds: f64,
}

enum Numeric {
    Llt(Llt<usize, f64>),
    Ldlt(Arc<SymbolicCholesky<usize>>, Vec<f64>),
    Lblt(Box<LbltFactor>),
    Lu(Box<Lu<usize, f64>>),
}

/// The owned parts of an intranodal LBLᵀ factor: L's values, the
/// subdiagonal of the block-diagonal B, and the pivoting permutation.
struct LbltFactor {
    symbolic: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    subdiag: Vec<f64>,
    forward: Vec<usize>,
    inverse: Vec<usize>,
}

impl LbltFactor {
    /// Whether every 1×1 and 2×2 block of B is safely nonsingular:
    /// Bunch–Kaufman never divides by an exact zero when another pivot is
    /// available, so a singular matrix shows up as a pivot at rounding
    /// level (≤ n ε max|a_ij|), not as a zero, and the solve would return
    /// huge finite values.
    fn pivots_are_nonsingular(&self, scale: f64) -> bool {
        let SymbolicCholeskyRaw::Supernodal(symbolic) = self.symbolic.raw() else {
            // The analysis forces the supernodal kernel; a simplicial factor
            // was never pivoted and is judged by its finite values alone.
            return true;
        };
        let size = self.subdiag.len();
        let tolerance = size as f64 * f64::EPSILON * scale;
        let perm = faer::perm::PermRef::new_checked(&self.forward, &self.inverse, size);
        let factor = supernodal::SupernodalIntranodeLbltRef::new(
            symbolic,
            &self.values,
            &self.subdiag,
            perm,
        );
        for s in 0..symbolic.n_supernodes() {
            let node = factor.supernode(s);
            let block = node.val();
            let (start, width) = (node.start(), block.ncols());
            let mut i = 0;
            while i < width {
                let e = self.subdiag[start + i];
                if e == 0.0 {
                    if block[(i, i)].abs() <= tolerance {
                        return false;
                    }
                    i += 1;
                } else {
                    // |det| / ‖·‖_F is the block's smaller singular value
                    // up to a factor √2 (σ_max ≤ ‖·‖_F ≤ √2 σ_max).
                    let (a, b) = (block[(i, i)], block[(i + 1, i + 1)]);
                    let norm = (a * a + b * b + 2.0 * e * e).sqrt();
                    if (a * b - e * e).abs() <= tolerance * norm {
                        return false;
                    }
                    i += 2;
                }
            }
        }
        true
    }
}

/// max |a_ij| over the stored entries.
fn largest_entry(matrix: SparseColMatRef<'_, usize, f64>) -> f64 {
    matrix.val().iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Figures of one solve, for the user's report.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    pub factorization: Factorization,
    pub unknowns: usize,
    pub nonzeros: usize,
    pub symbolic_seconds: f64,
    pub numeric_seconds: f64,
    pub solve_seconds: f64,
    /// ‖b − M x‖₂ / ‖b‖₂ (0 when b = 0 and x = 0).
    pub relative_residual: f64,
}

impl DirectSolver {
    /// Symbolic analysis of `matrix` (only the lower triangle is read for
    /// the symmetric factorisations).
    pub fn analyse(
        matrix: SparseColMatRef<'_, usize, f64>,
        kind: Factorization,
    ) -> Result<Self, SolveError> {
        if matrix.nrows() != matrix.ncols() {
            return Err(SolveError::NotSquare {
                rows: matrix.nrows(),
                cols: matrix.ncols(),
            });
        }
        let started = Instant::now();
        let analysis = match kind {
            Factorization::Llt => Analysis::Llt(
                SymbolicLlt::try_new(matrix.symbolic(), Side::Lower)
                    .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?,
            ),
            Factorization::Ldlt => Analysis::Ldlt(Arc::new(
                factorize_symbolic_cholesky(
                    matrix.symbolic(),
                    Side::Lower,
                    Default::default(),
                    CholeskySymbolicParams::default(),
                )
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?,
            )),
            Factorization::Lblt => Analysis::Lblt(Arc::new(
                factorize_symbolic_cholesky(
                    matrix.symbolic(),
                    Side::Lower,
                    Default::default(),
                    // Bunch–Kaufman pivoting lives in faer's supernodal
                    // kernel only; the simplicial one is LDLᵀ unpivoted.
                    CholeskySymbolicParams {
                        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                        ..Default::default()
                    },
                )
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?,
            )),
            Factorization::Lu => Analysis::Lu(
                SymbolicLu::try_new(matrix.symbolic())
                    .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?,
            ),
        };
        Ok(Self {
            kind,
            analysis,
            size: matrix.nrows(),
            symbolic_seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// The factorisation this analysis is for.
    pub fn kind(&self) -> Factorization {
        self.kind
    }

    /// Numeric factorisation of a matrix with the analysed pattern.
    pub fn factorize(&self, matrix: SparseColMatRef<'_, usize, f64>) -> Result<Factor, SolveError> {
        let started = Instant::now();
        let inner = match &self.analysis {
            Analysis::Llt(symbolic) => Numeric::Llt(
                Llt::try_new_with_symbolic(symbolic.clone(), matrix, Side::Lower)
                    .map_err(|_| SolveError::NotPositiveDefinite)?,
            ),
            Analysis::Ldlt(symbolic) => {
                let mut values = vec![0.0; symbolic.len_val()];
                let par = Par::Seq;
                let mut buffer = MemBuffer::try_new(
                    symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
                )
                .map_err(|_| SolveError::OutOfMemory)?;
                symbolic
                    .factorize_numeric_ldlt(
                        &mut values,
                        matrix,
                        Side::Lower,
                        Default::default(),
                        par,
                        MemStack::new(&mut buffer),
                        Default::default(),
                    )
                    .map_err(|_| SolveError::Singular { method: "LDLᵀ" })?;
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(SolveError::Singular { method: "LDLᵀ" });
                }
                Numeric::Ldlt(symbolic.clone(), values)
            }
            Analysis::Lblt(symbolic) => {
                let size = symbolic.nrows();
                let mut factor = LbltFactor {
                    symbolic: symbolic.clone(),
                    values: vec![0.0; symbolic.len_val()],
                    subdiag: vec![0.0; size],
                    forward: vec![0; size],
                    inverse: vec![0; size],
                };
                let par = Par::Seq;
                let mut buffer = MemBuffer::try_new(
                    symbolic
                        .factorize_numeric_intranode_lblt_scratch::<f64>(par, Default::default()),
                )
                .map_err(|_| SolveError::OutOfMemory)?;
                symbolic.factorize_numeric_intranode_lblt(
                    &mut factor.values,
                    &mut factor.subdiag,
                    &mut factor.forward,
                    &mut factor.inverse,
                    matrix,
                    Side::Lower,
                    par,
                    MemStack::new(&mut buffer),
                    Default::default(),
                );
                // A singular matrix leaves a zero 1×1 (or singular 2×2)
                // block in B, which shows up as non-finite entries of L.
                if factor
                    .values
                    .iter()
                    .chain(&factor.subdiag)
                    .any(|v| !v.is_finite())
                {
                    return Err(SolveError::Singular { method: "LBLᵀ" });
                }
                if !factor.pivots_are_nonsingular(largest_entry(matrix)) {
                    return Err(SolveError::Singular { method: "LBLᵀ" });
                }
                Numeric::Lblt(Box::new(factor))
            }
            Analysis::Lu(symbolic) => Numeric::Lu(Box::new(
                Lu::try_new_with_symbolic(symbolic.clone(), matrix)
                    .map_err(|_| SolveError::Singular { method: "LU" })?,
            )),
        };
        Ok(Factor {
            kind: self.kind,
            inner,
            size: self.size,
            numeric_seconds: started.elapsed().as_secs_f64(),
        })
    }
}

impl Factor {
    /// Solve M x = b.
    pub fn solve(&self, rhs: &[f64]) -> Result<Vec<f64>, SolveError> {
        if rhs.len() != self.size {
            return Err(SolveError::RhsSize {
                expected: self.size,
                found: rhs.len(),
            });
        }
        let mut x = Mat::from_fn(self.size, 1, |i, _| rhs[i]);
        match &self.inner {
            Numeric::Llt(f) => f.solve_in_place(x.as_mut()),
            Numeric::Lu(f) => f.solve_in_place(x.as_mut()),
            Numeric::Ldlt(symbolic, values) => {
                let par = Par::Seq;
                let mut buffer = MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(1, par))
                    .map_err(|_| SolveError::OutOfMemory)?;
                LdltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    x.as_mut(),
                    par,
                    MemStack::new(&mut buffer),
                );
            }
            Numeric::Lblt(f) => {
                let par = Par::Seq;
                let mut buffer =
                    MemBuffer::try_new(f.symbolic.solve_in_place_scratch::<f64>(1, par))
                        .map_err(|_| SolveError::OutOfMemory)?;
                // The permutation arrays were written by faer's factorisation
                // as mutual inverses of length n.
                let perm = faer::perm::PermRef::new_checked(&f.forward, &f.inverse, self.size);
                IntranodeLbltRef::new(&f.symbolic, &f.values, &f.subdiag, perm)
                    .solve_in_place_with_conj(
                        Conj::No,
                        x.as_mut(),
                        par,
                        MemStack::new(&mut buffer),
                    );
            }
        }
        let solution: Vec<f64> = (0..self.size).map(|i| x[(i, 0)]).collect();
        if solution.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::Singular {
                method: match self.kind {
                    Factorization::Llt => "LLᵀ",
                    Factorization::Ldlt => "LDLᵀ",
                    Factorization::Lblt => "LBLᵀ",
                    Factorization::Lu => "LU",
                },
            });
        }
        Ok(solution)
    }
}

/// ‖b − M x‖₂ / ‖b‖₂.
pub fn relative_residual(matrix: SparseColMatRef<'_, usize, f64>, x: &[f64], rhs: &[f64]) -> f64 {
    let mut r = rhs.to_vec();
    for (j, &xj) in x.iter().enumerate().take(matrix.ncols()) {
        let range = matrix.col_range(j);
        let rows = &matrix.row_idx()[range.clone()];
        let vals = &matrix.val()[range];
        for (&i, &v) in rows.iter().zip(vals) {
            r[i] -= v * xj;
        }
    }
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let b = norm(rhs);
    if b == 0.0 {
        norm(&r)
    } else {
        norm(&r) / b
    }
}

/// Analyse, factorise and solve once, and report.
pub fn solve(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    kind: Factorization,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let solver = DirectSolver::analyse(matrix.as_ref(), kind)?;
    let factor = solver.factorize(matrix.as_ref())?;
    let started = Instant::now();
    let x = factor.solve(rhs)?;
    let solve_seconds = started.elapsed().as_secs_f64();
    let relative_residual = relative_residual(matrix.as_ref(), &x, rhs);
    Ok((
        x,
        SolveReport {
            factorization: kind,
            unknowns: matrix.nrows(),
            nonzeros: matrix.compute_nnz(),
            symbolic_seconds: solver.symbolic_seconds,
            numeric_seconds: factor.numeric_seconds,
            solve_seconds,
            relative_residual,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    fn matrix(n: usize, entries: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
        let triplets: Vec<Triplet<usize, usize, f64>> = entries
            .iter()
            .map(|&(i, j, v)| Triplet::new(i, j, v))
            .collect();
        SparseColMat::try_new_from_triplets(n, n, &triplets).unwrap()
    }

    /// tridiag(−1, 2, −1) of size 4 and b = (1, 0, 0, 1): x = (1, 1, 1, 1).
    fn laplacian() -> SparseColMat<usize, f64> {
        let mut e = Vec::new();
        for i in 0..4 {
            e.push((i, i, 2.0));
            if i + 1 < 4 {
                e.push((i, i + 1, -1.0));
                e.push((i + 1, i, -1.0));
            }
        }
        matrix(4, &e)
    }

    #[test]
    fn every_factorization_solves_the_laplacian_exactly() {
        for kind in [
            Factorization::Llt,
            Factorization::Ldlt,
            Factorization::Lblt,
            Factorization::Lu,
        ] {
            let (x, report) = solve(&laplacian(), &[1.0, 0.0, 0.0, 1.0], kind).unwrap();
            for v in &x {
                assert!((v - 1.0).abs() < 1e-14, "{kind}: {x:?}");
            }
            assert!(report.relative_residual < 1e-15);
            assert_eq!(report.nonzeros, 10);
        }
    }

    #[test]
    fn symbolic_analysis_is_reused_for_new_values() {
        let a = laplacian();
        let solver = DirectSolver::analyse(a.as_ref(), Factorization::Llt).unwrap();
        let scaled = matrix(
            4,
            &a.triplet_iter()
                .map(|t| (t.row, t.col, 3.0 * *t.val))
                .collect::<Vec<_>>(),
        );
        let x = solver
            .factorize(scaled.as_ref())
            .unwrap()
            .solve(&[3.0, 0.0, 0.0, 3.0])
            .unwrap();
        assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-14));
    }

    #[test]
    fn indefinite_and_singular_matrices_are_reported() {
        // diag(1, −1) is not positive definite but LDLᵀ and LU handle it.
        let m = matrix(2, &[(0, 0, 1.0), (1, 1, -1.0)]);
        assert_eq!(
            solve(&m, &[1.0, 1.0], Factorization::Llt).unwrap_err(),
            SolveError::NotPositiveDefinite
        );
        let (x, _) = solve(&m, &[1.0, 1.0], Factorization::Ldlt).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] + 1.0).abs() < 1e-15);
        // A singular (rank 1) matrix.
        let s = matrix(2, &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)]);
        assert!(solve(&s, &[1.0, 2.0], Factorization::Lu).is_err());
        assert!(solve(&s, &[1.0, 2.0], Factorization::Llt).is_err());
    }

    /// [[A, B], [Bᵀ, 0]] with A = a·I (m×m) and B (m×k) dense with entries
    /// 1 + (i + 2j) mod 5 + i/10 (full column rank for the sizes used).
    fn saddle_point(m: usize, k: usize, a: f64) -> SparseColMat<usize, f64> {
        let mut e = Vec::new();
        for i in 0..m {
            if a != 0.0 {
                e.push((i, i, a));
            }
            for j in 0..k {
                let b = 1.0 + ((i + 2 * j) % 5) as f64 + i as f64 / 10.0;
                e.push((i, m + j, b));
                e.push((m + j, i, b));
            }
        }
        matrix(m + k, &e)
    }

    fn product(m: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; m.nrows()];
        for t in m.triplet_iter() {
            y[t.row] += t.val * x[t.col];
        }
        y
    }

    fn relative_error(x: &[f64], exact: &[f64]) -> f64 {
        let diff: f64 = x.iter().zip(exact).map(|(a, b)| (a - b).powi(2)).sum();
        let norm: f64 = exact.iter().map(|b| b * b).sum();
        (diff / norm).sqrt()
    }

    #[test]
    fn lblt_solves_saddle_point_systems_where_ldlt_meets_zero_pivots() {
        // A = I: indefinite (m positive, k negative eigenvalues).
        // A = 0, m = k: every diagonal entry is zero, so LDLᵀ without
        // pivoting breaks down at its first pivot whatever the ordering;
        // Bunch–Kaufman takes 2×2 pivots.
        for (m, k, a) in [(6, 3, 1.0), (4, 4, 0.0)] {
            let kkt = saddle_point(m, k, a);
            let exact: Vec<f64> = (0..m + k)
                .map(|i| 1.0 + 0.5 * i as f64 - 0.1 * (i * i) as f64)
                .collect();
            let rhs = product(&kkt, &exact);
            let (x, report) = solve(&kkt, &rhs, Factorization::Lblt).unwrap();
            let error = relative_error(&x, &exact);
            assert!(
                error < 1e-12,
                "m = {m}, k = {k}, a = {a}: relative error {error:e}"
            );
            assert!(report.relative_residual < 1e-13);
            assert_eq!(
                solve(&kkt, &rhs, Factorization::Llt).unwrap_err(),
                SolveError::NotPositiveDefinite
            );
            if a == 0.0 {
                assert_eq!(
                    solve(&kkt, &rhs, Factorization::Ldlt).unwrap_err(),
                    SolveError::Singular { method: "LDLᵀ" }
                );
            }
        }
    }

    #[test]
    fn lblt_analysis_is_reused_and_singular_matrices_are_reported() {
        let kkt = saddle_point(5, 2, 1.0);
        let solver = DirectSolver::analyse(kkt.as_ref(), Factorization::Lblt).unwrap();
        let exact: Vec<f64> = (0..7).map(|i| (i as f64).sin() + 2.0).collect();
        for scale in [1.0, -3.0] {
            let scaled = matrix(
                7,
                &kkt.triplet_iter()
                    .map(|t| (t.row, t.col, scale * *t.val))
                    .collect::<Vec<_>>(),
            );
            let x = solver
                .factorize(scaled.as_ref())
                .unwrap()
                .solve(&product(&scaled, &exact))
                .unwrap();
            assert!(relative_error(&x, &exact) < 1e-12, "scale {scale}: {x:?}");
        }
        // B with two equal columns: the matrix is singular.
        let mut e = vec![];
        for i in 0..3 {
            e.push((i, i, 1.0));
            for j in 0..2 {
                e.push((i, 3 + j, 1.0 + i as f64));
                e.push((3 + j, i, 1.0 + i as f64));
            }
        }
        let singular = matrix(5, &e);
        assert_eq!(
            solve(&singular, &[1.0; 5], Factorization::Lblt).unwrap_err(),
            SolveError::Singular { method: "LBLᵀ" }
        );
    }

    /// The five-point Laplacian of an m×m grid shifted by −σ I.
    fn shifted_laplacian(m: usize, sigma: f64) -> SparseColMat<usize, f64> {
        let mut e = Vec::new();
        let id = |i: usize, j: usize| i + m * j;
        for j in 0..m {
            for i in 0..m {
                e.push((id(i, j), id(i, j), 4.0 - sigma));
                if i + 1 < m {
                    e.push((id(i, j), id(i + 1, j), -1.0));
                    e.push((id(i + 1, j), id(i, j), -1.0));
                }
                if j + 1 < m {
                    e.push((id(i, j), id(i, j + 1), -1.0));
                    e.push((id(i, j + 1), id(i, j), -1.0));
                }
            }
        }
        matrix(m * m, &e)
    }

    #[test]
    fn lblt_solves_an_indefinite_shifted_laplacian_with_many_supernodes() {
        // Eigenvalues 4 − 2cos(iπ/31) − 2cos(jπ/31) − σ, 1 ≤ i, j ≤ 30: with
        // σ = 3.3, 317 of the 900 are negative; the nearest to zero is
        // 0.0092 (i = 5, j = 21) and the largest 4.68, so cond ≈ 510.
        let m = 30;
        let a = shifted_laplacian(m, 3.3);
        let exact: Vec<f64> = (0..m * m)
            .map(|k| ((k % 7) as f64 - 3.0) * 0.5 + (k as f64).cos())
            .collect();
        let rhs = product(&a, &exact);
        let (x, report) = solve(&a, &rhs, Factorization::Lblt).unwrap();
        assert!(report.relative_residual < 1e-13, "{report:?}");
        // Error ≤ cond · residual: well below 1e-10.
        assert!(
            relative_error(&x, &exact) < 1e-10,
            "{:e}",
            relative_error(&x, &exact)
        );
        let solver = DirectSolver::analyse(a.as_ref(), Factorization::Lblt).unwrap();
        let Analysis::Lblt(analysis) = &solver.analysis else {
            panic!("an LBLᵀ analysis was asked for");
        };
        let SymbolicCholeskyRaw::Supernodal(symbolic) = analysis.raw() else {
            panic!("the LBLᵀ analysis must be supernodal");
        };
        assert!(
            symbolic.n_supernodes() > 10,
            "{} supernodes",
            symbolic.n_supernodes()
        );
        assert_eq!(
            solve(&a, &rhs, Factorization::Llt).unwrap_err(),
            SolveError::NotPositiveDefinite
        );
    }
}
