//! Running a Hodge Laplacian case: the kernel of Δ_k (its dimension next
//! to the Betti number it must equal) and the smallest nonzero
//! eigenvalues, each eigenvector written as a k-cochain.

use super::{RunError, RunResult};
use crate::frontend::case::{Case, HodgeSpec};
use crate::frontend::output::Cochain;
use crate::la::direct::Factorization;
use crate::la::eigen::EigenError;
use crate::physics::forms::{Boundary, FormsError};
use hasse_complex::Complex;
use std::time::Instant;

fn run_error(case: &Case, e: FormsError) -> RunError {
    let message = e.to_string();
    let located = match &e {
        FormsError::Eigen(EigenError::NotConverged { .. })
        | FormsError::Eigen(EigenError::Solve(_))
        | FormsError::Eigen(EigenError::Dense(_))
        | FormsError::Solve(_) => RunError::solve(case, message, None),
        FormsError::NonPositiveStar { .. } | FormsError::Metric(_) => RunError::input_at(
            case,
            "problem.method",
            message,
            Some("set `method = \"dec-barycentric\"` or `method = \"whitney\"` (simplices) under [problem]".into()),
        ),
        FormsError::Degree { .. } => RunError::input_at(case, "problem.degree", message, None),
        _ => RunError::input(case, message),
    };
    located.because(e)
}

pub(super) fn solve(
    case: &Case,
    spec: &HodgeSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    phase("assembling Δ_k");
    let started = Instant::now();
    let k = spec.degree;
    let stars = super::stars::read_stars(case, &spec.stars, complex)?;
    let forms = super::stars::forms_of(case, spec.method, complex, &stars)?;
    let laplacian = forms
        .hodge_laplacian(k, spec.boundary)
        .map_err(|e| run_error(case, e))?;
    let assembly_seconds = started.elapsed().as_secs_f64();
    let betti = laplacian.betti();
    let available = laplacian.unknowns().saturating_sub(betti);
    if spec.modes > available {
        return Err(RunError::input_at(
            case,
            "problem.modes",
            format!(
                "{} modes asked for, but Δ_{k} has only {available} nonzero eigenvalues ({} free {k}-cells minus a kernel of dimension {betti})",
                spec.modes,
                laplacian.unknowns()
            ),
            Some("ask for fewer or refine the mesh".into()),
        ));
    }
    phase("shift-invert eigensolve");
    let solving = Instant::now();
    let options = laplacian.default_options();
    let modes = laplacian
        .modes(spec.modes, &options)
        .map_err(|e| run_error(case, e))?;
    let solve_seconds = solving.elapsed().as_secs_f64();
    let exact: &[f64] = case.exact.as_ref().map_or(&[], |e| &e.eigenvalues);
    let mut warnings = Vec::new();
    if modes.kernel != betti {
        warnings.push(format!(
            "the kernel of Δ_{k} has dimension {} (eigenvalue 0 to rounding), but the Betti number says {betti}",
            modes.kernel
        ));
    }
    if exact.len() > modes.eigenvalues.len() {
        warnings.push(format!(
            "exact.eigenvalues lists {} values; only the first {} (problem.modes) are compared",
            exact.len(),
            modes.eigenvalues.len()
        ));
    }
    let betti_name = match spec.boundary {
        Boundary::Natural => format!("β_{k}"),
        Boundary::Essential => format!("β_{k}(K, ∂K)"),
    };
    let mut table = String::from("  j   λ                 exact λ           rel. error  residual");
    let mut rows = Vec::new();
    for (j, (&value, &residual)) in modes.eigenvalues.iter().zip(&modes.residuals).enumerate() {
        let want = exact.get(j).copied();
        let relative = want.map(|w| (value - w).abs() / w.abs().max(f64::MIN_POSITIVE));
        table.push_str(&format!(
            "\n{:>3}   {value:<17.10e} {:<17} {:<11} {residual:.1e}",
            j + 1,
            want.map_or("—".into(), |w| format!("{w:.10e}")),
            relative.map_or("—".into(), |r| format!("{r:.3e}")),
        ));
        rows.push(serde_json::json!({
            "mode": j + 1,
            "eigenvalue": value,
            "exact": want,
            "relative_error": relative,
            "residual": residual,
        }));
    }
    let mut fields: Vec<Cochain> = modes
        .harmonic
        .iter()
        .enumerate()
        .map(|(j, h)| {
            Cochain::new(format!("harmonic_{}", j + 1), k, h.clone()).with_description(format!(
                "a harmonic {k}-cochain (Δ_{k} h = 0), ⋆-orthonormal"
            ))
        })
        .collect();
    fields.extend(modes.fields.iter().zip(&modes.eigenvalues).enumerate().map(
        |(j, (u, value))| {
            Cochain::new(format!("mode_{}", j + 1), k, u.clone()).with_description(format!(
                "eigen-{k}-cochain {} of Δ_{k} (λ = {value:.10e}), ⋆-orthonormal",
                j + 1
            ))
        },
    ));
    let worst_residual = modes.residuals.iter().fold(0.0f64, |m, r| m.max(*r));
    let mut report = serde_json::Map::new();
    report.insert("modes".into(), serde_json::Value::Array(rows));
    report.insert(
        "kernel".into(),
        serde_json::json!({
            "dimension": modes.kernel,
            "betti": betti,
            "betti_kind": if spec.boundary == Boundary::Natural { "absolute" } else { "relative, from the relative cochain complex" },
        }),
    );
    let form = if laplacian.is_mixed() {
        "mixed block form [[−M_{k−1}, dᵀM_k], [M_k d, dᵀM_{k+1}d]]"
    } else {
        "K = dᵀ⋆d + ⋆d⋆⁻¹dᵀ⋆, M = ⋆"
    };
    let notes = vec![
        (
            "forms".to_string(),
            format!(
                "Δ_{k} on {} free {k}-cells, {} boundary, {form}, shift σ = {:.3e}",
                laplacian.unknowns(),
                spec.boundary.name(),
                options.shift
            ),
        ),
        (
            "kernel".to_string(),
            format!(
                "dim ker Δ_{k} = {} (eigenvalue 0 to rounding), {betti_name} = {betti}{}",
                modes.kernel,
                if modes.kernel == betti {
                    ""
                } else {
                    "  ← differs"
                }
            ),
        ),
        ("modes".to_string(), table),
    ];
    Ok(RunResult {
        problem: "hodge-laplacian".into(),
        method: Some(spec.method.name().to_string()),
        unknowns: laplacian.unknowns(),
        fields,
        errors: None,
        flux_error: None,
        relative_residual: Some(worst_residual),
        factorization: Some(if laplacian.is_mixed() {
            Factorization::Lblt
        } else {
            Factorization::Llt
        }),
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
