//! Running a nonlinear diffusion case (a conductivity that uses `u`, or a
//! `reaction`): the library's problem with k, ∂k/∂u, r, ∂r/∂u from the
//! case's expressions (the derivatives by exmex), Newton's or Picard's
//! iteration as `[solver.nonlinear]` asks, and the fields and summary lines
//! of a diffusion run.

use super::*;
use crate::frontend::case::expr::Expression;
use crate::physics::diffusion as physics;
use crate::physics::nonlinear::{
    self, FieldFn, NonlinearDiffusion, NonlinearError, NonlinearOptions, NonlinearSolution, Step,
};

fn field_fn(e: &Expression) -> FieldFn {
    let e = e.clone();
    Arc::new(move |u: f64, x: &[f64]| e.eval_with(x, 0.0, u))
}

/// c(u, x) and ∂c/∂u from one expression; the reader has checked that the
/// derivative exists, so an error here is a case changed since.
pub(super) fn coefficient(
    case: &Case,
    key: &str,
    e: &Expression,
) -> Result<nonlinear::Coefficient, RunError> {
    let derivative = e
        .derivative_u()
        .map_err(|error| RunError::input_at(case, key, error.to_string(), None))?;
    Ok(nonlinear::Coefficient::new(
        field_fn(e),
        field_fn(&derivative),
    ))
}

pub(super) fn nonlinear_problem(
    case: &Case,
    spec: &DiffusionSpec,
) -> Result<NonlinearDiffusion, RunError> {
    let Coefficient::Scalar(k) = &spec.conductivity else {
        return Err(RunError::input_at(
            case,
            "problem.conductivity",
            "a nonlinear problem takes a scalar conductivity",
            None,
        ));
    };
    if k.regions().is_some() || spec.source.regions().is_some() {
        let key = if k.regions().is_some() {
            "problem.conductivity"
        } else {
            "problem.source"
        };
        return Err(RunError::input_at(
            case,
            key,
            "values per region are not supported in a nonlinear problem",
            Some("write one expression (if(…) selects by position)".into()),
        ));
    }
    let mut problem = NonlinearDiffusion::new(
        spec.method,
        coefficient(case, "problem.conductivity", k)?,
        scalar_fn(&spec.source),
    );
    if let Some(r) = &spec.reaction {
        problem = problem.with_reaction(coefficient(case, "problem.reaction", r)?);
    }
    for b in &spec.boundary {
        problem = problem.with_boundary(&b.tag, super::boundary_kind(&b.kind));
    }
    let settings = &case.solver.nonlinear;
    let monitor: Option<nonlinear::Monitor> = settings.monitor.then(|| {
        let name = settings.iteration.name();
        let monitor: nonlinear::Monitor = Arc::new(move |step: &Step| {
            eprintln!("{name} {}", monitor_figures(step));
        });
        monitor
    });
    problem.options = options(settings, monitor);
    Ok(problem)
}

/// A monitor line's figures for one iteration: its number, the residual
/// (absolute and relative), the line search's step and the rate.
pub(super) fn monitor_figures(step: &Step) -> String {
    format!(
        "{:>3}: residual {:.3e} (relative {:.2e}), step {}, rate {}",
        step.iteration,
        step.residual,
        step.relative,
        step.step_length,
        if step.rate.is_nan() {
            "-".to_string()
        } else {
            format!("{:.3e}", step.rate)
        }
    )
}

/// The library's iteration settings from `[solver.nonlinear]`.
pub(super) fn options(
    settings: &crate::frontend::case::NonlinearSolverSpec,
    monitor: Option<nonlinear::Monitor>,
) -> NonlinearOptions {
    NonlinearOptions {
        iteration: settings.iteration,
        tolerance: settings.tolerance,
        max_iterations: settings.max_iterations,
        initial: None,
        monitor,
        krylov: settings.krylov,
        preconditioner: settings.preconditioner,
    }
}

fn keys(spec: &DiffusionSpec) -> Keys<'_> {
    Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    }
}

/// A library error in the case's terms: data errors at their keys, a
/// method the nonlinear solve cannot take at `problem.method`, and a
/// non-converging iteration as a failed solve (exit 1) with its history.
fn nonlinear_error(case: &Case, spec: &DiffusionSpec, error: NonlinearError) -> RunError {
    match error {
        NonlinearError::Diffusion(e) => diffusion_error(case, &keys(spec), e),
        NonlinearError::Unsupported { .. } => {
            RunError::input_at(case, "problem.method", error.to_string(), None).because(error)
        }
        NonlinearError::NotConverged { .. } | NonlinearError::AtTimeStep { .. } => RunError::solve(
            case,
            error.to_string(),
            Some("raise [solver.nonlinear] max_iterations, or check that a solution exists (a positive conductivity, a reaction that does not drive u away)".into()),
        )
        .because(error),
        NonlinearError::Canonical(_) | NonlinearError::Stepping { .. } => {
            RunError::solve(case, error.to_string(), None).because(error)
        }
    }
}

/// The summary line of the iteration.
fn iteration_note(solved: &NonlinearSolution) -> (String, String) {
    let last = solved.steps.last();
    (
        solved.iteration.name().to_string(),
        format!(
            "{} iterations, final residual {:.3e} (relative {:.2e}), residuals {}, {} symbolic analysis of the Jacobian",
            solved.iterations(),
            solved.final_residual(),
            last.map_or(0.0, |s| s.relative),
            nonlinear::history_text(&solved.history),
            solved.symbolic_analyses,
        ),
    )
}

pub(super) fn solve(
    case: &Case,
    spec: &DiffusionSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let problem = nonlinear_problem(case, spec)?;
    phase("assembling and solving (nonlinear)");
    let started = Instant::now();
    let solved = problem
        .solve(complex)
        .map_err(|e| nonlinear_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    let solution = &solved.solution;
    let report = &solution.report;
    let mut warnings = Vec::new();
    check_residual(case, report.relative_residual, &mut warnings)?;
    let notes = vec![iteration_note(&solved)];
    let post = Instant::now();
    let n = complex.dim();
    let field_dim = match solution.location {
        Location::Nodal => 0,
        _ => n,
    };
    let field = solution.field(complex).to_vec();
    let mut fields =
        vec![Cochain::new("u", field_dim, field.clone()).with_description("the solution")];
    match solution.location {
        Location::Nodal => fields.push(
            Cochain::new("edge_flux", 1, solution.flux.iter().map(|q| -q).collect())
                .with_description("−Ω(u) A u: the flux across each edge's dual cell, along the edge (k at the edge midpoint)"),
        ),
        _ => fields.push(
            Cochain::new("flux", n - 1, solution.flux.clone()).with_description(
                "−k(u)∇u·n through each (n−1)-cell along its orientation (k at the face value of u)",
            ),
        ),
    }
    let exact = case
        .exact
        .as_ref()
        .and_then(|e| Some((e.solution.as_ref()?, e)));
    let errors = match exact {
        None => None,
        Some((solution_fn, exact)) => {
            let u = scalar_fn(solution_fn);
            let grad: Option<VectorFn> = exact.gradient.as_ref().map(|g| vector_fn(g));
            let errors = physics::errors(complex, solution, &u, grad.as_ref());
            let exact_values: Vec<f64> = field_points(complex, field_dim)
                .iter()
                .map(|x| u(x))
                .collect();
            let difference = field
                .iter()
                .zip(&exact_values)
                .map(|(a, b)| a - b)
                .collect();
            fields.push(
                Cochain::new("u_exact", field_dim, exact_values)
                    .with_description("the exact solution at the unknowns' points"),
            );
            fields
                .push(Cochain::new("error", field_dim, difference).with_description("u − u_exact"));
            Some(errors)
        }
    };
    let mut run_report = serde_json::Map::new();
    run_report.insert(
        "nonlinear".into(),
        serde_json::json!({
            "method": solved.iteration.name(),
            "iterations": solved.iterations(),
            "residuals": solved.history,
            "step_lengths": solved.steps.iter().map(|s| s.step_length).collect::<Vec<_>>(),
        }),
    );
    let timings = vec![
        ("assembly".to_string(), solution.assembly_seconds),
        (
            "iteration (assembly + solves)".to_string(),
            total - solution.assembly_seconds,
        ),
        ("post-processing".into(), post.elapsed().as_secs_f64()),
        ("assembly + solve".into(), total),
    ];
    Ok(RunResult {
        problem: "diffusion (nonlinear)".into(),
        method: Some(spec.method.name().into()),
        unknowns: solution.unknowns(),
        fields,
        errors,
        flux_error: None,
        relative_residual: Some(report.relative_residual),
        factorization: Some(report.factorization),
        ordering: report.ordering,
        timings,
        warnings,
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report: run_report,
    })
}

/// The checks of a nonlinear case that need the mesh, without iterating:
/// the method's Ω on this mesh (diagonal: not Q1 or virtual elements),
/// boundary tags, and the source where the load evaluates it.
pub(super) fn check(case: &Case, spec: &DiffusionSpec, complex: &Complex) -> Result<(), RunError> {
    nonlinear_problem(case, spec)?
        .check_data(complex)
        .map_err(|e| nonlinear_error(case, spec, e))
}
