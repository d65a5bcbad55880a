//! Running the DEC kinds of the k-form layer besides the Hodge Laplacian:
//! `cohomology` (a basis of harmonic k-forms from cohomology generators)
//! and `hodge-decomposition` (a k-cochain split into exact, coexact and
//! harmonic parts). Both write their cochains and, where the degree's
//! proxy is a vector field, its Whitney vector per top cell
//! (`NAME_x`, `NAME_y`, `NAME_z`).

use super::stars::{forms_of, read_cochain, read_stars};
use super::{vector_fn, RunError, RunResult};
use crate::frontend::case::expr::Expression;
use crate::frontend::case::{Case, CohomologySpec, DecompositionSpec};
use crate::frontend::output::Cochain;
use crate::la::direct::Factorization;
use crate::physics::forms::whitney_map::{cell_vectors, de_rham, Field, ProxyKind};
use crate::physics::forms::{Boundary, FormsError};
use hasse_complex::Complex;
use std::time::Instant;

/// Above this, a harmonic form's closedness or co-closedness residual is
/// worth a warning: the construction is exact to rounding (≈ 1e-15).
const RESIDUAL_WARNING: f64 = 1e-10;

fn run_error(case: &Case, e: FormsError) -> RunError {
    run_error_at(case, e, "problem.field")
}

/// A forms error as a run error; a field that does not fit is reported at
/// `field_key`.
pub(super) fn run_error_at(case: &Case, e: FormsError, field_key: &str) -> RunError {
    let message = e.to_string();
    let located = match &e {
        FormsError::Solve(_) | FormsError::Eigen(_) => RunError::solve(case, message, None),
        FormsError::NonPositiveStar { .. } | FormsError::Metric(_) => RunError::input_at(
            case,
            "problem.method",
            message,
            Some("set `method = \"dec-barycentric\"` under [problem]".into()),
        ),
        FormsError::Degree { .. } | FormsError::Cohomology(_) => {
            RunError::input_at(case, "problem.degree", message, None)
        }
        FormsError::Field(_) | FormsError::NotSimplex { .. } => {
            RunError::input_at(case, field_key, message, None)
        }
        _ => RunError::input(case, message),
    };
    located.because(e)
}

/// The Whitney vector per top cell of a k-cochain as one cell field per
/// embedding axis, when k-forms are vector fields here.
pub(super) fn vector_fields(
    case: &Case,
    complex: &Complex,
    k: usize,
    name: &str,
    cochain: &[f64],
    what: &str,
) -> Result<Vec<Cochain>, RunError> {
    let is_vector = ProxyKind::of(complex, k).is_ok_and(|p| p.is_vector());
    if !is_vector {
        return Ok(Vec::new());
    }
    let vectors = cell_vectors(complex, k, cochain).map_err(|e| run_error(case, e))?;
    let n = complex.dim();
    Ok(["x", "y", "z"]
        .iter()
        .enumerate()
        .take(complex.embedding_dim())
        .map(|(a, axis)| {
            Cochain::new(
                format!("{name}_{axis}"),
                n,
                vectors.iter().map(|v| v[a]).collect(),
            )
            .with_description(format!(
                "{what}: component {axis} of its Whitney vector at each top cell's centroid (least-squares constant field on cells that are not simplices)"
            ))
        })
        .collect())
}

pub(super) fn cohomology(
    case: &Case,
    spec: &CohomologySpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    phase("cohomology generators and harmonic projection");
    let started = Instant::now();
    let k = spec.degree;
    let stars = read_stars(case, &spec.stars, complex)?;
    let forms = forms_of(case, spec.method, complex, &stars)?;
    let basis = forms
        .harmonic_basis_with(k, spec.boundary)
        .map_err(|e| run_error(case, e))?;
    let betti_name = match spec.boundary {
        Boundary::Natural => format!("β_{k}"),
        Boundary::Essential => format!("β_{k}(K, ∂K)"),
    };
    // An independent figure for relative classes: on an orientable
    // n-manifold with boundary Lefschetz duality gives β_k(K, ∂K) =
    // β_{n−k}(K), from the absolute ranks (a different matrix rank).
    let n = complex.dim();
    let lefschetz = match spec.boundary {
        Boundary::Natural => String::new(),
        Boundary::Essential => format!(
            " (Lefschetz duality on an orientable manifold: β_{} = {})",
            n - k,
            complex.betti_numbers().get(n - k).copied().unwrap_or(0)
        ),
    };
    let seconds = started.elapsed().as_secs_f64();
    let count = basis.forms.len();
    let mut warnings = Vec::new();
    if count != basis.betti {
        warnings.push(format!(
            "{count} cohomology generators of degree {k}, but the Betti number {betti_name} = {} (a non-manifold or non-orientable complex?)",
            basis.betti
        ));
    }
    let mut table = String::from("  j   ‖h‖_⋆             ‖dh‖/‖h‖    ‖dᵀ⋆h‖/‖⋆h‖");
    let mut rows = Vec::new();
    let mut fields = Vec::new();
    for (j, (h, c)) in basis.forms.iter().zip(&basis.generators).enumerate() {
        let norm = forms.inner(k, h, h).map_err(|e| run_error(case, e))?.sqrt();
        let (closed, coclosed) = (basis.closed[j], basis.coclosed[j]);
        if closed.max(coclosed) > RESIDUAL_WARNING {
            warnings.push(format!(
                "harmonic form {} is closed to {closed:.1e} and co-closed to {coclosed:.1e}, above {RESIDUAL_WARNING:.0e}",
                j + 1
            ));
        }
        table.push_str(&format!(
            "\n{:>3}   {norm:<17.10e} {closed:<11.3e} {coclosed:.3e}",
            j + 1
        ));
        rows.push(serde_json::json!({
            "form": j + 1,
            "norm": norm,
            "closed": closed,
            "coclosed": coclosed,
        }));
        fields.push(
            Cochain::new(format!("generator_{}", j + 1), k, c.clone())
                .with_description(format!("integer {k}-cocycle of cohomology class {}", j + 1)),
        );
        fields.push(
            Cochain::new(format!("harmonic_{}", j + 1), k, h.clone()).with_description(format!(
                "the harmonic {k}-form of class {} (generator − dα)",
                j + 1
            )),
        );
        fields.extend(vector_fields(
            case,
            complex,
            k,
            &format!("harmonic_{}", j + 1),
            h,
            &format!("harmonic {k}-form {}", j + 1),
        )?);
    }
    let worst = basis
        .closed
        .iter()
        .chain(&basis.coclosed)
        .fold(0.0f64, |m, r| m.max(*r));
    let mut report = serde_json::Map::new();
    report.insert("forms".into(), serde_json::Value::Array(rows));
    report.insert(
        "cohomology".into(),
        serde_json::json!({
            "degree": k,
            "count": count,
            "betti": basis.betti,
            "boundary": spec.boundary.name(),
        }),
    );
    let notes = vec![
        (
            "cohomology".to_string(),
            format!(
                "{count} harmonic {k}-forms from {count} cocycle generators, {betti_name} = {}{}{lefschetz}",
                basis.betti,
                if count == basis.betti {
                    ""
                } else {
                    "  ← differs"
                }
            ),
        ),
        ("forms".to_string(), table),
    ];
    Ok(RunResult {
        problem: "cohomology".into(),
        method: Some(spec.method.name().to_string()),
        unknowns: complex.cell_count(k),
        fields,
        errors: None,
        flux_error: None,
        relative_residual: Some(worst),
        factorization: Some(Factorization::Llt),
        ordering: None,
        timings: vec![("generators + projection".to_string(), seconds)],
        warnings,
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report,
    })
}

/// The field must fit the degree's proxy (one expression per coordinate
/// for a vector one, one expression for a scalar one) and be finite at
/// the k-cells' centroids (where `hasse check` can see it).
pub(super) fn check(
    case: &Case,
    spec: &DecompositionSpec,
    complex: &Complex,
) -> Result<(), RunError> {
    omega_from_file(case, spec, complex)?;
    if spec.cochain.is_none() {
        check_field(case, complex, spec.degree, &spec.field, "problem.field")?;
    }
    read_stars(case, &spec.stars, complex).map(|_| ())
}

/// ω read from `problem.cochain`, when the case gives it so.
fn omega_from_file(
    case: &Case,
    spec: &DecompositionSpec,
    complex: &Complex,
) -> Result<Option<Vec<f64>>, RunError> {
    let k = spec.degree;
    spec.cochain
        .as_ref()
        .map(|path| {
            read_cochain(
                case,
                path,
                "problem.cochain",
                &format!("the {k}-cochain ω"),
                "one value per k-cell of problem.degree, in hasse's cell order (that of the cochains in hasse's output)",
                k,
                complex.cell_count(k),
            )
        })
        .transpose()
}

/// [`check`] for the proxy field `field` of a k-form written at `key`.
pub(super) fn check_field(
    case: &Case,
    complex: &Complex,
    k: usize,
    field: &[Expression],
    key: &str,
) -> Result<(), RunError> {
    let d = complex.embedding_dim();
    let proxy = ProxyKind::of(complex, k).map_err(|e| run_error_at(case, e, key))?;
    let (wanted, help) = if proxy.is_vector() {
        (d, format!("give {d} expressions, one per coordinate"))
    } else {
        (
            1,
            "give one expression (a string), not an array".to_string(),
        )
    };
    if field.len() != wanted {
        return Err(RunError::input_at(
            case,
            key,
            format!(
                "{} expression(s), but {k}-cochains on this {}-dimensional mesh in R^{d} are the de Rham map of {}",
                field.len(),
                complex.dim(),
                match proxy {
                    ProxyKind::Function => "a function (its vertex values)",
                    ProxyKind::Density => "a density (its integrals over the top cells)",
                    ProxyKind::Tangent => "a vector field (its line integrals along the edges)",
                    ProxyKind::Flux => "a vector field (its fluxes through the faces)",
                }
            ),
            Some(help),
        ));
    }
    let centroids = complex.centroid(k);
    for c in 0..complex.cell_count(k) {
        let x = &centroids[c * d..(c + 1) * d];
        let finite = if proxy.is_vector() {
            vector_fn(field)(x)[..d].iter().all(|v| v.is_finite())
        } else {
            field[0].eval(x, 0.0).is_finite()
        };
        if !finite {
            return Err(RunError::input_at(
                case,
                key,
                format!("the field is not finite at {x:?} (the centroid of {k}-cell {c})"),
                Some("the field must be defined on the whole mesh".into()),
            ));
        }
    }
    Ok(())
}

/// The de Rham cochain R_k F of the proxy field `field` (checked by
/// [`check_field`]).
pub(super) fn de_rham_of(
    case: &Case,
    complex: &Complex,
    k: usize,
    field: &[Expression],
    key: &str,
) -> Result<Vec<f64>, RunError> {
    if ProxyKind::of(complex, k).is_ok_and(|p| p.is_vector()) {
        let f = vector_fn(field);
        de_rham(complex, k, Field::Vector(&*f))
    } else {
        let f = &field[0];
        de_rham(complex, k, Field::Scalar(&|x| f.eval(x, 0.0)))
    }
    .map_err(|e| run_error_at(case, e, key))
}

pub(super) fn decomposition(
    case: &Case,
    spec: &DecompositionSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    check(case, spec, complex)?;
    let k = spec.degree;
    let n = complex.dim();
    let star = spec.method.star();
    let mixed = !star.is_diagonal();
    phase(if mixed {
        "de Rham map, Poisson solve and mixed saddle-point solve"
    } else {
        "de Rham map and two Poisson solves"
    });
    let started = Instant::now();
    let omega = match omega_from_file(case, spec, complex)? {
        Some(omega) => omega,
        None => de_rham_of(case, complex, k, &spec.field, "problem.field")?,
    };
    let stars = read_stars(case, &spec.stars, complex)?;
    let forms = forms_of(case, spec.method, complex, &stars)?;
    let split = forms.decompose(k, &omega).map_err(|e| run_error(case, e))?;
    let seconds = started.elapsed().as_secs_f64();
    let inner = |a: &[f64], b: &[f64]| forms.inner(k, a, b).map_err(|e| run_error(case, e));
    let total = inner(&omega, &omega)?;
    let scale = total.max(f64::MIN_POSITIVE);
    let names = ["exact", "coexact", "harmonic"];
    let parts = split.parts();
    let mut norms = Vec::new();
    for p in parts {
        norms.push(inner(p, p)?.sqrt());
    }
    let mut products = Vec::new();
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        products.push((i, j, inner(parts[i], parts[j])?));
    }
    let sum_squares: f64 = norms.iter().map(|n| n * n).sum();
    let pythagoras = (total - sum_squares).abs() / scale;
    let remainder: Vec<f64> = omega
        .iter()
        .enumerate()
        .map(|(e, w)| w - parts.iter().map(|p| p[e]).sum::<f64>())
        .collect();
    let remainder_norm = inner(&remainder, &remainder)?.sqrt();
    let mut table = format!("  ‖ω‖_⋆ = {:.10e}", total.sqrt());
    for (name, norm) in names.iter().zip(&norms) {
        table.push_str(&format!("\n  ‖{name}‖_⋆ = {norm:.10e}"));
    }
    let mut worst = pythagoras;
    for (i, j, p) in &products {
        let relative = p.abs() / scale;
        worst = worst.max(relative);
        table.push_str(&format!(
            "\n  ⟨{}, {}⟩_⋆ / ‖ω‖² = {relative:.3e}",
            names[*i], names[*j]
        ));
    }
    table.push_str(&format!(
        "\n  |‖ω‖² − Σ‖part‖²| / ‖ω‖² = {pythagoras:.3e}\n  ‖ω − (exact + coexact + harmonic)‖_⋆ = {remainder_norm:.3e}"
    ));
    let mut warnings = Vec::new();
    if worst > RESIDUAL_WARNING {
        warnings.push(format!(
            "the parts are ⋆-orthogonal only to {worst:.1e} of ‖ω‖², above {RESIDUAL_WARNING:.0e}"
        ));
    }
    let mut fields =
        vec![
            Cochain::new("omega", k, omega.clone()).with_description(match &spec.cochain {
                Some(path) => format!("ω on the {k}-cells, read from {}", path.display()),
                None => format!("ω = R_{k}F, the de Rham cochain of the field on the {k}-cells"),
            }),
        ];
    fields.extend(vector_fields(case, complex, k, "omega", &omega, "ω")?);
    let descriptions = [
        "the exact part dα",
        "the coexact part M_k⁻¹ d_kᵀ γ (δβ)",
        "the harmonic part",
    ];
    for ((name, part), what) in names.iter().zip(parts).zip(descriptions) {
        fields.push(Cochain::new(*name, k, part.to_vec()).with_description(what));
        fields.extend(vector_fields(case, complex, k, name, part, what)?);
    }
    // The potentials exist only where their degree does (α for k ≥ 1,
    // γ for k < n).
    if k >= 1 {
        fields.push(
            Cochain::new("potential", k - 1, split.potential.clone())
                .with_description(format!("α on the {}-cells, exact part = dα", k - 1)),
        );
    }
    if k < n {
        fields.push(
            Cochain::new("copotential", k + 1, split.copotential.clone()).with_description(
                format!(
                    "γ = ⋆_{}β on the {}-cells, coexact part = M_{k}⁻¹ d_{k}ᵀ γ",
                    k + 1,
                    k + 1
                ),
            ),
        );
    }
    let mut report = serde_json::Map::new();
    report.insert(
        "decomposition".into(),
        serde_json::json!({
            "degree": k,
            "norm": total.sqrt(),
            "exact": norms[0],
            "coexact": norms[1],
            "harmonic": norms[2],
            "exact_coexact": products[0].2,
            "exact_harmonic": products[1].2,
            "coexact_harmonic": products[2].2,
            "pythagoras": pythagoras,
            "remainder": remainder_norm,
        }),
    );
    let lower = if k >= 1 {
        format!("Poisson on {} {}-cells", complex.cell_count(k - 1), k - 1)
    } else {
        "no exact part (degree 0)".to_string()
    };
    let upper = match (k < n, mixed) {
        (false, _) => format!("no coexact part (degree {n} = the top degree)"),
        (true, false) => format!("Poisson on {} {}-cells", complex.cell_count(k + 1), k + 1),
        (true, true) => format!(
            "mixed saddle-point system on {} {k}-cells and {} {}-cells",
            complex.cell_count(k),
            complex.cell_count(k + 1),
            k + 1
        ),
    };
    let notes = vec![
        (
            "split".to_string(),
            format!(
                "{} on {} {k}-cells = exact + coexact + harmonic ({lower}; {upper})",
                match &spec.cochain {
                    Some(path) => format!("ω from {}", path.display()),
                    None => format!("ω = R_{k}F"),
                },
                complex.cell_count(k),
            ),
        ),
        ("parts".to_string(), table),
    ];
    let unknowns = if k >= 1 { complex.cell_count(k - 1) } else { 0 }
        + if k < n {
            complex.cell_count(k + 1) + if mixed { complex.cell_count(k) } else { 0 }
        } else {
            0
        };
    Ok(RunResult {
        problem: "hodge-decomposition".into(),
        method: Some(spec.method.name().to_string()),
        unknowns,
        fields,
        errors: None,
        flux_error: None,
        relative_residual: Some(worst),
        factorization: Some(if mixed {
            Factorization::Lu
        } else {
            Factorization::Llt
        }),
        ordering: None,
        timings: vec![("de Rham map + two solves".to_string(), seconds)],
        warnings,
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report,
    })
}
