//! Running a transient heat case: the θ-scheme of [`crate::physics::heat`] on
//! the case's mesh, the temperature written at every saved level, errors
//! against an exact u(x, t) at each of them.

use super::{conductivity, diffusion_error, scalar_fn, Keys, LevelStream, RunError, RunResult};
use crate::frontend::case::expr::Expression;
use crate::frontend::case::{BoundaryKindSpec, BoundarySpec, Case, HeatSpec};
use crate::frontend::output::Cochain;
use crate::metric::mass::lumped_vertex_volumes;
use crate::physics::diffusion::Errors;
use crate::physics::diffusion::{Iterative, Preconditioning};
use crate::physics::heat::{Adaptive, Heat, HeatBoundary, HeatError, HeatEvent, History, TimeFn};
use crate::physics::regions::Regional;
use hasse_complex::Complex;
use std::sync::Arc;
use std::time::Instant;

/// Steady data are assembled once; data that use t are re-assembled at
/// every step, so the distinction matters for speed.
pub(super) fn time_fn(e: &Expression) -> TimeFn {
    if e.uses_time() {
        let e = e.clone();
        TimeFn::Varying(Arc::new(move |x: &[f64], t: f64| e.eval(x, t)))
    } else {
        TimeFn::Steady(scalar_fn(e))
    }
}

/// `heat` with the case's boundary conditions, data in time.
pub(super) fn with_boundaries(mut heat: Heat, boundary: &[BoundarySpec]) -> Heat {
    for b in boundary {
        let kind = match &b.kind {
            BoundaryKindSpec::Dirichlet(v) => HeatBoundary::Dirichlet(time_fn(v)),
            BoundaryKindSpec::Neumann(v) => HeatBoundary::Neumann(time_fn(v)),
            BoundaryKindSpec::Robin { alpha, value } => HeatBoundary::Robin {
                alpha: scalar_fn(alpha),
                value: time_fn(value),
            },
        };
        heat = heat.with_boundary(&b.tag, kind);
    }
    heat
}

fn heat_problem(case: &Case, spec: &HeatSpec) -> Heat {
    let mut heat = Heat::new(spec.method, conductivity(&spec.conductivity), spec.time.dt)
        .with_theta(spec.time.theta)
        .with_source(time_fn(&spec.source));
    if let Some(regions) = spec.source.regions() {
        heat = heat.with_source_by_region(Regional::new(
            regions
                .pieces
                .iter()
                .map(|(name, piece)| (name.clone(), time_fn(piece)))
                .collect(),
            regions.default.as_ref().map(time_fn),
        ));
    }
    heat.start = spec.time.start;
    heat = with_boundaries(heat, &spec.boundary);
    if let Some(f) = case.solver.factorization {
        heat.factorization = f;
    }
    heat.ordering = case.solver.ordering;
    heat
}

fn run_error(case: &Case, spec: &HeatSpec, e: HeatError) -> RunError {
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    };
    let message = e.to_string();
    let located = match e {
        HeatError::Diffusion(d) => return diffusion_error(case, &keys, d),
        HeatError::NonFinite { datum, .. } => RunError::input_at(
            case,
            &keys.of(datum),
            message,
            Some(super::FINITE_HELP.into()),
        ),
        HeatError::TimeStep { .. } => RunError::input_at(case, "time.dt", message, None),
        HeatError::Theta { .. } => RunError::input_at(case, "time.theta", message, None),
        HeatError::StartTime { .. } => RunError::input_at(case, "time.start", message, None),
        HeatError::Unsupported { .. } => RunError::input_at(case, "problem.method", message, None),
        HeatError::Overflow { .. } => RunError::solve(case, message, None),
        HeatError::InitialField { .. } => RunError::input_at(case, "problem.initial.from", message, None),
        HeatError::AdaptiveTolerance { .. } | HeatError::AdaptiveTheta { .. } => {
            RunError::input_at(case, "time.adaptive", message, None)
        }
        HeatError::StepTooSmall { .. } => RunError::solve(
            case,
            message,
            Some("raise time.adaptive.tolerance, or check that the data are continuous in time".into()),
        ),
        HeatError::Cg(_) | HeatError::Multigrid(_) => RunError::solve(
            case,
            format!("solving M/Δt + θK iteratively: {message}"),
            Some("raise solver.tolerance, or use solver.type = \"direct\"".into()),
        ),
        HeatError::Solve(_) | HeatError::Canonical(_) => RunError::solve(
            case,
            format!("factorising M/Δt + θK: {message}"),
            Some("the matrix is symmetric positive definite for θ > 0 with K ≥ 0; check solver.factorization".into()),
        ),
    };
    located.because(e)
}

pub(super) fn solve(
    case: &Case,
    spec: &HeatSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    solve_streaming(case, spec, complex, phase, None)
}

/// As [`solve`], handing each saved level to `stream` as soon as it is
/// computed.
pub(super) fn solve_streaming<'a>(
    case: &'a Case,
    spec: &HeatSpec,
    complex: &'a Complex,
    phase: &mut dyn FnMut(&str),
    mut stream: Option<&mut LevelStream<'a>>,
) -> Result<RunResult, RunError> {
    // k(u) or r(u): Newton in every step, nothing streamed.
    if super::nonlinear_heat::is_nonlinear(spec) {
        return super::nonlinear_heat::solve(case, spec, complex, phase);
    }
    let mut heat = heat_problem(case, spec);
    let mut time = spec.time.clone();
    let mut restarted = None;
    if let Some(restart) = &spec.restart {
        let state = super::restart::read(case, spec, restart, complex)?;
        heat.start = state.time;
        heat.initial_field = Some(state.field);
        time.start = state.time;
        time.steps = state.steps;
        restarted = Some((state.note, state.report));
    }
    let time = &time;
    if let Some(choice) = super::diffusion::solver_choice(case)? {
        heat = heat.with_solver(choice, case.solver.tolerance, complex);
        if let Some(Iterative {
            preconditioner: Preconditioning::Multigrid { options, .. },
            ..
        }) = &mut heat.iterative
        {
            options.cell_prolongation = case.solver.cell_prolongation;
        }
    }
    if let Some(tolerance) = time.adaptive {
        heat = heat.with_adaptive(Adaptive { tolerance });
    }
    phase(if heat.iterative.is_some() {
        "assembling and setting up multigrid"
    } else {
        "assembling and factorising"
    });
    let started = Instant::now();
    let initial = |x: &[f64]| spec.initial.eval(x, time.start);
    let (dim, points, weights) = level_points(complex, heat.at(time.start).location());
    let exact = case.exact.as_ref().and_then(|e| e.solution.as_ref());
    let method = spec.method.name();
    // The fields of each level are made as it completes, so that they can
    // be written while the run goes on.
    let mut series = Vec::new();
    let mut level_errors = Vec::new();
    let mut level_quantities = Vec::new();
    let mut level_probes = Vec::new();
    let location = heat.at(time.start).location();
    let mut post_seconds = 0.0;
    let mut stream_seconds = 0.0;
    // The step before the last saved level, for the balance; fluxes at
    // every saved level when a quantity asks for one (the first failure
    // to compute them is reported after the run).
    let mut last_step: Option<(f64, Vec<f64>)> = None;
    let wants_fluxes = case
        .output
        .quantities
        .iter()
        .any(|q| q.kind == crate::frontend::case::QuantityKind::Flux);
    let mut flux_failure: Option<HeatError> = None;
    // Fluxes that leave vertices out do so at every level: warned once.
    let mut flux_warnings: Option<Vec<String>> = None;
    // Progress on long runs: at most ~100 updates, each a phase message.
    let report_every = (time.steps / 100).max(1);
    let history = heat
        .run_observed(
            complex,
            &initial,
            time.steps,
            time.save_every,
            &mut |event| match event {
                HeatEvent::Level {
                    time: t,
                    field: u,
                    previous,
                    ..
                } => {
                    let post = Instant::now();
                    if let Some((t_before, before)) = previous {
                        last_step = Some((t_before, before.to_vec()));
                    }
                    let fluxes = if wants_fluxes {
                        match heat.level_solution(complex, t, u) {
                            Ok(solution) => {
                                let problem = heat.at(t);
                                problem
                                    .boundary_outflow(complex, &solution)
                                    .and_then(|outflow| {
                                        super::quantities::flux_values(
                                            case, &problem, complex, &solution, &outflow,
                                        )
                                    })
                                    .map_err(|e| flux_failure.get_or_insert(e.into()))
                                    .ok()
                            }
                            Err(e) => {
                                flux_failure.get_or_insert(e);
                                None
                            }
                        }
                    } else {
                        None
                    };
                    if let (None, Some(f)) = (&flux_warnings, &fluxes) {
                        flux_warnings = Some(f.warnings(case, complex));
                    }
                    level_quantities.push(super::quantities::level_values(
                        case,
                        complex,
                        u,
                        location,
                        fluxes.as_ref(),
                    ));
                    level_probes.push(super::probes::probe_values(
                        case, complex, location, u, None,
                    ));
                    let mut fields = vec![
                        Cochain::new("u", dim, u.to_vec()).with_description("the temperature")
                    ];
                    if let Some(solution) = exact {
                        let exact_values: Vec<f64> =
                            points.iter().map(|x| solution.eval(x, t)).collect();
                        let (difference, l2, max) =
                            super::weighted_errors(u, &exact_values, &weights);
                        level_errors.push((t, l2, max));
                        fields.push(
                            Cochain::new("u_exact", dim, exact_values)
                                .with_description("the exact solution at the unknowns' points"),
                        );
                        fields.push(
                            Cochain::new("error", dim, difference).with_description("u − u_exact"),
                        );
                    }
                    post_seconds += post.elapsed().as_secs_f64();
                    if let Some(stream) = stream.as_deref_mut() {
                        let writing = Instant::now();
                        stream.level(complex, t, &fields, Some(method), phase);
                        stream_seconds += writing.elapsed().as_secs_f64();
                    }
                    series.push((t, fields));
                }
                HeatEvent::Step {
                    number: step,
                    time: t,
                } => {
                    if step % report_every == 0 || step == time.steps {
                        let saved = stream
                            .as_deref()
                            .and_then(|s| s.partial())
                            .filter(|p| !p.is_empty())
                            .map(|p| format!(", completed levels in {}", p.xdmf().display()))
                            .unwrap_or_default();
                        // Adaptive runs take as many steps as the control
                        // decides: only the time tells how far they are.
                        let of = if time.adaptive.is_some() {
                            String::new()
                        } else {
                            format!("/{}", time.steps)
                        };
                        phase(&format!("time step {step}{of} (t = {t:.6}){saved}"));
                    }
                }
            },
        )
        .map_err(|e| run_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    for (t, field) in history.times.iter().zip(&history.fields) {
        if let Some(i) = field.iter().position(|v| !v.is_finite()) {
            return Err(RunError::solve(
                case,
                format!(
                    "the temperature is not finite at unknown {i} at t = {t}: the θ-scheme with θ = {} is only conditionally stable",
                    time.theta
                ),
                Some("use θ ≥ 0.5 or a smaller time.dt".into()),
            ));
        }
    }

    if let Some(e) = flux_failure {
        return Err(run_error(case, spec, e));
    }

    phase("post-processing");
    let post = Instant::now();
    let balance = match (&last_step, history.times.last(), history.fields.last()) {
        (Some((t0, u0)), Some(&t1), Some(u1)) => Some(
            heat.step_balance(complex, (*t0, u0), (t1, u1))
                .map_err(|e| run_error(case, spec, e))?,
        ),
        _ => None,
    };
    let errors = level_errors
        .last()
        .map(|&(_, l2, max)| Errors::sampled(l2, max));
    let fields = series.last().map(|(_, f)| f.clone()).unwrap_or_default();
    let mut report = serde_json::Map::new();
    report.insert("time".into(), time_json(time, &history));
    if let Some(errors) = errors_per_level(&level_errors) {
        report.insert("errors_per_level".into(), errors);
    }
    let scheme = match time.theta {
        1.0 => "backward Euler".to_string(),
        0.5 => "Crank–Nicolson".to_string(),
        t => format!("θ = {t}"),
    };
    let quantities = super::quantities::heat_quantities(case, &history.times, &level_quantities);
    report.extend(quantities.report);
    let steps = match &history.adaptive {
        None => format!("{} steps of dt = {}", history.steps, time.dt),
        Some(a) => {
            let (lo, hi) = a
                .step_sizes
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), &h| {
                    (lo.min(h), hi.max(h))
                });
            format!(
                "{} adaptive steps of dt = {lo:.3e} to {hi:.3e} ({} rejected, {} step sizes set up; tolerance {:e})",
                history.steps,
                a.rejected,
                a.systems,
                time.adaptive.unwrap_or_default()
            )
        }
    };
    let setup = match &history.iterations {
        None => format!("{}: factorisation", history.solver),
        Some(_) => format!("{}: setup", history.solver),
    };
    let iterations = history
        .iterations
        .map(|i| {
            format!(
                ", {:.1} CG iterations per step (at most {})",
                i.mean(),
                i.max
            )
        })
        .unwrap_or_default();
    let mut notes = vec![(
        "time".to_string(),
        format!(
            "{steps} from t = {} to {} ({scheme}), {} levels saved\n{setup} {:.3} s, {:.3} ms per step ({:.3} ms in solves){iterations}",
            time.start,
            history.times.last().copied().unwrap_or(time.start),
            history.times.len(),
            history.factorization_seconds,
            1e3 * history.seconds_per_step,
            1e3 * history.solve_seconds_per_step,
        ),
    )];
    if let Some((note, entry)) = restarted {
        notes.insert(0, ("restart".to_string(), note));
        report.insert("restart".into(), entry);
    }
    if let Some(b) = &balance {
        notes.push((
            "balance".to_string(),
            format!(
                "last step (t = {} to {}): stored {:.6e} + outflow {:.6e} − sources {:.6e} = {:.2e}, {:.1e} of the largest term (rates; the method's own fluxes)",
                short(b.times.0), short(b.times.1), b.stored, b.outflow, b.sources, b.imbalance, b.relative
            ),
        ));
        report.insert(
            "balance".into(),
            serde_json::json!({
                "times": [b.times.0, b.times.1],
                "stored": b.stored,
                "outflow": b.outflow,
                "sources": b.sources,
                "imbalance": b.imbalance,
                "relative": b.relative,
            }),
        );
    }
    notes.extend(quantities.notes);
    let (probe_notes, probes) = super::probes::probe_report(case, &history.times, &level_probes);
    notes.extend(probe_notes);
    if let Some(probes) = probes {
        report.insert("probes".into(), probes);
    }
    let mut timings = vec![
        (
            if heat.iterative.is_some() {
                "multigrid setup".to_string()
            } else {
                "factorisation".to_string()
            },
            history.factorization_seconds,
        ),
        (
            "time stepping".to_string(),
            history.seconds_per_step * history.steps as f64,
        ),
        (
            "post-processing".to_string(),
            post_seconds + post.elapsed().as_secs_f64(),
        ),
        ("assembly + stepping".to_string(), total),
    ];
    if stream.is_some() {
        timings.insert(3, ("partial output".to_string(), stream_seconds));
    }
    Ok(RunResult {
        problem: "heat".into(),
        method: Some(spec.method.name().into()),
        unknowns: history.fields.first().map_or(0, Vec::len),
        fields,
        errors,
        flux_error: None,
        relative_residual: None,
        factorization: heat.iterative.is_none().then_some(heat.factorization),
        ordering: history.ordering,
        timings,
        warnings: {
            let mut warnings = super::consistency::diffusion_warnings(
                complex,
                spec.method,
                &spec.conductivity,
                false,
            );
            warnings.extend(flux_warnings.unwrap_or_default());
            warnings
        },
        pure_neumann: false,
        series,
        notes,
        report,
    })
}

fn time_json(time: &crate::frontend::case::TimeSpec, history: &History) -> serde_json::Value {
    serde_json::json!({
        "dt": time.dt,
        "theta": time.theta,
        "start": time.start,
        "steps": history.steps,
        "saved_times": history.times,
        "factorization_seconds": history.factorization_seconds,
        "seconds_per_step": history.seconds_per_step,
        "solve_seconds_per_step": history.solve_seconds_per_step,
        "solver": history.solver,
        "iterations": history.iterations.map(|i| serde_json::json!({
            "total": i.total, "max": i.max, "mean": i.mean(), "solves": i.solves,
        })),
        "adaptive": history.adaptive.as_ref().map(|a| serde_json::json!({
            "tolerance": time.adaptive,
            "step_sizes": a.step_sizes,
            "estimates": a.estimates,
            "rejected": a.rejected,
            "step_sizes_set_up": a.systems,
        })),
    })
}

/// The conductivity and the source at t₀ evaluated where the solve
/// evaluates them, without solving.
pub(super) fn check(case: &Case, spec: &HeatSpec, complex: &Complex) -> Result<(), RunError> {
    if super::nonlinear_heat::is_nonlinear(spec) {
        return super::nonlinear_heat::check(case, spec, complex);
    }
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    };
    if let Some(restart) = &spec.restart {
        super::restart::read(case, spec, restart, complex)?;
    }
    heat_problem(case, spec)
        .at(spec.time.start)
        .check_data(complex)
        .map_err(|e| diffusion_error(case, &keys, e))
}

/// A time with at most 10 significant digits, as a person would write it
/// (0.199 rather than 0.19900000000000012).
fn short(t: f64) -> String {
    let text = format!("{t:.10e}");
    let value: f64 = text.parse().unwrap_or(t);
    format!("{value}")
}

/// Where a heat run's unknowns sit, for its per-level errors: the
/// dimension of their cells (0 for nodal methods), their points and
/// their weights (lumped vertex volumes or cell measures).
pub(super) fn level_points(
    complex: &Complex,
    location: crate::metric::Location,
) -> (usize, Vec<Vec<f64>>, Vec<f64>) {
    let dim = if location == crate::metric::Location::Nodal {
        0
    } else {
        complex.dim()
    };
    let weights = if dim == 0 {
        lumped_vertex_volumes(complex)
    } else {
        complex.measure(dim).to_vec()
    };
    (dim, super::field_points(complex, dim), weights)
}

/// The report's `errors_per_level` of a heat run: (t, L², max) per saved
/// level that has an exact solution; `None` when none has.
pub(super) fn errors_per_level(level_errors: &[(f64, f64, f64)]) -> Option<serde_json::Value> {
    (!level_errors.is_empty()).then(|| {
        level_errors
            .iter()
            .map(|&(t, l2, max)| serde_json::json!({ "time": t, "l2": l2, "max": max }))
            .collect()
    })
}
