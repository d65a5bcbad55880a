//! The system of one step size: L = M/Δt + θK on the free unknowns, and
//! the solver that every step with that Δt reuses.
//!
//! L is the canonical operator [I; A]ᵀ diag(m/Δt, θΩ) [I; A] (the lumped
//! mass stacked on the diffusion operator), so a new step size changes Ω
//! only; the pattern of L, and with it a direct solver's symbolic
//! analysis, is the same for every Δt. A direct solve factorises L once
//! per step size; multigrid builds its levels once per step size and then
//! starts conjugate gradients at every step from the previous levels
//! (projected, see the projection module): that warm start is what makes
//! iterative stepping cheap. The solve's vectors are kept between steps.

use super::HeatError;
use crate::la::direct::{DirectSolver, Factor, Factorization, SolveError};
use crate::la::fixed::FixedSplit;
use crate::la::iterative::{preconditioned_cg_in, CgOptions, CgWork, Jacobi, RowMatrix};
use crate::la::ordering::Ordering;
use crate::multigrid::{self, Hierarchy, Multigrid, MultigridOptions};
use crate::operator::Canonical;
use crate::physics::diffusion::{Iterative, Preconditioning};
use std::time::Instant;

/// How the step systems are solved, for every step size alike.
pub(super) enum StepSolver<'a> {
    /// Factorised, all with one symbolic analysis (made by the first).
    Direct {
        /// LLᵀ, LDLᵀ, LBLᵀ or LU.
        factorization: Factorization,
        /// Its fill-reducing ordering.
        ordering: Ordering,
        /// The analysis, once the first system has been factorised.
        analysis: Option<DirectSolver>,
    },
    /// Conjugate gradients from the previous level.
    Iterative {
        /// Tolerance, iteration limit and preconditioner.
        settings: &'a Iterative,
    },
}

impl StepSolver<'_> {
    /// The fill-reducing ordering the direct solves use, once analysed.
    pub(super) fn ordering(&self) -> Option<Ordering> {
        match self {
            StepSolver::Direct { analysis, .. } => analysis.as_ref().and_then(|a| a.ordering()),
            StepSolver::Iterative { .. } => None,
        }
    }

    /// The solver's name for the summary.
    pub(super) fn name(&self) -> String {
        match self {
            StepSolver::Direct { factorization, .. } => format!("direct {factorization}"),
            StepSolver::Iterative { settings } => match &settings.preconditioner {
                Preconditioning::Jacobi => "Jacobi-preconditioned CG".into(),
                Preconditioning::Multigrid {
                    hierarchy: Hierarchy::Algebraic,
                    ..
                } => "CG with algebraic multigrid (smoothed aggregation)".into(),
                Preconditioning::Multigrid { .. } => "CG with geometric multigrid".into(),
            },
        }
    }
}

/// A step solver's own state for one Δt.
enum Solve {
    /// No free unknowns: every value is a Dirichlet value.
    Nothing,
    Factor(Factor),
    Jacobi(RowMatrix, Jacobi),
    Multigrid(Box<Multigrid>),
}

/// L = M/Δt + θK for one Δt: the coupling that lifts Dirichlet values to
/// the free rows, and the solver of its free block.
pub(super) struct StepSystem {
    /// The step size it is for.
    pub(super) dt: f64,
    lift: Vec<(usize, usize, f64)>,
    solve: Solve,
    /// Seconds spent building it (assembly, factorisation or multigrid
    /// setup).
    pub(super) setup_seconds: f64,
}

impl StepSystem {
    /// Assemble L for `dt` and prepare `solver` for it.
    pub(super) fn new(
        dt: f64,
        theta: f64,
        lumped: &Canonical,
        stiffness: &Canonical,
        split: &FixedSplit,
        solver: &mut StepSolver<'_>,
    ) -> Result<Self, HeatError> {
        let started = Instant::now();
        let matrix = Canonical::sum(&[(1.0 / dt, lumped), (theta, stiffness)])?.assemble_owned();
        let reduced = split.free_block(&matrix);
        let lift = split.coupling(&matrix);
        drop(matrix);
        let solve = if split.free().is_empty() {
            Solve::Nothing
        } else {
            match solver {
                StepSolver::Direct {
                    factorization,
                    ordering,
                    analysis,
                } => {
                    // The pattern of L does not depend on Δt: one analysis.
                    if analysis.is_none() {
                        *analysis = Some(DirectSolver::analyze_with(
                            reduced.as_ref(),
                            *factorization,
                            *ordering,
                        )?);
                    }
                    match analysis {
                        Some(a) => Solve::Factor(a.factorize(reduced.as_ref())?),
                        None => Solve::Nothing,
                    }
                }
                StepSolver::Iterative { settings } => {
                    let rows = RowMatrix::from_symmetric(&reduced).map_err(HeatError::Cg)?;
                    drop(reduced);
                    match &settings.preconditioner {
                        Preconditioning::Jacobi => {
                            let jacobi = Jacobi::new(&rows).map_err(HeatError::Cg)?;
                            Solve::Jacobi(rows, jacobi)
                        }
                        Preconditioning::Multigrid { hierarchy, options } => Solve::Multigrid(
                            Box::new(multigrid_for(rows, hierarchy, options, split)?),
                        ),
                    }
                }
            }
        };
        Ok(Self {
            dt,
            lift,
            solve,
            setup_seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// Add the Dirichlet values' part −L_{free,fixed} g to `rhs`.
    pub(super) fn lift_into(&self, fixed: &[Option<f64>], rhs: &mut [f64]) {
        FixedSplit::lift_into(&self.lift, fixed, rhs);
    }

    /// Solve L_free x = rhs. For an iterative solve `x` holds the start on
    /// entry, and `work` keeps the vectors between steps and, after the
    /// solve, its final residual. Returns the iterations taken (none for a
    /// direct solve).
    pub(super) fn solve(
        &self,
        rhs: &[f64],
        x: &mut [f64],
        options: Option<&CgOptions>,
        work: &mut CgWork,
    ) -> Result<Option<usize>, StepFailure> {
        let options = options.copied().unwrap_or_default();
        match &self.solve {
            Solve::Nothing => Ok(None),
            Solve::Factor(factor) => match factor.solve(rhs) {
                Ok(solution) => {
                    x.copy_from_slice(&solution);
                    Ok(None)
                }
                // The matrix was factorised, so a singular solve means a
                // non-finite solution: overflow of an unstable scheme.
                Err(SolveError::Singular { .. }) => Err(StepFailure::Overflow),
                Err(e) => Err(StepFailure::Error(e.into())),
            },
            Solve::Jacobi(rows, jacobi) => {
                let report = preconditioned_cg_in(rows, rhs, x, &options, jacobi, work)
                    .map_err(|e| StepFailure::Error(HeatError::Cg(e)))?;
                Ok(Some(report.iterations))
            }
            Solve::Multigrid(mg) => {
                let report = mg
                    .solve_in(rhs, x, &options, work)
                    .map_err(|e| StepFailure::Error(HeatError::Multigrid(e)))?;
                Ok(Some(report.iterations))
            }
        }
    }

    /// y = L_free x, for the iterative solvers (which keep L by rows);
    /// false for a direct or empty system, which keep no rows.
    pub(super) fn multiply(&self, x: &[f64], y: &mut [f64]) -> bool {
        match &self.solve {
            Solve::Jacobi(rows, _) => rows.multiply(x, y),
            Solve::Multigrid(mg) => mg.matrix().multiply(x, y),
            Solve::Nothing | Solve::Factor(_) => return false,
        }
        true
    }
}

/// Why a step's solve failed.
pub(super) enum StepFailure {
    /// The solution is not finite (an unstable θ < ½ scheme).
    Overflow,
    /// Anything else.
    Error(HeatError),
}

/// The multigrid preconditioner of the free block: the hierarchy's
/// prolongations for all unknowns, restricted to the free ones.
fn multigrid_for(
    rows: RowMatrix,
    hierarchy: &Hierarchy,
    options: &MultigridOptions,
    split: &FixedSplit,
) -> Result<Multigrid, HeatError> {
    let prolongations = hierarchy.prolongations(split.unknowns())?;
    let prolongations = multigrid::restrict_to_free(&prolongations, split)?;
    Ok(Multigrid::new(rows, prolongations, options)?)
}
