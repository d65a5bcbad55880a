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
//!
//! ```
//! use hasse_solver::la::iterative::{CgOptions, RowMatrix};
//! use hasse_solver::multigrid::{Hierarchy, Multigrid, MultigridOptions};
//! // The 1D Dirichlet Laplacian on 64 cells (cell-centred, ghost at both ends).
//! let n = 64;
//! let rows = (0..n)
//!     .map(|i| {
//!         let mut row = vec![(i, if i == 0 || i == n - 1 { 3.0 } else { 2.0 })];
//!         if i > 0 { row.push((i - 1, -1.0)); }
//!         if i + 1 < n { row.push((i + 1, -1.0)); }
//!         row.sort_by_key(|e| e.0);
//!         row
//!     })
//!     .collect();
//! let m = RowMatrix::from_rows(n, rows).unwrap();
//! let options = MultigridOptions { coarse_size: 4, ..Default::default() };
//! let p = Hierarchy::Grid { cells: vec![n] }.prolongations(n).unwrap();
//! let mg = Multigrid::new(m, p, &options).unwrap();
//! assert!(mg.levels().len() > 3);
//! let cg = CgOptions { tolerance: 1e-10, max_iterations: 50 };
//! let (_, report) = mg.solve(&vec![1.0; n], None, &cg).unwrap();
//! assert!(report.iterations < 15);
//! ```

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
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Smoother {
    /// `sweeps` steps of x ← x + ω D⁻¹(b − M x) before and after the
    /// coarse correction.
    Jacobi { omega: f64, sweeps: usize },
    /// The Chebyshev polynomial of `degree` in D⁻¹M that is smallest on
    /// [λ/ratio, λ], λ an upper bound of the spectrum of D⁻¹M (estimated by
    /// power iteration, widened by 10 %, capped by Gershgorin's bound); the
    /// modes below λ/ratio are left to the coarse levels.
    Chebyshev { degree: usize, ratio: f64 },
}

/// How cell-centred (piecewise-constant) prolongations are used; see the
/// module documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellProlongation {
    /// P = (I − ω D⁻¹ M) P₀, ω = 4/(3λ): mesh-independent V-cycle counts.
    Smoothed,
    /// P₀ as is, the coarse correction multiplied by `correction` (about
    /// 2 undoes the stiffness of the Galerkin operator; 1 is plain).
    Constant { correction: f64 },
}

/// Settings of a multigrid hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct MultigridOptions {
    pub smoother: Smoother,
    /// Levels with at most this many unknowns are factorised directly.
    pub coarse_size: usize,
    /// At most this many levels, the coarsest included.
    pub max_levels: usize,
    /// Strength of connection of the algebraic levels: j is a strong
    /// neighbour of i when a_ij² ≥ θ² |a_ii a_jj|.
    pub strength: f64,
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
    #[error("multigrid level {level}: the prolongation has {found} rows but the level has {expected} unknowns")]
    Size {
        level: usize,
        expected: usize,
        found: usize,
    },
    #[error("the multigrid hierarchy does not fit the system with {unknowns} unknowns: {detail}")]
    Mismatch { unknowns: usize, detail: String },
    #[error("multigrid level {level}: diagonal entry {index} is {value}, not positive: the matrix is not symmetric positive definite")]
    NotPositive {
        level: usize,
        index: usize,
        value: f64,
    },
    #[error("multigrid coarsest level ({size} unknowns): {detail}")]
    Coarse { size: usize, detail: String },
    #[error("multigrid option {option}: {detail}")]
    Option {
        option: &'static str,
        detail: String,
    },
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
