//! Running a `kind = "growth"` case: the growing, dividing tissue of
//! [`crate::refine::growth`] on the case's mesh, every saved level on its
//! own mesh (a series that ParaView plays), and a per-level summary of
//! cells, χ, mass and the mass balance.

use super::heat::{time_fn, with_boundaries};
use super::{conductivity, diffusion_error, Keys, RunError, RunResult};
use crate::frontend::case::{Case, GrowthSpec, Problem};
use crate::frontend::output::{
    Cochain, MeshStep, OutputError, OutputFiles, Provenance, SeriesOutput,
};
use crate::physics::heat::{Heat, SpaceTimeFn};
use crate::refine::growth::{Growth, GrowthError, GrowthStep, Tissue};
use hasse_complex::Complex;
use std::sync::Arc;
use std::time::Instant;

/// A growth run: every step's record, the saved levels (time, complex,
/// fields `c` and `amount`) and the result on the final complex.
pub struct CaseGrowth {
    /// One record per step.
    pub steps: Vec<GrowthStep>,
    /// The saved levels: t₀, every `time.save_every` steps, and the last.
    pub levels: Vec<(f64, Complex, Vec<Cochain>)>,
    /// The final complex.
    pub complex: Complex,
    /// The summary and report; its `fields` are the last level's, on
    /// [`CaseGrowth::complex`].
    pub result: RunResult,
}

/// The library's growth problem of the case on a mesh of dimension `dim`.
fn growth_problem(case: &Case, spec: &GrowthSpec, dim: usize) -> Growth {
    let mut heat = Heat::new(spec.method, conductivity(&spec.conductivity), spec.time.dt)
        .with_source(time_fn(&spec.source));
    heat.start = spec.time.start;
    heat = with_boundaries(heat, &spec.boundary);
    heat.ordering = case.solver.ordering;
    let velocity: Vec<SpaceTimeFn> = spec
        .velocity
        .iter()
        .map(|e| -> SpaceTimeFn {
            let e = e.clone();
            Arc::new(move |x: &[f64], t: f64| e.eval(x, t))
        })
        .collect();
    Growth::new(heat, velocity, spec.divide_above, spec.rule_for(dim)).with_decay(spec.decay)
}

/// A growth error as a diagnostic at the key that causes it.
fn growth_error(case: &Case, spec: &GrowthSpec, e: GrowthError) -> RunError {
    let message = e.to_string();
    match e {
        GrowthError::Diffusion(d) => {
            let keys = Keys {
                prefix: "problem".into(),
                coefficient: "conductivity",
                boundary: &spec.boundary,
            };
            diffusion_error(case, &keys, d)
        }
        GrowthError::Dimension { .. } => RunError::input_at(
            case,
            "mesh",
            message,
            Some(
                "grow an interval (a filament) or a 2D mesh such as generator = \"voronoi\"".into(),
            ),
        ),
        GrowthError::Velocity { expected, .. } => RunError::input_at(
            case,
            "growth.velocity",
            message,
            Some(format!("give {expected} expression(s), one per coordinate")),
        ),
        GrowthError::Threshold(_) => RunError::input_at(case, "growth.divide_above", message, None),
        GrowthError::Rule { .. } => RunError::input_at(case, "growth.rule", message, None),
        GrowthError::Method(_) => RunError::input_at(case, "problem.method", message, None),
        GrowthError::Decay(_) => RunError::input_at(case, "problem.decay", message, None),
        GrowthError::TimeStep(_) => RunError::input_at(case, "time.dt", message, None),
        GrowthError::NonFiniteVelocity { .. } => RunError::input_at(
            case,
            "growth.velocity",
            message,
            Some(super::FINITE_HELP.into()),
        ),
        GrowthError::Inverted { .. } => RunError::input_at(
            case,
            "time.dt",
            message,
            Some("a vertex may move less than its cells' size in one step".into()),
        ),
        GrowthError::TooManyCells { .. } => RunError::input_at(
            case,
            "growth.divide_above",
            message,
            Some("raise growth.divide_above, or shorten the run (time.end)".into()),
        ),
        GrowthError::Heat(_)
        | GrowthError::Complex(_)
        | GrowthError::Split(_)
        | GrowthError::Amounts { .. }
        | GrowthError::Assembly(_) => RunError::solve(case, message, None),
    }
}

/// What `hasse check` refuses once the mesh exists: a mesh that cannot
/// grow (3D, or not filling its space), a velocity of the wrong length, a
/// rule for the other dimension, and data that do not evaluate.
pub(super) fn check(case: &Case, spec: &GrowthSpec, complex: &Complex) -> Result<(), RunError> {
    let growth = growth_problem(case, spec, complex.dim());
    growth
        .check(complex)
        .map_err(|e| growth_error(case, spec, e))?;
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    };
    growth
        .heat
        .at(spec.time.start)
        .check_data(complex)
        .map_err(|e| diffusion_error(case, &keys, e))
}

/// The fields of a level: the concentration and the amount per cell.
fn level_fields(case: &Case, tissue: &Tissue) -> Vec<Cochain> {
    let n = tissue.complex.dim();
    let method = case.method().map(|m| m.name());
    [
        Cochain::new("c", n, tissue.concentration())
            .with_description("the morphogen's concentration (amount / cell measure)"),
        Cochain::new("amount", n, tissue.amount.clone())
            .with_description("the morphogen's amount in each cell (∫ c)"),
    ]
    .into_iter()
    .filter(|c| case.output.keeps(&c.name))
    .map(|c| match method {
        Some(m) => c.with_method(m),
        None => c,
    })
    .collect()
}

/// Grow the case's tissue from `complex` for `time.steps` steps.
pub fn grow_case(
    case: &Case,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<CaseGrowth, RunError> {
    let Problem::Growth(spec) = &case.problem else {
        return Err(RunError::input_at(
            case,
            "problem.kind",
            format!(
                "a growth run needs kind = \"growth\"; this case is kind = \"{}\"",
                case.problem.kind()
            ),
            None,
        ));
    };
    check(case, spec, complex)?;
    let growth = growth_problem(case, spec, complex.dim());
    let time = &spec.time;
    let initial = spec.initial.clone();
    let started = Instant::now();
    let mut levels: Vec<(f64, Complex, Vec<Cochain>)> = Vec::new();
    let mut saved_steps: Vec<usize> = vec![0];
    let mut last: Option<Complex> = None;
    let mut start_mass = 0.0;
    let mut start_cells = 0;
    let steps = growth
        .run(
            complex,
            &move |x: &[f64]| initial.eval(x, time.start),
            time.steps,
            &mut |tissue, record| {
                let k = record.map_or(0, |r| r.number);
                if k == 0 {
                    start_mass = tissue.mass();
                    start_cells = tissue.complex.cell_count(tissue.complex.dim());
                } else {
                    phase(&format!("step {k} of {}", time.steps));
                }
                let save =
                    k == 0 || k == time.steps || (time.save_every > 0 && k % time.save_every == 0);
                if save {
                    if k > 0 {
                        saved_steps.push(k);
                    }
                    levels.push((
                        tissue.time,
                        tissue.complex.clone(),
                        level_fields(case, tissue),
                    ));
                }
                if k == time.steps {
                    last = Some(tissue.complex.clone());
                }
            },
        )
        .map_err(|e| growth_error(case, spec, e))?;
    let seconds = started.elapsed().as_secs_f64();
    let final_complex = last.unwrap_or_else(|| complex.clone());
    let n = final_complex.dim();
    let fields = levels.last().map(|(_, _, f)| f.clone()).unwrap_or_default();
    let worst = steps.iter().map(|s| s.relative).fold(0.0, f64::max);
    let solver_worst = steps.iter().map(|s| s.solver_residual).fold(0.0, f64::max);
    let mut table = String::from("step        t   cells   χ        size          mass   balance\n");
    let row = |k: usize, t: f64, cells: usize, chi: i64, size: f64, mass: f64, bal: String| {
        format!("{k:>4} {t:>8.4} {cells:>7} {chi:>3} {size:>11.6} {mass:>13.6e}   {bal}\n")
    };
    table.push_str(&row(
        0,
        time.start,
        start_cells,
        complex.euler_characteristic(),
        complex.measure(complex.dim()).iter().sum(),
        start_mass,
        "—".into(),
    ));
    for &k in saved_steps.iter().skip(1) {
        if let Some(s) = steps.get(k - 1) {
            table.push_str(&row(
                k,
                s.time,
                s.cells,
                s.euler,
                s.size,
                s.mass,
                format!("{:.1e}", s.relative),
            ));
        }
    }
    let divided: usize = steps.iter().map(|s| s.divided).sum();
    let notes = vec![
        (
            "growth".to_string(),
            format!(
                "rule {}, divide above {}, velocity [{}], decay λ = {}",
                growth.rule.name(),
                spec.divide_above,
                spec.velocity
                    .iter()
                    .map(|e| e.text().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                spec.decay
            ),
        ),
        (
            "stepping".to_string(),
            format!(
                "{} steps of dt = {} (backward Euler, LLᵀ each step), {divided} divisions, {} → {} cells",
                steps.len(),
                time.dt,
                start_cells,
                final_complex.cell_count(n)
            ),
        ),
        ("levels".to_string(), table.trim_end().to_string()),
        (
            "balance".to_string(),
            format!(
                "M^(n+1) − M^n = Δt(∫f − λM^(n+1) − outflow): worst residual {worst:.1e} relative to the largest term, over all {} steps",
                steps.len()
            ),
        ),
    ];
    let report: serde_json::Map<String, serde_json::Value> = [(
        "growth".to_string(),
        serde_json::json!({
            "rule": growth.rule.name(),
            "divide_above": spec.divide_above,
            "decay": spec.decay,
            "dt": time.dt,
            "steps": steps.iter().map(|s| serde_json::json!({
                "step": s.number,
                "time": s.time,
                "divided": s.divided,
                "cells": s.cells,
                "euler_characteristic": s.euler,
                "size": s.size,
                "mass_before": s.mass_before,
                "mass_carried": s.mass_carried,
                "mass": s.mass,
                "sources": s.sources,
                "decay": s.decay,
                "outflow": s.outflow,
                "residual": s.residual,
                "relative_residual": s.relative,
            })).collect::<Vec<_>>(),
        }),
    )]
    .into_iter()
    .collect();
    let result = RunResult {
        problem: "growth".into(),
        method: Some(spec.method.name().into()),
        // Cell averages, and fv-mimetic's face values beside them.
        unknowns: match spec.method.location() {
            crate::metric::Location::Hybrid => {
                final_complex.cell_count(n) + final_complex.cell_count(n - 1)
            }
            _ => final_complex.cell_count(n),
        },
        fields,
        errors: None,
        flux_error: None,
        relative_residual: Some(solver_worst),
        factorization: Some(crate::la::direct::Factorization::Llt),
        ordering: None,
        timings: vec![("growth".into(), seconds)],
        warnings: Vec::new(),
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report,
    };
    Ok(CaseGrowth {
        steps,
        levels,
        complex: final_complex,
        result,
    })
}

/// [`grow_case`]'s result alone (its fields live on the final complex,
/// not on `complex`: `hasse run` writes the levels with
/// [`write_series`]).
pub(super) fn solve(
    case: &Case,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    grow_case(case, complex, phase).map(|g| g.result)
}

/// Write the saved levels as a time series whose mesh changes (one h5
/// file, `<stem>.xdmf` for the series and `<stem>.level-<k>.xdmf` for each
/// level alone; see `cases/OUTPUT.md`).
pub fn write_series(
    case: &Case,
    growth: &CaseGrowth,
    report: serde_json::Value,
    stem: &std::path::Path,
) -> Result<OutputFiles, OutputError> {
    let mut provenance = Provenance::new(report);
    provenance.case_text = Some(case.text.clone());
    provenance.case_path = Some(case.path.display().to_string());
    let steps = growth
        .levels
        .iter()
        .map(|(time, complex, fields)| MeshStep {
            time: *time,
            complex,
            cochains: fields.clone(),
        })
        .collect();
    crate::frontend::output::write_mesh_series_with(
        stem,
        &SeriesOutput { steps, provenance },
        case.output.complex,
    )
}
