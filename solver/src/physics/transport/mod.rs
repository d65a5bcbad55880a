//! Advection–diffusion −∇·(K∇u) + ∇·(v u) = f on cell-centred finite
//! volumes: the two-point diffusion of [`Method::Fv`] unchanged, plus an
//! advection operator written on the same boundary matrix ∂ₙ.
//!
//! # The advection operator
//!
//! Conventions (those of the complex, see `Complex::normal`): every
//! (n−1)-cell f carries a unit normal n_f that points *out of* the top
//! cells c with ∂ₙ(f, c) = +1 and *into* those with ∂ₙ(f, c) = −1. The face
//! flux is
//!
//! ```text
//!     F_f = ∫_f v·n_f          (positive: flow along n_f)
//! ```
//!
//! integrated over the face by Gauss quadrature ([`face_fluxes`]: exact for
//! velocities polynomial of degree ≤ 3 on edges, ≤ 2 on polygonal faces),
//! or given directly as a face cochain ([`FaceFlux::Given`]). The flux
//! leaving cell c through f is ∂ₙ(f, c) F_f. The upwind value of a face is
//! that of the cell the flow leaves: the cell with ∂ₙ(f, c) = +1 when
//! F_f > 0, the one with −1 when F_f < 0. This choice is an exact (0/1)
//! *selection matrix* U (faces × cells), and the cell balance of the
//! advective fluxes is
//!
//! ```text
//!     (∂ₙᵀ diag(F) U) u = Σ_f ∂ₙ(f, c) F_f u_upwind(f)
//! ```
//!
//! one [`Canonical`] coupling operator Aᵀ Ω B with A = ∂ₙ, Ω = diag(F),
//! B = U: topology stays in the integer matrices, the velocity in Ω. It is
//! conservative by construction: an interior face enters the two balances
//! of its cells with opposite signs (∂ₙ's row of an interior face sums to
//! zero), so Σ_c of the balances is the boundary fluxes alone, to rounding.
//!
//! On a boundary face of cell c with s = ∂ₙ(f, c), s F_f > 0 is outflow
//! (upwind from inside, a row of U) and s F_f < 0 inflow, which needs a
//! Dirichlet value g: its flux s F_f g is data and moves to the right-hand
//! side. Face fluxes smaller than 10⁻¹² of the largest are rounding of a
//! zero normal velocity (sin π ≠ 0 in floating point) and are set to zero,
//! so that a closed box needs no inflow value and conserves mass exactly.
//!
//! The whole steady operator is M = Aᵀ Ω_K A + ∂ₙᵀ diag(F) U, an M-matrix
//! for any cell Péclet number (upwinding never makes an off-diagonal
//! positive), hence a discrete maximum principle: no oscillations in
//! boundary layers. It is nonsymmetric: solved by sparse LU (faer) or by
//! BiCGStab / GMRES(m) with ILU(0) ([`crate::la::krylov`]).
//!
//! Without a conductivity ([`Transport::conductivity`] `None`) the problem
//! is pure advection: the upwind operator alone, still an M-matrix (each
//! column's diagonal is the cell's outflow), solvable when every cell is
//! reached from an inflow boundary (no closed streamlines in steady runs).
//!
//! # In time
//!
//! [`Transport::solve_transient`] steps V u̇ + M u = b with the θ-scheme
//! (one LU factorisation for the run; θ = 0 is forward Euler, refused
//! above the positivity limit Δt M_cc / |c| ≤ 1), or with the limited
//! second-order scheme ([`Scheme::Limited`]): a least-squares cell
//! gradient limited by Barth–Jespersen (the multidimensional minmod) gives
//! the upwind face value, stepped by the two-stage strong-stability-
//! preserving Runge–Kutta method (Heun). See [`transient`].
//!
//! # Nodal finite elements
//!
//! For comparison, [`nodal::NodalTransport`] solves the same equation
//! (advective form v·∇u) on vertex unknowns: the FE diffusion of
//! [`Method::Fe`] plus a Galerkin advection operator Pᵀ Ω_v P over the
//! cell–vertex incidence P, stabilised by SUPG with the optimal τ. See
//! [`nodal`] and [`crate::metric::fe::advection`].

mod flux;
mod limiter;
pub mod nodal;
mod steady;
pub mod transient;

pub use flux::face_fluxes;
pub use steady::TransportSystem;
pub use transient::{Scheme, TimeStepping, TransportTransient};

use crate::la::direct::SolveError;
use crate::la::iterative::CgError;
use crate::la::krylov::{KrylovError, KrylovOptions};
use crate::metric::Method;
use crate::multigrid::{MultigridError, MultigridOptions};
use crate::operator::CanonicalError;
use crate::physics::diffusion::DiffusionError;
use crate::physics::{point_text, BoundaryCondition, BoundaryKind, Conductivity, ScalarFn};
use crate::physics::{TagError, VectorFn};
use std::sync::Arc;

/// The advecting field: a velocity to integrate over the faces, or the
/// face fluxes themselves.
#[derive(Clone)]
pub enum FaceFlux {
    /// v(x); F_f = ∫_f v·n_f by quadrature ([`face_fluxes`]).
    Velocity(VectorFn),
    /// F_f on every (n−1)-cell, along its normal n_f (e.g. the flux
    /// cochain of a Darcy solve).
    Given(Arc<[f64]>),
}

/// Which Krylov method solves the nonsymmetric system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KrylovMethod {
    /// BiCGStab: short recurrences, two products an iteration.
    Bicgstab,
    /// Restarted GMRES(m): monotone residual within a cycle.
    Gmres,
}

impl KrylovMethod {
    /// The name used in case files (`[solver] type`).
    pub fn name(&self) -> &'static str {
        match self {
            KrylovMethod::Bicgstab => "bicgstab",
            KrylovMethod::Gmres => "gmres",
        }
    }
}

/// The preconditioner of a Krylov solve.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum KrylovPreconditioner {
    /// ILU(0) of the whole nonsymmetric matrix: robust at any Péclet
    /// number, iteration counts growing with the mesh when diffusion
    /// dominates.
    #[default]
    Ilu0,
    /// One algebraic multigrid V-cycle ([`crate::multigrid`]) of the
    /// symmetric diffusion part alone (Aᵀ Ω_K A, plus V/Δt in a time
    /// step): iteration counts independent of the mesh while diffusion
    /// dominates (cell Péclet ≲ 1); it needs a conductivity.
    DiffusionMultigrid(MultigridOptions),
}

impl KrylovPreconditioner {
    /// The name used in case files (`[solver] preconditioner`) and reports.
    pub fn name(&self) -> &'static str {
        match self {
            KrylovPreconditioner::Ilu0 => "ILU(0)",
            KrylovPreconditioner::DiffusionMultigrid(_) => "multigrid of the diffusion part",
        }
    }
}

/// How the linear systems of a transport problem are solved.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum LinearSolver {
    /// Sparse LU with partial pivoting (faer).
    #[default]
    Lu,
    /// A preconditioned Krylov method.
    Krylov {
        /// BiCGStab or GMRES.
        method: KrylovMethod,
        /// Tolerance, iteration limit, restart length.
        options: KrylovOptions,
        /// ILU(0) or multigrid on the diffusion part.
        preconditioner: KrylovPreconditioner,
    },
}

/// The problem −∇·(K∇u) + ∇·(v u) = f with Dirichlet values on (at least)
/// every inflow face.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::transport::{FaceFlux, Transport};
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// // Pure advection of u = 1 entering at x = 0 with v = (1, 0), f = 0:
/// // the steady state is 1 everywhere.
/// let mesh = rectangle(8, 2, [0.0, 1.0], [0.0, 0.25]).unwrap();
/// let problem = Transport::new(None, FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])), Arc::new(|_| 0.0))
///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 1.0)));
/// let solution = problem.solve(&mesh).unwrap();
/// assert!(solution.values.iter().all(|u| (u - 1.0).abs() < 1e-13));
/// // The same with diffusion K = 1 and u = 0 on the right: the face
/// // fluxes are |face| v·n (0.125 on every vertical edge).
/// let problem = Transport::new(Some(Conductivity::Scalar(Arc::new(|_| 1.0))),
///     FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])), Arc::new(|_| 0.0))
///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 1.0)))
///     .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
/// let solution = problem.solve(&mesh).unwrap();
/// assert!(solution.values.windows(2).take(7).all(|w| w[0] > w[1]));
/// let largest = solution.face_flux.iter().fold(0.0f64, |m, f| m.max(f.abs()));
/// assert!((largest - 0.125).abs() < 1e-15);
/// ```
#[derive(Clone)]
pub struct Transport {
    /// K (two-point flux at the faces); `None` for pure advection.
    pub conductivity: Option<Conductivity>,
    /// The velocity or the face fluxes.
    pub flux: FaceFlux,
    /// f, per unit volume.
    pub source: ScalarFn,
    /// Applied in order (a later condition on a face wins). Dirichlet
    /// gives the inflow value and the diffusion's ghost; Neumann and Robin
    /// act on the diffusion only and may not sit on inflow faces.
    pub boundary: Vec<BoundaryCondition>,
    /// LU (default) or a Krylov method.
    pub solver: LinearSolver,
}

/// Why a transport problem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TransportError {
    /// The diffusion part refused its data (tags, conductivity, source).
    #[error(transparent)]
    Diffusion(#[from] DiffusionError),
    /// A boundary condition names a tag the mesh lacks.
    #[error(transparent)]
    Tag(#[from] TagError),
    /// The advection operator could not be built.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The LU factorisation or solve failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The Krylov solve failed.
    #[error(transparent)]
    Krylov(#[from] KrylovError),
    /// The multigrid preconditioner could not be built.
    #[error(transparent)]
    Multigrid(#[from] MultigridError),
    /// The diffusion part could not be read by rows for the multigrid
    /// preconditioner.
    #[error(transparent)]
    Iterative(#[from] CgError),
    /// A nodal (FE) problem without a Dirichlet or Robin boundary: its
    /// operator keeps constants in its kernel.
    #[error("the nodal (fe) transport problem has no Dirichlet or Robin boundary: its solution is fixed only up to a constant; give a Dirichlet value where the flow enters")]
    NoFixedValue,
    /// The multigrid preconditioner was asked for without a conductivity.
    #[error("the multigrid preconditioner acts on the diffusion part, and a pure advection problem has none; use ILU(0)")]
    NoDiffusion,
    /// Flow enters the domain through a face without a Dirichlet value.
    #[error("flow enters the domain through face {face} at {} (inflow flux {flux:e}) {}, but an inflow face needs a Dirichlet value", point_text(.point), match .condition { Some((tag, kind)) => format!("where tag '{tag}' gives a {kind} condition"), None => "where no boundary condition is given".into() })]
    InflowWithoutDirichlet {
        /// The (n−1)-cell.
        face: usize,
        /// Its centroid.
        point: Vec<f64>,
        /// The flux entering (negative: into the cell).
        flux: f64,
        /// The tag and kind of the condition there, if any.
        condition: Option<(String, &'static str)>,
    },
    /// The velocity is NaN or infinite at a quadrature point, or a given
    /// face flux is.
    #[error("the velocity is not finite at {}", point_text(.point))]
    NonFiniteVelocity {
        /// Where.
        point: Vec<f64>,
    },
    /// A Dirichlet value or the source is NaN or infinite.
    #[error("{what} is not finite at {}", point_text(.point))]
    NonFiniteData {
        /// "the source" or "a Dirichlet value".
        what: &'static str,
        /// Where.
        point: Vec<f64>,
    },
    /// Given face fluxes do not have one entry per (n−1)-cell.
    #[error("{found} face fluxes given for {expected} (n−1)-cells")]
    FluxSize {
        /// (n−1)-cells of the mesh.
        expected: usize,
        /// Entries given.
        found: usize,
    },
    /// Time stepping that is not Δt > 0, θ ∈ [0, 1], at least one step.
    #[error("time stepping needs Δt > 0, θ in [0, 1] and at least one step; got Δt = {dt}, θ = {theta}, {steps} steps")]
    Stepping {
        /// Δt.
        dt: f64,
        /// Steps.
        steps: usize,
        /// θ.
        theta: f64,
    },
    /// An explicit step above its stability (positivity) limit.
    #[error("the explicit {scheme} step is unstable: {number_name} {number:.3} > 1 in cell {cell} at {} (Δt = {dt}); take Δt ≤ {limit:.3e}, or use the implicit upwind scheme (θ > 0)", point_text(.point))]
    Courant {
        /// "forward Euler" or "limited (SSP-RK2)".
        scheme: &'static str,
        /// What the number is, in words.
        number_name: &'static str,
        /// Its largest value.
        number: f64,
        /// The cell where it is largest.
        cell: usize,
        /// Its centroid.
        point: Vec<f64>,
        /// The step asked for.
        dt: f64,
        /// The largest step that passes.
        limit: f64,
    },
}

/// A steady solution with the figures a report needs.
#[derive(Clone, Debug)]
pub struct TransportSolution {
    /// u per top cell.
    pub values: Vec<f64>,
    /// F_f per (n−1)-cell (advective face flux along n_f, of velocity
    /// alone: the advective flux of u is F_f u_upwind).
    pub face_flux: Vec<f64>,
    /// Cell Péclet numbers ([`Peclet`]).
    pub peclet: Peclet,
    /// Iterations of a Krylov solve (`None` for LU).
    pub iterations: Option<crate::la::iterative::CgReport>,
    /// ‖b − M u‖₂ / ‖b‖₂.
    pub relative_residual: f64,
    /// Unknowns and stored entries of M.
    pub unknowns: usize,
    /// Stored entries of M.
    pub nonzeros: usize,
}

/// The cell Péclet number |v| h / K over the cells: h = |c|^{1/n}, |v| the
/// largest |F_f| / |f| over the cell's faces, K the cell's conductivity
/// (the largest diagonal entry of a tensor). Infinite without diffusion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peclet {
    /// Smallest cell Péclet number.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Transport {
    /// A problem with no boundary conditions and the LU solver.
    pub fn new(conductivity: Option<Conductivity>, flux: FaceFlux, source: ScalarFn) -> Self {
        Self {
            conductivity,
            flux,
            source,
            boundary: Vec::new(),
            solver: LinearSolver::Lu,
        }
    }

    /// Add a boundary condition on the faces of `tag`.
    pub fn with_boundary(mut self, tag: &str, kind: BoundaryKind) -> Self {
        self.boundary.push(BoundaryCondition {
            tag: tag.to_string(),
            kind,
        });
        self
    }

    /// Choose the linear solver.
    pub fn with_solver(mut self, solver: LinearSolver) -> Self {
        self.solver = solver;
        self
    }

    /// The diffusion part as a [`crate::physics::diffusion::Diffusion`]
    /// problem of the two-point FV method (LU: the sum is nonsymmetric).
    pub(crate) fn diffusion(&self) -> Option<crate::physics::diffusion::Diffusion> {
        self.conductivity.as_ref().map(|k| {
            let mut d = crate::physics::diffusion::Diffusion::new(
                Method::Fv,
                k.clone(),
                Arc::clone(&self.source),
            );
            d.boundary = self.boundary.clone();
            d.factorization = crate::la::direct::Factorization::Lu;
            d
        })
    }
}
