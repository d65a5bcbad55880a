//! Nonlinear diffusion–reaction −∇·(k(u, x) ∇u) + r(u, x) = f, steady,
//! solved by Newton's method (or Picard iteration) with a backtracking
//! line search.
//!
//! The discretisation is the linear diffusion's (see
//! [`crate::physics::diffusion`]) with the conductivity moved out of Ω and
//! evaluated at the *face value* of u on every row of A: with Ω₀ the
//! geometric weights of the method (conductivity 1), w the Dirichlet ghost
//! values, b the load and V the lumped volumes of the unknowns,
//!
//! ```text
//!     R(u) = Aᵀ Ω(u) (A u − w) + V r(u) − b,   Ω(u) = diag(ω₀_F k(u_F, x_F))
//! ```
//!
//! where u_F = ½ (u_i + u_j) on a row joining two unknowns (an edge of a
//! nodal method, an interior face of a cell-centred one) and the Dirichlet
//! value itself on a boundary face of a cell-centred method. For FV/FD this
//! is the two-point flux with the conductivity at the face; for DEC and P1
//! it is the conductivity at the edge midpoint, where the circumcentric
//! dual face crosses the edge. Methods whose Ω is not diagonal (Q1, VEM,
//! the hybrid mimetic method) are refused.
//!
//! The Jacobian is again one canonical operator, Lᵀ Ω_J R with
//!
//! ```text
//!     L = [A; A; I],  R = [A; |A|; I],  Ω_J = diag(Ω(u), ½ Ω₀ k'(u_F) (A u − w), V r'(u))
//! ```
//!
//! (|A| with the rows of boundary faces emptied, since their face value is
//! data): the first block is Aᵀ Ω(u) A, the second the derivative of the
//! face weights through the face value, the third the reaction's
//! derivative. Its pattern, and the LU analysis of it, are built once and
//! only values change from one step to the next. Picard iteration drops
//! the second block (the coefficient frozen at the last iterate, the
//! reaction still linearised), which leaves a symmetric matrix and linear
//! convergence.
//!
//! In time ([`NonlinearDiffusion::solve_transient`], and
//! [`NonlinearDiffusion::solve_transient_with`] for data in t), each step
//! of the θ-scheme V (uⁿ⁺¹ − uⁿ)/Δt + θ F(uⁿ⁺¹, tⁿ⁺¹) + (1 − θ) F(uⁿ, tⁿ)
//! = 0 (F the residual above with the source and boundary data at the
//! given time: the ghosts and Dirichlet values from g_D(·, t), the load
//! from f(·, t) and g_N(·, t); tⁿ = t₀ + n Δt; F(uⁿ, tⁿ) is the previous
//! step's converged residual, so each level's data are assembled once)
//! is solved the same way: its Jacobian V/Δt + θ J scales the
//! first blocks of Ω_J and adds V/Δt to the third, on the same pattern and
//! the same analysis for every step.

mod krylov_step;
mod newton;
mod transient;

pub use transient::{NonlinearTransient, TimeStepping, TransientData};

use crate::la::direct::SolveError;
use crate::la::fixed::FixedSplit;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::{Location, Method};
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use crate::physics::diffusion::{Diffusion, DiffusionError, Solution};
use crate::physics::{BoundaryCondition, BoundaryKind, Conductivity, ScalarFn};
use hasse_complex::Complex;
use sprs::CsMat;
use std::sync::Arc;

/// A function of the solution value u and position x.
pub type FieldFn = Arc<dyn Fn(f64, &[f64]) -> f64 + Send + Sync>;

/// A coefficient that depends on u, with its derivative ∂/∂u.
///
/// ```
/// use hasse_solver::physics::nonlinear::Coefficient;
/// use std::sync::Arc;
/// let k = Coefficient::new(Arc::new(|u, _| 1.0 + u * u), Arc::new(|u, _| 2.0 * u));
/// assert_eq!(((k.value)(2.0, &[0.0]), (k.derivative)(2.0, &[0.0])), (5.0, 4.0));
/// assert_eq!((Coefficient::constant(3.0).derivative)(1.0, &[0.0]), 0.0);
/// ```
#[derive(Clone)]
pub struct Coefficient {
    /// The coefficient c(u, x).
    pub value: FieldFn,
    /// ∂c/∂u (u, x).
    pub derivative: FieldFn,
}

impl Coefficient {
    /// A coefficient and its derivative with respect to u.
    pub fn new(value: FieldFn, derivative: FieldFn) -> Self {
        Self { value, derivative }
    }

    /// A constant coefficient (derivative zero).
    pub fn constant(c: f64) -> Self {
        Self::new(Arc::new(move |_, _| c), Arc::new(|_, _| 0.0))
    }
}

/// How each step linearises the residual.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Iteration {
    /// Newton's method: the exact Jacobian (quadratic convergence).
    #[default]
    Newton,
    /// Picard iteration: the coefficient frozen at the last iterate, the
    /// reaction linearised (linear convergence, symmetric matrix).
    Picard,
}

impl Iteration {
    /// The name used in case files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Iteration::Newton => "newton",
            Iteration::Picard => "picard",
        }
    }
}

impl std::fmt::Display for Iteration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One iteration as the monitor sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// 0 for the initial guess, then 1, 2, …
    pub iteration: usize,
    /// ‖R(u_k)‖₂ over the free unknowns.
    pub residual: f64,
    /// The residual relative to the size of its terms (what the tolerance
    /// is compared with; see [`NonlinearOptions::tolerance`]).
    pub relative: f64,
    /// The line search's step length α (1 for a full step; 0 at k = 0).
    pub step_length: f64,
    /// ‖R(u_k)‖ / ‖R(u_{k−1})‖ (NaN at k = 0).
    pub rate: f64,
}

/// Called after every iteration (e.g. to print a line).
pub type Monitor = Arc<dyn Fn(&Step) + Send + Sync>;

/// Settings of the nonlinear iteration.
#[derive(Clone)]
pub struct NonlinearOptions {
    /// Newton or Picard.
    pub iteration: Iteration,
    /// Converged when ‖R(u)‖ ≤ tolerance · ‖|Aᵀ| |q| + V |r(u)| + |b|‖,
    /// the residual relative to the size of the terms it is the sum of (so
    /// a zero load or a good initial guess do not make the test
    /// unreachable, and rounding stays far below it).
    pub tolerance: f64,
    /// Steps before giving up.
    pub max_iterations: usize,
    /// The initial guess on every unknown (fixed ones are ignored);
    /// `None`: zero.
    pub initial: Option<Vec<f64>>,
    /// Called after every iteration.
    pub monitor: Option<Monitor>,
    /// Newton–Krylov: each Newton correction by GMRES on the exact
    /// Jacobian, preconditioned by an LLᵀ of its symmetric part (Picard's
    /// matrix) kept over the steps, instead of a sparse LU per step (see
    /// the module `krylov_step`); a step falls back to LU when that part
    /// is not positive definite or GMRES does not converge. Newton only.
    pub krylov: bool,
    /// What preconditions Newton–Krylov's GMRES: the LLᵀ of the Jacobian's
    /// symmetric part, or an algebraic multigrid V-cycle of it.
    pub preconditioner: KrylovPreconditioner,
}

/// The preconditioner of Newton–Krylov steps ([`NonlinearOptions::krylov`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KrylovPreconditioner {
    /// A sparse LLᵀ of the Jacobian's symmetric part P (Picard's matrix):
    /// GMRES needs few iterations, each a pair of triangular solves.
    #[default]
    Factor,
    /// A smoothed-aggregation V-cycle of P: no factorisation and cheap
    /// iterations, more of them; for large 2D and for 3D problems, where
    /// the factor's fill dominates.
    Multigrid,
}

impl Default for NonlinearOptions {
    fn default() -> Self {
        Self {
            iteration: Iteration::Newton,
            tolerance: 1e-10,
            max_iterations: 50,
            initial: None,
            monitor: None,
            krylov: false,
            preconditioner: KrylovPreconditioner::Factor,
        }
    }
}

/// Why the iteration stopped without converging.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Stall {
    /// The iteration limit was reached.
    #[error("no convergence in {0} iterations")]
    MaxIterations(usize),
    /// No step length down to 2⁻²⁰ reduced the residual.
    #[error("the line search found no step that reduces the residual")]
    LineSearch,
    /// The linearised system could not be solved.
    #[error("the linearised system could not be solved: {0}")]
    Solve(SolveError),
    /// The residual at the initial guess is not finite (a coefficient or
    /// the reaction is NaN or infinite there).
    #[error("the residual at the initial guess is not finite")]
    NonFinite,
}

/// Why a nonlinear problem could not be solved.
#[derive(Debug, thiserror::Error)]
pub enum NonlinearError {
    /// The linear diffusion part (boundary tags, data) was refused.
    #[error(transparent)]
    Diffusion(#[from] DiffusionError),
    /// The Jacobian operator could not be built.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The method cannot carry a u-dependent conductivity on this mesh.
    #[error("nonlinear diffusion with method {method}: {reason}")]
    Unsupported {
        /// The method's name.
        method: &'static str,
        /// Why not.
        reason: String,
    },
    /// Time stepping that is not Δt > 0, θ ∈ (0, 1], at least one step.
    #[error("time stepping needs Δt > 0, θ in (0, 1] and at least one step; got Δt = {dt}, θ = {theta}, {steps} steps")]
    Stepping {
        /// Δt.
        dt: f64,
        /// Steps.
        steps: usize,
        /// θ.
        theta: f64,
    },
    /// A time step did not converge.
    #[error("time step {step} (t = {time}): {error}")]
    AtTimeStep {
        /// 1, 2, …
        step: usize,
        /// The time the step ends at.
        time: f64,
        /// Why it failed.
        error: Box<NonlinearError>,
    },
    /// The iteration did not converge; the residual norms ‖R(u_k)‖ so far.
    #[error("{iteration} did not converge: {stall}; residual history {}", history_text(.history))]
    NotConverged {
        /// Newton or Picard.
        iteration: Iteration,
        /// Why it stopped.
        stall: Stall,
        /// ‖R(u_k)‖ for k = 0, 1, …
        history: Vec<f64>,
    },
}

/// The residual history as `1.2e0 → 3.4e-2 → …`.
pub fn history_text(history: &[f64]) -> String {
    history
        .iter()
        .map(|r| format!("{r:.3e}"))
        .collect::<Vec<_>>()
        .join(" → ")
}

/// The problem −∇·(k(u, x) ∇u) + r(u, x) = f with Dirichlet and Neumann
/// boundary conditions (Neumann data is the flux k∇u·n).
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::nonlinear::{Coefficient, NonlinearDiffusion};
/// use hasse_solver::physics::BoundaryKind;
/// use std::sync::Arc;
/// // −((1 + u) u')' = 0 with u(0) = 0, u(1) = 1: the Kirchhoff transform
/// // u + u²/2 is linear in x, so u = −1 + √(1 + 3x).
/// let k = Coefficient::new(Arc::new(|u, _| 1.0 + u), Arc::new(|_, _| 1.0));
/// let mesh = interval(64, 0.0, 1.0).unwrap();
/// let solved = NonlinearDiffusion::new(Method::Fe, k, Arc::new(|_| 0.0))
///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///     .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| 1.0)))
///     .solve(&mesh)
///     .unwrap();
/// let x = 0.5;
/// let exact = -1.0 + (1.0f64 + 3.0 * x).sqrt();
/// assert!((solved.solution.values[32] - exact).abs() < 1e-4);
/// assert!(solved.iterations() <= 8);
/// ```
#[derive(Clone)]
pub struct NonlinearDiffusion {
    /// The discretisation (fe on simplices, fv, fd, dec).
    pub method: Method,
    /// k(u, x), positive.
    pub conductivity: Coefficient,
    /// r(u, x); `None`: no reaction.
    pub reaction: Option<Coefficient>,
    /// f(x).
    pub source: ScalarFn,
    /// Dirichlet and Neumann conditions, applied in order.
    pub boundary: Vec<BoundaryCondition>,
    /// Newton/Picard settings.
    pub options: NonlinearOptions,
}

/// A converged solution and how the iteration went.
#[derive(Clone, Debug)]
pub struct NonlinearSolution {
    /// The field, its flux Ω(u)(A u − w) and the last linear solve, in the
    /// layout of the linear diffusion (so its errors and output apply).
    pub solution: Solution,
    /// Newton or Picard.
    pub iteration: Iteration,
    /// ‖R(u_k)‖ for k = 0, 1, …, the last one converged.
    pub history: Vec<f64>,
    /// Every step as the monitor saw it.
    pub steps: Vec<Step>,
    /// Symbolic analyses of the Jacobian made (one for the whole run).
    pub symbolic_analyses: usize,
}

impl NonlinearSolution {
    /// Steps taken (the initial guess not counted).
    pub fn iterations(&self) -> usize {
        self.history.len().saturating_sub(1)
    }

    /// ‖R‖ at the solution.
    pub fn final_residual(&self) -> f64 {
        self.history.last().copied().unwrap_or(0.0)
    }
}

impl NonlinearDiffusion {
    /// A problem with default Newton settings and no reaction.
    pub fn new(method: Method, conductivity: Coefficient, source: ScalarFn) -> Self {
        Self {
            method,
            conductivity,
            reaction: None,
            source,
            boundary: Vec::new(),
            options: NonlinearOptions::default(),
        }
    }

    /// Add a reaction term r(u, x).
    pub fn with_reaction(mut self, reaction: Coefficient) -> Self {
        self.reaction = Some(reaction);
        self
    }

    /// Add a boundary condition on the faces tagged `tag`.
    pub fn with_boundary(mut self, tag: &str, kind: BoundaryKind) -> Self {
        self.boundary.push(BoundaryCondition {
            tag: tag.into(),
            kind,
        });
        self
    }

    /// The method's refusals that the input alone shows: a method without
    /// a diagonal Ω everywhere, or a Robin condition (its ghost weight
    /// would need the conductivity of the boundary cell).
    pub fn check(&self) -> Result<(), NonlinearError> {
        let method = self.method.name();
        if matches!(self.method, Method::FvMimetic) {
            return Err(NonlinearError::Unsupported {
                method,
                reason:
                    "the hybrid mimetic metric couples the faces of a cell; use fv, fe, fd or dec"
                        .into(),
            });
        }
        if let Some(bc) = self
            .boundary
            .iter()
            .find(|bc| matches!(bc.kind, BoundaryKind::Robin { .. }))
        {
            return Err(NonlinearError::Unsupported {
                method,
                reason: format!(
                    "Robin conditions (on `{}`) are not supported with a u-dependent conductivity; use Dirichlet or Neumann",
                    bc.tag
                ),
            });
        }
        Ok(())
    }

    /// The checks that need the mesh, without iterating: the method's Ω
    /// on `complex` (diagonal), the boundary tags and the load's data, as
    /// [`NonlinearDiffusion::solve`] would report them.
    pub fn check_data(&self, complex: &Complex) -> Result<(), NonlinearError> {
        System::new(self, complex).map(|_| ())
    }

    /// Assemble and solve on `complex`.
    pub fn solve(&self, complex: &Complex) -> Result<NonlinearSolution, NonlinearError> {
        let system = System::new(self, complex)?;
        newton::solve(self, &system)
    }
}

/// Everything the iteration needs that does not change with u.
pub(crate) struct System {
    pub(crate) location: Location,
    /// A over all unknowns (rows of the flux, CSR).
    pub(crate) incidence: Arc<CsMat<i8>>,
    /// Ω₀: the method's weights with conductivity 1.
    pub(crate) weights: Vec<f64>,
    /// Dirichlet ghost values w on the rows of A.
    pub(crate) ghosts: Vec<f64>,
    /// b: sources and Neumann data.
    pub(crate) load: Vec<f64>,
    /// Unknowns held at Dirichlet values (nodal methods).
    pub(crate) fixed: Vec<Option<f64>>,
    pub(crate) split: FixedSplit,
    /// The point of every row (face or edge centroid), stride d.
    pub(crate) row_points: Vec<f64>,
    /// The point of every unknown (vertex or centroid), stride d.
    pub(crate) unknown_points: Vec<f64>,
    /// Lumped volume of every unknown.
    pub(crate) volumes: Vec<f64>,
    /// The Jacobian Lᵀ Ω_J R on the free unknowns (see the module
    /// documentation); only Ω_J changes.
    pub(crate) jacobian: Canonical,
    pub(crate) assembly_seconds: f64,
    pub(crate) dimension: usize,
}

/// The parts of [`System`] that come from the source and boundary data
/// (the ones a transient run with data in t re-makes at every level).
pub(crate) struct Data {
    /// Dirichlet ghost values w on the rows of A.
    pub(crate) ghosts: Vec<f64>,
    /// b: sources and Neumann data.
    pub(crate) load: Vec<f64>,
    /// Unknowns held at Dirichlet values (nodal methods).
    pub(crate) fixed: Vec<Option<f64>>,
}

/// The linear diffusion with conductivity 1 and the problem's data: its
/// assembly gives Ω₀, A, and the data's ghosts, load and fixed values.
fn assemble_linear(
    problem: &NonlinearDiffusion,
    complex: &Complex,
) -> Result<(crate::physics::diffusion::Assembled, Data), NonlinearError> {
    let mut linear = Diffusion::new(
        problem.method,
        Conductivity::Scalar(Arc::new(|_| 1.0)),
        Arc::clone(&problem.source),
    );
    linear.boundary = problem.boundary.clone();
    let assembled = linear.assemble(complex)?;
    let ghosts = assembled.ghost_values.clone();
    // The linear assembly lifted the ghosts with Ω₀ (b += Aᵀ Ω₀ w);
    // here they enter the residual through Ω(u), so take them out.
    let lifted = assembled
        .canonical
        .sum_transpose(&assembled.canonical.metric().apply(&ghosts));
    let load: Vec<f64> = assembled
        .rhs
        .iter()
        .zip(&lifted)
        .map(|(b, l)| b - l)
        .collect();
    let fixed = assembled.fixed.clone();
    Ok((
        assembled,
        Data {
            ghosts,
            load,
            fixed,
        },
    ))
}

impl System {
    /// The data of `problem` (the same method and mesh as this system's,
    /// other source and boundary values), without the rest of the set-up.
    pub(crate) fn data(
        problem: &NonlinearDiffusion,
        complex: &Complex,
    ) -> Result<Data, NonlinearError> {
        assemble_linear(problem, complex).map(|(_, data)| data)
    }

    /// Replace the source and boundary data (same fixed unknowns).
    pub(crate) fn set_data(&mut self, data: Data) {
        self.ghosts = data.ghosts;
        self.load = data.load;
        self.fixed = data.fixed;
    }

    fn new(problem: &NonlinearDiffusion, complex: &Complex) -> Result<Self, NonlinearError> {
        problem.check()?;
        let started = std::time::Instant::now();
        let method = problem.method.name();
        let (assembled, data) = assemble_linear(problem, complex)?;
        let weights = match assembled.canonical.metric().diagonal_weights() {
            Some(w) => w.to_vec(),
            None => {
                return Err(NonlinearError::Unsupported {
                    method,
                    reason: "its Ω is not diagonal on this mesh (Q1 or virtual elements); use simplices (P1), fv, fd or dec".into(),
                })
            }
        };
        let incidence = assembled.canonical.shared_incidence();
        let Data {
            ghosts,
            load,
            fixed,
        } = data;
        let n = complex.dim();
        let location = assembled.location;
        let (row_points, unknown_points, volumes) = match location {
            Location::Nodal => (
                complex.centroid(1).to_vec(),
                complex.vertices().as_slice().to_vec(),
                lumped_vertex_volumes(complex),
            ),
            _ => (
                complex.centroid(n - 1).to_vec(),
                complex.centroid(n).to_vec(),
                complex.measure(n).to_vec(),
            ),
        };
        let split = FixedSplit::new(&fixed);
        let jacobian = jacobian_operator(&incidence, &split)?;
        Ok(Self {
            location,
            incidence,
            weights,
            ghosts,
            load,
            fixed,
            split,
            row_points,
            unknown_points,
            volumes,
            jacobian,
            assembly_seconds: started.elapsed().as_secs_f64(),
            dimension: complex.embedding_dim(),
        })
    }
}

/// Rows stacked: `parts` one after the other, all with the same columns.
fn stack(parts: &[&CsMat<i8>], cols: usize) -> CsMat<i8> {
    let mut indptr = vec![0];
    let mut indices = Vec::new();
    let mut data = Vec::new();
    for part in parts {
        for row in part.outer_iterator() {
            indices.extend_from_slice(row.indices());
            data.extend_from_slice(row.data());
            indptr.push(indices.len());
        }
    }
    CsMat::new((indptr.len() - 1, cols), indptr, indices, data)
}

/// The Jacobian's canonical operator Lᵀ Ω_J R on the free unknowns, with
/// L = [A; A; I] and R = [A; |A|; I] (|A| keeps only rows with two
/// entries: a boundary face's value is its Dirichlet datum).
fn jacobian_operator(a: &CsMat<i8>, split: &FixedSplit) -> Result<Canonical, CanonicalError> {
    let a = if a.is_csr() { a.clone() } else { a.to_csr() };
    let mut indptr = vec![0];
    let mut indices = Vec::new();
    let mut data = Vec::new();
    for row in a.outer_iterator() {
        if row.nnz() == 2 {
            indices.extend_from_slice(row.indices());
            data.extend(std::iter::repeat_n(1i8, 2));
        }
        indptr.push(indices.len());
    }
    let average = CsMat::new(a.shape(), indptr, indices, data);
    let a_free = split.restrict_columns(&a);
    let average_free = split.restrict_columns(&average);
    let free = split.free().len();
    let identity = CsMat::<i8>::eye(free);
    let left = stack(&[&a_free, &a_free, &identity], free);
    let right = stack(&[&a_free, &average_free, &identity], free);
    let rows = left.rows();
    Canonical::coupling(left, BlockMetric::from_weights(vec![0.0; rows]), right)
}
