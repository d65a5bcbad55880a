//! The assembled steady system M u = b and its solve (LU or Krylov).

use super::flux::{Advection, Inflow};
use super::{
    KrylovMethod, KrylovPreconditioner, LinearSolver, Peclet, Transport, TransportError,
    TransportSolution,
};
use crate::la::direct::{self, Factorization};
use crate::la::iterative::{Preconditioner, RowMatrix};
use crate::la::krylov::{bicgstab, gmres, rows_of, Ilu0};
use crate::multigrid::Multigrid;
use crate::physics::diffusion::CellCoefficients;
use faer::sparse::SparseColMat;
use hasse_complex::Complex;

/// The discrete problem V u̇ + M u = b on the top cells, with its parts.
#[derive(Clone, Debug)]
pub struct TransportSystem {
    /// M = Aᵀ Ω_K A + ∂ₙᵀ diag(F) U (cells × cells).
    pub matrix: SparseColMat<usize, f64>,
    /// The diffusion part Aᵀ Ω_K A alone (`None` for pure advection).
    pub diffusion: Option<SparseColMat<usize, f64>>,
    /// b: the source, the diffusion's boundary data and the inflow
    /// Σ |F| g of the Dirichlet inflow faces.
    pub rhs: Vec<f64>,
    /// The part of b that the limited scheme recomputes itself (the
    /// inflow's, which it keeps as face values): b − inflow.
    pub rhs_without_inflow: Vec<f64>,
    /// F_f on every (n−1)-cell.
    pub face_flux: Vec<f64>,
    /// |c| of every top cell.
    pub volume: Vec<f64>,
    /// Σ of the flux leaving every cell.
    pub outflow: Vec<f64>,
    /// Cell Péclet numbers.
    pub peclet: Peclet,
    pub(super) inflow: Vec<Inflow>,
}

impl Transport {
    /// Assemble M and b.
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// use hasse_solver::physics::transport::{FaceFlux, Transport};
    /// use hasse_solver::physics::BoundaryKind;
    /// use std::sync::Arc;
    /// // Pure advection with v = 2 on 4 cells of [0, 1]: M is the upwind
    /// // difference 2 (u_i − u_{i−1}), the inflow 2 g on the first cell.
    /// let mesh = interval(4, 0.0, 1.0).unwrap();
    /// let system = Transport::new(None, FaceFlux::Velocity(Arc::new(|_| [2.0, 0.0, 0.0])), Arc::new(|_| 0.0))
    ///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 3.0)))
    ///     .assemble(&mesh)
    ///     .unwrap();
    /// let m = system.matrix.to_dense();
    /// for i in 0..4 {
    ///     assert_eq!(m[(i, i)], 2.0);
    ///     if i > 0 { assert_eq!(m[(i, i - 1)], -2.0); }
    /// }
    /// assert_eq!(system.rhs, vec![6.0, 0.0, 0.0, 0.0]);
    /// ```
    pub fn assemble(&self, complex: &Complex) -> Result<TransportSystem, TransportError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let cells = complex.cell_count(n);
        let advection: Advection = self.advection(complex)?;
        let operator = advection.operator(complex)?;
        let upwind = operator.assemble();
        let volume = complex.measure(n).to_vec();
        let (matrix, diffusion, mut rhs, k) = match self.diffusion() {
            Some(problem) => {
                let assembled = problem.assemble(complex)?;
                let k = match problem.cell_coefficients(complex)? {
                    CellCoefficients::Scalar(v) => v,
                    CellCoefficients::Tensor(t) => t
                        .iter()
                        .map(|t| (0..d).map(|i| t[i][i]).fold(0.0f64, f64::max))
                        .collect(),
                };
                let sum = faer::sparse::ops::add(assembled.matrix.as_ref(), upwind.as_ref())
                    .map_err(|_| direct::SolveError::OutOfMemory)?;
                (sum, Some(assembled.matrix), assembled.rhs, Some(k))
            }
            None => {
                let centre = complex.centroid(n);
                let mut rhs = vec![0.0; cells];
                for (c, b) in rhs.iter_mut().enumerate() {
                    let x = &centre[c * d..(c + 1) * d];
                    let f = (self.source)(x);
                    if !f.is_finite() {
                        return Err(TransportError::NonFiniteData {
                            what: "the source",
                            point: x.to_vec(),
                        });
                    }
                    *b = f * volume[c];
                }
                (upwind, None, rhs, None)
            }
        };
        let rhs_without_inflow = rhs.clone();
        for (b, l) in rhs.iter_mut().zip(advection.inflow_load(cells)) {
            *b += l;
        }
        let peclet = advection.peclet(complex, k.as_deref());
        let outflow = advection.outflow(complex);
        Ok(TransportSystem {
            matrix,
            diffusion,
            rhs,
            rhs_without_inflow,
            face_flux: advection.flux,
            volume,
            outflow,
            peclet,
            inflow: advection.inflow,
        })
    }

    /// The checks an assembly makes before building a matrix: the face
    /// fluxes (finite), a Dirichlet value on every inflow face, the
    /// diffusion's data (conductivity, source) or, without diffusion, the
    /// source at the centroids. The errors are those of
    /// [`Transport::assemble`].
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::transport::{FaceFlux, Transport, TransportError};
    /// use std::sync::Arc;
    /// // Flow along +x enters through the left side, which has no condition.
    /// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let problem = Transport::new(None, FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])), Arc::new(|_| 0.0));
    /// let error = problem.check_data(&mesh).unwrap_err();
    /// assert!(matches!(error, TransportError::InflowWithoutDirichlet { condition: None, .. }));
    /// assert!(error.to_string().starts_with("flow enters the domain through face"));
    /// ```
    pub fn check_data(&self, complex: &Complex) -> Result<(), TransportError> {
        self.advection(complex)?;
        match self.diffusion() {
            Some(problem) => problem.check_data(complex)?,
            None => {
                let n = complex.dim();
                let d = complex.embedding_dim();
                for x in complex.centroid(n).chunks(d) {
                    if !(self.source)(x).is_finite() {
                        return Err(TransportError::NonFiniteData {
                            what: "the source",
                            point: x.to_vec(),
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// Solve the steady problem M u = b.
    pub fn solve(&self, complex: &Complex) -> Result<TransportSolution, TransportError> {
        let system = self.assemble(complex)?;
        let (values, iterations, relative_residual) = solve_system(
            &system.matrix,
            system.diffusion.as_ref(),
            &system.rhs,
            &self.solver,
        )?;
        Ok(TransportSolution {
            values,
            unknowns: system.matrix.nrows(),
            nonzeros: system.matrix.compute_nnz(),
            face_flux: system.face_flux,
            peclet: system.peclet,
            iterations,
            relative_residual,
        })
    }
}

type Solved = (Vec<f64>, Option<crate::la::iterative::CgReport>, f64);

/// The preconditioner of a Krylov solve of `rows`, with `diffusion` the
/// symmetric part a multigrid preconditioner is built from.
pub(super) fn preconditioner(
    rows: &RowMatrix,
    diffusion: Option<&SparseColMat<usize, f64>>,
    kind: &KrylovPreconditioner,
) -> Result<Box<dyn Preconditioner>, TransportError> {
    Ok(match kind {
        KrylovPreconditioner::Ilu0 => Box::new(Ilu0::new(rows)?),
        KrylovPreconditioner::DiffusionMultigrid(options) => {
            let diffusion = diffusion.ok_or(TransportError::NoDiffusion)?;
            Box::new(Multigrid::algebraic(
                RowMatrix::from_symmetric(diffusion)?,
                options,
            )?)
        }
    })
}

/// Solve `matrix` x = `rhs` with `solver` (`diffusion`: the symmetric part
/// for a multigrid preconditioner).
pub(super) fn solve_system(
    matrix: &SparseColMat<usize, f64>,
    diffusion: Option<&SparseColMat<usize, f64>>,
    rhs: &[f64],
    solver: &LinearSolver,
) -> Result<Solved, TransportError> {
    match solver {
        LinearSolver::Lu => {
            let (x, report) = direct::solve(matrix, rhs, Factorization::Lu)?;
            Ok((x, None, report.relative_residual))
        }
        LinearSolver::Krylov {
            method,
            options,
            preconditioner: kind,
        } => {
            let rows = rows_of(matrix)?;
            let b = preconditioner(&rows, diffusion, kind)?;
            let (x, report) = match method {
                KrylovMethod::Bicgstab => bicgstab(&rows, rhs, None, options, b.as_ref())?,
                KrylovMethod::Gmres => gmres(&rows, rhs, None, options, b.as_ref())?,
            };
            Ok((x, Some(report), report.relative_residual))
        }
    }
}
