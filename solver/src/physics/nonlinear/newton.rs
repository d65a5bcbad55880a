//! The Newton (or Picard) loop with a backtracking line search, on one
//! Jacobian pattern and one symbolic LU analysis.

use super::krylov_step::KrylovState;
use super::{
    Iteration, NonlinearDiffusion, NonlinearError, NonlinearSolution, Stall, Step, System,
};
use crate::la::direct::{self, DirectSolver, Factorization, SolveReport};
use crate::la::ordering::Ordering;
use crate::operator::{BlockMetric, Canonical};
use crate::physics::diffusion::Solution;

/// Armijo constant of the line search: a step of length α is accepted
/// when it reduces ‖R‖ by at least the fraction 10⁻⁴ α.
const SUFFICIENT_DECREASE: f64 = 1e-4;
/// The line search halves α at most this many times (α ≥ 2⁻²⁰).
const HALVINGS: usize = 20;

/// The residual at one u and the parts the Jacobian reuses.
struct Evaluation {
    /// R on the free unknowns.
    residual: Vec<f64>,
    norm: f64,
    /// ‖|Aᵀ| |q| + V |r| + |b|‖ on the free unknowns.
    scale: f64,
    /// A u − w on every row.
    difference: Vec<f64>,
    /// u_F on every row.
    face_values: Vec<f64>,
    /// Ω(u)(A u − w): the flux.
    flux: Vec<f64>,
    /// F(u) = Aᵀ q + V r − b on every unknown (the steady residual,
    /// before a time step adds its terms).
    forcing: Vec<f64>,
}

/// One step of the θ-scheme V (u − u⁰)/Δt + θ F(u) + (1 − θ) F(u⁰) = 0:
/// its residual is the steady one with these terms added, and its
/// Jacobian V/Δt + θ J_F has the steady Jacobian's pattern.
pub(super) struct TimeStep<'a> {
    /// 1/Δt.
    pub(super) rate: f64,
    /// θ ∈ (0, 1].
    pub(super) theta: f64,
    /// u⁰ on every unknown.
    pub(super) previous: &'a [f64],
    /// F(u⁰) on every unknown.
    pub(super) previous_forcing: &'a [f64],
}

impl Evaluation {
    fn relative(&self) -> f64 {
        if self.scale > 0.0 {
            self.norm / self.scale
        } else {
            self.norm
        }
    }
}

fn point(points: &[f64], i: usize, d: usize) -> &[f64] {
    &points[i * d..(i + 1) * d]
}

fn evaluate(
    problem: &NonlinearDiffusion,
    system: &System,
    u: &[f64],
    step: Option<&TimeStep>,
) -> Evaluation {
    let d = system.dimension;
    let a = &*system.incidence;
    let k = &problem.conductivity.value;
    let rows = a.rows();
    let mut difference = vec![0.0; rows];
    let mut face_values = vec![0.0; rows];
    let mut flux = vec![0.0; rows];
    let mut full = vec![0.0; a.cols()];
    let mut scale = vec![0.0; a.cols()];
    for (r, row) in a.outer_iterator().enumerate() {
        let mut g = -system.ghosts[r];
        let mut sum = 0.0;
        for (j, &s) in row.iter() {
            g += f64::from(s) * u[j];
            sum += u[j];
        }
        // Two ends: their mean; one end (a cell-centred boundary face):
        // the ghost value w_F = s g_D is the Dirichlet datum on the face.
        let face = match row.nnz() {
            2 => 0.5 * sum,
            1 => row.data()[0].signum() as f64 * system.ghosts[r],
            _ => sum,
        };
        let weight = system.weights[r];
        let q = if weight == 0.0 {
            0.0
        } else {
            weight * k(face, point(&system.row_points, r, d)) * g
        };
        difference[r] = g;
        face_values[r] = face;
        flux[r] = q;
        for (j, &s) in row.iter() {
            full[j] += f64::from(s) * q;
            scale[j] += q.abs();
        }
    }
    for (j, (f, s)) in full.iter_mut().zip(scale.iter_mut()).enumerate() {
        let b = system.load[j];
        *f -= b;
        *s += b.abs();
        if let Some(reaction) = &problem.reaction {
            let r = system.volumes[j] * (reaction.value)(u[j], point(&system.unknown_points, j, d));
            *f += r;
            *s += r.abs();
        }
    }
    let forcing = full.clone();
    if let Some(step) = step {
        for (j, (f, s)) in full.iter_mut().zip(scale.iter_mut()).enumerate() {
            let stored = system.volumes[j] * (u[j] - step.previous[j]) * step.rate;
            let old = (1.0 - step.theta) * step.previous_forcing[j];
            *f = step.theta * *f + old + stored;
            *s = step.theta * *s + old.abs() + stored.abs();
        }
    }
    let residual = system.split.restrict(&full);
    let norm = residual.iter().map(|r| r * r).sum::<f64>().sqrt();
    let scale = system
        .split
        .restrict(&scale)
        .iter()
        .map(|s| s * s)
        .sum::<f64>()
        .sqrt();
    Evaluation {
        residual,
        norm: if norm.is_finite() {
            norm
        } else {
            f64::INFINITY
        },
        scale,
        difference,
        face_values,
        flux,
        forcing,
    }
}

/// Ω_J at the evaluated u: [Ω(u); ½ Ω₀ k'(u_F)(A u − w); V r'(u)].
fn jacobian_weights(
    problem: &NonlinearDiffusion,
    system: &System,
    u: &[f64],
    at: &Evaluation,
    step: Option<&TimeStep>,
) -> Vec<f64> {
    let theta = step.map_or(1.0, |s| s.theta);
    let d = system.dimension;
    let rows = system.weights.len();
    let free = system.split.free();
    let mut weights = Vec::with_capacity(2 * rows + free.len());
    for r in 0..rows {
        let x = point(&system.row_points, r, d);
        weights
            .push(theta * system.weights[r] * (problem.conductivity.value)(at.face_values[r], x));
    }
    for r in 0..rows {
        let w = match problem.options.iteration {
            Iteration::Picard => 0.0,
            Iteration::Newton => {
                let x = point(&system.row_points, r, d);
                0.5 * system.weights[r]
                    * (problem.conductivity.derivative)(at.face_values[r], x)
                    * at.difference[r]
            }
        };
        weights.push(theta * w);
    }
    for &i in free {
        let w = match &problem.reaction {
            Some(reaction) => {
                system.volumes[i] * (reaction.derivative)(u[i], point(&system.unknown_points, i, d))
            }
            None => 0.0,
        };
        let stored = step.map_or(0.0, |s| system.volumes[i] * s.rate);
        weights.push(theta * w + stored);
    }
    weights
}

/// What the iterations of a run share: the Jacobian operator (whose
/// pattern never changes) and the one LU analysis made for it.
pub(super) struct Workspace {
    jacobian: Canonical,
    analysis: Option<DirectSolver>,
    /// Newton–Krylov's kept preconditioner ([`super::NonlinearOptions::krylov`]).
    krylov: Option<KrylovState>,
    /// Symbolic analyses made so far (one per run, and one more for
    /// Newton–Krylov's preconditioner).
    pub(super) analyses: usize,
}

impl Workspace {
    pub(super) fn new(system: &System) -> Self {
        Self {
            jacobian: system.jacobian.clone(),
            analysis: None,
            krylov: None,
            analyses: 0,
        }
    }
}

/// A converged iteration.
pub(super) struct Converged {
    /// u on every unknown.
    pub(super) u: Vec<f64>,
    /// F(u) on every unknown.
    pub(super) forcing: Vec<f64>,
    /// The flux Ω(u)(A u − w).
    pub(super) flux: Vec<f64>,
    pub(super) history: Vec<f64>,
    pub(super) steps: Vec<Step>,
    /// The last linear solve, if one was needed.
    pub(super) report: Option<SolveReport>,
}

/// u on every unknown: `guess` on the free ones (zero where it has no
/// entry), the Dirichlet values on the fixed ones.
pub(super) fn lifted(system: &System, guess: Option<&[f64]>) -> Vec<f64> {
    let unknowns = system.incidence.cols();
    let guess: Vec<f64> = (0..unknowns)
        .map(|i| guess.and_then(|g| g.get(i)).copied().unwrap_or(0.0))
        .collect();
    system
        .split
        .lift(&system.split.restrict(&guess), &system.fixed)
}

/// F(u) on every unknown (the steady residual).
pub(super) fn forcing(problem: &NonlinearDiffusion, system: &System, u: &[f64]) -> Vec<f64> {
    evaluate(problem, system, u, None).forcing
}

/// Newton's (or Picard's) iteration from `u`, for the steady problem or
/// one time step.
pub(super) fn iterate(
    problem: &NonlinearDiffusion,
    system: &System,
    work: &mut Workspace,
    mut u: Vec<f64>,
    time_step: Option<&TimeStep>,
) -> Result<Converged, NonlinearError> {
    let options = &problem.options;
    let iteration = options.iteration;
    let free = system.split.free().to_vec();
    let mut at = evaluate(problem, system, &u, time_step);
    let mut history = vec![at.norm];
    let mut steps = vec![Step {
        iteration: 0,
        residual: at.norm,
        relative: at.relative(),
        step_length: 0.0,
        rate: f64::NAN,
    }];
    let report_step = |step: &Step| {
        if let Some(monitor) = &options.monitor {
            monitor(step);
        }
    };
    report_step(&steps[0]);
    let stop = |stall: Stall, history: &[f64]| NonlinearError::NotConverged {
        iteration,
        stall,
        history: history.to_vec(),
    };
    if !at.norm.is_finite() {
        return Err(stop(Stall::NonFinite, &history));
    }
    let mut report = None;
    let mut k = 0;
    while at.relative() > options.tolerance {
        if k == options.max_iterations {
            return Err(stop(Stall::MaxIterations(k), &history));
        }
        k += 1;
        let weights = jacobian_weights(problem, system, &u, &at, time_step);
        let krylov_weights =
            (options.krylov && iteration == Iteration::Newton).then(|| weights.clone());
        work.jacobian
            .set_metric(BlockMetric::from_weights(weights))?;
        let matrix = work.jacobian.assemble();
        let minus: Vec<f64> = at.residual.iter().map(|r| -r).collect();
        let krylov_delta = krylov_weights.and_then(|weights| {
            let state = work
                .krylov
                .get_or_insert_with(|| KrylovState::new(&work.jacobian, options.preconditioner));
            let eta = at.relative().clamp(1e-12, 0.1);
            let before = state.analyses;
            let step = state
                .step(&matrix, &weights, system.weights.len(), &minus, eta)
                .map(|(delta, _)| delta);
            work.analyses += state.analyses - before;
            step
        });
        let delta = match krylov_delta {
            Some(delta) => delta,
            None => {
                // The pattern never changes: analyze once (LU, since the
                // derivative of the face weights makes J unsymmetric).
                let solver = match work.analysis.take() {
                    Some(solver) => solver,
                    None => {
                        work.analyses += 1;
                        DirectSolver::analyze_pattern(
                            matrix.symbolic(),
                            Factorization::Lu,
                            Ordering::Automatic,
                        )
                        .map_err(|e| stop(Stall::Solve(e), &history))?
                    }
                };
                let solved = direct::solve_analyzed(&solver, &matrix, &minus);
                work.analysis = Some(solver);
                let (delta, solved) = solved.map_err(|e| stop(Stall::Solve(e), &history))?;
                report = Some(solved);
                delta
            }
        };
        // Backtracking: halve α until ‖R‖ decreases enough.
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..=HALVINGS {
            let mut trial = u.clone();
            for (&i, dx) in free.iter().zip(&delta) {
                trial[i] += alpha * dx;
            }
            let next = evaluate(problem, system, &trial, time_step);
            if next.norm <= (1.0 - SUFFICIENT_DECREASE * alpha) * at.norm {
                accepted = Some((trial, next));
                break;
            }
            alpha *= 0.5;
        }
        let Some((trial, next)) = accepted else {
            return Err(stop(Stall::LineSearch, &history));
        };
        let step = Step {
            iteration: k,
            residual: next.norm,
            relative: next.relative(),
            step_length: alpha,
            rate: next.norm / at.norm,
        };
        report_step(&step);
        steps.push(step);
        history.push(next.norm);
        u = trial;
        at = next;
    }
    Ok(Converged {
        u,
        forcing: at.forcing,
        flux: at.flux,
        history,
        steps,
        report,
    })
}

/// The solution in the layout of the linear diffusion's.
pub(super) fn solution(
    problem: &NonlinearDiffusion,
    system: &System,
    u: Vec<f64>,
    flux: Vec<f64>,
    report: Option<SolveReport>,
) -> Solution {
    let report = report.unwrap_or(SolveReport {
        factorization: Factorization::Lu,
        ordering: None,
        unknowns: system.split.free().len(),
        nonzeros: 0,
        symbolic_seconds: 0.0,
        numeric_seconds: 0.0,
        solve_seconds: 0.0,
        relative_residual: 0.0,
        factor_entries: None,
        factor_flops: None,
    });
    Solution {
        method: problem.method,
        location: system.location,
        values: u,
        flux,
        report,
        assembly_seconds: system.assembly_seconds,
        analyzed_during_assembly: false,
        pure_neumann: false,
        neumann_imbalance: 0.0,
        cell_points: None,
        iterations: None,
        condition_bound: f64::NAN,
    }
}

pub(super) fn solve(
    problem: &NonlinearDiffusion,
    system: &System,
) -> Result<NonlinearSolution, NonlinearError> {
    let mut work = Workspace::new(system);
    let u = lifted(system, problem.options.initial.as_deref());
    let converged = iterate(problem, system, &mut work, u, None)?;
    Ok(NonlinearSolution {
        solution: solution(
            problem,
            system,
            converged.u,
            converged.flux,
            converged.report,
        ),
        iteration: problem.options.iteration,
        history: converged.history,
        steps: converged.steps,
        symbolic_analyses: work.analyses,
    })
}
