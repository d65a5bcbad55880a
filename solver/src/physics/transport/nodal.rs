//! Advection–diffusion −∇·(K∇u) + v·∇u = f on nodal finite elements (P1
//! simplices, Q1 quadrilaterals and hexahedra), Galerkin or stabilised by
//! SUPG: the comparison to the cell-centred finite volumes of this module.
//!
//! The operator is the sum of two canonical operators on the vertex
//! unknowns:
//!
//! ```text
//!     M = δ⁰ᵀ Ω_K δ⁰  +  Pᵀ Ω_v P
//! ```
//!
//! the nodal FE diffusion exactly as [`Method::Fe`] assembles it (with its
//! boundary rows: Dirichlet values at the vertices of the tagged faces,
//! Neumann data K∇u·n = g, Robin ghosts), and the advection with its SUPG
//! terms over the cell–vertex incidence P
//! ([`crate::metric::fe::advection`], where the weak form, τ and the
//! element length are stated). The right-hand side is the FE load ∫ f φ_i
//! plus the SUPG load Σ_T τ_T ∫_T (v·∇φ_i) f and the boundary data.
//!
//! Natural conditions act on the diffusive flux alone (the advective weak
//! form), so a Neumann face may be an outflow face (K∇u·n = 0 there is the
//! usual outflow condition) and, unlike the upwind finite volumes, an
//! inflow face needs no Dirichlet value to make the system solvable; it
//! needs one to make the data mean what inflow data usually mean. Without
//! any Dirichlet or Robin boundary, M has constants in its kernel (every
//! row of M sums to zero: δ⁰1 = 0 and P1 hits Σ_j v·∇φ_j = 0) and the
//! problem is refused.
//!
//! In time, [`NodalTransport::solve_transient`] steps the θ-scheme with
//! the Petrov–Galerkin mass on the same P.
//!
//! M is nonsymmetric; the Dirichlet vertices are eliminated
//! ([`FixedSplit`]) and the free system solved by LU or a Krylov method,
//! as [`Transport::solver`](super::Transport) chooses for finite volumes.

use super::steady::solve_system;
use super::{LinearSolver, Peclet, TransportError};
use crate::la::direct::{self, Factorization};
use crate::la::fixed::FixedSplit;
use crate::la::iterative::CgReport;
pub use crate::metric::fe::advection::Stabilisation;
use crate::metric::fe::advection::{advection_metric, AdvectionError};
use crate::metric::{CellTensors, Method, MetricError};
use crate::operator::Canonical;
use crate::physics::diffusion::{CellCoefficients, Diffusion, DiffusionError};
use crate::physics::{BoundaryCondition, BoundaryKind, Conductivity, ScalarFn, VectorFn};
use faer::sparse::SparseColMat;
use hasse_complex::Complex;
use std::sync::Arc;

/// The problem −∇·(K∇u) + v·∇u = f on vertex unknowns, with SUPG or
/// without.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::transport::nodal::{NodalTransport, Stabilisation};
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// // −u″ + u′ = 0 with u(0) = 0, u(1) = 1 on Q1 squares, Galerkin: the
/// // linear u = x is not a solution, but the exact one is reproduced at
/// // the vertices by SUPG's optimal τ.
/// let mesh = rectangle(4, 1, [0.0, 1.0], [0.0, 0.25]).unwrap();
/// let problem = NodalTransport::new(Conductivity::Scalar(Arc::new(|_| 1.0)),
///     Arc::new(|_| [1.0, 0.0, 0.0]), Arc::new(|_| 0.0))
///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///     .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| 1.0)));
/// let solution = problem.solve(&mesh).unwrap();
/// let exact = |x: f64| (x.exp() - 1.0) / (1f64.exp() - 1.0);
/// for (v, u) in solution.values.iter().enumerate() {
///     assert!((u - exact(mesh.vertices().point(v)[0])).abs() < 1e-13);
/// }
/// assert_eq!(problem.stabilisation, Stabilisation::Supg);
/// ```
#[derive(Clone)]
pub struct NodalTransport {
    /// K (> 0): the FE stiffness of [`Method::Fe`].
    pub conductivity: Conductivity,
    /// v(x).
    pub velocity: VectorFn,
    /// f, per unit volume.
    pub source: ScalarFn,
    /// As for FE diffusion: Dirichlet at the vertices of the tagged faces,
    /// Neumann and Robin on the diffusive flux K∇u·n.
    pub boundary: Vec<BoundaryCondition>,
    /// SUPG (default) or plain Galerkin.
    pub stabilisation: Stabilisation,
    /// LU (default) or a Krylov method.
    pub solver: LinearSolver,
}

/// The assembled system on all vertices, before the Dirichlet vertices
/// are eliminated.
#[derive(Clone, Debug)]
pub struct NodalSystem {
    /// M = δ⁰ᵀ Ω_K δ⁰ + Pᵀ Ω_v P.
    pub matrix: SparseColMat<usize, f64>,
    /// The diffusion part δ⁰ᵀ Ω_K δ⁰ (with Robin ghost rows).
    pub diffusion: SparseColMat<usize, f64>,
    /// The advection part Pᵀ Ω_v P (with the SUPG terms).
    pub advection: SparseColMat<usize, f64>,
    /// δ⁰ᵀ Ω_K δ⁰ as a canonical operator (boundary rows included).
    pub diffusion_operator: Canonical,
    /// Pᵀ Ω_v P as a canonical operator.
    pub advection_operator: Canonical,
    /// The Petrov–Galerkin mass Pᵀ Ω_m P of a time derivative.
    pub mass_operator: Canonical,
    /// FE load, SUPG load and boundary data.
    pub rhs: Vec<f64>,
    /// Vertices held at a Dirichlet value.
    pub fixed: Vec<Option<f64>>,
    /// τ_T per top cell.
    pub tau: Vec<f64>,
    /// Element Péclet numbers |v̄| h_T / (2 K_v).
    pub peclet: Peclet,
}

/// A steady nodal solution with the figures a report needs.
#[derive(Clone, Debug)]
pub struct NodalSolution {
    /// u per vertex.
    pub values: Vec<f64>,
    /// Element Péclet numbers |v̄| h_T / (2 K_v) (smallest and largest).
    pub peclet: Peclet,
    /// The largest τ_T (zero for Galerkin).
    pub tau_max: f64,
    /// Iterations of a Krylov solve (`None` for LU).
    pub iterations: Option<CgReport>,
    /// ‖b − M u‖₂ / ‖b‖₂ of the free system.
    pub relative_residual: f64,
    /// Free unknowns solved for.
    pub unknowns: usize,
    /// Stored entries of the free system's matrix.
    pub nonzeros: usize,
}

/// A θ-scheme run on nodal elements.
#[derive(Clone, Debug)]
pub struct NodalTransient {
    /// (t, u per vertex) at t = 0 and every kept step.
    pub levels: Vec<(f64, Vec<f64>)>,
    /// Element Péclet numbers |v̄| h_T / (2 K_v).
    pub peclet: Peclet,
    /// The largest τ_T (zero for Galerkin).
    pub tau_max: f64,
}

impl NodalTransport {
    /// A problem with SUPG, no boundary conditions and the LU solver.
    pub fn new(conductivity: Conductivity, velocity: VectorFn, source: ScalarFn) -> Self {
        Self {
            conductivity,
            velocity,
            source,
            boundary: Vec::new(),
            stabilisation: Stabilisation::Supg,
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

    /// SUPG or Galerkin.
    pub fn with_stabilisation(mut self, stabilisation: Stabilisation) -> Self {
        self.stabilisation = stabilisation;
        self
    }

    /// Choose the linear solver.
    pub fn with_solver(mut self, solver: LinearSolver) -> Self {
        self.solver = solver;
        self
    }

    /// The diffusion part as an FE diffusion problem (LU: the sum with the
    /// advection is nonsymmetric).
    fn diffusion(&self) -> Diffusion {
        let mut d = Diffusion::new(
            Method::Fe,
            self.conductivity.clone(),
            Arc::clone(&self.source),
        );
        d.boundary = self.boundary.clone();
        d.factorization = Factorization::Lu;
        d
    }

    /// Assemble M and b on every vertex, with the Dirichlet values.
    pub fn assemble(&self, complex: &Complex) -> Result<NodalSystem, TransportError> {
        let problem = self.diffusion();
        let assembled = problem.assemble(complex)?;
        if assembled.pure_neumann {
            return Err(TransportError::NoFixedValue);
        }
        let coefficients = problem.cell_coefficients(complex)?;
        let tensors = match &coefficients {
            CellCoefficients::Scalar(v) => CellTensors::scalar(v),
            CellCoefficients::Tensor(t) => CellTensors::full(t),
        };
        let (v, f) = (&self.velocity, &self.source);
        let velocity = move |x: &[f64]| v(x);
        let source = move |x: &[f64]| f(x);
        let advection = advection_metric(
            complex,
            &velocity,
            tensors,
            Some(&source),
            self.stabilisation,
        )
        .map_err(advection_error)?;
        let peclet = Peclet {
            min: advection
                .peclet
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min),
            max: advection.peclet.iter().copied().fold(0.0, f64::max),
        };
        let incidence = Arc::new(advection.incidence);
        let operator = Canonical::new(Arc::clone(&incidence), advection.metric)?;
        let mass_operator = Canonical::new(incidence, advection.mass)?;
        let advective = operator.assemble();
        let matrix = faer::sparse::ops::add(assembled.matrix.as_ref(), advective.as_ref())
            .map_err(|_| direct::SolveError::OutOfMemory)?;
        let mut rhs = assembled.rhs;
        for (b, l) in rhs.iter_mut().zip(&advection.load) {
            *b += l;
        }
        Ok(NodalSystem {
            matrix,
            diffusion: assembled.matrix,
            advection: advective,
            diffusion_operator: assembled.canonical,
            advection_operator: operator,
            mass_operator,
            rhs,
            fixed: assembled.fixed,
            tau: advection.tau,
            peclet,
        })
    }

    /// Solve the steady problem: the Dirichlet vertices eliminated, the
    /// free system M_ff u_f = b_f − M_fd g by the chosen solver.
    pub fn solve(&self, complex: &Complex) -> Result<NodalSolution, TransportError> {
        let system = self.assemble(complex)?;
        let split = FixedSplit::new(&system.fixed);
        let tau_max = system.tau.iter().copied().fold(0.0, f64::max);
        if split.free().is_empty() {
            return Ok(NodalSolution {
                values: split.lift(&[], &system.fixed),
                peclet: system.peclet,
                tau_max,
                iterations: None,
                relative_residual: 0.0,
                unknowns: 0,
                nonzeros: 0,
            });
        }
        let matrix = split.free_block(&system.matrix);
        let diffusion = split.free_block(&system.diffusion);
        let rhs = split.reduced_rhs(&system.matrix, &system.rhs, &system.fixed);
        let (free, iterations, relative_residual) =
            solve_system(&matrix, Some(&diffusion), &rhs, &self.solver)?;
        Ok(NodalSolution {
            values: split.lift(&free, &system.fixed),
            peclet: system.peclet,
            tau_max,
            iterations,
            relative_residual,
            unknowns: matrix.nrows(),
            nonzeros: matrix.compute_nnz(),
        })
    }

    /// Step M_m u̇ + M u = b from u(0) = `initial` with the θ-scheme:
    ///
    /// ```text
    ///     (M_m/Δt + θ M) u^{k+1} = (M_m/Δt − (1 − θ) M) u^k + b
    /// ```
    ///
    /// with M_m the Petrov–Galerkin mass ∫ u̇ (w + τ_T v·∇w) (consistent,
    /// with the steady τ_T), the Dirichlet vertices held at their values
    /// from the first level on, and the step matrix — one canonical
    /// operator, the sum (1/Δt) M_m + θ δ⁰ᵀΩ_Kδ⁰ + θ PᵀΩ_vP — factorised
    /// once (LU) or solved by the Krylov method of [`NodalTransport::solver`]
    /// at every step (the multigrid preconditioner needs the diffusion
    /// part alone and is refused here). θ = 1 is backward Euler; θ < 1/2
    /// is only conditionally stable, which is not checked. Levels are kept
    /// every `keep_every` steps and at the last.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::transport::nodal::NodalTransport;
    /// use hasse_solver::physics::{BoundaryKind, Conductivity};
    /// use std::sync::Arc;
    /// // u = 2 everywhere and on the inflow side stays 2 (M 1 = 0).
    /// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let run = NodalTransport::new(Conductivity::Scalar(Arc::new(|_| 0.01)),
    ///     Arc::new(|_| [1.0, 0.0, 0.0]), Arc::new(|_| 0.0))
    ///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 2.0)))
    ///     .solve_transient(&mesh, &|_| 2.0, 0.1, 5, 1.0, 5)
    ///     .unwrap();
    /// assert_eq!(run.levels.len(), 2);
    /// assert!(run.levels[1].1.iter().all(|u| (u - 2.0).abs() < 1e-14));
    /// ```
    #[allow(clippy::too_many_arguments)]
    pub fn solve_transient(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        dt: f64,
        steps: usize,
        theta: f64,
        keep_every: usize,
    ) -> Result<NodalTransient, TransportError> {
        if !(dt > 0.0 && dt.is_finite() && (0.0..=1.0).contains(&theta) && steps >= 1) {
            return Err(TransportError::Stepping { dt, steps, theta });
        }
        if matches!(
            self.solver,
            LinearSolver::Krylov {
                preconditioner: super::KrylovPreconditioner::DiffusionMultigrid(_),
                ..
            }
        ) {
            return Err(TransportError::NoDiffusion);
        }
        let system = self.assemble(complex)?;
        let mut u = Vec::with_capacity(complex.cell_count(0));
        for v in 0..complex.cell_count(0) {
            let x = complex.vertices().point(v);
            let value = match system.fixed[v] {
                Some(g) => g,
                None => initial(x),
            };
            if !value.is_finite() {
                return Err(TransportError::NonFiniteData {
                    what: "the initial value",
                    point: x.to_vec(),
                });
            }
            u.push(value);
        }
        let step = Canonical::sum(&[
            (1.0 / dt, &system.mass_operator),
            (theta, &system.diffusion_operator),
            (theta, &system.advection_operator),
        ])?
        .assemble();
        let split = FixedSplit::new(&system.fixed);
        let free = split.free_block(&step);
        let factor = match (&self.solver, free.nrows()) {
            (LinearSolver::Lu, rows) if rows > 0 => Some(
                direct::DirectSolver::analyze(free.as_ref(), Factorization::Lu)?
                    .factorize(free.as_ref())?,
            ),
            _ => None,
        };
        let keep_every = keep_every.max(1);
        let mut levels = vec![(0.0, u.clone())];
        for k in 1..=steps {
            // (M_m/Δt − (1 − θ) M) u^k + b, by the operators' products.
            let mass = system.mass_operator.apply(&u);
            let diffusion = system.diffusion_operator.apply(&u);
            let advection = system.advection_operator.apply(&u);
            let rhs: Vec<f64> = (0..u.len())
                .map(|i| {
                    mass[i] / dt - (1.0 - theta) * (diffusion[i] + advection[i]) + system.rhs[i]
                })
                .collect();
            let reduced = split.reduced_rhs(&step, &rhs, &system.fixed);
            let x = match &factor {
                Some(factor) => factor.solve(&reduced)?,
                None if reduced.is_empty() => Vec::new(),
                None => solve_system(&free, None, &reduced, &self.solver)?.0,
            };
            u = split.lift(&x, &system.fixed);
            if k % keep_every == 0 || k == steps {
                levels.push((k as f64 * dt, u.clone()));
            }
        }
        Ok(NodalTransient {
            levels,
            peclet: system.peclet,
            tau_max: system.tau.iter().copied().fold(0.0, f64::max),
        })
    }

    /// The checks before solving: the assembly, without the solve (tags,
    /// conductivity, source, velocity, a Dirichlet or Robin boundary).
    pub fn check_data(&self, complex: &Complex) -> Result<(), TransportError> {
        self.assemble(complex).map(|_| ())
    }
}

/// An advection metric's error in the problem's terms.
fn advection_error(error: AdvectionError) -> TransportError {
    match error {
        AdvectionError::NonFiniteVelocity { point, .. } => {
            TransportError::NonFiniteVelocity { point }
        }
        AdvectionError::Metric(MetricError::NonFiniteSource { point, .. }) => {
            TransportError::NonFiniteData {
                what: "the source",
                point,
            }
        }
        AdvectionError::Metric(e) => TransportError::Diffusion(DiffusionError::from(e)),
    }
}
