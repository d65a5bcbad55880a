//! Sparse direct solves through faer: LLᵀ for symmetric positive definite
//! systems, LDLᵀ for symmetric quasi-definite ones, LBLᵀ (Bunch–Kaufman
//! pivoting) for symmetric indefinite ones, LU for the rest.
//!
//! As in faer, the symbolic analysis (ordering, elimination tree, pattern
//! of the factor) is a value of its own ([`DirectSolver`]) that is kept and
//! reused when only the values of the matrix change; the numeric
//! factorisation ([`Factor`]) solves any number of right-hand sides.
//!
//! The symmetric factorisations take a fill-reducing [`Ordering`]: faer's
//! AMD, or METIS nested dissection ([`crate::la::ordering`]) passed to faer as a
//! custom permutation, or nested dissection from the unknowns' positions;
//! [`Ordering::Automatic`] picks one (measured, see there). LU keeps faer's
//! COLAMD column ordering.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};
use std::sync::Arc;

mod factor;
use std::time::Instant;

use crate::la::ordering::{self, Ordering, OrderingError, UnknownPoints, ND_MIN_FILL_PER_UNKNOWN};

/// Which factorisation to use.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::direct::{solve, Factorization, SolveError};
/// // [[0, 1], [1, 0]]: symmetric and indefinite, with a zero leading minor.
/// let m = SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &[
///     Triplet::new(0, 0, 0.0), Triplet::new(1, 0, 1.0),
///     Triplet::new(0, 1, 1.0), Triplet::new(1, 1, 0.0),
/// ]).unwrap();
/// let b = [2.0, 3.0];
/// assert_eq!(solve(&m, &b, Factorization::Llt).unwrap_err(), SolveError::NotPositiveDefinite);
/// assert!(matches!(solve(&m, &b, Factorization::Ldlt), Err(SolveError::Singular { .. })));
/// // A 2×2 pivot block (LBLᵀ) or a row exchange (LU) solves it: x = (3, 2).
/// for kind in [Factorization::Lblt, Factorization::Lu] {
///     let (x, _) = solve(&m, &b, kind).unwrap();
///     assert!((x[0] - 3.0).abs() < 1e-15 && (x[1] - 2.0).abs() < 1e-15, "{kind}");
/// }
/// ```
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
    /// The matrix is not square, so it has no factorisation to solve with.
    #[error("the matrix is {rows}×{cols}; a direct solve needs a square matrix")]
    NotSquare {
        /// Rows of the matrix.
        rows: usize,
        /// Columns of the matrix.
        cols: usize,
    },
    /// The right-hand side does not have one entry per unknown.
    #[error("right-hand side has {found} entries for {expected} unknowns")]
    RhsSize {
        /// Unknowns of the factorised matrix.
        expected: usize,
        /// Entries of the right-hand side.
        found: usize,
    },
    /// LLᵀ met a pivot ≤ 0. For a discretised diffusion problem this
    /// usually means a floating part of the domain (pure Neumann without a
    /// mean constraint) or a coefficient that is not positive.
    #[error("LLᵀ failed: the matrix is not positive definite (a pivot was ≤ 0). The system is singular or indefinite: check that every connected part of the domain has a Dirichlet or Robin boundary, or that the coefficients are positive")]
    NotPositiveDefinite,
    /// A zero pivot (or, for LBLᵀ, a pivot block at rounding level), or a
    /// solution with non-finite entries: the matrix is singular to working
    /// precision.
    #[error("{method} factorisation failed: the matrix is singular (a zero pivot). Check the boundary conditions and coefficients")]
    Singular {
        /// The factorisation that failed: "LLᵀ", "LDLᵀ", "LBLᵀ" or "LU".
        method: &'static str,
    },
    /// faer's symbolic analysis rejected the pattern (its message).
    #[error("symbolic analysis failed: {0}")]
    Symbolic(String),
    /// The factor's values or faer's scratch memory could not be allocated.
    #[error("out of memory while factorising")]
    OutOfMemory,
    /// The fill-reducing ordering could not be computed.
    #[error("fill-reducing ordering: {0}")]
    Ordering(#[from] OrderingError),
}

enum Analysis {
    Llt(Arc<SymbolicCholesky<usize>>),
    Ldlt(Arc<SymbolicCholesky<usize>>),
    Lblt(Arc<SymbolicCholesky<usize>>),
    Lu(SymbolicLu<usize>),
}

impl Analysis {
    /// A symmetric (LLᵀ, LDLᵀ or LBLᵀ) analysis of `kind`.
    fn symmetric(kind: Factorization, symbolic: Arc<SymbolicCholesky<usize>>) -> Self {
        match kind {
            Factorization::Ldlt => Analysis::Ldlt(symbolic),
            Factorization::Lblt => Analysis::Lblt(symbolic),
            _ => Analysis::Llt(symbolic),
        }
    }
}

/// The symbolic phase of a factorisation, reusable for every matrix with
/// the same sparsity pattern.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::direct::{DirectSolver, Factorization};
/// // [[a, −1], [−1, a]] for two values of a: one analysis, two factorisations.
/// let m = |a: f64| SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &[
///     Triplet::new(0, 0, a), Triplet::new(1, 0, -1.0),
///     Triplet::new(0, 1, -1.0), Triplet::new(1, 1, a),
/// ]).unwrap();
/// let solver = DirectSolver::analyze(m(2.0).as_ref(), Factorization::Llt).unwrap();
/// for a in [2.0, 3.0] {
///     let x = solver.factorize(m(a).as_ref()).unwrap().solve(&[1.0, 1.0]).unwrap();
///     // Both rows read (a − 1) x = 1.
///     assert!((x[0] - 1.0 / (a - 1.0)).abs() < 1e-15 && (x[1] - x[0]).abs() < 1e-15);
/// }
/// ```
pub struct DirectSolver {
    kind: Factorization,
    analysis: Analysis,
    size: usize,
    ordering: Option<Ordering>,
    /// Seconds spent in the symbolic analysis (the ordering included).
    pub symbolic_seconds: f64,
}

/// A numeric factorisation, ready to solve any number of right-hand sides.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::direct::{DirectSolver, Factorization};
/// let m = SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &[
///     Triplet::new(0, 0, 2.0), Triplet::new(1, 0, -1.0),
///     Triplet::new(0, 1, -1.0), Triplet::new(1, 1, 2.0),
/// ]).unwrap();
/// let factor = DirectSolver::analyze(m.as_ref(), Factorization::Llt)
///     .unwrap()
///     .factorize(m.as_ref())
///     .unwrap();
/// // The columns of M⁻¹ = ⅓ [[2, 1], [1, 2]], one solve each.
/// let x0 = factor.solve(&[1.0, 0.0]).unwrap();
/// let x1 = factor.solve(&[0.0, 1.0]).unwrap();
/// assert!((x0[0] - 2.0 / 3.0).abs() < 1e-15 && (x0[1] - 1.0 / 3.0).abs() < 1e-15);
/// assert!((x1[0] - 1.0 / 3.0).abs() < 1e-15 && (x1[1] - 2.0 / 3.0).abs() < 1e-15);
/// ```
pub struct Factor {
    kind: Factorization,
    inner: Numeric,
    size: usize,
    /// Seconds spent in the numeric factorisation.
    pub(crate) numeric_seconds: f64,
}

enum Numeric {
    Llt(Arc<SymbolicCholesky<usize>>, Vec<f64>),
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

/// Σ_j c_j² over the columns of the factor ([`DirectSolver::factor_flops`]).
/// A supernode of k columns and r rows below its diagonal block stores
/// r + k − i values in its i-th column (i = 0, …, k − 1), so it adds
/// Σ_{m=r+1}^{r+k} m².
fn factor_flops(symbolic: &SymbolicCholesky<usize>) -> f64 {
    let squares = |m: f64| m * (m + 1.0) * (2.0 * m + 1.0) / 6.0;
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(factor) => factor
            .col_ptr()
            .windows(2)
            .map(|c| ((c[1] - c[0]) as f64).powi(2))
            .sum(),
        SymbolicCholeskyRaw::Supernodal(factor) => {
            let rows = factor.col_ptr_for_row_idx();
            (0..factor.n_supernodes())
                .map(|s| {
                    let k = (factor.supernode_end()[s] - factor.supernode_begin()[s]) as f64;
                    let r = (rows[s + 1] - rows[s]) as f64;
                    squares(r + k) - squares(r)
                })
                .sum()
        }
    }
}

/// max |a_ij| over the stored entries.
fn largest_entry(matrix: SparseColMatRef<'_, usize, f64>) -> f64 {
    matrix.val().iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

/// Figures of one solve, for the user's report.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    /// The factorisation used.
    pub factorization: Factorization,
    /// The fill-reducing ordering of a symmetric factorisation made by
    /// [`DirectSolver`]; `None` for LU (COLAMD), an iterative solve, or a
    /// caller's own ordering.
    pub ordering: Option<Ordering>,
    /// Size n of the n×n system.
    pub unknowns: usize,
    /// Stored entries of the matrix (both triangles of a symmetric one).
    pub nonzeros: usize,
    /// Seconds of the symbolic analysis, the ordering included.
    pub symbolic_seconds: f64,
    /// Seconds of the numeric factorisation.
    pub numeric_seconds: f64,
    /// Seconds of the forward and back substitution.
    pub solve_seconds: f64,
    /// ‖b − M x‖₂ / ‖b‖₂ (0 when b = 0 and x = 0).
    pub relative_residual: f64,
    /// Values the factor stores, for a symmetric factorisation made by
    /// [`DirectSolver`] ([`DirectSolver::factor_entries`]); `None`
    /// otherwise.
    pub factor_entries: Option<usize>,
    /// Work of that factorisation, Σ_j c_j² with c_j the values stored in
    /// column j of the factor (supernode padding included): orderings are
    /// compared by it, as it follows the factorisation's time more closely
    /// than the factor's size. `None` where `factor_entries` is.
    pub factor_flops: Option<f64>,
}

impl DirectSolver {
    /// Symbolic analysis of `matrix` (only the lower triangle is read for
    /// the symmetric factorisations) with the [`Ordering::Automatic`]
    /// fill-reducing ordering.
    pub fn analyze(
        matrix: SparseColMatRef<'_, usize, f64>,
        kind: Factorization,
    ) -> Result<Self, SolveError> {
        Self::analyze_with(matrix, kind, Ordering::Automatic)
    }

    /// Symbolic analysis of `matrix` with the given fill-reducing ordering
    /// (ignored by LU). The ordering's time counts as analysis time.
    ///
    /// ```
    /// use faer::sparse::{SparseColMat, Triplet};
    /// use hasse_solver::la::direct::{DirectSolver, Factorization};
    /// use hasse_solver::la::ordering::Ordering;
    /// // tridiag(−1, 2, −1), n = 5, stored whole.
    /// let mut t = Vec::new();
    /// for i in 0..5 {
    ///     t.push(Triplet::new(i, i, 2.0));
    ///     if i + 1 < 5 {
    ///         t.push(Triplet::new(i + 1, i, -1.0));
    ///         t.push(Triplet::new(i, i + 1, -1.0));
    ///     }
    /// }
    /// let a = SparseColMat::<usize, f64>::try_new_from_triplets(5, 5, &t).unwrap();
    /// let solver = DirectSolver::analyze_with(a.as_ref(), Factorization::Ldlt, Ordering::Amd).unwrap();
    /// let x = solver.factorize(a.as_ref()).unwrap().solve(&[1.0, 0.0, 0.0, 0.0, 1.0]).unwrap();
    /// assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-14));
    /// assert_eq!(solver.ordering(), Some(Ordering::Amd));
    /// ```
    pub fn analyze_with(
        matrix: SparseColMatRef<'_, usize, f64>,
        kind: Factorization,
        ordering: Ordering,
    ) -> Result<Self, SolveError> {
        Self::analyze_pattern(matrix.symbolic(), kind, ordering)
    }

    /// Symbolic analysis of a sparsity pattern alone: the analysis never
    /// reads values, so it can run before (or while) they are computed,
    /// when the pattern is known from topology. Every matrix later
    /// factorised must have exactly this pattern.
    pub fn analyze_pattern(
        matrix: SymbolicSparseColMatRef<'_, usize>,
        kind: Factorization,
        ordering: Ordering,
    ) -> Result<Self, SolveError> {
        Self::analyze_pattern_at(matrix, kind, ordering, None)
    }

    /// [`DirectSolver::analyze_pattern`] for unknowns at `points`, which
    /// [`Ordering::Geometric`] needs and [`Ordering::Automatic`] uses for
    /// LLᵀ (see there).
    pub fn analyze_pattern_at(
        matrix: SymbolicSparseColMatRef<'_, usize>,
        kind: Factorization,
        ordering: Ordering,
        points: Option<UnknownPoints<'_>>,
    ) -> Result<Self, SolveError> {
        if matrix.nrows() != matrix.ncols() {
            return Err(SolveError::NotSquare {
                rows: matrix.nrows(),
                cols: matrix.ncols(),
            });
        }
        let started = Instant::now();
        let size = matrix.nrows();
        let symbolic = |order: SymmetricOrdering<'_, usize>| {
            let params = match kind {
                // Bunch–Kaufman pivoting lives in faer's supernodal kernel
                // only; the simplicial one is LDLᵀ unpivoted.
                Factorization::Lblt => CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                    ..Default::default()
                },
                _ => CholeskySymbolicParams::default(),
            };
            factorize_symbolic_cholesky(matrix, Side::Lower, order, params)
                .map(Arc::new)
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))
        };
        // The geometric ordering: asked for (positions required), or the
        // automatic rule's for LLᵀ when the positions are usable (within
        // 32-bit graph indices, all finite); otherwise the rule without.
        let geometric = match (kind, ordering, points) {
            (Factorization::Lu, _, _) => None,
            (_, Ordering::Geometric, points) => {
                let p = points.ok_or(OrderingError::NoPoints)?;
                Some(ordering::coordinate_dissection(
                    matrix,
                    p.coordinates,
                    p.dimension,
                )?)
            }
            (Factorization::Llt, Ordering::Automatic, Some(p)) => {
                ordering::coordinate_dissection(matrix, p.coordinates, p.dimension).ok()
            }
            _ => None,
        };
        let (analysis, ordering) = match (kind, ordering, geometric) {
            (Factorization::Lu, _, _) => (
                Analysis::Lu(
                    SymbolicLu::try_new(matrix)
                        .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?,
                ),
                None,
            ),
            (_, _, Some(perm)) => (
                Analysis::symmetric(kind, symbolic(SymmetricOrdering::Custom(perm.as_ref()))?),
                Some(Ordering::Geometric),
            ),
            (_, Ordering::NestedDissection, None) => {
                let perm = ordering::nested_dissection(matrix)?;
                let analysed = symbolic(SymmetricOrdering::Custom(perm.as_ref()))?;
                (
                    Analysis::symmetric(kind, analysed),
                    Some(Ordering::NestedDissection),
                )
            }
            (Factorization::Llt, Ordering::Automatic, None) => {
                let amd = symbolic(SymmetricOrdering::Amd)?;
                if amd.len_val() < ND_MIN_FILL_PER_UNKNOWN.saturating_mul(size) {
                    (Analysis::Llt(amd), Some(Ordering::Amd))
                } else {
                    match ordering::nested_dissection(matrix) {
                        Ok(perm) => {
                            let nd = symbolic(SymmetricOrdering::Custom(perm.as_ref()))?;
                            // Whichever stores less; on every measured
                            // graph past the threshold that is ND.
                            if nd.len_val() < amd.len_val() {
                                (Analysis::Llt(nd), Some(Ordering::NestedDissection))
                            } else {
                                (Analysis::Llt(amd), Some(Ordering::Amd))
                            }
                        }
                        // Beyond METIS's 32-bit indices the automatic choice
                        // keeps AMD; an explicit request fails instead.
                        Err(OrderingError::TooLarge { .. }) => {
                            (Analysis::Llt(amd), Some(Ordering::Amd))
                        }
                        Err(e) => return Err(e.into()),
                    }
                }
            }
            // (A geometric request always has its permutation by now.)
            (_, Ordering::Amd | Ordering::Automatic | Ordering::Geometric, None) => (
                Analysis::symmetric(kind, symbolic(SymmetricOrdering::Amd)?),
                Some(Ordering::Amd),
            ),
        };
        Ok(Self {
            kind,
            analysis,
            size,
            ordering,
            symbolic_seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// The factorisation this analysis is for.
    pub fn kind(&self) -> Factorization {
        self.kind
    }

    /// The fill-reducing ordering used (never `Automatic`); `None` for LU.
    pub fn ordering(&self) -> Option<Ordering> {
        self.ordering
    }

    /// Number of values the numeric factor stores: nnz(L) for a
    /// simplicial factor, nnz(L) plus the padding of dense supernodal
    /// blocks for a supernodal one; `None` for LU, whose size is only
    /// known after pivoting.
    pub fn factor_entries(&self) -> Option<usize> {
        match &self.analysis {
            Analysis::Llt(s) | Analysis::Ldlt(s) | Analysis::Lblt(s) => Some(s.len_val()),
            Analysis::Lu(_) => None,
        }
    }

    /// Floating-point work of the numeric factorisation, as Σ_j c_j², c_j
    /// the number of values stored in column j of the factor (padding of
    /// supernodes included); `None` for LU. Orderings are compared by it:
    /// it tracks the factorisation's time more closely than the factor's
    /// size does.
    pub fn factor_flops(&self) -> Option<f64> {
        match &self.analysis {
            Analysis::Llt(s) | Analysis::Ldlt(s) | Analysis::Lblt(s) => Some(factor_flops(s)),
            Analysis::Lu(_) => None,
        }
    }

    /// Numeric factorisation of a matrix with the analysed pattern.
    pub fn factorize(&self, matrix: SparseColMatRef<'_, usize, f64>) -> Result<Factor, SolveError> {
        let started = Instant::now();
        let inner = match &self.analysis {
            Analysis::Llt(symbolic) => {
                let mut values = Vec::new();
                values
                    .try_reserve_exact(symbolic.len_val())
                    .map_err(|_| SolveError::OutOfMemory)?;
                values.resize(symbolic.len_val(), 0.0);
                // faer's own `Llt` runs with the global parallelism; so
                // does this, to keep the factorisation's speed.
                let par = faer::get_global_parallelism();
                let mut buffer = MemBuffer::try_new(
                    symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
                )
                .map_err(|_| SolveError::OutOfMemory)?;
                symbolic
                    .factorize_numeric_llt(
                        &mut values,
                        matrix,
                        Side::Lower,
                        Default::default(),
                        par,
                        MemStack::new(&mut buffer),
                        Default::default(),
                    )
                    .map_err(|_| SolveError::NotPositiveDefinite)?;
                Numeric::Llt(symbolic.clone(), values)
            }
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

/// ‖b − M x‖₂ / ‖b‖₂, or ‖b − M x‖₂ when b = 0 (M may be rectangular; x
/// has one entry per column, b one per row).
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

/// Analyse, factorise and solve once with the automatic ordering, and
/// report.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::direct::{solve, Factorization};
/// use hasse_solver::la::ordering::Ordering;
/// // tridiag(−1, 2, −1) x = (1, 0, 1) has x = (1, 1, 1).
/// let t = [(0, 0, 2.0), (1, 1, 2.0), (2, 2, 2.0), (0, 1, -1.0), (1, 0, -1.0), (1, 2, -1.0), (2, 1, -1.0)];
/// let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
/// let m = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
/// let (x, report) = solve(&m, &[1.0, 0.0, 1.0], Factorization::Llt).unwrap();
/// assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-15));
/// assert_eq!((report.unknowns, report.nonzeros), (3, 7));
/// // Three unknowns fill little: the automatic rule keeps AMD.
/// assert_eq!(report.ordering, Some(Ordering::Amd));
/// assert!(report.relative_residual < 1e-15);
/// ```
pub fn solve(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    kind: Factorization,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    solve_with(matrix, rhs, kind, Ordering::Automatic)
}

/// Analyse with `ordering`, factorise and solve once, and report.
pub(crate) fn solve_with(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    kind: Factorization,
    ordering: Ordering,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let solver = DirectSolver::analyze_with(matrix.as_ref(), kind, ordering)?;
    solve_analyzed(&solver, matrix, rhs)
}

/// Factorise and solve once with an analysis made beforehand (of this
/// matrix's pattern, see [`DirectSolver::analyze_pattern`]), and report;
/// the report's symbolic time is the analysis's own.
pub fn solve_analyzed(
    solver: &DirectSolver,
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let kind = solver.kind();
    let factor = solver.factorize(matrix.as_ref())?;
    let started = Instant::now();
    let x = factor.solve(rhs)?;
    let solve_seconds = started.elapsed().as_secs_f64();
    let relative_residual = relative_residual(matrix.as_ref(), &x, rhs);
    Ok((
        x,
        SolveReport {
            factorization: kind,
            ordering: solver.ordering(),
            unknowns: matrix.nrows(),
            nonzeros: matrix.compute_nnz(),
            symbolic_seconds: solver.symbolic_seconds,
            numeric_seconds: factor.numeric_seconds,
            solve_seconds,
            relative_residual,
            factor_entries: solver.factor_entries(),
            factor_flops: solver.factor_flops(),
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
            // Four unknowns: the automatic rule keeps AMD; LU has COLAMD.
            let expected = (kind != Factorization::Lu).then_some(Ordering::Amd);
            assert_eq!(report.ordering, expected, "{kind}");
        }
    }

    #[test]
    fn symbolic_analysis_is_reused_for_new_values() {
        let a = laplacian();
        let solver = DirectSolver::analyze(a.as_ref(), Factorization::Llt).unwrap();
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
        let solver = DirectSolver::analyze(kkt.as_ref(), Factorization::Lblt).unwrap();
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
        let solver = DirectSolver::analyze(a.as_ref(), Factorization::Lblt).unwrap();
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

    /// The 2d+1-point Laplacian (Dirichlet) on an m^dim grid, stored whole.
    fn grid_laplacian(m: usize, dim: u32) -> SparseColMat<usize, f64> {
        let n = m.pow(dim);
        let mut e = Vec::new();
        for v in 0..n {
            e.push((v, v, 2.0 * dim as f64));
            let mut stride = 1;
            for _ in 0..dim {
                if (v / stride) % m + 1 < m {
                    e.push((v, v + stride, -1.0));
                    e.push((v + stride, v, -1.0));
                }
                stride *= m;
            }
        }
        matrix(n, &e)
    }

    fn smooth_field(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| 1.0 + (0.37 * k as f64).sin() + 0.1 * ((k % 11) as f64))
            .collect()
    }

    #[test]
    fn nested_dissection_solves_like_amd_on_a_3d_grid() {
        // 10³ seven-point Laplacian: eigenvalues 2Σ(1 − cos(k_a π/11)), so
        // cond = (1 + cos(π/11)) / (1 − cos(π/11)) ≈ 48. Cholesky is
        // backward stable with a backward error of a few ε per entry, so
        // either ordering's forward error is below 48 · 10³ · ε ≈ 1e-11.
        let a = grid_laplacian(10, 3);
        let exact = smooth_field(1000);
        let rhs = product(&a, &exact);
        let (amd, amd_report) = solve_with(&a, &rhs, Factorization::Llt, Ordering::Amd).unwrap();
        let (nd, nd_report) =
            solve_with(&a, &rhs, Factorization::Llt, Ordering::NestedDissection).unwrap();
        assert_eq!(amd_report.ordering, Some(Ordering::Amd));
        assert_eq!(nd_report.ordering, Some(Ordering::NestedDissection));
        for x in [&amd, &nd] {
            assert!(
                relative_error(x, &exact) < 1e-11,
                "{:e}",
                relative_error(x, &exact)
            );
        }
        assert!(relative_error(&nd, &amd) < 2e-11);
        // LDLᵀ and LBLᵀ take the ordering too.
        for kind in [Factorization::Ldlt, Factorization::Lblt] {
            let (x, report) = solve_with(&a, &rhs, kind, Ordering::NestedDissection).unwrap();
            assert_eq!(report.ordering, Some(Ordering::NestedDissection), "{kind}");
            assert!(relative_error(&x, &exact) < 1e-11, "{kind}");
        }
    }

    #[test]
    fn nested_dissection_analysis_is_reused_for_new_values() {
        // Same pattern, other values: the 12² Laplacian plus a varying
        // diagonal (still SPD: diagonally dominant).
        let a = grid_laplacian(12, 2);
        let solver =
            DirectSolver::analyze_with(a.as_ref(), Factorization::Llt, Ordering::NestedDissection)
                .unwrap();
        assert_eq!(solver.ordering(), Some(Ordering::NestedDissection));
        let exact = smooth_field(144);
        for shift in [0.0, 0.5, 3.0] {
            let b = matrix(
                144,
                &a.triplet_iter()
                    .map(|t| {
                        let extra = if t.row == t.col {
                            shift * (1.0 + (t.row % 5) as f64)
                        } else {
                            0.0
                        };
                        (t.row, t.col, *t.val + extra)
                    })
                    .collect::<Vec<_>>(),
            );
            let x = solver
                .factorize(b.as_ref())
                .unwrap()
                .solve(&product(&b, &exact))
                .unwrap();
            // cond ≤ that of the unshifted 12² Laplacian, ≈ 60.
            assert!(relative_error(&x, &exact) < 1e-12, "shift {shift}");
        }
    }

    /// nnz(L) of the LLᵀ analysis with `ordering`, counted exactly: a
    /// simplicial factor stores L's nonzeros and nothing else.
    fn exact_factor_nonzeros(
        a: &SparseColMat<usize, f64>,
        ordering: SymmetricOrdering<'_, usize>,
    ) -> usize {
        factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
                ..Default::default()
            },
        )
        .unwrap()
        .len_val()
    }

    #[test]
    fn nested_dissection_fills_less_than_amd_on_a_3d_grid() {
        // On an m³ grid nested dissection's separators are planes of m²
        // vertices, which bounds nnz(L) by O(m⁴) = O(n^{4/3}) (George's
        // analysis); minimum degree has no such bound and its greedy local
        // choices leave more fill on 3D grids.
        let a = grid_laplacian(24, 3);
        let perm = ordering::nested_dissection(a.symbolic()).unwrap();
        let nd = exact_factor_nonzeros(&a, SymmetricOrdering::Custom(perm.as_ref()));
        let amd = exact_factor_nonzeros(&a, SymmetricOrdering::Amd);
        assert!(nd < amd, "nnz(L): nested dissection {nd}, AMD {amd}");
        // Sanity of the count: L holds at least A's lower triangle.
        let lower = a.triplet_iter().filter(|t| t.row >= t.col).count();
        assert!(nd >= lower);
    }

    #[test]
    fn automatic_ordering_follows_the_fill_rule() {
        // AMD fill per unknown (measured, see ND_MIN_FILL_PER_UNKNOWN): 42
        // on the 300² grid, 143 on 20³, 414 on 40³.
        let entries_per_unknown = |a: &SparseColMat<usize, f64>| {
            let amd =
                DirectSolver::analyze_with(a.as_ref(), Factorization::Llt, Ordering::Amd).unwrap();
            amd.factor_entries().unwrap() as f64 / a.nrows() as f64
        };
        for (a, expected) in [
            (grid_laplacian(300, 2), Ordering::Amd),
            (grid_laplacian(20, 3), Ordering::Amd),
            (grid_laplacian(40, 3), Ordering::NestedDissection),
        ] {
            let fill = entries_per_unknown(&a);
            let solver = DirectSolver::analyze(a.as_ref(), Factorization::Llt).unwrap();
            assert_eq!(
                solver.ordering(),
                Some(expected),
                "AMD fill {fill} per unknown"
            );
            assert_eq!(
                expected == Ordering::NestedDissection,
                fill >= ND_MIN_FILL_PER_UNKNOWN as f64,
                "{fill}"
            );
            // LDLᵀ keeps AMD whatever the fill.
            let ldlt = DirectSolver::analyze(a.as_ref(), Factorization::Ldlt).unwrap();
            assert_eq!(ldlt.ordering(), Some(Ordering::Amd));
        }
        let lu = DirectSolver::analyze(grid_laplacian(6, 3).as_ref(), Factorization::Lu).unwrap();
        assert_eq!(lu.ordering(), None);
        assert_eq!(lu.factor_entries(), None);
    }

    /// The grid points of `grid_laplacian(m, dim)`'s unknowns.
    fn grid_points(m: usize, dim: u32) -> Vec<f64> {
        let n = m.pow(dim);
        (0..n)
            .flat_map(|v| (0..dim).map(move |a| ((v / m.pow(a)) % m) as f64))
            .collect()
    }

    #[test]
    fn factor_flops_are_the_sum_of_squared_column_counts() {
        // Tridiagonal, n = 10, at x = 0..9: one leaf, so the geometric
        // ordering is the natural one and there is no fill; columns hold
        // 2 values but the last, which holds 1: 9 · 4 + 1.
        let n = 10;
        let mut e = Vec::new();
        for i in 0..n {
            e.push((i, i, 2.0));
            if i + 1 < n {
                e.push((i + 1, i, -1.0));
                e.push((i, i + 1, -1.0));
            }
        }
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let points = UnknownPoints {
            coordinates: &x,
            dimension: 1,
        };
        let a = matrix(n, &e);
        let solver = DirectSolver::analyze_pattern_at(
            a.symbolic(),
            Factorization::Llt,
            Ordering::Geometric,
            Some(points),
        )
        .unwrap();
        assert_eq!(solver.factor_entries(), Some(2 * n - 1));
        assert_eq!(solver.factor_flops(), Some(37.0));
        // A dense SPD matrix of size 200 (I + 1 1ᵀ) is one supernode whose
        // columns hold 200, 199, …, 1 values: Σ c² = 200 · 201 · 401 / 6.
        let m = 200;
        let mut dense = Vec::new();
        for j in 0..m {
            for i in 0..m {
                dense.push((i, j, if i == j { 2.0 } else { 1.0 }));
            }
        }
        let solver = DirectSolver::analyze_with(
            matrix(m, &dense).as_ref(),
            Factorization::Llt,
            Ordering::Amd,
        )
        .unwrap();
        assert!(matches!(
            solver.analysis,
            Analysis::Llt(ref s) if matches!(s.raw(), SymbolicCholeskyRaw::Supernodal(_))
        ));
        assert_eq!(solver.factor_flops(), Some((200 * 201 * 401 / 6) as f64));
        let lu = DirectSolver::analyze(a.as_ref(), Factorization::Lu).unwrap();
        assert_eq!(lu.factor_flops(), None);
    }

    #[test]
    fn automatic_ordering_with_points_is_geometric_for_llt_only() {
        // 14³ seven-point Laplacian, cond ≈ 85: both orderings' forward
        // errors are below 85 · 14³ · ε ≈ 5e-11.
        let m = 14;
        let a = grid_laplacian(m, 3);
        let x = grid_points(m, 3);
        let points = UnknownPoints {
            coordinates: &x,
            dimension: 3,
        };
        let analyze = |kind, ordering, points| {
            DirectSolver::analyze_pattern_at(a.symbolic(), kind, ordering, points).unwrap()
        };
        let automatic = analyze(Factorization::Llt, Ordering::Automatic, Some(points));
        assert_eq!(automatic.ordering(), Some(Ordering::Geometric));
        assert_eq!(
            analyze(Factorization::Ldlt, Ordering::Automatic, Some(points)).ordering(),
            Some(Ordering::Amd)
        );
        assert_eq!(
            analyze(Factorization::Llt, Ordering::Automatic, None).ordering(),
            DirectSolver::analyze(a.as_ref(), Factorization::Llt)
                .unwrap()
                .ordering()
        );
        let exact = smooth_field(m * m * m);
        let rhs = product(&a, &exact);
        let u = automatic
            .factorize(a.as_ref())
            .unwrap()
            .solve(&rhs)
            .unwrap();
        assert!(
            relative_error(&u, &exact) < 5e-11,
            "{:e}",
            relative_error(&u, &exact)
        );
        // Unusable points fall back to the rule without points; asking for
        // the geometric ordering with them, or without any, is an error.
        let mut bad = x.clone();
        bad[5] = f64::INFINITY;
        let bad_points = UnknownPoints {
            coordinates: &bad,
            dimension: 3,
        };
        assert_ne!(
            analyze(Factorization::Llt, Ordering::Automatic, Some(bad_points)).ordering(),
            Some(Ordering::Geometric)
        );
        for points in [Some(bad_points), None] {
            let error = DirectSolver::analyze_pattern_at(
                a.symbolic(),
                Factorization::Llt,
                Ordering::Geometric,
                points,
            )
            .err()
            .unwrap();
            assert!(matches!(error, SolveError::Ordering(_)), "{error}");
        }
    }

    #[test]
    fn a_pattern_alone_is_analysed_before_the_values() {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(
            2,
            2,
            &[
                Triplet::new(0, 0, 2.0),
                Triplet::new(1, 0, -1.0),
                Triplet::new(0, 1, -1.0),
                Triplet::new(1, 1, 2.0),
            ],
        )
        .unwrap();
        let solver =
            DirectSolver::analyze_pattern(a.symbolic(), Factorization::Llt, Ordering::Amd).unwrap();
        let x = solver
            .factorize(a.as_ref())
            .unwrap()
            .solve(&[1.0, 1.0])
            .unwrap();
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
    }

    #[test]
    fn the_geometric_ordering_solves_the_1d_laplacian_exactly() {
        // tridiag(−1, 2, −1) on 100 unknowns at x = 0, 1, …, 99.
        let n = 100;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0));
            if i + 1 < n {
                t.push(Triplet::new(i + 1, i, -1.0));
                t.push(Triplet::new(i, i + 1, -1.0));
            }
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap();
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let points = UnknownPoints {
            coordinates: &x,
            dimension: 1,
        };
        let solver = DirectSolver::analyze_pattern_at(
            a.symbolic(),
            Factorization::Llt,
            Ordering::Geometric,
            Some(points),
        )
        .unwrap();
        assert_eq!(solver.ordering(), Some(Ordering::Geometric));
        let u = solver
            .factorize(a.as_ref())
            .unwrap()
            .solve(&vec![1.0; n])
            .unwrap();
        // u_i = (i + 1)(n − i)/2, the discrete solution of −u'' = 1.
        assert!((u[49] - 50.0 * 51.0 / 2.0).abs() < 1e-9);
    }
}
