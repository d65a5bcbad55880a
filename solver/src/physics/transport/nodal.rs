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
        let operator = Canonical::new(advection.incidence, advection.metric)?;
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
