//! Multigrid V-cycles as preconditioners of conjugate gradients, for
//! symmetric positive definite systems M x = b too large to factorise.
//!
//! A hierarchy is a sequence of prolongations P_l (fine × coarse), finest
//! first. Coarse operators are Galerkin products M_{l+1} = P_lᵀ M_l P_l of
//! the assembled fine matrix, formed as sparse products of row-stored
//! matrices ([`RowMatrix`](crate::la::iterative::RowMatrix)), not as
//! [`Canonical`](crate::operator::Canonical) operators. For M = Aᵀ Ω A the
//! product equals (A P)ᵀ Ω (A P), so the coarse levels inherit symmetry
//! and positive definiteness from Ω without being rediscretised; but A P
//! has the real weights of P, not the integer entries the canonical form
//! keeps in A, so it is not formed that way.
//!
//! Where the prolongations come from ([`Hierarchy`]):
//!
//! - [`Hierarchy::Grid`]: a grid from the rectangle/box generators with an
//!   even number of cells per axis, coarsened by two per axis as long as
//!   the counts stay even. Nodal unknowns interpolate bilinearly /
//!   trilinearly; cell-centred unknowns take their parent's value (the
//!   transpose of the chain map ζ_n of the refinement from coarse to fine).
//! - [`Hierarchy::Refinements`]: the SPLIT refinements that produced the
//!   mesh: ζ_n (sign dropped: a piece of a cell takes the cell's value) for
//!   cell unknowns, the nodal interpolation for vertex unknowns.
//! - [`Hierarchy::Algebraic`]: smoothed aggregation from the matrix alone
//!   (strength of connection, greedy aggregation, tentative P from the
//!   aggregates, one damped-Jacobi smoothing of P). It also continues any
//!   geometric hierarchy that stops while the coarsest level is still
//!   larger than [`MultigridOptions::coarse_size`].
//!
//! Cell-centred unknowns with the piecewise-constant P need care: the
//! Galerkin operator of a piecewise-constant P is twice as stiff as the
//! rediscretised one (a coarse face collects 2^(d−1) fine faces of
//! transmissibility |F|/h while the rediscretised face has 2^(d−1)|F|/(2h)),
//! so the coarse correction is half as long as it should be and V-cycle
//! counts grow with the number of levels. [`CellProlongation::Smoothed`]
//! (the default) smooths P once by damped Jacobi, as smoothed aggregation
//! does with its aggregates, which restores mesh-independent counts at the
//! price of denser coarse operators (27-point in 3D instead of 7-point);
//! [`CellProlongation::Constant`] keeps the sparse coarse operators and
//! scales the coarse correction instead. The measured counts of both are
//! in `scripts/multigrid-scaling` and the README.
//!
//! Smoothing is Chebyshev (default) or damped Jacobi, both polynomials in
//! D⁻¹M, so the V-cycle with the same smoother before and after the coarse
//! correction is symmetric, as conjugate gradients needs. Every operation
//! runs in parallel over rows with rayon, and every inner product sums in
//! fixed chunks: the result has the same bits for any number of threads.
//! The coarsest level is factorised (faer sparse LLᵀ, sequential).

#![warn(missing_docs)]

use crate::la::iterative::CgError;

mod aggregation;
mod cycle;
#[cfg(test)]
mod tests;
mod transfer;

pub use cycle::{LevelInfo, Multigrid};
pub use transfer::{
    grid_prolongations, refinement_prolongations, restrict_to_free, Hierarchy, Prolongation,
    Transfer,
};

/// The smoother of every level but the coarsest.
///
/// ```
/// use hasse_solver::la::iterative::RowMatrix;
/// use hasse_solver::multigrid::{Multigrid, MultigridError, MultigridOptions, Smoother};
/// let m = RowMatrix::from_rows(2, vec![vec![(0, 2.0), (1, -1.0)], vec![(0, -1.0), (1, 2.0)]]).unwrap();
/// // The damping ω of Jacobi must lie in (0, 2).
/// let options = MultigridOptions {
///     smoother: Smoother::Jacobi { omega: 2.5, sweeps: 1 },
///     ..Default::default()
/// };
/// let error = Multigrid::algebraic(m, &options).err().unwrap();
/// assert!(matches!(error, MultigridError::Option { option: "smoother", .. }));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smoother {
    /// `sweeps` steps of x ← x + ω D⁻¹(b − M x) before and after the
    /// coarse correction.
    Jacobi {
        /// The damping ω, in (0, 2).
        omega: f64,
        /// Steps before and after the coarse correction, at least one.
        sweeps: usize,
    },
    /// The Chebyshev polynomial of `degree` in D⁻¹M that is smallest on
    /// [λ/ratio, λ], λ an upper bound of the spectrum of D⁻¹M (the largest
    /// Ritz value of a few Lanczos steps, widened by 10 %, capped by
    /// Gershgorin's bound); the modes below λ/ratio are left to the coarse
    /// levels.
    Chebyshev {
        /// Degree of the polynomial (products with M per smoothing), at
        /// least 1.
        degree: usize,
        /// λ_max / λ_min of the interval smoothed, above 1.
        ratio: f64,
    },
}

/// How cell-centred (piecewise-constant) prolongations are used; see the
/// module documentation.
///
/// ```
/// use hasse_solver::la::iterative::RowMatrix;
/// use hasse_solver::multigrid::{CellProlongation, Multigrid, MultigridError, MultigridOptions};
/// let m = RowMatrix::from_rows(1, vec![vec![(0, 1.0)]]).unwrap();
/// // The factor of the coarse correction must lie in (0, 2.5).
/// let options = MultigridOptions {
///     cell_prolongation: CellProlongation::Constant { correction: 3.0 },
///     ..Default::default()
/// };
/// assert!(matches!(
///     Multigrid::algebraic(m, &options),
///     Err(MultigridError::Option { option: "cell_prolongation", .. })
/// ));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellProlongation {
    /// P = (I − ω D⁻¹ M) P₀, ω = 4/(3λ): mesh-independent V-cycle counts.
    Smoothed,
    /// P₀ as is, the coarse correction multiplied by `correction` (about
    /// 2 undoes the stiffness of the Galerkin operator; 1 is plain).
    Constant {
        /// The factor of the coarse correction, in (0, 2.5).
        correction: f64,
    },
}

/// Settings of a multigrid hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct MultigridOptions {
    /// The smoother of every level but the coarsest.
    pub smoother: Smoother,
    /// Levels with at most this many unknowns are factorised directly.
    pub coarse_size: usize,
    /// At most this many levels, the coarsest included.
    pub max_levels: usize,
    /// Strength of connection θ of the finest algebraic level: j is a
    /// strong neighbour of i when a_ij² ≥ θ² |a_ii a_jj|. On the Galerkin
    /// levels below it, whose rows spread over many more neighbours, j is
    /// strong when its scaled coupling |a_ij|/√|a_ii a_jj| is at least a
    /// quarter of the row's strongest (the classical, row-relative test
    /// with hypre's default threshold 0.25).
    pub strength: f64,
    /// How cell-centred prolongations of a geometric hierarchy are used.
    pub cell_prolongation: CellProlongation,
}

impl Default for MultigridOptions {
    fn default() -> Self {
        Self {
            smoother: Smoother::Chebyshev {
                degree: 2,
                ratio: 4.0,
            },
            coarse_size: 4000,
            max_levels: 20,
            strength: 0.08,
            cell_prolongation: CellProlongation::Smoothed,
        }
    }
}

/// Why a multigrid setup or solve failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MultigridError {
    /// A prolongation does not fit the level it prolongs to (a hierarchy
    /// built for another mesh, or refinements listed out of order).
    #[error("multigrid level {level}: the prolongation has {found} rows but the level has {expected} unknowns")]
    Size {
        /// The level, 0 the finest.
        level: usize,
        /// Unknowns of the level.
        expected: usize,
        /// Rows of the prolongation.
        found: usize,
    },
    /// The hierarchy's mesh does not say what the system's unknowns are:
    /// it has neither as many vertices nor as many top cells as the system
    /// has unknowns (or, after refinements, as many of both).
    #[error("the multigrid hierarchy does not fit the system with {unknowns} unknowns: {detail}")]
    Mismatch {
        /// Unknowns of the system.
        unknowns: usize,
        /// What the hierarchy has instead.
        detail: String,
    },
    /// A level's operator has a diagonal entry ≤ 0 or NaN, which no
    /// symmetric positive definite matrix has.
    #[error("multigrid level {level}: diagonal entry {index} is {value}, not positive: the matrix is not symmetric positive definite")]
    NotPositive {
        /// The level, 0 the finest.
        level: usize,
        /// Row of the entry.
        index: usize,
        /// The entry.
        value: f64,
    },
    /// The coarsest level could not be factorised (LLᵀ), e.g. because the
    /// system is singular.
    #[error("multigrid coarsest level ({size} unknowns): {detail}")]
    Coarse {
        /// Unknowns of the coarsest level.
        size: usize,
        /// What failed.
        detail: String,
    },
    /// An option is out of its range: a field of [`MultigridOptions`], or
    /// the cell counts of a [`Hierarchy::Grid`].
    #[error("multigrid option {option}: {detail}")]
    Option {
        /// The field, or "grid cells" for the cell counts of a grid
        /// hierarchy.
        option: &'static str,
        /// The range and the value given.
        detail: String,
    },
    /// The conjugate gradients that the V-cycle preconditions failed.
    #[error(transparent)]
    Cg(#[from] CgError),
}

fn check_options(options: &MultigridOptions) -> Result<(), MultigridError> {
    let bad = |option, detail: String| Err(MultigridError::Option { option, detail });
    match options.smoother {
        Smoother::Jacobi { omega, sweeps } if !(omega > 0.0 && omega < 2.0) || sweeps == 0 => {
            return bad(
                "smoother",
                format!("Jacobi needs 0 < ω < 2 and at least one sweep, got ω = {omega}, {sweeps} sweeps"),
            )
        }
        Smoother::Chebyshev { degree, ratio } if degree == 0 || !ratio.is_finite() || ratio <= 1.0 => {
            return bad(
                "smoother",
                format!("Chebyshev needs degree ≥ 1 and a finite ratio > 1, got degree {degree}, ratio {ratio}"),
            )
        }
        _ => {}
    }
    if let CellProlongation::Constant { correction } = options.cell_prolongation {
        if !(correction > 0.0 && correction < 2.5) {
            return bad(
                "cell_prolongation",
                format!("the coarse-correction factor must lie in (0, 2.5), got {correction}"),
            );
        }
    }
    if !(options.strength >= 0.0 && options.strength < 1.0) {
        return bad(
            "strength",
            format!("θ must lie in [0, 1), got {}", options.strength),
        );
    }
    if options.max_levels == 0 {
        return bad("max_levels", "at least one level is needed".into());
    }
    Ok(())
}

/// How to solve a symmetric positive definite system.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::multigrid::{Hierarchy, SolverChoice};
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// let mesh = rectangle(16, 16, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let problem = |choice| {
///     Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
///         .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///         .with_solver(choice, 1e-10, &mesh)
///         .solve(&mesh)
///         .unwrap()
/// };
/// // A 2D problem: the automatic rule factorises, so there are no CG iterations.
/// let direct = problem(SolverChoice::Auto(None));
/// assert!(direct.iterations.is_none());
/// let grid = Hierarchy::Grid { cells: vec![16, 16] };
/// let multigrid = problem(SolverChoice::Multigrid(grid));
/// assert!(multigrid.iterations.unwrap().relative_residual <= 1e-10);
/// for (a, b) in direct.values.iter().zip(&multigrid.values) {
///     assert!((a - b).abs() < 1e-8);
/// }
/// ```
#[derive(Clone, Debug)]
pub enum SolverChoice {
    /// Sparse LLᵀ.
    Direct,
    /// Conjugate gradients with a multigrid V-cycle from this hierarchy.
    Multigrid(Hierarchy),
    /// [`automatic`] decides, with this hierarchy when multigrid is chosen
    /// (`None`: algebraic).
    Auto(Option<Hierarchy>),
}

/// Unknowns above which a 3D system goes to multigrid-CG; see [`automatic`].
pub const DIRECT_LIMIT_3D: usize = 20_000;

/// The automatic rule: a direct factorisation for 1D and 2D problems and for
/// 3D problems with at most [`DIRECT_LIMIT_3D`] unknowns; multigrid-CG for
/// larger 3D problems, geometric when a hierarchy is given, else algebraic.
/// In 2D the factor's fill grows like n log n: at 10⁶ cell-centred
/// unknowns LLᵀ takes 2.4 s (factorisation and solve) against 1.2 s for
/// multigrid-CG with the smoothed cell prolongation and 0.7 s with the
/// constant one (`cargo bench --bench multigrid -- 2d-1000`, quiet
/// machine). Direct stays the rule there: it needs no hierarchy, its cost
/// does not depend on the coefficients, and it is within 2–3.5× of a solve
/// that a case asks for with `solver.type = "multigrid"`. In 3D factorisation work grows like n²: at 60³ it
/// takes 22 s against 0.6 s for multigrid-CG, and extrapolating by n² the
/// two meet near 2·10⁴ unknowns, where both take a few hundredths of a
/// second.
///
/// ```
/// use hasse_solver::multigrid::{automatic, Hierarchy, SolverChoice};
/// assert!(matches!(automatic(2, 4_000_000, None), SolverChoice::Direct));
/// assert!(matches!(automatic(3, 8_000, None), SolverChoice::Direct));
/// assert!(matches!(automatic(3, 1_000_000, None), SolverChoice::Multigrid(Hierarchy::Algebraic)));
/// ```
pub fn automatic(dim: usize, unknowns: usize, hierarchy: Option<Hierarchy>) -> SolverChoice {
    if dim < 3 || unknowns <= DIRECT_LIMIT_3D {
        SolverChoice::Direct
    } else {
        SolverChoice::Multigrid(hierarchy.unwrap_or(Hierarchy::Algebraic))
    }
}
