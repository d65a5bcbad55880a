//! Running a transport case (`kind = "transport"`): the library's
//! advection–diffusion problem from the case, steady or stepped in time,
//! with u per cell and the face fluxes as output and the cell Péclet and
//! Courant numbers in the summary; or, with `method = "fe"`, steady on
//! nodal elements (Galerkin or SUPG) with u per vertex and the element
//! Péclet number and largest τ in the summary.

use super::*;
use crate::frontend::case::{SolverKind, TransportSpec};
use crate::la::krylov::KrylovOptions;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::Method;
use crate::multigrid::MultigridOptions;
use crate::physics::transport::nodal::{NodalTransport, Stabilisation};
use crate::physics::transport::{
    FaceFlux, KrylovMethod, KrylovPreconditioner, LinearSolver, Peclet, Scheme, TimeStepping,
    Transport, TransportError,
};

fn problem(case: &Case, spec: &TransportSpec) -> Result<Transport, RunError> {
    let velocity = vector_fn(&spec.velocity);
    let mut problem = Transport::new(
        spec.conductivity.as_ref().map(conductivity),
        FaceFlux::Velocity(velocity),
        scalar_fn(&spec.source),
    );
    for b in &spec.boundary {
        problem = problem.with_boundary(&b.tag, super::boundary_kind(&b.kind));
    }
    let options = KrylovOptions {
        tolerance: case.solver.tolerance,
        ..KrylovOptions::default()
    };
    let preconditioner = if case.solver.multigrid_preconditioner {
        if spec.conductivity.is_none() {
            return Err(RunError::input_at(
                case,
                "solver.preconditioner",
                TransportError::NoDiffusion.to_string(),
                Some("remove solver.preconditioner (ILU(0)), or give a conductivity".into()),
            ));
        }
        KrylovPreconditioner::DiffusionMultigrid(MultigridOptions::default())
    } else {
        KrylovPreconditioner::Ilu0
    };
    let method = match case.solver.kind {
        SolverKind::Gmres => Some(KrylovMethod::Gmres),
        SolverKind::Bicgstab => Some(KrylovMethod::Bicgstab),
        // Others are refused for transport when the case is read.
        _ => None,
    };
    problem.solver = match method {
        Some(method) => LinearSolver::Krylov {
            method,
            options,
            preconditioner,
        },
        None => LinearSolver::Lu,
    };
    Ok(problem)
}

/// A library error in the case's terms.
fn run_error(case: &Case, spec: &TransportSpec, error: TransportError) -> RunError {
    let message = error.to_string();
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    };
    match error {
        TransportError::Diffusion(e) => diffusion_error(case, &keys, e),
        TransportError::Tag(ref tag) => {
            let name = match tag {
                crate::physics::TagError::UnknownTag { tag, .. }
                | crate::physics::TagError::TagDimension { tag, .. }
                | crate::physics::TagError::InteriorFace { tag, .. } => tag.clone(),
            };
            let key = spec
                .boundary
                .iter()
                .find(|b| b.tag == name)
                .map_or_else(|| "boundary".into(), |b| format!("{}.tag", b.key));
            RunError::input_at(case, &key, message, None).because(error)
        }
        TransportError::InflowWithoutDirichlet { .. } => RunError::input_at(
            case,
            "boundary",
            message,
            Some("add a [[boundary]] with type = \"dirichlet\" on the tag of the faces where the flow enters (e.g. tag = \"xmin\" for velocity = [\"1\", \"0\"])".into()),
        )
        .because(error),
        TransportError::NonFiniteVelocity { .. } => {
            RunError::input_at(case, "problem.velocity", message, Some(FINITE_HELP.into()))
                .because(error)
        }
        TransportError::NonFiniteData { what, .. } => {
            let key = match what {
                "the source" => "problem.source",
                "the initial value" => "problem.initial",
                _ => "boundary",
            };
            RunError::input_at(case, key, message, Some(FINITE_HELP.into())).because(error)
        }
        TransportError::Courant { .. } => RunError::input_at(
            case,
            "time.dt",
            message,
            Some("a smaller time.dt, or problem.scheme = \"upwind\" with time.theta > 0 (implicit)".into()),
        )
        .because(error),
        TransportError::Stepping { .. } => {
            RunError::input_at(case, "time", message, None).because(error)
        }
        TransportError::NoFixedValue => RunError::input_at(
            case,
            "boundary",
            message,
            Some("add a [[boundary]] with type = \"dirichlet\" on the tag where the flow enters".into()),
        )
        .because(error),
        TransportError::NoDiffusion => {
            RunError::input_at(case, "solver.preconditioner", message, None).because(error)
        }
        TransportError::FluxSize { .. }
        | TransportError::Multigrid(_)
        | TransportError::Iterative(_)
        | TransportError::Canonical(_)
        | TransportError::Solve(_)
        | TransportError::Krylov(_) => RunError::solve(case, message, None).because(error),
    }
}

/// The velocity must have one component per coordinate of the mesh.
fn check_dimension(case: &Case, spec: &TransportSpec, complex: &Complex) -> Result<(), RunError> {
    let d = complex.embedding_dim();
    if spec.velocity.len() != d {
        return Err(RunError::input_at(
            case,
            "problem.velocity",
            format!(
                "the velocity has {} components, but the mesh lives in {d} dimensions",
                spec.velocity.len()
            ),
            Some(format!("give {d} expressions, one per coordinate")),
        ));
    }
    Ok(())
}

fn peclet_text(peclet: &Peclet) -> String {
    if peclet.max.is_infinite() {
        "∞ (pure advection)".into()
    } else {
        format!("{:.3e} to {:.3e}", peclet.min, peclet.max)
    }
}

/// u at t = 0 of a run in time, which the case must give.
fn initial_field(case: &Case, spec: &TransportSpec) -> Result<ScalarFn, RunError> {
    spec.initial
        .as_ref()
        .map(scalar_fn)
        .ok_or_else(|| RunError::input_at(case, "problem.initial", "missing: u at t = 0", None))
}

/// The smallest and largest value of the last saved level ((0, 0) when
/// none was saved), for the summary's maximum-principle line.
fn last_level_range(levels: &[(f64, Vec<f64>)]) -> (f64, f64) {
    levels
        .last()
        .map(|(_, u)| {
            u.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                })
        })
        .unwrap_or((0.0, 0.0))
}

/// The parts every transport run's result shares: the method, the
/// unknowns, whether LU factorised the system, and the one timing; the
/// caller fills in what it computed.
fn transport_result(method: &str, unknowns: usize, lu: bool, timing: (&str, f64)) -> RunResult {
    RunResult {
        problem: "transport".into(),
        method: Some(method.into()),
        unknowns,
        fields: Vec::new(),
        errors: None,
        flux_error: None,
        relative_residual: None,
        factorization: lu.then_some(crate::la::direct::Factorization::Lu),
        ordering: None,
        timings: vec![(timing.0.into(), timing.1)],
        warnings: Vec::new(),
        pure_neumann: false,
        series: Vec::new(),
        notes: Vec::new(),
        report: serde_json::Map::new(),
    }
}

pub(super) fn solve(
    case: &Case,
    spec: &TransportSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    check_dimension(case, spec, complex)?;
    if spec.method == Method::Fe {
        return solve_nodal(case, spec, complex, phase);
    }
    let transport = problem(case, spec)?;
    let n = complex.dim();
    let started = Instant::now();
    let exact = case.exact.as_ref().and_then(|e| e.solution.as_ref());
    let points = field_points(complex, n);
    let weights = complex.measure(n).to_vec();
    let level_fields = |t: f64, u: &[f64], flux: &[f64]| {
        let mut fields = vec![
            Cochain::new("u", n, u.to_vec()).with_description("the transported quantity per cell"),
            Cochain::new("face_flux", n - 1, flux.to_vec()).with_description(
                "F = ∫ v·n over each (n−1)-cell along its orientation (the advective flux of u is F times the upwind value)",
            ),
        ];
        let mut errors = None;
        if let Some(solution) = exact {
            let exact_values: Vec<f64> = points.iter().map(|x| solution.eval(x, t)).collect();
            let (difference, l2, max) = weighted_errors(u, &exact_values, &weights);
            fields.push(
                Cochain::new("u_exact", n, exact_values)
                    .with_description("the exact solution at the centroids"),
            );
            fields.push(Cochain::new("error", n, difference).with_description("u − u_exact"));
            errors = Some(Errors::sampled(l2, max));
        }
        (fields, errors)
    };
    let mut notes = Vec::new();
    let mut warnings = Vec::new();
    let mut report = serde_json::Map::new();
    let solver_name = match &transport.solver {
        LinearSolver::Lu => "sparse LU (faer)".to_string(),
        LinearSolver::Krylov {
            method,
            preconditioner,
            ..
        } => format!("{} with {}", method.name(), preconditioner.name()),
    };
    let Some(time) = &spec.time else {
        phase("assembling and solving (transport)");
        let solution = transport
            .solve(complex)
            .map_err(|e| run_error(case, spec, e))?;
        if solution.iterations.is_none() {
            check_residual(case, solution.relative_residual, &mut warnings)?;
        }
        let total = started.elapsed().as_secs_f64();
        let (fields, errors) = level_fields(0.0, &solution.values, &solution.face_flux);
        let iterations = solution
            .iterations
            .map(|r| format!(", {} iterations", r.iterations))
            .unwrap_or_default();
        notes.push((
            "transport".to_string(),
            format!(
                "steady, upwind face values, {solver_name}{iterations}\ncell Péclet |v|h/K {}",
                peclet_text(&solution.peclet)
            ),
        ));
        report.insert(
            "transport".into(),
            serde_json::json!({
                "scheme": "upwind",
                "peclet_min": solution.peclet.min,
                "peclet_max": solution.peclet.max.is_finite().then_some(solution.peclet.max),
                "iterations": solution.iterations.map(|r| r.iterations),
            }),
        );
        return Ok(RunResult {
            fields,
            errors,
            relative_residual: Some(solution.relative_residual),
            warnings,
            notes,
            report,
            ..transport_result(
                "fv",
                solution.unknowns,
                solution.iterations.is_none(),
                ("assembly + solve", total),
            )
        });
    };
    let initial = initial_field(case, spec)?;
    let stepping = TimeStepping {
        dt: time.dt,
        steps: time.steps,
        theta: time.theta,
        scheme: spec.scheme,
        keep_every: if time.save_every == 0 {
            time.steps
        } else {
            time.save_every
        },
    };
    phase("assembling and stepping (transport)");
    let run = transport
        .solve_transient(complex, &|x| initial(x), &stepping)
        .map_err(|e| run_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    let start = time.start;
    let mut series = Vec::new();
    let mut errors = None;
    let mut level_errors = Vec::new();
    for (t, u) in &run.levels {
        if let Some(i) = u.iter().position(|v| !v.is_finite()) {
            return Err(RunError::solve(
                case,
                format!("u is not finite in cell {i} at t = {}", start + t),
                Some("take a smaller time.dt, or θ = 1".into()),
            ));
        }
        let (fields, e) = level_fields(start + t, u, &run.face_flux);
        if let Some(e) = e {
            level_errors.push((start + t, e.l2, e.max));
        }
        errors = e;
        series.push((start + t, fields));
    }
    let fields = series.last().map(|(_, f)| f.clone()).unwrap_or_default();
    let scheme = match spec.scheme {
        Scheme::Upwind if time.theta == 0.0 => "upwind, forward Euler".to_string(),
        Scheme::Upwind if time.theta == 1.0 => format!("upwind, backward Euler, {solver_name}"),
        Scheme::Upwind => format!("upwind, θ = {}, {solver_name}", time.theta),
        Scheme::Limited => "limited (Barth–Jespersen), SSP-RK2".to_string(),
    };
    let (lo, hi) = last_level_range(&run.levels);
    let first = run.mass.first().copied().unwrap_or(0.0);
    let last = run.mass.last().copied().unwrap_or(0.0);
    notes.push((
        "transport".to_string(),
        format!(
            "{} steps of dt = {} ({scheme}), {} levels saved\ncell Péclet |v|h/K {}, Courant Δt Σout F/|c| max {:.3} (cell {}), positivity number {:.3}\nmass Σ|c|u {first:.9e} → {last:.9e}, u in [{lo:.3e}, {hi:.6}] at the last level",
            time.steps,
            time.dt,
            run.levels.len(),
            peclet_text(&run.peclet),
            run.courant,
            run.courant_cell,
            run.positivity,
        ),
    ));
    if run.courant > 1.0 {
        warnings.push(format!(
            "the largest cell Courant number is {:.3} > 1: a front crosses more than one cell per step, and the implicit upwind step smears it over several cells",
            run.courant
        ));
    }
    warnings.extend(run.warnings.iter().cloned());
    report.insert(
        "transport".into(),
        serde_json::json!({
            "scheme": spec.scheme.name(),
            "theta": time.theta,
            "courant_max": run.courant,
            "positivity": run.positivity,
            "peclet_min": run.peclet.min,
            "peclet_max": run.peclet.max.is_finite().then_some(run.peclet.max),
            "mass": run.mass,
        }),
    );
    if !level_errors.is_empty() {
        report.insert(
            "errors_per_level".into(),
            level_errors
                .iter()
                .map(|&(t, l2, max)| serde_json::json!({ "time": t, "l2": l2, "max": max }))
                .collect(),
        );
    }
    let lu =
        spec.scheme == Scheme::Upwind && time.theta > 0.0 && transport.solver == LinearSolver::Lu;
    Ok(RunResult {
        fields,
        errors,
        warnings,
        series,
        notes,
        report,
        ..transport_result(
            "fv",
            complex.cell_count(n),
            lu,
            ("assembly + stepping", total),
        )
    })
}

/// What `hasse check` can refuse with the mesh: the velocity's dimension,
/// the boundary tags, an inflow face without a Dirichlet value, and data
/// that are not finite where they are evaluated.
pub(super) fn check(case: &Case, spec: &TransportSpec, complex: &Complex) -> Result<(), RunError> {
    check_dimension(case, spec, complex)?;
    if spec.method == Method::Fe {
        return nodal_problem(case, spec)?
            .check_data(complex)
            .map_err(|e| run_error(case, spec, e));
    }
    problem(case, spec)?
        .check_data(complex)
        .map_err(|e| run_error(case, spec, e))
}

/// The nodal (FE) problem of a case: the FV problem's boundary conditions
/// and linear solver, with the stabilisation.
fn nodal_problem(case: &Case, spec: &TransportSpec) -> Result<NodalTransport, RunError> {
    let fv = problem(case, spec)?;
    // The reader refuses conductivity = 0 with method = "fe".
    let Some(k) = spec.conductivity.as_ref() else {
        return Err(RunError::input_at(
            case,
            "problem.conductivity",
            "nodal finite elements (method = \"fe\") need a positive conductivity",
            None,
        ));
    };
    let mut nodal = NodalTransport::new(
        conductivity(k),
        vector_fn(&spec.velocity),
        scalar_fn(&spec.source),
    )
    .with_stabilisation(spec.stabilisation)
    .with_solver(fv.solver);
    nodal.boundary = fv.boundary;
    Ok(nodal)
}

/// A steady run on nodal elements: u per vertex, the element Péclet number
/// and τ in the summary.
fn solve_nodal(
    case: &Case,
    spec: &TransportSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let nodal = nodal_problem(case, spec)?;
    if let Some(time) = &spec.time {
        return step_nodal(case, spec, complex, &nodal, time, phase);
    }
    let started = Instant::now();
    phase("assembling and solving (transport, nodal elements)");
    let solution = nodal.solve(complex).map_err(|e| run_error(case, spec, e))?;
    let mut warnings = Vec::new();
    if solution.iterations.is_none() {
        check_residual(case, solution.relative_residual, &mut warnings)?;
    }
    let total = started.elapsed().as_secs_f64();
    let mut fields = vec![Cochain::new("u", 0, solution.values.clone())
        .with_description("the transported quantity per vertex (P1/Q1)")];
    let mut errors = None;
    if let Some(exact) = case.exact.as_ref().and_then(|e| e.solution.as_ref()) {
        let values: Vec<f64> = field_points(complex, 0)
            .iter()
            .map(|x| exact.eval(x, 0.0))
            .collect();
        let weights = lumped_vertex_volumes(complex);
        let (difference, l2, max) = weighted_errors(&solution.values, &values, &weights);
        fields.push(
            Cochain::new("u_exact", 0, values)
                .with_description("the exact solution at the vertices"),
        );
        fields.push(Cochain::new("error", 0, difference).with_description("u − u_exact"));
        errors = Some(Errors::sampled(l2, max));
    }
    let solver_name = match &nodal.solver {
        LinearSolver::Lu => "sparse LU (faer)".to_string(),
        LinearSolver::Krylov {
            method,
            preconditioner,
            ..
        } => format!("{} with {}", method.name(), preconditioner.name()),
    };
    let iterations = solution
        .iterations
        .map(|r| format!(", {} iterations", r.iterations))
        .unwrap_or_default();
    let scheme = match spec.stabilisation {
        Stabilisation::Supg => "SUPG (optimal τ)",
        Stabilisation::None => "Galerkin (no stabilisation)",
    };
    if spec.stabilisation == Stabilisation::None && solution.peclet.max > 1.0 {
        warnings.push(format!(
            "the largest element Péclet number is {:.3} > 1: plain Galerkin oscillates in layers that the mesh does not resolve; stabilisation = \"supg\" does not",
            solution.peclet.max
        ));
    }
    let notes = vec![(
        "transport".to_string(),
        format!(
            "steady, nodal elements (P1/Q1), {scheme}, {solver_name}{iterations}\nelement Péclet |v|h/(2K) {:.3e} to {:.3e}, largest τ {:.3e}",
            solution.peclet.min, solution.peclet.max, solution.tau_max
        ),
    )];
    let mut report = serde_json::Map::new();
    report.insert(
        "transport".into(),
        serde_json::json!({
            "scheme": spec.stabilisation.name(),
            "peclet_min": solution.peclet.min,
            "peclet_max": solution.peclet.max,
            "tau_max": solution.tau_max,
            "iterations": solution.iterations.map(|r| r.iterations),
        }),
    );
    Ok(RunResult {
        fields,
        errors,
        relative_residual: Some(solution.relative_residual),
        warnings,
        notes,
        report,
        ..transport_result(
            "fe",
            solution.unknowns,
            solution.iterations.is_none(),
            ("assembly + solve", total),
        )
    })
}

/// A θ-scheme run on nodal elements: u per vertex at every saved level.
fn step_nodal(
    case: &Case,
    spec: &TransportSpec,
    complex: &Complex,
    nodal: &NodalTransport,
    time: &crate::frontend::case::TimeSpec,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let initial = initial_field(case, spec)?;
    let started = Instant::now();
    phase("assembling and stepping (transport, nodal elements)");
    let keep_every = if time.save_every == 0 {
        time.steps
    } else {
        time.save_every
    };
    let run = nodal
        .solve_transient(
            complex,
            &|x| initial(x),
            time.dt,
            time.steps,
            time.theta,
            keep_every,
        )
        .map_err(|e| run_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    let exact = case.exact.as_ref().and_then(|e| e.solution.as_ref());
    let points = field_points(complex, 0);
    let weights = lumped_vertex_volumes(complex);
    let mut series = Vec::new();
    let mut errors = None;
    for (t, u) in &run.levels {
        let t = time.start + t;
        if let Some(i) = u.iter().position(|v| !v.is_finite()) {
            return Err(RunError::solve(
                case,
                format!("u is not finite at vertex {i} at t = {t}"),
                Some("take a smaller time.dt, or θ = 1".into()),
            ));
        }
        let mut fields = vec![Cochain::new("u", 0, u.clone())
            .with_description("the transported quantity per vertex (P1/Q1)")];
        if let Some(solution) = exact {
            let values: Vec<f64> = points.iter().map(|x| solution.eval(x, t)).collect();
            let (difference, l2, max) = weighted_errors(u, &values, &weights);
            fields.push(
                Cochain::new("u_exact", 0, values)
                    .with_description("the exact solution at the vertices"),
            );
            fields.push(Cochain::new("error", 0, difference).with_description("u − u_exact"));
            errors = Some(Errors::sampled(l2, max));
        }
        series.push((t, fields));
    }
    let fields = series.last().map(|(_, f)| f.clone()).unwrap_or_default();
    let (lo, hi) = last_level_range(&run.levels);
    let scheme = match spec.stabilisation {
        Stabilisation::Supg => "SUPG (optimal τ)",
        Stabilisation::None => "Galerkin (no stabilisation)",
    };
    let notes = vec![(
        "transport".to_string(),
        format!(
            "{} steps of dt = {} (nodal elements, {scheme}, θ = {}), {} levels saved\nelement Péclet |v|h/(2K) {:.3e} to {:.3e}, largest τ {:.3e}\nu in [{lo:.3e}, {hi:.6}] at the last level",
            time.steps,
            time.dt,
            time.theta,
            run.levels.len(),
            run.peclet.min,
            run.peclet.max,
            run.tau_max
        ),
    )];
    let mut report = serde_json::Map::new();
    report.insert(
        "transport".into(),
        serde_json::json!({
            "scheme": spec.stabilisation.name(),
            "theta": time.theta,
            "peclet_min": run.peclet.min,
            "peclet_max": run.peclet.max,
            "tau_max": run.tau_max,
        }),
    );
    Ok(RunResult {
        fields,
        errors,
        series,
        notes,
        report,
        ..transport_result(
            "fe",
            complex.cell_count(0),
            nodal.solver == LinearSolver::Lu,
            ("assembly + stepping", total),
        )
    })
}
