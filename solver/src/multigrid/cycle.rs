//! The V-cycle: levels of Galerkin operators, Chebyshev or Jacobi
//! smoothing, the factorised coarsest level, and the cycle as a
//! preconditioner of conjugate gradients.

use super::aggregation::{aggregate, smooth_prolongation, Strength};
use super::transfer::{Prolongation, Transfer};
use super::{check_options, CellProlongation, MultigridError, MultigridOptions, Smoother};
use crate::la::iterative::{
    dot, preconditioned_cg, preconditioned_cg_in, CgOptions, CgReport, CgWork, Preconditioner,
    RowMatrix, DOT_CHUNK,
};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
};
use faer::{Conj, Mat, Par, Side};
use rayon::prelude::*;
use std::sync::Mutex;
use std::time::Instant;

/// Rows per parallel task (as in [`crate::la::iterative`]).
pub(super) const ROW_CHUNK: usize = 4096;

/// Sizes of one level, for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelInfo {
    /// Unknowns of the level (rows of its operator).
    pub unknowns: usize,
    /// Stored entries of the level's operator.
    pub nonzeros: usize,
    /// Whether the prolongation to this level came from aggregation.
    pub algebraic: bool,
}

struct Level {
    matrix: RowMatrix,
    inverse_diagonal: Vec<f64>,
    /// Upper bound of the spectrum of D⁻¹M.
    lambda: f64,
    p: RowMatrix,
    r: RowMatrix,
    correction: f64,
    algebraic: bool,
}

struct Coarse {
    matrix: RowMatrix,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    algebraic: bool,
}

/// The vectors of one level, allocated once at setup. The finest level
/// takes b and x from the caller (the residual and the preconditioned
/// residual of CG) and uses only the scratch.
#[derive(Default)]
struct Work {
    b: Vec<f64>,
    x: Vec<f64>,
    scratch: Scratch,
}

/// The smoother's residual and two Chebyshev directions (the new one is
/// written while the old one is read by the neighbouring rows).
#[derive(Default)]
struct Scratch {
    r: Vec<f64>,
    d: Vec<f64>,
    e: Vec<f64>,
}

/// A multigrid hierarchy, ready to be applied as a preconditioner: one
/// V-cycle per [`Preconditioner::apply`].
///
/// ```
/// use hasse_solver::la::iterative::{Preconditioner, RowMatrix};
/// use hasse_solver::multigrid::{Multigrid, MultigridOptions};
/// // The 1D Dirichlet Laplacian tridiag(−1, 2, −1) on 200 unknowns.
/// let n = 200;
/// let rows = (0..n)
///     .map(|i| {
///         let mut row = vec![(i, 2.0)];
///         if i > 0 { row.insert(0, (i - 1, -1.0)); }
///         if i + 1 < n { row.push((i + 1, -1.0)); }
///         row
///     })
///     .collect();
/// let m = RowMatrix::from_rows(n, rows).unwrap();
/// let options = MultigridOptions { coarse_size: 10, ..Default::default() };
/// let mg = Multigrid::algebraic(m, &options).unwrap();
/// let levels = mg.levels();
/// assert!(levels.len() >= 3 && levels[0].unknowns == n && levels[1].algebraic);
/// // The same smoother before and after the coarse correction makes the
/// // cycle a symmetric operator B, as conjugate gradients need: eᵢᵀ B eⱼ = eⱼᵀ B eᵢ.
/// let column = |j: usize| {
///     let mut e = vec![0.0; n];
///     e[j] = 1.0;
///     let mut z = vec![0.0; n];
///     mg.apply(&e, &mut z);
///     z
/// };
/// let (b3, b70) = (column(3), column(70));
/// assert!((b3[70] - b70[3]).abs() < 1e-12 * b3[3].abs());
/// ```
pub struct Multigrid {
    levels: Vec<Level>,
    coarse: Coarse,
    smoother: Smoother,
    work: Mutex<Vec<Work>>,
    /// Seconds spent building the hierarchy.
    pub(crate) setup_seconds: f64,
}

fn inverse_diagonal(matrix: &RowMatrix, level: usize) -> Result<Vec<f64>, MultigridError> {
    matrix
        .diagonal()
        .into_iter()
        .enumerate()
        .map(|(index, value)| {
            if value.is_nan() || value <= 0.0 {
                Err(MultigridError::NotPositive {
                    level,
                    index,
                    value,
                })
            } else {
                Ok(1.0 / value)
            }
        })
        .collect()
}

/// An upper bound of the spectrum of D⁻¹M: 1.1 × the largest Ritz value of
/// 20 Lanczos steps (run as Jacobi-preconditioned CG, whose coefficients
/// give the Lanczos matrix), capped by Gershgorin's bound
/// max_i Σ_j |a_ij| / a_ii. Lanczos finds the top of the spectrum in a few
/// steps where power iteration creeps towards it from below, and a bound
/// that is too low makes the Chebyshev smoother amplify the top modes.
///
/// The largest Ritz value only grows with the steps (the Lanczos matrices
/// are nested), so once 1.1 × it passes the Gershgorin bound the answer is
/// that bound and the remaining steps are skipped: on M-matrices such as
/// the finest two-point-flux operator (D⁻¹M ≤ 2) this happens within a few
/// steps. Each step is one pass for the product and pᵀq and one for the
/// residual, the scaled residual and rᵀz, summed as [`dot`] sums.
pub(super) fn spectral_bound(matrix: &RowMatrix, inverse_diagonal: &[f64]) -> f64 {
    let n = matrix.nrows();
    let gershgorin = (0..n)
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| {
            let (_, v) = matrix.row(i);
            v.iter().map(|a| a.abs()).sum::<f64>() * inverse_diagonal[i]
        })
        .reduce(|| 0.0, f64::max);
    // A fixed, non-smooth right-hand side (no random state): it has
    // components along the high modes.
    let mut r: Vec<f64> = (0..n)
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| ((i.wrapping_mul(2_654_435_761)) % 1000) as f64 / 1000.0 - 0.5)
        .collect();
    let mut z: Vec<f64> = r
        .par_iter()
        .with_min_len(ROW_CHUNK)
        .zip(inverse_diagonal)
        .map(|(r, d)| r * d)
        .collect();
    let mut p = z.clone();
    let mut q = vec![0.0; n];
    let mut rz = dot(&r, &z);
    let (mut alphas, mut betas) = (Vec::new(), Vec::new());
    // 1.1 × ritz ≥ this means the result is the Gershgorin bound whatever
    // the later steps find (the margin covers the rounding of the small
    // eigenproblems).
    let capped = gershgorin * (1.0 + 1e-12);
    for _ in 0..20.min(n) {
        if rz.is_nan() || rz <= 0.0 {
            break;
        }
        let pq = matrix.multiply_dot(&p, &mut q);
        if pq.is_nan() || pq <= 0.0 {
            break;
        }
        let alpha = rz / pq;
        let partial: Vec<f64> = r
            .par_chunks_mut(DOT_CHUNK)
            .zip(z.par_chunks_mut(DOT_CHUNK))
            .zip(q.par_chunks(DOT_CHUNK))
            .zip(inverse_diagonal.par_chunks(DOT_CHUNK))
            .map(|(((r, z), q), d)| {
                r.iter_mut().zip(q).for_each(|(r, q)| *r -= alpha * q);
                z.iter_mut()
                    .zip(r.iter())
                    .zip(d)
                    .for_each(|((z, r), d)| *z = r * d);
                r.iter().zip(z.iter()).map(|(r, z)| r * z).sum::<f64>()
            })
            .collect();
        let rz_next: f64 = partial.iter().sum();
        let beta = rz_next / rz;
        alphas.push(alpha);
        betas.push(beta);
        rz = rz_next;
        if 1.1 * largest_ritz(&alphas, &betas) >= capped {
            return gershgorin.max(f64::MIN_POSITIVE);
        }
        p.par_iter_mut()
            .with_min_len(ROW_CHUNK)
            .zip(&z)
            .for_each(|(p, z)| *p = z + beta * *p);
    }
    if alphas.is_empty() {
        return gershgorin.max(f64::MIN_POSITIVE);
    }
    (1.1 * largest_ritz(&alphas, &betas))
        .min(gershgorin)
        .max(f64::MIN_POSITIVE)
}

/// The largest eigenvalue of the Lanczos matrix of CG coefficients
/// `alphas`, `betas` (one of each per step; the last β is not used).
fn largest_ritz(alphas: &[f64], betas: &[f64]) -> f64 {
    let k = alphas.len();
    let mut t = nalgebra::DMatrix::<f64>::zeros(k, k);
    for j in 0..k {
        t[(j, j)] = 1.0 / alphas[j]
            + if j > 0 {
                betas[j - 1] / alphas[j - 1]
            } else {
                0.0
            };
        if j + 1 < k {
            let off = betas[j].sqrt() / alphas[j];
            t[(j, j + 1)] = off;
            t[(j + 1, j)] = off;
        }
    }
    t.symmetric_eigenvalues()
        .iter()
        .fold(0.0f64, |m, &v| m.max(v))
}

/// Row-relative threshold of the Galerkin levels ([`Strength::Relative`]):
/// hypre BoomerAMG's default strong threshold, the same test on the
/// scaled couplings.
pub(super) const COARSE_STRENGTH: f64 = 0.25;

/// The strength measure of `level` (0 the finest): the absolute threshold
/// θ = `strength` on the finest level, and on the Galerkin levels below it
/// each row measured against its own strongest coupling,
/// [`COARSE_STRENGTH`].
///
/// A fixed θ stops the coarsening after one level in 3D. The scaled
/// coupling |a_ij|/√(a_ii a_jj) is 1/6 for every neighbour of the 7-point
/// stencil, but a Galerkin operator of smoothed aggregation spreads each
/// row over ~30 neighbours (60³ box: 30.3 entries per row on level 1),
/// and there the strongest scaled coupling of a row is 0.055–0.082
/// (10th–90th percentile) against θ = 0.08: most unknowns had no strong
/// neighbour, became singletons, coarsening stalled, and the whole
/// level 1 (1/8 of the unknowns, 30 entries per row) went to the sparse
/// LLᵀ meant for ≤ `coarse_size` unknowns: 82 s and 4.4 GiB of setup at
/// 100³.
///
/// Halving θ per level (Vaněk, Mandel and Brezina's θ·2^(−l), the rule
/// before this one) fixed the stall but not the counts: the couplings of
/// a Galerkin row do not shrink by a fixed factor per level, so on the
/// 100³ box θ = 0.02 turned level 2 (10 677 unknowns, 105 entries per row)
/// into 261 aggregates of 40 and CG took 13 iterations against 8 at 20³;
/// every coupling strong below the finest level (θ = 0) held the 3D FV
/// counts at 10–11 but made 2D Delaunay P1 (16/20/23) and Kuhn P1
/// 48³/80³ (15/17) worse. Measuring each row against its own strongest
/// coupling follows whatever spread the Galerkin product gives: FV box
/// 20³/40³/64³/100³ in 8/9/9/11 iterations (θ halving: 8/9/9/13), Kuhn P1
/// 24³/48³/80³ in 9/10/11 (9/10/11), jittered Delaunay P1 with 1.6·10⁴ /
/// 2.5·10⁵ / 10⁶ triangles in 11/12/13 (11/12/13)
/// (`cargo bench --bench multigrid -- CASE sa|amg`, benches/README.md).
/// The finest level keeps the absolute θ: its stencils are the
/// discretisation's own, and there the row-relative test would call the
/// weak couplings of a jittered Delaunay row strong.
pub(super) fn level_strength(strength: f64, level: usize) -> Strength {
    if level == 0 {
        Strength::Absolute(strength)
    } else {
        Strength::Relative(COARSE_STRENGTH)
    }
}

impl Multigrid {
    /// Build the hierarchy of `matrix` (symmetric positive definite) from
    /// `prolongations` (finest first, already restricted to the unknowns
    /// of `matrix`, see [`restrict_to_free`](super::restrict_to_free)),
    /// continued by smoothed aggregation while the coarsest level is larger
    /// than `options.coarse_size`.
    pub fn new(
        matrix: RowMatrix,
        prolongations: Vec<Prolongation>,
        options: &MultigridOptions,
    ) -> Result<Self, MultigridError> {
        let started = Instant::now();
        check_options(options)?;
        let mut levels: Vec<Level> = Vec::new();
        let mut a = matrix;
        let mut geometric = prolongations.into_iter();
        // The near-null vector of the current level (the constant on the
        // finest): what the coarse spaces must contain. A geometric
        // prolongation maps the coarse constant to the fine one (nodal
        // interpolation and piecewise constants exactly, the smoothed cell
        // prolongation away from Dirichlet boundaries), so after one the
        // candidate is the constant again; after an aggregation it is the
        // vector of aggregate norms.
        let mut candidate = vec![1.0; a.nrows()];
        loop {
            if a.nrows() <= options.coarse_size || levels.len() + 1 >= options.max_levels {
                break;
            }
            let level = levels.len();
            let inverse_diagonal = inverse_diagonal(&a, level)?;
            let lambda = spectral_bound(&a, &inverse_diagonal);
            let mut coarse_candidate = None;
            let (p, correction, algebraic) = match geometric.next() {
                Some(prolongation) => {
                    if prolongation.matrix.nrows() != a.nrows() {
                        return Err(MultigridError::Size {
                            level,
                            expected: a.nrows(),
                            found: prolongation.matrix.nrows(),
                        });
                    }
                    match (prolongation.transfer, options.cell_prolongation) {
                        (Transfer::Cells, CellProlongation::Constant { correction }) => {
                            (prolongation.matrix, correction, false)
                        }
                        (Transfer::Cells, CellProlongation::Smoothed) => (
                            smooth_prolongation(
                                &a,
                                &inverse_diagonal,
                                lambda,
                                &prolongation.matrix,
                            )?,
                            1.0,
                            false,
                        ),
                        (Transfer::Nodal, _) => (prolongation.matrix, 1.0, false),
                    }
                }
                None => {
                    let Some((tentative, restricted)) =
                        aggregate(&a, level_strength(options.strength, level), &candidate)?
                    else {
                        break;
                    };
                    coarse_candidate = Some(restricted);
                    // Coarsening that stalls would only add levels (when
                    // most unknowns have no strong neighbour they are
                    // singletons and it stalls), and when most unknowns
                    // are decoupled there is nothing to coarsen: factorise
                    // this level instead.
                    if tentative.ncols() * 10 > a.nrows() * 9 || tentative.nnz() * 2 < a.nrows() {
                        break;
                    }
                    (
                        smooth_prolongation(&a, &inverse_diagonal, lambda, &tentative)?,
                        1.0,
                        true,
                    )
                }
            };
            if p.ncols() == 0 {
                break;
            }
            let r = p.transpose();
            let coarse = r.product(&a.product(&p));
            candidate = coarse_candidate.unwrap_or_else(|| vec![1.0; coarse.nrows()]);
            levels.push(Level {
                matrix: a,
                inverse_diagonal,
                lambda,
                p,
                r,
                correction,
                algebraic,
            });
            a = coarse;
        }
        let algebraic = levels.last().is_some_and(|l| l.algebraic);
        let coarse = Coarse::new(a, algebraic)?;
        let work = levels
            .iter()
            .map(|l| l.matrix.nrows())
            .chain([coarse.matrix.nrows()])
            .enumerate()
            .map(|(l, n)| {
                // The finest level's b and x are the caller's; the coarsest
                // level needs no smoother scratch.
                let (vectors, scratch) = match (l == 0 && !levels.is_empty(), l < levels.len()) {
                    (true, _) => (0, n),
                    (false, true) => (n, n),
                    (false, false) => (n, 0),
                };
                Work {
                    b: vec![0.0; vectors],
                    x: vec![0.0; vectors],
                    scratch: Scratch {
                        r: vec![0.0; scratch],
                        d: vec![0.0; scratch],
                        e: vec![0.0; scratch],
                    },
                }
            })
            .collect();
        Ok(Self {
            levels,
            coarse,
            smoother: options.smoother,
            work: Mutex::new(work),
            setup_seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Smoothed aggregation alone.
    pub fn algebraic(
        matrix: RowMatrix,
        options: &MultigridOptions,
    ) -> Result<Self, MultigridError> {
        Self::new(matrix, Vec::new(), options)
    }

    /// The operator of the finest level.
    pub(crate) fn matrix(&self) -> &RowMatrix {
        self.levels
            .first()
            .map_or(&self.coarse.matrix, |l| &l.matrix)
    }

    /// Unknowns and nonzeros per level, finest first.
    pub fn levels(&self) -> Vec<LevelInfo> {
        self.levels
            .iter()
            .enumerate()
            .map(|(k, l)| LevelInfo {
                unknowns: l.matrix.nrows(),
                nonzeros: l.matrix.nnz(),
                algebraic: k > 0 && self.levels[k - 1].algebraic,
            })
            .chain([LevelInfo {
                unknowns: self.coarse.matrix.nrows(),
                nonzeros: self.coarse.matrix.nnz(),
                algebraic: self.coarse.algebraic,
            }])
            .collect()
    }

    /// Σ nonzeros over all levels / nonzeros of the finest.
    pub fn operator_complexity(&self) -> f64 {
        let levels = self.levels();
        let total: usize = levels.iter().map(|l| l.nonzeros).sum();
        total as f64 / levels[0].nonzeros.max(1) as f64
    }

    /// Solve the finest system by conjugate gradients preconditioned with
    /// one V-cycle per iteration.
    pub fn solve(
        &self,
        rhs: &[f64],
        initial: Option<&[f64]>,
        options: &CgOptions,
    ) -> Result<(Vec<f64>, CgReport), MultigridError> {
        Ok(preconditioned_cg(
            self.matrix(),
            rhs,
            initial,
            options,
            self,
        )?)
    }

    /// [`solve`](Self::solve) in place with kept vectors (see
    /// [`preconditioned_cg_in`]): `x` holds the initial guess on entry and
    /// the solution on return.
    pub fn solve_in(
        &self,
        rhs: &[f64],
        x: &mut [f64],
        options: &CgOptions,
        work: &mut CgWork,
    ) -> Result<CgReport, MultigridError> {
        Ok(preconditioned_cg_in(
            self.matrix(),
            rhs,
            x,
            options,
            self,
            work,
        )?)
    }

    /// Smoothing steps on M x = b from x (from zero when `zero_start`,
    /// whatever x holds), leaving b − M x in `w.r` when `want_residual`.
    ///
    /// Chebyshev runs one pass over the rows per step: the step's product
    /// M d, the new residual, the new direction and the update of x, all
    /// row by row (x is not read by other rows then, only d). The numbers
    /// are those of the textbook order of vector operations.
    fn smooth(
        &self,
        level: &Level,
        b: &[f64],
        x: &mut [f64],
        w: &mut Scratch,
        zero_start: bool,
        want_residual: bool,
    ) {
        let a = &level.matrix;
        let dinv = &level.inverse_diagonal[..];
        match self.smoother {
            Smoother::Jacobi { omega, sweeps } => {
                for sweep in 0..sweeps {
                    if sweep == 0 && zero_start {
                        x.par_iter_mut()
                            .with_min_len(ROW_CHUNK)
                            .zip(b)
                            .zip(dinv)
                            .for_each(|((x, b), d)| *x = omega * d * b);
                        continue;
                    }
                    a.residual(b, x, &mut w.r);
                    x.par_iter_mut()
                        .with_min_len(ROW_CHUNK)
                        .zip(&w.r)
                        .zip(dinv)
                        .for_each(|((x, r), d)| *x += omega * d * r);
                }
                if want_residual {
                    a.residual(b, x, &mut w.r);
                }
            }
            Smoother::Chebyshev { degree, ratio } => {
                // Chebyshev iteration on D⁻¹M (Saad, Iterative Methods,
                // Algorithm 12.1) for the interval [λ/ratio, λ], keeping
                // the residual r = b − M x up to date:
                //   r₀ = b − M x, d₀ = D⁻¹r₀/θ, x += d₀;
                //   r_{k+1} = r_k − M d_k, d_{k+1} = s₁ d_k + s₂ D⁻¹ r_{k+1},
                //   x += d_{k+1}.
                let (hi, lo) = (level.lambda, level.lambda / ratio);
                let theta = 0.5 * (hi + lo);
                let delta = 0.5 * (hi - lo);
                let sigma = theta / delta;
                let mut rho = 1.0 / sigma;
                let Scratch { r, d, e } = w;
                // Whether x still lacks d₀ (when the first pass had to read
                // x at the neighbouring rows).
                let mut pending = !zero_start;
                if zero_start {
                    // r₀ = b (read from b below), x = 0 + d₀.
                    x.par_iter_mut()
                        .with_min_len(ROW_CHUNK)
                        .zip(d.par_iter_mut())
                        .zip(b)
                        .zip(dinv)
                        .for_each(|(((x, d), b), di)| {
                            *d = di * b / theta;
                            *x = 0.0 + *d;
                        });
                } else {
                    let xr: &[f64] = x;
                    r.par_iter_mut()
                        .with_min_len(ROW_CHUNK)
                        .zip(d.par_iter_mut())
                        .enumerate()
                        .for_each(|(i, (ri, di))| {
                            *ri = b[i] - a.row_dot(i, xr);
                            *di = dinv[i] * *ri / theta;
                        });
                }
                // The residual so far: b until the first product.
                let mut from_b = zero_start;
                for _ in 1..degree {
                    let rho_next = 1.0 / (2.0 * sigma - rho);
                    let (s1, s2) = (rho_next * rho, 2.0 * rho_next / delta);
                    let dk: &[f64] = d;
                    let source: Option<&[f64]> = from_b.then_some(b);
                    x.par_iter_mut()
                        .with_min_len(ROW_CHUNK)
                        .zip(r.par_iter_mut())
                        .zip(e.par_iter_mut())
                        .enumerate()
                        .for_each(|(i, ((x, r), e))| {
                            let old = source.map_or(*r, |b| b[i]);
                            *r = old - a.row_dot(i, dk);
                            *e = s1 * dk[i] + s2 * dinv[i] * *r;
                            if pending {
                                *x += dk[i];
                            }
                            *x += *e;
                        });
                    std::mem::swap(d, e);
                    rho = rho_next;
                    from_b = false;
                    pending = false;
                }
                if want_residual {
                    let dk: &[f64] = d;
                    let source: Option<&[f64]> = from_b.then_some(b);
                    x.par_iter_mut()
                        .with_min_len(ROW_CHUNK)
                        .zip(r.par_iter_mut())
                        .enumerate()
                        .for_each(|(i, (x, r))| {
                            let old = source.map_or(*r, |b| b[i]);
                            *r = old - a.row_dot(i, dk);
                            if pending {
                                *x += dk[i];
                            }
                        });
                } else if pending {
                    x.par_iter_mut()
                        .with_min_len(ROW_CHUNK)
                        .zip(&d[..])
                        .for_each(|(x, d)| *x += d);
                }
            }
        }
    }

    fn cycle(&self, r: &[f64], z: &mut [f64]) {
        let mut guard = self.work.lock().unwrap_or_else(|e| e.into_inner());
        let work = &mut *guard;
        let depth = self.levels.len();
        if depth == 0 {
            let w = &mut work[0];
            w.b.copy_from_slice(r);
            self.coarse.solve(w);
            z.copy_from_slice(&w.x);
            return;
        }
        for (l, level) in self.levels.iter().enumerate() {
            let (here, below) = work.split_at_mut(l + 1);
            let Work { b, x, scratch } = &mut here[l];
            let (b, x): (&[f64], &mut [f64]) = if l == 0 { (r, &mut *z) } else { (b, x) };
            self.smooth(level, b, x, scratch, true, true);
            level.r.multiply(&scratch.r, &mut below[0].b);
        }
        self.coarse.solve(&mut work[depth]);
        for (l, level) in self.levels.iter().enumerate().rev() {
            let (here, below) = work.split_at_mut(l + 1);
            let Work { b, x, scratch } = &mut here[l];
            let (b, x): (&[f64], &mut [f64]) = if l == 0 { (r, &mut *z) } else { (b, x) };
            let xc = &below[0].x;
            let (p, c) = (&level.p, level.correction);
            x.par_iter_mut()
                .with_min_len(ROW_CHUNK)
                .enumerate()
                .for_each(|(i, x)| *x += c * p.row_dot(i, xc));
            self.smooth(level, b, x, scratch, false, false);
        }
    }
}

impl Coarse {
    fn new(matrix: RowMatrix, algebraic: bool) -> Result<Self, MultigridError> {
        let size = matrix.nrows();
        let fail = |detail: String| MultigridError::Coarse { size, detail };
        let faer_matrix = matrix.to_faer();
        let symbolic = factorize_symbolic_cholesky(
            faer_matrix.symbolic(),
            Side::Lower,
            Default::default(),
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| fail(format!("symbolic analysis: {e:?}")))?;
        let mut values = vec![0.0; symbolic.len_val()];
        // Sequential: the coarsest level is small, and a fixed order keeps
        // the bits independent of the thread count.
        let par = Par::Seq;
        let mut buffer = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| fail("out of memory".into()))?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                faer_matrix.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|_| fail("LLᵀ failed: the coarse operator is not positive definite".into()))?;
        Ok(Self {
            matrix,
            symbolic,
            values,
            algebraic,
        })
    }

    fn solve(&self, w: &mut Work) {
        let n = w.b.len();
        let mut x = Mat::from_fn(n, 1, |i, _| w.b[i]);
        let par = Par::Seq;
        // The scratch of a solve is a few vectors of the coarse size; when
        // even that cannot be allocated the correction is skipped (zero),
        // which keeps the preconditioner symmetric.
        let Ok(mut buffer) =
            MemBuffer::try_new(self.symbolic.solve_in_place_scratch::<f64>(1, par))
        else {
            w.x.iter_mut().for_each(|x| *x = 0.0);
            return;
        };
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            par,
            MemStack::new(&mut buffer),
        );
        for (i, xi) in w.x.iter_mut().enumerate() {
            *xi = x[(i, 0)];
        }
    }
}

impl Preconditioner for Multigrid {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.cycle(r, z);
    }

    fn name(&self) -> &'static str {
        "multigrid V-cycle"
    }
}
