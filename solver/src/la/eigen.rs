//! The smallest eigenpairs of a symmetric pencil K x = λ M x by shift-invert
//! block Krylov iteration with Rayleigh–Ritz on (K, M).
//!
//! K is symmetric positive semidefinite and M symmetric positive definite
//! (on the subspace the optional constraint projects onto). The operator
//! T = (K − σM)⁻¹ M is self-adjoint in the M inner product and maps the
//! eigenvalue λ to 1/(λ − σ), so the eigenvalues closest to σ dominate its
//! Krylov spaces. K − σM is factored once (faer LLᵀ for σ < 0, where it is
//! positive definite; Bunch–Kaufman LBLᵀ otherwise) and every step costs
//! one forward/back substitution per vector.
//!
//! Why not `faer::matrix_free::eigen::partial_self_adjoint_eigen`: it is a
//! single-vector, restarted Lanczos for the largest-magnitude eigenvalues
//! of an operator self-adjoint in the Euclidean inner product. T is only
//! M-self-adjoint (a symmetric form needs M^{±1/2}, which for a Whitney
//! mass is a second factorisation), and a single start vector sees one direction of every
//! eigenspace: the exact multiplicities of symmetric grids (2 on a square,
//! 3 and 6 on a cube) would only appear through rounding. A block of b
//! random vectors sees b directions of each eigenspace, so multiplicities up
//! to b are found deterministically.
//!
//! The basis is kept M-orthonormal by full classical Gram–Schmidt applied
//! twice (the "twice is enough" rule), sizes here are ≤ 10⁵ unknowns and a
//! few hundred basis vectors. Instead of the block-tridiagonal matrix of
//! block Lanczos, the Ritz values come from the projected matrix Qᵀ K Q
//! (Qᵀ M Q = I), which gives λ directly and stays accurate when σ is far
//! from the wanted eigenvalues.

use crate::la::direct::{DirectSolver, Factorization, SolveError};
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Mat, Side};

/// Why an eigensolve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// More eigenpairs were asked for than the (projected) space has.
    #[error("{requested} modes requested, but the problem has only {available}")]
    TooManyModes {
        /// Eigenpairs asked for.
        requested: usize,
        /// Dimension of the space they live in: the unknowns, or the range
        /// of the projection that removes a known null space.
        available: usize,
    },
    /// Zero eigenpairs were asked for.
    #[error("no modes requested: ask for at least one")]
    NoModes,
    /// K and M are not square matrices of one size.
    #[error("K is {k}×{k} but M is {m}×{m}; the pencil needs matrices of one size")]
    SizeMismatch {
        /// Rows of K.
        k: usize,
        /// Rows of M.
        m: usize,
    },
    /// The shift σ ([`Options::shift`]) is NaN or infinite.
    #[error("the shift σ = {0} is not finite")]
    BadShift(f64),
    /// The basis reached [`Options::max_basis`] before every wanted pair
    /// reached [`Options::tolerance`].
    #[error("not converged: {converged} of {requested} eigenpairs reached the tolerance with a basis of {basis} vectors (worst relative residual {worst:e}); raise max_basis or the block size, or move the shift closer to the wanted eigenvalues")]
    NotConverged {
        /// Pairs that reached the tolerance.
        converged: usize,
        /// Pairs asked for.
        requested: usize,
        /// Size of the basis when the iteration stopped.
        basis: usize,
        /// Largest relative residual among the pairs asked for.
        worst: f64,
    },
    /// faer's dense self-adjoint eigensolver failed on the projected
    /// matrix Qᵀ K Q (its message).
    #[error("the dense Rayleigh–Ritz eigenproblem failed: {0}")]
    Dense(String),
    /// K − σM could not be factorised, e.g. because σ is an eigenvalue.
    #[error("factorising K − σM: {0}")]
    Solve(#[from] SolveError),
}

/// Settings of [`smallest`] (and of
/// [`Cavity::modes`](crate::physics::maxwell::Cavity::modes), which calls it).
///
/// ```
/// let o = hasse_solver::la::eigen::Options::default();
/// assert!(o.shift < 0.0 && o.block >= 2);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// The shift σ: the eigenvalues closest to it are returned. A negative
    /// σ below the spectrum of a semidefinite K gives the smallest ones and
    /// a positive definite K − σM (LLᵀ).
    pub shift: f64,
    /// Vectors per Krylov block; at least the largest multiplicity wanted.
    pub block: usize,
    /// Relative residual ‖Kx − λMx‖₂ / (‖Kx‖₂ + |λ| ‖Mx‖₂) every returned
    /// pair must reach. A pair whose λ is zero to rounding (|λ| ≤ 1e-10 ·
    /// ‖K‖₁/‖M‖₁, a kernel vector of K) is measured against ‖K‖₁‖x‖₂
    /// instead: for it ‖Kx‖ and |λ|‖Mx‖ are themselves rounding, and the
    /// ratio above is about 1 however exact the vector.
    pub tolerance: f64,
    /// Largest basis before giving up with [`EigenError::NotConverged`].
    pub max_basis: usize,
    /// Seed of the deterministic random start block.
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            shift: -1.0,
            block: 8,
            tolerance: 1e-9,
            max_basis: 600,
            seed: 0x5eed_cafe,
        }
    }
}

/// Eigenpairs in ascending order of eigenvalue.
#[derive(Clone, Debug, PartialEq)]
pub struct Eigenpairs {
    /// λ, ascending.
    pub values: Vec<f64>,
    /// M-orthonormal eigenvectors, one per value.
    pub vectors: Vec<Vec<f64>>,
    /// Relative residual of each pair (see [`Options::tolerance`]).
    pub residuals: Vec<f64>,
    /// How many of the values (the first ones) are zero to rounding:
    /// kernel vectors of K inside the projection's range.
    pub zeros: usize,
    /// Size of the final Krylov basis.
    pub basis: usize,
    /// Number of solves with K − σM.
    pub solves: usize,
    /// Which factorisation of K − σM was used.
    pub factorization: Factorization,
}

/// A projection applied to every basis vector, e.g. onto the M-orthogonal
/// complement of a known null space of K. It must commute with T for the
/// Krylov space to stay inside its range (true for the complement of a
/// null space of K: Kg = 0 gives gᵀ M T v = −gᵀ M v / σ).
pub type Projection<'a> = &'a dyn Fn(&mut [f64]) -> Result<(), SolveError>;

/// The `count` eigenpairs of K x = λ M x closest to `options.shift`,
/// inside the range of `projection` if one is given; `available` is the
/// dimension of that range (the most pairs that exist).
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::eigen::{smallest, Options};
/// // The 1D Dirichlet Laplacian on 9 interior points, h = 1/10, lumped mass h.
/// let n = 9;
/// let h = 0.1;
/// let mut k = Vec::new();
/// for i in 0..n {
///     k.push(Triplet::new(i, i, 2.0 / h));
///     if i + 1 < n {
///         k.push(Triplet::new(i, i + 1, -1.0 / h));
///         k.push(Triplet::new(i + 1, i, -1.0 / h));
///     }
/// }
/// let k = SparseColMat::try_new_from_triplets(n, n, &k).unwrap();
/// let m = SparseColMat::try_new_from_triplets(n, n, &(0..n).map(|i| Triplet::new(i, i, h)).collect::<Vec<_>>()).unwrap();
/// let pairs = smallest(k.as_ref(), m.as_ref(), 3, None, n, &Options { block: 2, ..Default::default() }).unwrap();
/// for (j, lambda) in pairs.values.iter().enumerate() {
///     // (4/h²) sin²(jπh/2): the exact discrete eigenvalues.
///     let exact = 4.0 / (h * h) * ((j + 1) as f64 * std::f64::consts::PI * h / 2.0).sin().powi(2);
///     assert!((lambda - exact).abs() < 1e-8 * exact);
/// }
/// ```
pub fn smallest(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    count: usize,
    projection: Option<Projection<'_>>,
    available: usize,
    options: &Options,
) -> Result<Eigenpairs, EigenError> {
    let n = k.nrows();
    if m.nrows() != n || k.ncols() != n || m.ncols() != n {
        return Err(EigenError::SizeMismatch { k: n, m: m.nrows() });
    }
    if count == 0 {
        return Err(EigenError::NoModes);
    }
    let available = available.min(n);
    if count > available {
        return Err(EigenError::TooManyModes {
            requested: count,
            available,
        });
    }
    let sigma = options.shift;
    if !sigma.is_finite() {
        return Err(EigenError::BadShift(sigma));
    }
    // The scale of the spectrum, for telling zero eigenvalues from small
    // ones: ‖K‖₁/‖M‖₁ is of the order of the largest eigenvalue.
    let scale = Scale {
        k: column_norm(k),
        m: column_norm(m),
    };
    let shifted = combine(k, m, -sigma);
    // K − σM is positive definite for σ < 0 (K ⪰ 0, M ≻ 0), indefinite
    // above the lowest eigenvalue.
    let kind = if sigma < 0.0 {
        Factorization::Llt
    } else {
        Factorization::Lblt
    };
    let factor = DirectSolver::analyze(shifted.as_ref(), kind)?.factorize(shifted.as_ref())?;
    let project = |v: &mut [f64]| -> Result<(), SolveError> {
        match projection {
            Some(p) => p(v),
            None => Ok(()),
        }
    };

    let block = options.block.clamp(1, available);
    let mut rng = SplitMix(options.seed);
    let mut basis = Basis::default();
    let mut solves = 0;
    // The start block: random vectors inside the projection's range.
    let mut pending = Vec::new();
    for _ in 0..block {
        let mut v: Vec<f64> = (0..n).map(|_| rng.next()).collect();
        project(&mut v)?;
        pending.push(v);
    }
    loop {
        let mut added = Vec::new();
        for v in pending.drain(..) {
            if let Some(q) = basis.push(v, k, m) {
                added.push(q);
            } else {
                // The new direction already lies in the basis (an invariant
                // subspace was reached): replace it by a fresh random one.
                let mut fresh: Vec<f64> = (0..n).map(|_| rng.next()).collect();
                project(&mut fresh)?;
                if let Some(q) = basis.push(fresh, k, m) {
                    added.push(q);
                }
            }
        }
        let ritz = basis.rayleigh_ritz(count, sigma, scale)?;
        let converged = ritz
            .residuals
            .iter()
            .filter(|&&r| r <= options.tolerance)
            .count();
        if converged == count {
            let zeros = ritz.values.iter().filter(|&&l| scale.is_zero(l)).count();
            return Ok(Eigenpairs {
                values: ritz.values,
                vectors: ritz.vectors,
                residuals: ritz.residuals,
                zeros,
                basis: basis.len(),
                solves,
                factorization: kind,
            });
        }
        // No new direction: the basis spans an invariant subspace that
        // holds every vector reachable from the start block, and the Ritz
        // pairs cannot improve.
        let exhausted = added.is_empty() || basis.len() >= available;
        if exhausted || basis.len() + block > options.max_basis {
            return Err(EigenError::NotConverged {
                converged,
                requested: count,
                basis: basis.len(),
                worst: ritz.residuals.iter().fold(0.0f64, |a, &b| a.max(b)),
            });
        }
        // Next block: T applied to the newest vectors, projected.
        for &q in &added {
            let mut w = factor.solve(&basis.mq[q])?;
            solves += 1;
            project(&mut w)?;
            pending.push(w);
        }
    }
}

/// A + s·B for matrices of one size (patterns merged).
fn combine(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    s: f64,
) -> SparseColMat<usize, f64> {
    let mut entries = Vec::with_capacity(a.compute_nnz() + b.compute_nnz());
    for (mat, scale) in [(a, 1.0), (b, s)] {
        for j in 0..mat.ncols() {
            let range = mat.col_range(j);
            for (&i, &v) in mat.row_idx()[range.clone()].iter().zip(&mat.val()[range]) {
                entries.push(Triplet::new(i, j, scale * v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(a.nrows(), a.ncols(), &entries)
        .expect("indices come from matrices of this size")
}

/// y = A x.
pub(crate) fn multiply(a: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    for (j, &xj) in x.iter().enumerate().take(a.ncols()) {
        let range = a.col_range(j);
        for (&i, &v) in a.row_idx()[range.clone()].iter().zip(&a.val()[range]) {
            y[i] += v * xj;
        }
    }
    y
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// An M-orthonormal basis Q with M Q, K Q and the projected matrix Qᵀ K Q.
#[derive(Default)]
struct Basis {
    q: Vec<Vec<f64>>,
    mq: Vec<Vec<f64>>,
    kq: Vec<Vec<f64>>,
    /// Qᵀ K Q, row-major, grown one row/column per vector.
    h: Vec<Vec<f64>>,
}

/// Below this fraction of ‖K‖₁/‖M‖₁ an eigenvalue is zero: kernel
/// vectors give about 1e-16 of it, the smallest physical eigenvalue of a
/// second-order operator (h/L)² of it, 1e-10 at h = L/10⁵.
const ZERO_EIGENVALUE: f64 = 1e-10;

/// ‖K‖₁ and ‖M‖₁ (largest column sums of |entries|).
#[derive(Clone, Copy)]
struct Scale {
    k: f64,
    m: f64,
}

impl Scale {
    fn is_zero(&self, lambda: f64) -> bool {
        self.m > 0.0 && lambda.abs() <= ZERO_EIGENVALUE * self.k / self.m
    }
}

fn column_norm(a: SparseColMatRef<'_, usize, f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.val()[a.col_range(j)].iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

struct Ritz {
    values: Vec<f64>,
    vectors: Vec<Vec<f64>>,
    residuals: Vec<f64>,
}

impl Basis {
    fn len(&self) -> usize {
        self.q.len()
    }

    /// M-orthogonalise v against the basis (classical Gram–Schmidt, twice)
    /// and append it; `None` when nothing independent is left of it.
    fn push(
        &mut self,
        mut v: Vec<f64>,
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
    ) -> Option<usize> {
        let start = dot(&v, &multiply(m, &v)).max(0.0).sqrt();
        if start == 0.0 || !start.is_finite() {
            return None;
        }
        for _ in 0..2 {
            let coefficients: Vec<f64> = self.mq.iter().map(|mq| dot(mq, &v)).collect();
            for (c, q) in coefficients.iter().zip(&self.q) {
                v.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
            }
        }
        let mut mv = multiply(m, &v);
        let size = dot(&v, &mv).max(0.0).sqrt();
        // Below this the vector is rounding noise of directions already in Q.
        if size <= 1e-10 * start {
            return None;
        }
        v.iter_mut().for_each(|x| *x /= size);
        mv.iter_mut().for_each(|x| *x /= size);
        let kv = multiply(k, &v);
        let column: Vec<f64> = self.q.iter().map(|q| dot(q, &kv)).collect();
        for (row, &c) in self.h.iter_mut().zip(&column) {
            row.push(c);
        }
        let mut row = column;
        row.push(dot(&v, &kv));
        self.h.push(row);
        self.q.push(v);
        self.mq.push(mv);
        self.kq.push(kv);
        Some(self.q.len() - 1)
    }

    /// The `count` Ritz pairs with values closest to σ, ascending.
    fn rayleigh_ritz(&self, count: usize, sigma: f64, spectrum: Scale) -> Result<Ritz, EigenError> {
        let size = self.len();
        // Symmetrise: rounding makes qᵢᵀKqⱼ and qⱼᵀKqᵢ differ slightly.
        let h = Mat::from_fn(size, size, |i, j| 0.5 * (self.h[i][j] + self.h[j][i]));
        let eigen = h
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| EigenError::Dense(format!("{e:?}")))?;
        let (s, u) = (eigen.S(), eigen.U());
        let mut order: Vec<usize> = (0..size).collect();
        order.sort_by(|&a, &b| {
            (s[a] - sigma)
                .abs()
                .total_cmp(&(s[b] - sigma).abs())
                .then(a.cmp(&b))
        });
        order.truncate(count);
        order.sort_by(|&a, &b| s[a].total_cmp(&s[b]));
        let n = self.q.first().map_or(0, Vec::len);
        let mut ritz = Ritz {
            values: Vec::new(),
            vectors: Vec::new(),
            residuals: Vec::new(),
        };
        for &c in &order {
            let lambda = s[c];
            let (mut x, mut kx, mut mx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            for i in 0..size {
                let y = u[(i, c)];
                for (t, s) in [
                    (&mut x, &self.q[i]),
                    (&mut kx, &self.kq[i]),
                    (&mut mx, &self.mq[i]),
                ] {
                    t.iter_mut().zip(s).for_each(|(a, b)| *a += y * b);
                }
            }
            let r: Vec<f64> = kx.iter().zip(&mx).map(|(a, b)| a - lambda * b).collect();
            let scale = if spectrum.is_zero(lambda) {
                spectrum.k * norm(&x)
            } else {
                norm(&kx) + lambda.abs() * norm(&mx)
            };
            ritz.residuals.push(if scale > 0.0 {
                norm(&r) / scale
            } else {
                norm(&r)
            });
            ritz.values.push(lambda);
            ritz.vectors.push(x);
        }
        Ok(ritz)
    }
}

/// SplitMix64: a tiny deterministic generator for start vectors, so runs
/// are reproducible without a dependency.
struct SplitMix(u64);

impl SplitMix {
    /// Uniform in [−1, 1).
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use faer::sparse::Triplet;

    #[test]
    fn a_kernel_vector_is_returned_as_a_zero_eigenvalue() {
        // The 1D Neumann Laplacian on n points (K = path-graph Laplacian /
        // h, zero row sums) with M = h I: λ_j = (2 − 2 cos(jπ/n)) / h²,
        // j = 0 … n − 1, the constant vector being the kernel (λ₀ = 0).
        let (n, h) = (20usize, 0.05);
        let mut k = Vec::new();
        for i in 0..n - 1 {
            k.push(Triplet::new(i, i, 1.0 / h));
            k.push(Triplet::new(i + 1, i + 1, 1.0 / h));
            k.push(Triplet::new(i, i + 1, -1.0 / h));
            k.push(Triplet::new(i + 1, i, -1.0 / h));
        }
        let k = SparseColMat::try_new_from_triplets(n, n, &k).unwrap();
        let m: Vec<_> = (0..n).map(|i| Triplet::new(i, i, h)).collect();
        let m = SparseColMat::try_new_from_triplets(n, n, &m).unwrap();
        let options = Options {
            block: 2,
            ..Default::default()
        };
        let pairs = smallest(k.as_ref(), m.as_ref(), 3, None, n, &options).unwrap();
        assert_eq!(pairs.zeros, 1);
        assert!(pairs.values[0].abs() < 1e-9, "{:?}", pairs.values);
        for j in 1..3 {
            let exact = (2.0 - 2.0 * (j as f64 * std::f64::consts::PI / n as f64).cos()) / (h * h);
            assert_relative_eq!(pairs.values[j], exact, max_relative = 1e-9);
        }
        // The kernel vector is the constant, M-normalised: 1/√(n h).
        let c = 1.0 / (n as f64 * h).sqrt();
        for x in &pairs.vectors[0] {
            assert_relative_eq!(x.abs(), c, max_relative = 1e-8);
        }
    }
}
