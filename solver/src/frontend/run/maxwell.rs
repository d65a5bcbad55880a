//! Running a Maxwell cavity case: the smallest resonant modes of
//! [`crate::physics::maxwell::Cavity`], each written as an edge cochain, their ω²
//! compared with the case's exact eigenvalues.

use super::{RunError, RunResult};
use crate::frontend::case::{Case, MaxwellSpec};
use crate::frontend::output::Cochain;
use crate::la::eigen::EigenError;
use crate::metric::Method;
use crate::physics::maxwell::{Cavity, Mass, MaxwellError};
use hasse_complex::{Complex, DualKind};
use std::time::Instant;

fn method_name(spec: &MaxwellSpec) -> String {
    let dual = Method::Dec(spec.dual).name();
    match spec.mass {
        Mass::Hodge => dual.to_string(),
        Mass::Whitney => format!("{dual}, {} mass", Mass::Whitney.name()),
    }
}

fn run_error(case: &Case, e: MaxwellError) -> RunError {
    let message = e.to_string();
    let located = match &e {
        MaxwellError::Eigen(EigenError::NotConverged { .. })
        | MaxwellError::Eigen(EigenError::Solve(_))
        | MaxwellError::Eigen(EigenError::Dense(_))
        | MaxwellError::DependentGradients(_) => RunError::solve(case, message, None),
        // The library names its own values; the help names the case keys.
        MaxwellError::NonPositiveStar { .. } => RunError::input_at(
            case,
            "problem.method",
            message,
            Some(
                "set `method = \"dec-barycentric\"`, or `mass = \"whitney\"` (simplices) under [problem]"
                    .into(),
            ),
        ),
        _ => RunError::input(case, message),
    };
    located.because(e)
}

pub(super) fn solve(
    case: &Case,
    spec: &MaxwellSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    phase("assembling curl-curl and mass");
    let started = Instant::now();
    let cavity = Cavity::new(complex, spec.dual, spec.mass).map_err(|e| run_error(case, e))?;
    let assembly_seconds = started.elapsed().as_secs_f64();
    let available = cavity.physical_count() - cavity.static_count().min(cavity.physical_count());
    if spec.modes > available {
        return Err(RunError::input_at(
            case,
            "problem.modes",
            format!(
                "{} modes asked for, but this cavity has only {available} physical modes ({} interior edges minus {} gradients of interior vertices and {} static fields)",
                spec.modes,
                cavity.unknowns(),
                cavity.gradient_count(),
                cavity.static_count()
            ),
            Some("ask for fewer or refine the mesh".into()),
        ));
    }
    phase("shift-invert eigensolve");
    let solving = Instant::now();
    let modes = cavity
        .modes(spec.modes, &cavity.default_options())
        .map_err(|e| run_error(case, e))?;
    let solve_seconds = solving.elapsed().as_secs_f64();
    let exact: &[f64] = case.exact.as_ref().map_or(&[], |e| &e.eigenvalues);
    let mut warnings = Vec::new();
    // The Whitney mass is consistent; in 2D ⋆₂ = 1/|f| needs no dual, and
    // in 3D the curl-curl's barycentric ⋆₂ is not checked here.
    if (spec.dual, spec.mass) == (DualKind::Barycentric, Mass::Hodge) {
        warnings.extend(super::consistency::maxwell_warning(complex));
    }
    if exact.len() > modes.eigenvalues.len() {
        warnings.push(format!(
            "exact.eigenvalues lists {} values; only the first {} (problem.modes) are compared",
            exact.len(),
            modes.eigenvalues.len()
        ));
    }
    let worst_residual = modes.residuals.iter().fold(0.0f64, |m, r| m.max(*r));
    let mut table = String::from(
        "  k   ω²                ω                 exact ω²          rel. error  residual",
    );
    let mut rows = Vec::new();
    for (k, (&value, &residual)) in modes.eigenvalues.iter().zip(&modes.residuals).enumerate() {
        let want = exact.get(k).copied();
        let relative = want.map(|w| (value - w).abs() / w.abs().max(f64::MIN_POSITIVE));
        table.push_str(&format!(
            "\n{:>3}   {value:<17.10e} {:<17.10e} {:<17} {:<11} {residual:.1e}",
            k + 1,
            value.max(0.0).sqrt(),
            want.map_or("—".into(), |w| format!("{w:.10e}")),
            relative.map_or("—".into(), |r| format!("{r:.3e}")),
        ));
        rows.push(serde_json::json!({
            "mode": k + 1,
            "eigenvalue": value,
            "frequency": value.max(0.0).sqrt(),
            "exact": want,
            "relative_error": relative,
            "residual": residual,
        }));
    }
    let found = modes.static_fields.len();
    if found != cavity.static_count() {
        warnings.push(format!(
            "{found} static fields found (ω² = 0 to rounding), but the cavity's β_{} = {} says there are {}",
            complex.dim() - 1,
            cavity.static_count(),
            cavity.static_count()
        ));
    }
    let mut fields: Vec<Cochain> = modes
        .static_fields
        .iter()
        .enumerate()
        .map(|(k, e)| Cochain::new(format!("static_{}", k + 1), 1, cavity.extend(e)).with_description(
            "a static field (ω² = 0): curl-free and M-orthogonal to every gradient, zero on the walls, M-normalised".to_string()
        ))
        .collect();
    fields.extend(modes
        .fields
        .iter()
        .zip(&modes.eigenvalues)
        .enumerate()
        .map(|(k, (e, value))| Cochain::new(format!("mode_{}", k + 1), 1, cavity.extend(e)).with_description(format!(
                "electric field of mode {} (ω² = {value:.10e}) as an edge cochain ∫_e E·t, zero on the walls, M-normalised",
                k + 1
            ))));
    let mut report = serde_json::Map::new();
    report.insert("modes".into(), serde_json::Value::Array(rows));
    report.insert(
        "eigensolver".into(),
        serde_json::json!({
            "shift": modes.shift,
            "basis": modes.basis,
            "solves": modes.solves,
            "gradients_deflated": cavity.gradient_count(),
        }),
    );
    report.insert(
        "static_fields".into(),
        serde_json::json!({ "found": found, "betti": cavity.static_count() }),
    );
    let mut notes = vec![
        (
            "cavity".to_string(),
            format!(
                "{} interior edges, {} interior-vertex gradients deflated, shift σ = {:.3e}, basis {}, {} solves",
                cavity.unknowns(),
                cavity.gradient_count(),
                modes.shift,
                modes.basis,
                modes.solves
            ),
        ),
        ("modes".to_string(), table),
    ];
    if cavity.static_count() > 0 || found > 0 {
        notes.insert(
            1,
            (
                "static".to_string(),
                format!(
                    "{found} static field{} (ω² = 0), β_{} = {} of the cavity ({}); the modes below are the nonzero ω²",
                    if found == 1 { "" } else { "s" },
                    complex.dim() - 1,
                    cavity.static_count(),
                    if complex.dim() == 2 { "its holes" } else { "its enclosed voids" }
                ),
            ),
        );
    }
    Ok(RunResult {
        problem: "maxwell".into(),
        method: Some(method_name(spec)),
        unknowns: cavity.unknowns(),
        fields,
        errors: None,
        flux_error: None,
        relative_residual: Some(worst_residual),
        factorization: Some(crate::la::direct::Factorization::Llt),
        ordering: None,
        timings: vec![
            ("assembly".to_string(), assembly_seconds),
            ("eigensolve".to_string(), solve_seconds),
        ],
        warnings,
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report,
    })
}
