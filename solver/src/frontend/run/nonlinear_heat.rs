//! Running a nonlinear heat case (`kind = "heat"` with a conductivity that
//! uses `u`, or a `reaction`): the library's θ-scheme with Newton's (or
//! Picard's) iteration in every step
//! ([`NonlinearDiffusion::solve_transient_with`]), the source and boundary
//! values at the θ-scheme's times, and the levels, errors and summary of a
//! linear heat run with the iterations per step added.
//!
//! Nothing is streamed: a step that does not converge fails the run before
//! any level is written, so a failed run leaves no output file.

use super::heat::{errors_per_level, time_fn};
use super::nonlinear::{coefficient, monitor_figures, options};
use super::{diffusion_error, Keys, RunError, RunResult};
use crate::frontend::case::{BoundaryKindSpec, Case, Coefficient, HeatSpec};
use crate::frontend::output::Cochain;
use crate::la::direct::Factorization;
use crate::physics::diffusion::Errors;
use crate::physics::heat::HeatBoundary;
use crate::physics::nonlinear::{
    self, NonlinearDiffusion, NonlinearError, Step, TimeStepping, TransientData,
};
use hasse_complex::Complex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Whether the heat case is nonlinear: a reaction, or a scalar
/// conductivity that uses u.
pub(super) fn is_nonlinear(spec: &HeatSpec) -> bool {
    spec.reaction.is_some()
        || matches!(&spec.conductivity, Coefficient::Scalar(k) if k.uses_solution())
}

fn keys(spec: &HeatSpec) -> Keys<'_> {
    Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    }
}

/// The library's problem (k, r, method, iteration settings) and its data
/// in t; the monitor numbers the steps (a step's iteration 0 starts it).
fn problem(case: &Case, spec: &HeatSpec) -> Result<(NonlinearDiffusion, TransientData), RunError> {
    let Coefficient::Scalar(k) = &spec.conductivity else {
        return Err(RunError::input_at(
            case,
            "problem.conductivity",
            "a nonlinear problem takes a scalar conductivity",
            None,
        ));
    };
    let mut problem = NonlinearDiffusion::new(
        spec.method,
        coefficient(case, "problem.conductivity", k)?,
        Arc::new(|_| 0.0),
    );
    if let Some(r) = &spec.reaction {
        problem = problem.with_reaction(coefficient(case, "problem.reaction", r)?);
    }
    let settings = &case.solver.nonlinear;
    let monitor: Option<nonlinear::Monitor> = settings.monitor.then(|| {
        let name = settings.iteration.name();
        let step_number = AtomicUsize::new(0);
        let monitor: nonlinear::Monitor = Arc::new(move |step: &Step| {
            if step.iteration == 0 {
                step_number.fetch_add(1, Ordering::Relaxed);
            }
            eprintln!(
                "step {} {name} {}",
                step_number.load(Ordering::Relaxed),
                monitor_figures(step)
            );
        });
        monitor
    });
    problem.options = options(settings, monitor);
    let data = TransientData {
        start: spec.time.start,
        source: time_fn(&spec.source),
        boundary: spec
            .boundary
            .iter()
            .map(|b| {
                let kind = match &b.kind {
                    BoundaryKindSpec::Dirichlet(v) => HeatBoundary::Dirichlet(time_fn(v)),
                    BoundaryKindSpec::Neumann(v) => HeatBoundary::Neumann(time_fn(v)),
                    // Refused by the reader and by the library's check.
                    BoundaryKindSpec::Robin { alpha, value } => HeatBoundary::Robin {
                        alpha: super::scalar_fn(alpha),
                        value: time_fn(value),
                    },
                };
                (b.tag.clone(), kind)
            })
            .collect(),
    };
    Ok((problem, data))
}

/// A library error in the case's terms: data errors at their keys (also
/// when found at a later level), stepping at `time`, a method the
/// nonlinear solve cannot take at `problem.method`, and a step that does
/// not converge as a failed solve (exit 1) with its step, time and
/// residual history.
fn nonlinear_error(case: &Case, spec: &HeatSpec, error: NonlinearError) -> RunError {
    let error = match error {
        NonlinearError::AtTimeStep { error, .. }
            if matches!(*error, NonlinearError::Diffusion(_)) =>
        {
            *error
        }
        other => other,
    };
    match error {
        NonlinearError::Diffusion(e) => diffusion_error(case, &keys(spec), e),
        NonlinearError::Unsupported { .. } => {
            RunError::input_at(case, "problem.method", error.to_string(), None).because(error)
        }
        NonlinearError::Stepping { .. } => {
            RunError::input_at(case, "time.theta", error.to_string(), Some("a nonlinear heat run steps implicitly: use θ in (0, 1] (crank-nicolson or backward-euler)".into())).because(error)
        }
        NonlinearError::NotConverged { .. } | NonlinearError::AtTimeStep { .. } => RunError::solve(
            case,
            error.to_string(),
            Some("raise [solver.nonlinear] max_iterations, or take a smaller time.dt (each step starts from the last level)".into()),
        )
        .because(error),
        NonlinearError::Canonical(_) => RunError::solve(case, error.to_string(), None).because(error),
    }
}

fn stepping(spec: &HeatSpec) -> TimeStepping {
    TimeStepping {
        dt: spec.time.dt,
        steps: spec.time.steps,
        theta: spec.time.theta,
    }
}

/// Whether level n of `steps` is written: every `save_every`-th, and the
/// first and the last always (`save_every = 0`: only those).
fn saved(n: usize, steps: usize, save_every: usize) -> bool {
    n == 0 || n == steps || (save_every > 0 && n % save_every == 0)
}

pub(super) fn solve(
    case: &Case,
    spec: &HeatSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let (problem, data) = problem(case, spec)?;
    let time = &spec.time;
    phase("time stepping (nonlinear, Newton in every step)");
    let started = Instant::now();
    let initial = |x: &[f64]| spec.initial.eval(x, time.start);
    let run = problem
        .solve_transient_with(complex, &initial, &stepping(spec), &data)
        .map_err(|e| nonlinear_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    let post = Instant::now();
    let (dim, points, weights) = super::heat::level_points(complex, spec.method.location());
    let exact = case.exact.as_ref().and_then(|e| e.solution.as_ref());
    let mut series = Vec::new();
    let mut level_errors = Vec::new();
    for (n, (t, u)) in run.levels.iter().enumerate() {
        if !saved(n, time.steps, time.save_every) {
            continue;
        }
        let mut fields =
            vec![Cochain::new("u", dim, u.clone()).with_description("the temperature")];
        if let Some(solution) = exact {
            let exact_values: Vec<f64> = points.iter().map(|x| solution.eval(x, *t)).collect();
            let (difference, l2, max) = super::weighted_errors(u, &exact_values, &weights);
            level_errors.push((*t, l2, max));
            fields.push(
                Cochain::new("u_exact", dim, exact_values)
                    .with_description("the exact solution at the unknowns' points"),
            );
            fields.push(Cochain::new("error", dim, difference).with_description("u − u_exact"));
        }
        series.push((*t, fields));
    }
    let saved_times: Vec<f64> = series.iter().map(|(t, _)| *t).collect();
    let iteration = case.solver.nonlinear.iteration;
    let total_iterations: usize = run.iterations.iter().sum();
    let max_iterations = run.iterations.iter().copied().max().unwrap_or(0);
    let end = run.levels.last().map_or(time.start, |(t, _)| *t);
    let scheme = match time.theta {
        1.0 => "backward Euler".to_string(),
        0.5 => "Crank–Nicolson".to_string(),
        t => format!("θ = {t}"),
    };
    let notes = vec![
        (
            "time".to_string(),
            format!(
                "{} steps of dt = {} from t = {} to {end} ({scheme}), {} levels saved",
                time.steps,
                time.dt,
                time.start,
                series.len()
            ),
        ),
        (
            iteration.name().to_string(),
            format!(
                "{total_iterations} iterations in {} steps ({:.1} per step, at most {max_iterations}), {} symbolic analysis of the Jacobian",
                time.steps,
                total_iterations as f64 / time.steps.max(1) as f64,
                run.symbolic_analyses,
            ),
        ),
    ];
    let mut report = serde_json::Map::new();
    report.insert(
        "time".into(),
        serde_json::json!({
            "dt": time.dt,
            "theta": time.theta,
            "start": time.start,
            "steps": time.steps,
            "saved_times": saved_times,
        }),
    );
    report.insert(
        "nonlinear".into(),
        serde_json::json!({
            "method": iteration.name(),
            "iterations_per_step": run.iterations,
            "total": total_iterations,
            "max": max_iterations,
            "residuals_per_step": run.histories,
            "symbolic_analyses": run.symbolic_analyses,
        }),
    );
    if let Some(errors) = errors_per_level(&level_errors) {
        report.insert("errors_per_level".into(), errors);
    }
    let errors = level_errors
        .last()
        .map(|&(_, l2, max)| Errors::sampled(l2, max));
    let fields = series.last().map(|(_, f)| f.clone()).unwrap_or_default();
    Ok(RunResult {
        problem: "heat (nonlinear)".into(),
        method: Some(spec.method.name().into()),
        unknowns: run.levels.first().map_or(0, |(_, u)| u.len()),
        fields,
        errors,
        flux_error: None,
        relative_residual: None,
        factorization: Some(Factorization::Lu),
        ordering: None,
        timings: vec![
            ("time stepping (assembly + Newton)".to_string(), total),
            ("post-processing".to_string(), post.elapsed().as_secs_f64()),
        ],
        warnings: Vec::new(),
        pure_neumann: false,
        series,
        notes,
        report,
    })
}

/// The checks of a nonlinear heat case that need the mesh, without
/// stepping: θ and Δt, the method's Ω on this mesh (diagonal), boundary
/// tags, and the data at t₀ where the load evaluates them.
pub(super) fn check(case: &Case, spec: &HeatSpec, complex: &Complex) -> Result<(), RunError> {
    let TimeStepping { dt, steps, theta } = stepping(spec);
    if !(theta > 0.0 && theta <= 1.0) {
        return Err(nonlinear_error(
            case,
            spec,
            NonlinearError::Stepping { dt, steps, theta },
        ));
    }
    let (problem, data) = problem(case, spec)?;
    data.problem_at(&problem, spec.time.start)
        .check_data(complex)
        .map_err(|e| nonlinear_error(case, spec, e))
}
