//! Newton–Krylov steps ([`super::NonlinearOptions::krylov`]): the Newton
//! correction J δ = −R by right-preconditioned GMRES on the exact
//! Jacobian, preconditioned by one LLᵀ of its symmetric part
//! P = Aᵀ Ω(u) A + diag (the Jacobian without the face values' derivative,
//! i.e. Picard's matrix), instead of a sparse LU of J at every step.
//!
//! J − P is the derivative term ½ Aᵀ diag(k'(u_F) g_F) |A|, small where
//! k varies slowly, so GMRES needs few iterations; the factor of P is kept
//! over the steps while GMRES converges in at most [`REFACTOR_AFTER`]
//! iterations (P changes with u, slowly near the solution) and is
//! refactored (numeric only, one symbolic analysis per run) otherwise.
//! The linear tolerance is η = min(0.1, relative nonlinear residual):
//! the linear error then shrinks with ‖R‖, which keeps Newton's
//! convergence quadratic (an inexact Newton method with forcing terms
//! η_k = O(‖R_k‖), Dembo, Eisenstat and Steihaug 1982).

use super::KrylovPreconditioner;
use crate::la::direct::{DirectSolver, Factor, Factorization};
use crate::la::iterative::Preconditioner;
use crate::la::krylov::{gmres, rows_of, KrylovOptions};
use crate::multigrid::{Multigrid, MultigridOptions};
use crate::operator::{BlockMetric, Canonical};
use faer::sparse::SparseColMat;

/// Above this many GMRES iterations the kept factor of P is refreshed at
/// the next step.
pub(super) const REFACTOR_AFTER: usize = 20;

/// The same for a kept multigrid hierarchy of P, whose V-cycle is a
/// rougher approximation of P⁻¹ than the factor: GMRES needs more
/// iterations with it from the start (12–20 on 2D FV grids at the
/// tolerances Newton asks for), so only a clear rise means P has moved.
pub(super) const REBUILD_AFTER: usize = 40;

/// What approximates P⁻¹, kept over the steps.
enum Kept {
    Factor(Factor),
    Multigrid(Box<Multigrid>),
}

impl Preconditioner for Kept {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        match self {
            Kept::Factor(factor) => FactorPreconditioner(factor).apply(r, z),
            Kept::Multigrid(multigrid) => multigrid.apply(r, z),
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Kept::Factor(factor) => FactorPreconditioner(factor).name(),
            Kept::Multigrid(_) => "smoothed-aggregation V-cycle of the Jacobian's symmetric part",
        }
    }
}

/// What the Newton–Krylov steps of a run share.
pub(super) struct KrylovState {
    /// P's operator: the Jacobian's, with the derivative rows' weights 0.
    symmetric: Canonical,
    preconditioner: KrylovPreconditioner,
    analysis: Option<DirectSolver>,
    kept: Option<Kept>,
    /// GMRES iterations of the last step (refactor when above the limit).
    last_iterations: usize,
    /// Symbolic analyses of P made (one per run).
    pub(super) analyses: usize,
}

struct FactorPreconditioner<'a>(&'a Factor);

impl Preconditioner for FactorPreconditioner<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        match self.0.solve(r) {
            Ok(x) => z.copy_from_slice(&x),
            // Sizes agree by construction; an identity step keeps GMRES
            // correct (only slower) if they ever did not.
            Err(_) => z.copy_from_slice(r),
        }
    }

    fn name(&self) -> &'static str {
        "LLᵀ of the Jacobian's symmetric part"
    }
}

impl KrylovState {
    pub(super) fn new(jacobian: &Canonical, preconditioner: KrylovPreconditioner) -> Self {
        Self {
            symmetric: jacobian.clone(),
            preconditioner,
            analysis: None,
            kept: None,
            last_iterations: 0,
            analyses: 0,
        }
    }

    /// The correction δ of J δ = rhs to the relative tolerance `eta`, and
    /// the GMRES iterations; `None` when P cannot be factored by LLᵀ (not
    /// positive definite, e.g. a decreasing reaction) or GMRES does not
    /// converge: the caller then takes the direct step.
    pub(super) fn step(
        &mut self,
        jacobian: &SparseColMat<usize, f64>,
        weights: &[f64],
        rows: usize,
        rhs: &[f64],
        eta: f64,
    ) -> Option<(Vec<f64>, usize)> {
        let limit = match self.preconditioner {
            KrylovPreconditioner::Factor => REFACTOR_AFTER,
            KrylovPreconditioner::Multigrid => REBUILD_AFTER,
        };
        if self.kept.is_none() || self.last_iterations > limit {
            let mut symmetric = weights.to_vec();
            symmetric[rows..2 * rows].iter_mut().for_each(|w| *w = 0.0);
            self.symmetric
                .set_metric(BlockMetric::from_weights(symmetric))
                .ok()?;
            let p = self.symmetric.assemble();
            self.kept = Some(match self.preconditioner {
                KrylovPreconditioner::Factor => {
                    if self.analysis.is_none() {
                        self.analysis =
                            Some(DirectSolver::analyze(p.as_ref(), Factorization::Llt).ok()?);
                        self.analyses += 1;
                    }
                    Kept::Factor(self.analysis.as_ref()?.factorize(p.as_ref()).ok()?)
                }
                KrylovPreconditioner::Multigrid => Kept::Multigrid(Box::new(
                    Multigrid::algebraic(rows_of(&p).ok()?, &MultigridOptions::default()).ok()?,
                )),
            });
        }
        let kept = self.kept.as_ref()?;
        let matrix = rows_of(jacobian).ok()?;
        let options = KrylovOptions {
            tolerance: eta,
            max_iterations: 200,
            restart: 50,
        };
        let (delta, report) = gmres(&matrix, rhs, None, &options, kept).ok()?;
        self.last_iterations = report.iterations;
        Some((delta, report.iterations))
    }
}
