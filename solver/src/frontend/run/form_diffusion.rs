//! Running the Poisson problem for k-forms (`kind = "diffusion"` with
//! `degree` = k ≥ 1): Δ_k u = f with both parts of the Laplacian, the
//! source and the exact solution given as proxy fields and read through
//! the de Rham map (module [`crate::physics::forms::poisson`]).
//!
//! Errors are measured on the cochains, against R_k u with its harmonic
//! part removed (the solution is the one orthogonal to the harmonic
//! forms): `L2` is ‖u_h − R_k u‖_⋆, the star norm, which approximates the
//! L² norm of the field; `max` is the largest |u_h − R_k u| on a k-cell
//! divided by its measure (the mean tangential component of the error
//! along an edge for k = 1, its mean normal component through a face for
//! fluxes, its mean density on a top cell).

use super::dec::{check_field, de_rham_of, run_error_at, vector_fields};
use super::stars::{forms_of, read_stars};
use super::{check_residual, RunError, RunResult};
use crate::frontend::case::{Case, FormDiffusionSpec};
use crate::frontend::output::Cochain;
use crate::physics::diffusion::Errors;
use crate::physics::forms::Boundary;
use hasse_complex::Complex;
use std::time::Instant;

/// Above this relative size, the source's harmonic part (which Δ_k
/// cannot produce and the solve drops) is worth a warning.
const HARMONIC_WARNING: f64 = 1e-8;

/// The source and the exact solution must fit the degree's proxy and be
/// finite on the k-cells.
pub(super) fn check(
    case: &Case,
    spec: &FormDiffusionSpec,
    complex: &Complex,
) -> Result<(), RunError> {
    check_field(case, complex, spec.degree, &spec.source, "problem.source")?;
    if let Some(exact) = case.exact.as_ref().and_then(|e| e.form.as_ref()) {
        check_field(case, complex, spec.degree, exact, "exact.solution")?;
    }
    Ok(())
}

pub(super) fn solve(
    case: &Case,
    spec: &FormDiffusionSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    check(case, spec, complex)?;
    let k = spec.degree;
    let error = |e| run_error_at(case, e, "problem.source");
    phase("de Rham map, harmonic forms and the Δ_k solve");
    let started = Instant::now();
    let source = de_rham_of(case, complex, k, &spec.source, "problem.source")?;
    let stars = read_stars(case, &spec.stars, complex)?;
    let forms = forms_of(case, spec.method, complex, &stars)?;
    let solved = forms.poisson(k, spec.boundary, &source).map_err(error)?;
    let seconds = started.elapsed().as_secs_f64();
    let mut warnings = Vec::new();
    check_residual(case, solved.residual, &mut warnings)?;
    let inner = |a: &[f64], b: &[f64]| forms.inner(k, a, b).map_err(error);
    let source_norm = inner(&source, &source)?.sqrt();
    let harmonic_norm = inner(&solved.source_harmonic, &solved.source_harmonic)?.sqrt();
    let harmonic_ratio = if source_norm > 0.0 {
        harmonic_norm / source_norm
    } else {
        0.0
    };
    let beta = solved.harmonic.len();
    let betti_name = match spec.boundary {
        Boundary::Natural => format!("β_{k}"),
        Boundary::Essential => format!("β_{k}(K, ∂K)"),
    };
    if harmonic_ratio > HARMONIC_WARNING {
        warnings.push(format!(
            "the source has a harmonic part of relative size {harmonic_ratio:.3e}, which Δ_{k} cannot produce: the solution solves Δ_{k} u = f − P_ℌ f (the field `source_harmonic` is P_ℌ f)"
        ));
    }
    let mut fields = vec![
        Cochain::new("u", k, solved.solution.clone()).with_description(format!(
            "the solution u, a {k}-cochain, ⊥ the harmonic {k}-forms"
        )),
    ];
    fields.extend(vector_fields(case, complex, k, "u", &solved.solution, "u")?);
    if k >= 1 {
        fields.push(
            Cochain::new("codifferential", k - 1, solved.codifferential.clone())
                .with_description(format!("δu on the {}-cells", k - 1)),
        );
    }
    fields.push(
        Cochain::new("source", k, source.clone())
            .with_description(format!("f = R_{k} of problem.source")),
    );
    if beta > 0 {
        fields.push(
            Cochain::new("source_harmonic", k, solved.source_harmonic.clone())
                .with_description("the harmonic part of f, taken out of the source"),
        );
    }
    let errors = match case.exact.as_ref().and_then(|e| e.form.as_ref()) {
        None => None,
        Some(exact) => {
            let mut reference = de_rham_of(case, complex, k, exact, "exact.solution")?;
            for h in &solved.harmonic {
                let c = inner(&reference, h)?;
                reference.iter_mut().zip(h).for_each(|(r, v)| *r -= c * v);
            }
            let difference: Vec<f64> = solved
                .solution
                .iter()
                .zip(&reference)
                .map(|(a, b)| a - b)
                .collect();
            let l2 = inner(&difference, &difference)?.sqrt();
            let measure = complex.measure(k);
            let max = difference.iter().enumerate().fold(0.0f64, |m, (c, e)| {
                let size = if k == 0 { 1.0 } else { measure[c] };
                m.max(e.abs() / size)
            });
            fields.push(
                Cochain::new("exact", k, reference).with_description(format!(
                    "R_{k} of exact.solution, its harmonic part removed"
                )),
            );
            fields.push(
                Cochain::new("error", k, difference).with_description("u − exact on the k-cells"),
            );
            Some(Errors::sampled(l2, max))
        }
    };
    let parts = match (k, complex.dim()) {
        (k, n) if k == n => format!("dδ on {}-cells (δd = 0 in the top degree)", k),
        _ => format!(
            "dδ + δd: {} {}-cells, {} {}-cells, {} {}-cells",
            complex.cell_count(k - 1),
            k - 1,
            complex.cell_count(k),
            k,
            complex.cell_count(k + 1),
            k + 1
        ),
    };
    let mut notes = vec![
        (
            "forms".to_string(),
            format!(
                "Δ_{k} u = f for {k}-forms, {} conditions, {parts}",
                spec.boundary.name()
            ),
        ),
        (
            "kernel".to_string(),
            format!(
                "{beta} harmonic {k}-forms ({betti_name} = {beta}){}",
                if beta > 0 {
                    format!("; the source's harmonic part ‖P_ℌ f‖/‖f‖ = {harmonic_ratio:.3e} was taken out and u ⊥ ℌ")
                } else {
                    String::new()
                }
            ),
        ),
    ];
    if errors.is_some() {
        notes.push((
            "norms".to_string(),
            "L2 = ‖u − R u‖_⋆ (the star norm of the cochain), max = largest |u − R u| / |σ| over the k-cells σ".to_string(),
        ));
    }
    let mut report = serde_json::Map::new();
    report.insert(
        "forms".into(),
        serde_json::json!({
            "degree": k,
            "boundary": spec.boundary.name(),
            "harmonic_forms": beta,
            "source_harmonic_ratio": harmonic_ratio,
        }),
    );
    Ok(RunResult {
        problem: format!("diffusion of {k}-forms"),
        method: Some(spec.method.name().to_string()),
        unknowns: solved.unknowns,
        fields,
        errors,
        flux_error: None,
        relative_residual: Some(solved.residual),
        factorization: Some(solved.factorization),
        ordering: None,
        timings: vec![("de Rham map + solve".to_string(), seconds)],
        warnings,
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report,
    })
}
