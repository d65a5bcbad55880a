//! Scalar diffusion −∇·(K ∇u) = f in canonical form, with boundary
//! conditions on tagged boundary regions.
//!
//! Every method is the same assembly M = Aᵀ Ω A with a different Ω and,
//! for the hybrid mimetic method, a different A. Boundary conditions are
//! written in the same language:
//!
//! - Dirichlet on a cell-centred method keeps the boundary face as a row of
//!   A (a "ghost" at the face) and moves the known value to the right-hand
//!   side, b += Aᵀ Ω w with w the signed boundary values; on nodal and
//!   hybrid unknowns the fixed values are eliminated symmetrically (the
//!   system on the free unknowns stays symmetric positive definite).
//! - Neumann, K∇u·n = g with n the outward normal, adds ∫_F g to the
//!   equation of the unknown(s) at the face and removes the face's ghost.
//! - Robin, K∇u·n + α u = g, adds a row to A with one entry at the boundary
//!   unknown (a ghost with value g/α), weighted by α|F| in Ω (lumped on
//!   vertices for nodal methods); for cell-centred methods the ghost sits
//!   behind the cell-to-face transmissibility σ, giving σα|F|/(σ + α|F|).
//!
//! Unlisted boundary faces are homogeneous Neumann (no flux). A problem
//! without any Dirichlet or Robin boundary is singular: it is detected,
//! the data are checked for compatibility (Σ sources + Σ boundary fluxes
//! = 0 up to quadrature error), and the solution with zero mean is returned.

mod assemble;
mod balance;
mod interface;
mod norms;
mod post;
mod solve;

use crate::la::direct::{self, DirectSolver, Factorization, SolveError, SolveReport};
use crate::la::iterative::{conjugate_gradient, CgError, CgOptions, CgReport, RowMatrix};
use crate::la::ordering::Ordering;
use crate::la::ordering::UnknownPoints;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::{self, dec, fd, fe, fv, CellTensors, MetricError, Tensor};
use crate::metric::{Location, Method};
use crate::multigrid::{
    self, CellProlongation, Hierarchy, Multigrid, MultigridError, MultigridOptions, SolverChoice,
};
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use crate::physics::regions::{RegionError, Regional};
use crate::physics::{
    non_finite_text, point_text, tagged_boundary_faces, BoundaryCondition, BoundaryKind,
    Conductivity, Datum, ScalarFn, TagError, VectorFn,
};
pub use assemble::Assembled;
pub use balance::CellCoefficients;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use hasse_complex::Complex;
pub use interface::FacesFlux;
pub use post::{conservation_residual, errors, flux_error, gradient_of, reconstruct_gradient};
use rayon::prelude::*;
pub use solve::solve_with_fixed;
use sprs::TriMat;
use std::sync::Arc;
use std::time::Instant;

/// Where the cell values of the two-point finite-volume method ([`Method::Fv`])
/// are located. The two-point flux is consistent only when the line between
/// two neighbouring cell points is orthogonal to their common face; on
/// meshes that are orthogonal for other points than the centroids, put the
/// unknowns there.
///
/// ```
/// use hasse_complex::generate::voronoi_with_sites;
/// use hasse_solver::physics::diffusion::{CellPoints, Diffusion};
/// use hasse_solver::physics::Conductivity;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::BoundaryKind;
/// use std::sync::Arc;
/// let (mesh, sites) = voronoi_with_sites(100, [0.0, 1.0], [0.0, 1.0], 1, 0).unwrap();
/// let u = |x: &[f64]| 1.0 + 2.0 * x[0] - x[1];
/// let mut problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 0.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(u)));
/// problem.cell_points = CellPoints::Given(sites.iter().flatten().copied().collect());
/// let solution = problem.solve(&mesh).unwrap();
/// // Linear solutions are reproduced exactly at the sites.
/// for (c, s) in sites.iter().enumerate() {
///     assert!((solution.values[c] - u(s)).abs() < 1e-11);
/// }
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CellPoints {
    /// Cell centroids: consistent on K-orthogonal grids (boxes).
    #[default]
    Centroids,
    /// Circumcentres of simplices: consistent on Delaunay triangulations
    /// and well-centred simplicial meshes.
    Circumcentres,
    /// One point per top cell (stride d), e.g. the sites of a Voronoi mesh.
    Given(Arc<[f64]>),
}

/// The problem −∇·(K ∇u) = f with boundary conditions.
///
/// The fields configure it; [`Diffusion::new`] sets the solver ones to
/// their defaults and the `with_*` methods chain the common choices.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::f64::consts::PI;
/// use std::sync::Arc;
/// // −Δu = 2π² sin(πx) sin(πy), u = 0 on the boundary.
/// let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let problem = |method| {
///     Diffusion::new(method, Conductivity::Scalar(Arc::new(|_| 1.0)),
///         Arc::new(|x: &[f64]| 2.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin()))
///         .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
/// };
/// let fv = problem(Method::Fv).solve(&mesh).unwrap();
/// let fd = problem(Method::Fd).solve(&mesh).unwrap();
/// // On a uniform grid, two-point finite volumes are the five-point
/// // finite differences: the same Aᵀ Ω A.
/// assert!(fv.values.iter().zip(&fd.values).all(|(a, b)| (a - b).abs() < 1e-12));
/// // 64 cell values, close to u = sin(πx) sin(πy) at the centroids.
/// assert_eq!(fv.unknowns(), 64);
/// let centre = 4 * 8 + 4; // the cell at (0.5625, 0.5625)
/// let exact = (PI * 0.5625).sin().powi(2);
/// assert!((fv.values[centre] - exact).abs() < 2e-2);
/// ```
#[derive(Clone)]
pub struct Diffusion {
    /// The discretisation: which Ω (and A) and where the unknowns live.
    pub method: Method,
    /// K, evaluated at the top cells' centroids.
    pub conductivity: Conductivity,
    /// f, the source per unit volume (positive f adds heat).
    pub source: ScalarFn,
    /// f per region of top cells, when the source differs from region to
    /// region; it replaces [`Diffusion::source`] (see
    /// [`Diffusion::with_source_by_region`]).
    pub source_by_region: Option<Arc<Regional<ScalarFn>>>,
    /// Applied in order; a later condition on the same face replaces an earlier one.
    pub boundary: Vec<BoundaryCondition>,
    /// Direct factorisation (default: LLᵀ, the systems are SPD).
    pub factorization: Factorization,
    /// Fill-reducing ordering of the direct factorisation (default:
    /// automatic).
    pub ordering: Ordering,
    /// Where the cell values of [`Method::Fv`] live (default: centroids).
    pub cell_points: CellPoints,
    /// Largest relative imbalance Σ b / Σ |b| accepted for pure-Neumann data
    /// (quadrature makes consistent data slightly incompatible).
    pub neumann_tolerance: f64,
    /// Solve by preconditioned conjugate gradients instead of a
    /// factorisation (SPD systems), optionally from an initial guess.
    pub iterative: Option<Iterative>,
}

/// Settings of an iterative solve.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::la::iterative::CgOptions;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::{Diffusion, Iterative};
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let mut problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
/// let direct = problem.solve(&mesh).unwrap();
/// let options = CgOptions { tolerance: 1e-10, ..CgOptions::default() };
/// problem.iterative = Some(Iterative { options, ..Iterative::default() });
/// let cold = problem.solve(&mesh).unwrap();
/// assert!(cold.iterations.unwrap().iterations > 0);
/// assert!(cold.values.iter().zip(&direct.values).all(|(a, b)| (a - b).abs() < 1e-8));
/// // Started from the solution itself, there is nothing left to do.
/// problem.iterative = Some(Iterative { options, initial: Some(direct.values), ..Iterative::default() });
/// assert_eq!(problem.solve(&mesh).unwrap().iterations.unwrap().iterations, 0);
/// ```
#[derive(Clone, Debug, Default)]
pub struct Iterative {
    /// Tolerance and iteration limit of conjugate gradients.
    pub options: CgOptions,
    /// A guess for every unknown (fixed ones are ignored), e.g. a coarse
    /// solution transferred to a refined mesh.
    pub initial: Option<Vec<f64>>,
    /// The preconditioner of conjugate gradients (default: Jacobi).
    pub preconditioner: Preconditioning,
}

impl Iterative {
    /// The iterative solve `choice` asks for on `complex`, for unknowns at
    /// `location`: multigrid-preconditioned CG to `tolerance`, or `None`
    /// for a direct solve ([`SolverChoice::Auto`] decides by
    /// [`multigrid::automatic`] on the number of unknowns). Diffusion and
    /// heat choose alike.
    pub fn chosen(
        choice: SolverChoice,
        tolerance: f64,
        location: Location,
        complex: &Complex,
    ) -> Option<Self> {
        let choice = match choice {
            SolverChoice::Auto(hierarchy) => {
                let n = complex.dim();
                let unknowns = match location {
                    Location::Nodal => complex.cell_count(0),
                    Location::CellCentred => complex.cell_count(n),
                    Location::Hybrid => complex.cell_count(n) + complex.cell_count(n - 1),
                };
                multigrid::automatic(n, unknowns, hierarchy)
            }
            other => other,
        };
        match choice {
            SolverChoice::Multigrid(hierarchy) => Some(Iterative {
                options: CgOptions {
                    tolerance,
                    ..CgOptions::default()
                },
                initial: None,
                preconditioner: Preconditioning::Multigrid {
                    hierarchy,
                    options: MultigridOptions::default(),
                },
            }),
            _ => None,
        }
    }
}

/// The preconditioner of an iterative solve.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::la::iterative::CgOptions;
/// use hasse_solver::metric::Method;
/// use hasse_solver::multigrid::{Hierarchy, MultigridOptions};
/// use hasse_solver::physics::diffusion::{Diffusion, Iterative, Preconditioning};
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// let mesh = rectangle(32, 32, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let iterations = |preconditioner| {
///     let mut problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
///         .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
///     let options = CgOptions { tolerance: 1e-8, ..CgOptions::default() };
///     problem.iterative = Some(Iterative { options, initial: None, preconditioner });
///     problem.solve(&mesh).unwrap().iterations.unwrap().iterations
/// };
/// let jacobi = iterations(Preconditioning::Jacobi);
/// let multigrid = iterations(Preconditioning::Multigrid {
///     hierarchy: Hierarchy::Grid { cells: vec![32, 32] },
///     options: MultigridOptions::default(),
/// });
/// // Jacobi needs O(1/h) iterations, a V-cycle a few whatever h.
/// assert!(multigrid < 15 && 4 * multigrid < jacobi);
/// ```
#[derive(Clone, Debug, Default)]
pub enum Preconditioning {
    /// diag(M)⁻¹: cheap, iteration counts grow like 1/h.
    #[default]
    Jacobi,
    /// One multigrid V-cycle per iteration ([`crate::multigrid`]): counts
    /// independent of h. The hierarchy is for all unknowns of the mesh;
    /// Dirichlet unknowns are removed from it at solve time.
    Multigrid {
        /// How the coarse levels are made (grid levels, SPLIT refinements,
        /// or algebraic aggregation).
        hierarchy: Hierarchy,
        /// Cycle and smoother settings.
        options: MultigridOptions,
    },
}

/// Why a problem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiffusionError {
    /// A boundary condition names a tag the mesh does not have, or one
    /// that does not tag boundary faces.
    #[error(transparent)]
    Tag(#[from] TagError),
    /// A Robin α is zero or negative at a face: the condition would not
    /// bound the solution (α ≤ 0 can make the system singular or
    /// indefinite).
    #[error("the Robin coefficient α = {alpha} of boundary condition {condition} (tag '{tag}') at {} (face {face}) must be positive", point_text(.point))]
    RobinAlpha {
        /// Index of the condition among the problem's conditions.
        condition: usize,
        /// Its tag.
        tag: String,
        /// The (n−1)-cell where α was evaluated.
        face: usize,
        /// Where α was evaluated: a vertex of the face for nodal methods,
        /// a point of the face (its centroid on boxes) otherwise.
        point: Vec<f64>,
        /// The value α had there.
        alpha: f64,
    },
    /// A given function is NaN or ±∞ at a point (or, without a point, its
    /// load overflowed).
    #[error("{datum} is not finite ({}){}", non_finite_text(*.value), .point.as_deref().map(|x| format!(" at {}", point_text(x))).unwrap_or_else(|| " in the sum of its load".into()))]
    NonFinite {
        /// Which input gave the value.
        datum: Datum,
        /// Where it was evaluated; `None` for an overflowing load.
        point: Option<Vec<f64>>,
        /// The value (NaN or ±∞).
        value: f64,
    },
    /// A problem without Dirichlet or Robin boundary has a solution only
    /// when the sources and boundary fluxes balance, and they do not
    /// (beyond [`Diffusion::neumann_tolerance`]).
    #[error("pure Neumann problem with incompatible data: sources plus boundary fluxes sum to {imbalance:e} (relative {relative:e}, tolerance {tolerance:e}); they must balance (∫f + ∮g = 0)")]
    IncompatibleNeumann {
        /// Σ b over the unknowns: ∫f + ∮g as assembled.
        imbalance: f64,
        /// The imbalance relative to Σ |b|.
        relative: f64,
        /// The tolerance it exceeds ([`Diffusion::neumann_tolerance`]).
        tolerance: f64,
    },
    /// A problem without Dirichlet or Robin boundary on a domain in
    /// several pieces: one zero-mean constraint cannot fix a constant on
    /// each.
    #[error("pure Neumann problem on a disconnected domain ({components} parts): give every part a Dirichlet or Robin boundary")]
    Disconnected {
        /// Number of connected pieces of the domain.
        components: usize,
    },
    /// Some connected part of the domain has no Dirichlet or Robin
    /// boundary while another has: the system is singular on that part.
    #[error("the domain has {parts} disconnected parts and the part holding {what} {unknown} (at {point:?}) has no Dirichlet or Robin boundary: its solution is fixed only up to a constant and the system is singular; put a Dirichlet or Robin condition on a boundary tag of every part, or mesh the parts separately")]
    FloatingPart {
        /// Number of connected parts of the complex (its Betti number b₀).
        parts: usize,
        /// The kind of the unknown named: `"vertex"`, `"top cell"` or
        /// `"face"`.
        what: &'static str,
        /// One unknown of the floating part, numbered among the cells of
        /// its kind.
        unknown: usize,
        /// Where that unknown lives.
        point: Vec<f64>,
    },
    /// The conductivity at a cell is not finite or not symmetric positive
    /// definite.
    #[error("the conductivity at {} (top cell {cell}) is {}", point_text(.point), coefficient_problem(.source))]
    Coefficient {
        /// The top cell.
        cell: usize,
        /// Its centroid, where K was evaluated.
        point: Vec<f64>,
        /// What the check of the coefficients found.
        source: MetricError,
    },
    /// The method built a non-symmetric Ω but the chosen factorisation
    /// needs a symmetric system.
    #[error("the {method} metric is not symmetric, but {factorization} needs a symmetric positive definite system; use Factorization::Lu for a non-symmetric Ω")]
    NotSymmetric {
        /// The method's name.
        method: &'static str,
        /// The factorisation asked for.
        factorization: Factorization,
    },
    /// Data given per region do not fit the mesh's tags.
    #[error(transparent)]
    Region(#[from] RegionError),
    /// The method cannot do what the problem asks: cell points with a
    /// method other than `fv`, new data of other boundary kinds in
    /// [`Diffusion::data`], a Dirichlet or Robin face on a non-diagonal
    /// boundary metric.
    #[error("the {method} method cannot impose {what}")]
    Unsupported {
        /// The method's name.
        method: &'static str,
        /// What it cannot impose, in words.
        what: &'static str,
    },
    /// The method refused the mesh or the coefficients while building Ω.
    #[error(transparent)]
    Metric(#[from] MetricError),
    /// A and Ω do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The direct factorisation or solve failed (e.g. a singular matrix).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Conjugate gradients did not reach the tolerance or broke down.
    #[error(transparent)]
    Iterative(#[from] CgError),
    /// The multigrid hierarchy could not be built for this mesh.
    #[error(transparent)]
    Multigrid(#[from] MultigridError),
}

/// What is wrong with a coefficient, in words that fit after "is".
fn coefficient_problem(error: &MetricError) -> String {
    match error {
        MetricError::NonFinite { .. } => "not finite".into(),
        MetricError::NotPositive { value, .. } => format!(
            "not symmetric positive definite (eigenvalue estimate {value:e}); diffusion coefficients must be > 0"
        ),
        other => other.to_string(),
    }
}

/// The discrete solution and how it was obtained.
#[derive(Clone, Debug)]
pub struct Solution {
    /// The method that made it.
    pub method: Method,
    /// Where `values` live.
    pub location: Location,
    /// All unknowns (fixed ones included), in the layout of `location`.
    pub values: Vec<f64>,
    /// The flux cochain Ω A u on the rows of A (edges for nodal methods,
    /// (n−1)-cells for cell-centred ones, half-faces for the hybrid one).
    pub flux: Vec<f64>,
    /// The linear solve: sizes, seconds and relative residual.
    pub report: SolveReport,
    /// Seconds to build Ω, A and M = Aᵀ Ω A with the right-hand side.
    pub assembly_seconds: f64,
    /// Whether the direct solve's symbolic analysis ran beside the assembly
    /// (from the solved matrix's pattern known from topology: two-point
    /// FV/FD, nodal FE), so that its seconds overlap `assembly_seconds`
    /// instead of adding to them.
    pub analyzed_during_assembly: bool,
    /// Whether the problem was pure Neumann (solution normalised to zero mean).
    pub pure_neumann: bool,
    /// Relative imbalance of pure-Neumann data removed before solving.
    pub neumann_imbalance: f64,
    /// The points whose exact values the cell values approximate (stride d),
    /// when they are not the centroids (see [`CellPoints`]).
    pub cell_points: Option<Vec<f64>>,
    /// Iterations and residuals when solved iteratively.
    pub iterations: Option<CgReport>,
    /// A lower bound on the condition number of the solved (reduced)
    /// system: for a symmetric positive definite M, λ_max ≥ max M_ii and
    /// λ_min ≤ min M_ii, so κ(M) ≥ max M_ii / min M_ii. Free to compute,
    /// and large when coefficients or cell sizes span many orders.
    pub condition_bound: f64,
}

/// max M_ii / min M_ii over the unknowns not held fixed (see
/// [`Solution::condition_bound`]); infinite when a diagonal entry is zero.
pub(crate) fn diagonal_condition_bound(
    matrix: &SparseColMat<usize, f64>,
    fixed: &[Option<f64>],
) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for c in 0..matrix.ncols() {
        if fixed.get(c).is_some_and(Option::is_some) {
            continue;
        }
        let range = matrix.col_range(c);
        let diagonal = matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
            .find(|(&r, _)| r == c)
            .map_or(0.0, |(_, &v)| v.abs());
        lo = lo.min(diagonal);
        hi = hi.max(diagonal);
    }
    if hi == 0.0 {
        1.0
    } else {
        hi / lo
    }
}

impl Solution {
    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.values.len()
    }

    /// The primary field on its cells (top cells for hybrid).
    pub fn field(&self, complex: &Complex) -> &[f64] {
        match self.location {
            Location::Hybrid => &self.values[..complex.cell_count(complex.dim())],
            _ => &self.values,
        }
    }
}

/// Error figures against an exact solution.
///
/// Two kinds: norms of u_h − u by quadrature on every top cell, of the
/// field the method represents (`l2`, `gradient_l2`: the L² norm and the
/// H¹ seminorm; see [`errors`]), and figures from samples at the unknowns'
/// points (`max`, `l2_sampled`, `gradient_sampled`). Samples can
/// superconverge where the norms do not: on grids, Q1 and two-point FV
/// gradients at the centroids are second order while the H¹ seminorm is
/// first order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// ‖u_h − u‖ in L², by quadrature of the method's field on each cell.
    pub l2: f64,
    /// Largest error at the unknowns' points (vertices or cell points).
    pub max: f64,
    /// |u_h − u| in the H¹ seminorm, ‖∇u_h − ∇u‖ in L², by quadrature
    /// (for cell values, ∇u_h is the reconstructed cell gradient); NaN
    /// when no exact gradient was given.
    pub gradient_l2: f64,
    /// Discrete L² error at the unknowns' points (lumped-mass weights on
    /// vertices, cell volumes on cells): sqrt(Σ w_i (u_i − u(x_i))²) with
    /// x_i the vertices, or the cell points (centroids unless
    /// [`Solution::cell_points`] says otherwise).
    pub l2_sampled: f64,
    /// Discrete L² error of the cell-wise gradient
    /// ([`reconstruct_gradient`]) sampled at the centroids, weighted by
    /// cell volumes; NaN when no exact gradient was given.
    pub gradient_sampled: f64,
    /// Whether `l2` and `gradient_l2` are the quadrature norms. Problems
    /// that measure only at samples (heat levels, Darcy pressures,
    /// elasticity displacements) set it false and repeat the sampled
    /// figures there.
    pub quadrature: bool,
}

impl Errors {
    /// Figures measured only at samples: `l2` and `max` at the unknowns'
    /// points, no gradient.
    pub fn sampled(l2: f64, max: f64) -> Self {
        Errors {
            l2,
            max,
            gradient_l2: f64::NAN,
            l2_sampled: l2,
            gradient_sampled: f64::NAN,
            quadrature: false,
        }
    }
}

impl Diffusion {
    /// A problem with default solver settings.
    pub fn new(method: Method, conductivity: Conductivity, source: ScalarFn) -> Self {
        Self {
            method,
            conductivity,
            source,
            source_by_region: None,
            boundary: Vec::new(),
            factorization: Factorization::Llt,
            ordering: Ordering::Automatic,
            cell_points: CellPoints::Centroids,
            neumann_tolerance: 1e-2,
            iterative: None,
        }
    }

    /// A source per region of top cells instead of one function: each
    /// method integrates f_R over the part of each control volume inside
    /// region R (FE: quadrature per element; FV and FD: the cell's own
    /// f_R at its centroid; DEC, whose vertex dual cells straddle
    /// regions: f_R(x_v) times the share of the dual volume ⋆1(v)
    /// belonging to R, taken in proportion to the measures of the top
    /// cells of R around v).
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::physics::diffusion::Diffusion;
    /// use hasse_solver::physics::regions::Regional;
    /// use hasse_solver::physics::{BoundaryKind, Conductivity, ScalarFn};
    /// use std::sync::Arc;
    /// // −u″ = f on [0, 2] with f = 2 on the left half and 0 on the right,
    /// // u(0) = u(2) = 0: u = 3x/2 − x² on [0, 1] and (2 − x)/2 on [1, 2]
    /// // (u and u′ continuous at 1). P1 in one dimension is exact at the
    /// // nodes, and x = 1 is node 2.
    /// let mut mesh = interval(4, 0.0, 2.0).unwrap();
    /// mesh.set_tag("hot", 1, vec![0, 1]).unwrap();
    /// let two: ScalarFn = Arc::new(|_| 2.0);
    /// let zero: ScalarFn = Arc::new(|_| 0.0);
    /// let f = Regional::new(vec![("hot".into(), two)], Some(zero));
    /// let u = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 0.0))
    ///     .with_source_by_region(f)
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    ///     .solve(&mesh)
    ///     .unwrap();
    /// assert!((u.values[2] - 0.5).abs() < 1e-12);
    /// ```
    pub fn with_source_by_region(mut self, source: Regional<ScalarFn>) -> Self {
        self.source_by_region = Some(Arc::new(source));
        self
    }

    /// The source each top cell of `complex` sees: one function for all,
    /// or its region's.
    pub(crate) fn cell_sources(&self, complex: &Complex) -> Result<Vec<&ScalarFn>, RegionError> {
        match &self.source_by_region {
            Some(regional) => regional.per_cell(complex),
            None => Ok(vec![&self.source; complex.cell_count(complex.dim())]),
        }
    }

    /// Add a boundary condition on a tag.
    pub fn with_boundary(mut self, tag: &str, kind: BoundaryKind) -> Self {
        self.boundary.push(BoundaryCondition {
            tag: tag.to_string(),
            kind,
        });
        self
    }

    /// Choose the linear solver: [`SolverChoice::Direct`] factorises,
    /// [`SolverChoice::Multigrid`] runs multigrid-preconditioned CG to
    /// `tolerance`, [`SolverChoice::Auto`] applies [`multigrid::automatic`]
    /// to this method's unknowns on `complex`. A case file's
    /// `[solver] type = "direct" | "multigrid" | "amg" | "auto"` maps onto
    /// Direct, Multigrid(Grid or Refinements), Multigrid(Algebraic), Auto.
    ///
    /// ```
    /// use hasse_complex::generate::box3;
    /// use hasse_solver::physics::diffusion::Diffusion;
    /// use hasse_solver::physics::BoundaryKind;
    /// use hasse_solver::physics::Conductivity;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::multigrid::{Hierarchy, SolverChoice};
    /// use std::sync::Arc;
    /// let mesh = box3(16, 16, 16, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let grid = Hierarchy::Grid { cells: vec![16, 16, 16] };
    /// let problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    ///     .with_solver(SolverChoice::Multigrid(grid), 1e-8, &mesh);
    /// let solution = problem.solve(&mesh).unwrap();
    /// let report = solution.iterations.unwrap();
    /// assert!(report.relative_residual <= 1e-8 && report.iterations < 15);
    /// ```
    pub fn with_solver(mut self, choice: SolverChoice, tolerance: f64, complex: &Complex) -> Self {
        self.iterative = Iterative::chosen(choice, tolerance, self.location(), complex);
        self
    }

    /// How the multigrid chosen by [`Diffusion::with_solver`] prolongs
    /// cell-centred unknowns on grid levels (no effect on a direct solve or
    /// on nodal unknowns).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::diffusion::Diffusion;
    /// use hasse_solver::physics::BoundaryKind;
    /// use hasse_solver::physics::Conductivity;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::multigrid::{CellProlongation, Hierarchy, SolverChoice};
    /// use std::sync::Arc;
    /// let mesh = rectangle(32, 32, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    ///     .with_solver(SolverChoice::Multigrid(Hierarchy::Grid { cells: vec![32, 32] }), 1e-8, &mesh)
    ///     .with_cell_prolongation(CellProlongation::Constant { correction: 2.0 });
    /// let report = problem.solve(&mesh).unwrap().iterations.unwrap();
    /// assert!(report.relative_residual <= 1e-8);
    /// ```
    pub fn with_cell_prolongation(mut self, prolongation: CellProlongation) -> Self {
        if let Some(Iterative {
            preconditioner: Preconditioning::Multigrid { options, .. },
            ..
        }) = &mut self.iterative
        {
            options.cell_prolongation = prolongation;
        }
        self
    }

    /// Where this method's unknowns live.
    pub fn location(&self) -> Location {
        self.method.location()
    }

    /// The cell points of [`Method::Fv`] when they are not the centroids.
    fn cell_points(&self, complex: &Complex) -> Result<Option<Vec<f64>>, DiffusionError> {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        if self.cell_points != CellPoints::Centroids && self.method != Method::Fv {
            return Err(DiffusionError::Unsupported {
                method: self.method.name(),
                what: "cell points other than centroids (only the two-point method \"fv\" moves its unknowns)",
            });
        }
        Ok(match &self.cell_points {
            CellPoints::Centroids => None,
            CellPoints::Circumcentres => {
                Some(complex.circumcentre(n).map_err(MetricError::from)?.to_vec())
            }
            CellPoints::Given(points) => {
                let cells = complex.cell_count(n);
                if points.len() != cells * d {
                    return Err(DiffusionError::Metric(MetricError::UnsupportedMesh {
                        method: self.method.name(),
                        needs: "one given cell point per top cell",
                        detail: format!(
                            "{} coordinates given for {cells} top cells in R^{d}",
                            points.len()
                        ),
                    }));
                }
                Some(points.to_vec())
            }
        })
    }

    /// Weights of the zero-mean normalisation: cell volumes, or lumped
    /// (barycentric dual) vertex volumes.
    fn mean_weights(&self, complex: &Complex, location: Location, unknowns: usize) -> Vec<f64> {
        let n = complex.dim();
        match location {
            Location::Nodal => lumped_vertex_volumes(complex),
            Location::CellCentred => complex.measure(n).to_vec(),
            Location::Hybrid => {
                let mut w = complex.measure(n).to_vec();
                w.resize(unknowns, 0.0);
                w
            }
        }
    }
}
