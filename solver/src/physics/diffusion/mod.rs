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
use crate::physics::{
    non_finite_text, point_text, tagged_boundary_faces, BoundaryCondition, BoundaryKind,
    Conductivity, Datum, ScalarFn, TagError, VectorFn,
};
pub use assemble::Assembled;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use hasse_complex::Complex;
pub use post::{conservation_residual, errors, flux_error, reconstruct_gradient};
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
#[derive(Clone)]
pub struct Diffusion {
    pub method: Method,
    pub conductivity: Conductivity,
    pub source: ScalarFn,
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
#[derive(Clone, Debug, Default)]
pub struct Iterative {
    pub options: CgOptions,
    /// A guess for every unknown (fixed ones are ignored), e.g. a coarse
    /// solution transferred to a refined mesh.
    pub initial: Option<Vec<f64>>,
    /// The preconditioner of conjugate gradients (default: Jacobi).
    pub preconditioner: Preconditioning,
}

/// The preconditioner of an iterative solve.
#[derive(Clone, Debug, Default)]
pub enum Preconditioning {
    /// diag(M)⁻¹: cheap, iteration counts grow like 1/h.
    #[default]
    Jacobi,
    /// One multigrid V-cycle per iteration ([`crate::multigrid`]): counts
    /// independent of h. The hierarchy is for all unknowns of the mesh;
    /// Dirichlet unknowns are removed from it at solve time.
    Multigrid {
        hierarchy: Hierarchy,
        options: MultigridOptions,
    },
}

/// Why a problem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiffusionError {
    #[error(transparent)]
    Tag(#[from] TagError),
    #[error("the Robin coefficient α = {alpha} of boundary condition {condition} (tag '{tag}') at {} (face {face}) must be positive", point_text(.point))]
    RobinAlpha {
        condition: usize,
        tag: String,
        face: usize,
        point: Vec<f64>,
        alpha: f64,
    },
    /// A given function is NaN or ±∞ at a point (or, without a point, its
    /// load overflowed).
    #[error("{datum} is not finite ({}){}", non_finite_text(*.value), .point.as_deref().map(|x| format!(" at {}", point_text(x))).unwrap_or_else(|| " in the sum of its load".into()))]
    NonFinite {
        datum: Datum,
        point: Option<Vec<f64>>,
        value: f64,
    },
    #[error("pure Neumann problem with incompatible data: sources plus boundary fluxes sum to {imbalance:e} (relative {relative:e}); they must balance (∫f + ∮g = 0)")]
    IncompatibleNeumann { imbalance: f64, relative: f64 },
    #[error("pure Neumann problem on a disconnected domain ({components} parts): give every part a Dirichlet or Robin boundary")]
    Disconnected { components: usize },
    #[error("the domain has {parts} disconnected parts and the part holding {what} {unknown} (at {point:?}) has no Dirichlet or Robin boundary: its solution is fixed only up to a constant and the system is singular; put a Dirichlet or Robin condition on a boundary tag of every part, or mesh the parts separately")]
    FloatingPart {
        parts: usize,
        what: &'static str,
        unknown: usize,
        point: Vec<f64>,
    },
    #[error("the conductivity at {} (top cell {cell}) is {}", point_text(.point), coefficient_problem(.source))]
    Coefficient {
        cell: usize,
        point: Vec<f64>,
        source: MetricError,
    },
    #[error("the {method} metric is not symmetric, but {factorization} needs a symmetric positive definite system; use Factorization::Lu for a non-symmetric Ω")]
    NotSymmetric {
        method: &'static str,
        factorization: Factorization,
    },
    #[error("the {method} method cannot impose {what}")]
    Unsupported {
        method: &'static str,
        what: &'static str,
    },
    #[error(transparent)]
    Metric(#[from] MetricError),
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Iterative(#[from] CgError),
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
    pub method: Method,
    pub location: Location,
    /// All unknowns (fixed ones included), in the layout of `location`.
    pub values: Vec<f64>,
    /// The flux cochain Ω A u on the rows of A (edges for nodal methods,
    /// (n−1)-cells for cell-centred ones, half-faces for the hybrid one).
    pub flux: Vec<f64>,
    pub report: SolveReport,
    pub assembly_seconds: f64,
    /// Whether the direct solve's symbolic analysis ran beside the assembly
    /// (from the solved matrix's pattern known from topology: two-point
    /// FV/FD, nodal FE), so that its seconds overlap `assembly_seconds`
    /// instead of adding to them.
    pub analysed_during_assembly: bool,
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
pub fn diagonal_condition_bound(matrix: &SparseColMat<usize, f64>, fixed: &[Option<f64>]) -> f64 {
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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// Discrete L² error of the primary field (lumped-mass weights on
    /// vertices, cell volumes on cells): sqrt(Σ w_i (u_i − u(x_i))²) with
    /// x_i the vertices, or the cell points (centroids unless
    /// [`Solution::cell_points`] says otherwise).
    pub l2: f64,
    /// Largest pointwise error of the primary field.
    pub max: f64,
    /// Discrete L² error of the cell-wise reconstructed gradient.
    pub gradient_l2: f64,
}

impl Diffusion {
    /// A problem with default solver settings.
    pub fn new(method: Method, conductivity: Conductivity, source: ScalarFn) -> Self {
        Self {
            method,
            conductivity,
            source,
            boundary: Vec::new(),
            factorization: Factorization::Llt,
            ordering: Ordering::Automatic,
            cell_points: CellPoints::Centroids,
            neumann_tolerance: 1e-2,
            iterative: None,
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
    /// `[solver] kind = "direct" | "multigrid" | "amg" | "auto"` maps onto
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
        let choice = match choice {
            SolverChoice::Auto(hierarchy) => {
                let n = complex.dim();
                let unknowns = match self.location() {
                    Location::Nodal => complex.cell_count(0),
                    Location::CellCentred => complex.cell_count(n),
                    Location::Hybrid => complex.cell_count(n) + complex.cell_count(n - 1),
                };
                multigrid::automatic(n, unknowns, hierarchy)
            }
            other => other,
        };
        self.iterative = match choice {
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
        };
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
