//! Running a mixed Darcy case: flux on (n−1)-cells and pressure on top
//! cells from [`crate::physics::darcy`], with the conservation check ∂ₙᵀ-divergence
//! = ∫f per cell reported, and pressure and flux errors against an exact
//! pressure.

use super::{check_residual, RunError, RunResult};
use crate::frontend::case::expr::Expression;
use crate::frontend::case::{BoundaryKindSpec, Case, Coefficient, DarcySpec};
use crate::frontend::output::Cochain;
use crate::metric::{MetricError, Tensor};
use crate::physics::darcy::{self, BoundaryConditions, DarcyError, DarcySolution};
use crate::physics::diffusion::Errors;
use crate::physics::regions::Regional;
use crate::physics::{non_finite_text, point_text};
use hasse_complex::Complex;
use std::collections::BTreeMap;
use std::time::Instant;

/// K at `x` (a scalar is K I in the first `d` dimensions).
fn tensor_at(coefficient: &Coefficient, x: &[f64], d: usize) -> Tensor {
    let mut t: Tensor = [[0.0; 3]; 3];
    match coefficient {
        Coefficient::Scalar(e) => {
            let k = e.eval(x, 0.0);
            for (i, row) in t.iter_mut().enumerate().take(d) {
                row[i] = k;
            }
        }
        Coefficient::Tensor(rows) => {
            for (i, row) in rows.iter().enumerate() {
                for (j, e) in row.iter().enumerate() {
                    t[i][j] = e.eval(x, 0.0);
                }
            }
        }
    }
    t
}

/// The expression that holds in each top cell: one for all, or the piece
/// of the cell's region for a value per region (`hasse check` has made
/// sure that every cell has exactly one; `key` names it otherwise).
fn per_cell<'a>(
    case: &Case,
    key: &str,
    expression: &'a Expression,
    complex: &Complex,
) -> Result<Vec<&'a Expression>, RunError> {
    match expression.regions() {
        None => Ok(vec![expression; complex.cell_count(complex.dim())]),
        Some(regions) => Regional::new(
            regions.pieces.iter().map(|(n, e)| (n.clone(), e)).collect(),
            regions.default.as_ref(),
        )
        .per_cell(complex)
        .map(|pieces| pieces.into_iter().copied().collect())
        .map_err(|e| RunError::input_at(case, key, e.to_string(), None)),
    }
}

/// The permeability of each region and each top cell's region, when it is
/// given per region (`None` for one expression or tensor, the same
/// everywhere); a region may be a scalar (times I) or a tensor.
struct RegionalPermeability {
    pieces: Vec<Coefficient>,
    owner: Vec<usize>,
}

fn regional_permeability(
    case: &Case,
    coefficient: &Coefficient,
    complex: &Complex,
) -> Result<Option<RegionalPermeability>, RunError> {
    let Some(regional) = coefficient.by_region() else {
        return Ok(None);
    };
    let owner = regional
        .piece_per_cell(complex)
        .map_err(|e| RunError::input_at(case, "problem.permeability", e.to_string(), None))?;
    let mut pieces: Vec<Coefficient> = regional.pieces().iter().map(|(_, k)| k.clone()).collect();
    pieces.extend(regional.default().cloned());
    Ok(Some(RegionalPermeability { pieces, owner }))
}

/// K at `x` in top cell `c`: the cell's region's permeability, or
/// [`tensor_at`] of the one coefficient.
fn tensor_in(
    coefficient: &Coefficient,
    regional: Option<&RegionalPermeability>,
    c: usize,
    x: &[f64],
    d: usize,
) -> Tensor {
    match regional {
        Some(r) => tensor_at(&r.pieces[r.owner[c]], x, d),
        None => tensor_at(coefficient, x, d),
    }
}

/// ∫f per top cell by the midpoint rule, with the piece of each cell's
/// region for a source per region.
fn source_integrals(
    case: &Case,
    spec: &DarcySpec,
    complex: &Complex,
) -> Result<Vec<f64>, RunError> {
    let n = complex.dim();
    let pieces = per_cell(case, "problem.source", &spec.source, complex)?;
    let source: Vec<f64> = pieces
        .iter()
        .enumerate()
        .map(|(c, f)| complex.measure(n)[c] * f.eval(complex.centroid_of(n, c), 0.0))
        .collect();
    if let Some(c) = source.iter().position(|v| !v.is_finite()) {
        return Err(source_error(case, complex, c, source[c]));
    }
    Ok(source)
}

/// K at every top-cell centroid (`regional`: the permeability's piece in
/// each cell, when it is given per region).
fn tensors(
    case: &Case,
    coefficient: &Coefficient,
    regional: Option<&RegionalPermeability>,
    complex: &Complex,
) -> Result<Vec<Tensor>, RunError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let mut out = Vec::with_capacity(complex.cell_count(n));
    for c in 0..complex.cell_count(n) {
        let x = complex.centroid_of(n, c);
        let t = tensor_in(coefficient, regional, c, x, d);
        if let Some(&bad) = t.iter().flatten().find(|v| !v.is_finite()) {
            return Err(RunError::input_at(
                case,
                "problem.permeability",
                format!(
                    "the permeability is not finite ({}) at {} (centroid of top cell {c})",
                    non_finite_text(bad),
                    point_text(x)
                ),
                Some(super::FINITE_HELP.into()),
            ));
        }
        out.push(t);
    }
    Ok(out)
}

/// Face conditions from the tagged boundary conditions, later ones
/// replacing earlier ones on shared faces (as for diffusion).
fn conditions(
    case: &Case,
    spec: &DarcySpec,
    complex: &Complex,
) -> Result<BoundaryConditions, RunError> {
    let n = complex.dim();
    let on_boundary: std::collections::BTreeSet<usize> =
        darcy::boundary_faces(complex).into_iter().collect();
    let mut by_face: BTreeMap<usize, (bool, f64)> = BTreeMap::new();
    for b in &spec.boundary {
        // Tags were checked against the mesh when it was built.
        let tag_key = format!("{}.tag", b.key);
        let Some(tag) = complex.tag(&b.tag) else {
            return Err(RunError::input_at(
                case,
                &tag_key,
                format!("no tag `{}` in the mesh", b.tag),
                None,
            ));
        };
        for &face in &tag.cells {
            if !on_boundary.contains(&face) {
                return Err(RunError::input_at(
                    case,
                    &tag_key,
                    format!(
                        "tag `{}` contains face {face}, which is interior (it lies on two cells)",
                        b.tag
                    ),
                    Some("Darcy conditions go on boundary faces".into()),
                ));
            }
            let x = complex.centroid_of(n - 1, face);
            let (is_pressure, value) = match &b.kind {
                BoundaryKindSpec::Dirichlet(p) => (true, p.eval(x, 0.0)),
                BoundaryKindSpec::Neumann(u) => {
                    (false, u.eval(x, 0.0) * complex.measure(n - 1)[face])
                }
                BoundaryKindSpec::Robin { .. } => {
                    return Err(RunError::input_at(
                        case,
                        &format!("{}.type", b.key),
                        "a Darcy boundary is \"pressure\" or \"flux\"",
                        None,
                    ))
                }
            };
            if !value.is_finite() {
                return Err(RunError::input_at(
                    case,
                    &format!("{}.value", b.key),
                    format!(
                        "the boundary value is not finite ({}) at {} (centroid of face {face})",
                        non_finite_text(value),
                        point_text(x)
                    ),
                    Some(super::FINITE_HELP.into()),
                ));
            }
            by_face.insert(face, (is_pressure, value));
        }
    }
    let mut bc = BoundaryConditions::default();
    for (face, (is_pressure, value)) in by_face {
        if is_pressure {
            bc.pressure.push((face, value));
        } else {
            bc.flux.push((face, value));
        }
    }
    Ok(bc)
}

/// The source integral of top cell `c` is `value`, not finite.
fn source_error(case: &Case, complex: &Complex, c: usize, value: f64) -> RunError {
    RunError::input_at(
        case,
        "problem.source",
        format!(
            "the source is not finite ({}) at {} (centroid of top cell {c})",
            non_finite_text(value),
            point_text(complex.centroid_of(complex.dim(), c))
        ),
        Some(super::FINITE_HELP.into()),
    )
}

fn run_error(case: &Case, e: DarcyError) -> RunError {
    let message = e.to_string();
    let located = match &e {
        DarcyError::Solve(_) | DarcyError::Canonical(_) | DarcyError::Block(_) => {
            RunError::solve(case, message, None)
        }
        DarcyError::Metric(MetricError::NotPositive { .. } | MetricError::NonFinite { .. }) => {
            RunError::input_at(
                case,
                "problem.permeability",
                message,
                Some("the permeability must be finite and positive (a tensor: symmetric positive definite) in every cell".into()),
            )
        }
        DarcyError::Metric(_) | DarcyError::NotVolume { .. } => {
            RunError::input_at(case, "problem.method", message, None)
        }
        DarcyError::Incompatible { .. } => RunError::input_at(
            case,
            "problem.source",
            message,
            Some("add a \"pressure\" boundary or make problem.source balance the boundary fluxes".into()),
        ),
        _ => RunError::input(case, message),
    };
    located.because(e)
}

pub(super) fn solve(
    case: &Case,
    spec: &DarcySpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    if n == 0 || n != d {
        return Err(RunError::input_at(
            case,
            "mesh",
            format!(
                "mixed Darcy needs a mesh that fills its space; this one is {n}-dimensional in R^{d}"
            ),
            None,
        ));
    }
    phase("assembling");
    let started = Instant::now();
    let regional = regional_permeability(case, &spec.permeability, complex)?;
    let permeability = tensors(case, &spec.permeability, regional.as_ref(), complex)?;
    let source = source_integrals(case, spec, complex)?;
    let bc = conditions(case, spec, complex)?;
    // Without a pressure face p is defined up to a constant: the solve
    // picks the one with Σ |c| p_c = 0, and errors are measured with that
    // weighted mean removed from the exact pressure too.
    let pure_flux = bc.pressure.is_empty();
    let system = darcy::assemble(complex, &permeability, spec.mass, &source, &bc)
        .map_err(|e| run_error(case, e))?;
    let assembly_seconds = started.elapsed().as_secs_f64();
    phase("solving the saddle point");
    let solution = match case.solver.factorization {
        None => system.solve_ldlt(),
        Some(kind) => system.solve(kind),
    }
    .map_err(|e| run_error(case, e))?;
    let total = started.elapsed().as_secs_f64();
    let mut warnings = Vec::new();
    check_residual(case, solution.report.relative_residual, &mut warnings)?;

    phase("post-processing");
    let post = Instant::now();
    // Local conservation: the net outflow of every cell equals ∫f.
    let divergence = darcy::divergence(complex, &solution.flux);
    let imbalance: Vec<f64> = divergence.iter().zip(&source).map(|(a, b)| a - b).collect();
    let scale = conservation_scale(complex, &solution.flux, &source);
    let worst = imbalance.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut fields = vec![
        Cochain::new("pressure", n, solution.pressure.clone())
            .with_description("p per top cell (at the dual vertices of the flux mass)"),
        Cochain::new("flux", n - 1, solution.flux.clone())
            .with_description("∫_F u·n_F: total flux through each (n−1)-cell along its normal"),
        Cochain::new("conservation", n, imbalance).with_description(
            "net outflow − ∫f per cell (zero to rounding: local mass conservation)",
        ),
    ];
    let (errors, flux_error) = match case.exact.as_ref() {
        Some(exact) => match exact.solution.as_ref() {
            Some(p) => {
                let (errors, exact_values, difference) =
                    pressure_errors(complex, &solution, pure_flux, |x| p.eval(x, 0.0));
                fields.push(
                    Cochain::new("pressure_exact", n, exact_values)
                        .with_description("the exact pressure at the cell points"),
                );
                fields.push(Cochain::new("error", n, difference).with_description("p − p_exact"));
                let flux_error = exact.gradient.as_ref().map(|g| {
                    flux_error(
                        complex,
                        &solution,
                        &spec.permeability,
                        regional.as_ref(),
                        |x| {
                            let mut v = [0.0; 3];
                            for (slot, e) in v.iter_mut().zip(g) {
                                *slot = e.eval(x, 0.0);
                            }
                            v
                        },
                    )
                });
                (Some(errors), flux_error)
            }
            None => (None, None),
        },
        None => (None, None),
    };
    let notes = vec![(
        "mass".to_string(),
        format!(
            "max |net outflow − ∫f| over cells {worst:.2e} (relative {:.2e})",
            worst / scale
        ),
    )];
    let mut report = serde_json::Map::new();
    report.insert(
        "conservation".into(),
        serde_json::json!({ "max_abs": worst, "relative": worst / scale }),
    );
    let timings = vec![
        ("assembly".to_string(), assembly_seconds),
        (
            "factorisation".to_string(),
            solution.report.symbolic_seconds + solution.report.numeric_seconds,
        ),
        ("solve".to_string(), solution.report.solve_seconds),
        ("post-processing".to_string(), post.elapsed().as_secs_f64()),
        ("assembly + solve".to_string(), total),
    ];
    Ok(RunResult {
        problem: "darcy".into(),
        method: Some(spec.mass.to_string()),
        unknowns: solution.flux.len() + solution.pressure.len(),
        fields,
        errors,
        flux_error,
        relative_residual: Some(solution.report.relative_residual),
        factorization: Some(solution.report.factorization),
        ordering: solution.report.ordering,
        timings,
        warnings,
        pure_neumann: pure_flux,
        series: Vec::new(),
        notes,
        report,
    })
}

/// The scale the conservation imbalance is relative to: the largest
/// Σ_F |u_F| + |∫_c f| over the cells c (F the faces of c). The net outflow
/// Σ_F ±u_F of a cell is a sum of those terms, so its rounding error is
/// a few ε times this, whatever f is; with f = 0 the largest |∫f| or net
/// outflow is itself rounding and would make any imbalance look like 1.
fn conservation_scale(complex: &Complex, flux: &[f64], source: &[f64]) -> f64 {
    let n = complex.dim();
    let mut per_cell: Vec<f64> = source.iter().map(|f| f.abs()).collect();
    for (face, row) in complex.boundary(n).outer_iterator().enumerate() {
        for (c, _) in row.iter() {
            per_cell[c] += flux[face].abs();
        }
    }
    per_cell
        .iter()
        .fold(0.0f64, |m, v| m.max(*v))
        .max(f64::MIN_POSITIVE)
}

/// Discrete L² (weights |c|) and max errors of the pressure at the cell
/// points, the exact values there and p − p_exact. With `mean_free` (no
/// pressure face: p is defined up to a constant) the |c|-weighted mean —
/// the one the solve's constraint Σ |c| p_c = 0 fixes — is removed from
/// both before they are compared.
fn pressure_errors(
    complex: &Complex,
    solution: &DarcySolution,
    mean_free: bool,
    p: impl Fn(&[f64]) -> f64,
) -> (Errors, Vec<f64>, Vec<f64>) {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let measure = complex.measure(n);
    let exact: Vec<f64> = solution.points.chunks(d).map(&p).collect();
    let mean = |v: &[f64]| {
        let volume: f64 = measure.iter().sum();
        let total: f64 = v.iter().zip(measure).map(|(x, w)| x * w).sum();
        if mean_free && volume > 0.0 {
            total / volume
        } else {
            0.0
        }
    };
    let shift = mean(&solution.pressure) - mean(&exact);
    let difference: Vec<f64> = solution
        .pressure
        .iter()
        .zip(&exact)
        .map(|(a, b)| a - b - shift)
        .collect();
    let sum: f64 = difference.iter().zip(measure).map(|(e, w)| w * e * e).sum();
    let max = difference.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    (Errors::sampled(sum.sqrt(), max), exact, difference)
}

/// Discrete L² error of the flux density U_F/|F| against u = −K∇p at the
/// face centroid (midpoint rule), each face weighted by its share
/// Σ_c |c| / (faces of c) of the volume. K is that of the face's first
/// top cell; with a permeability per region, K and ∇p jump across a
/// region's boundary, so both are taken on that cell's side, at a point
/// moved 10⁻⁶ of the way from the face's centroid towards the cell's.
fn flux_error(
    complex: &Complex,
    solution: &DarcySolution,
    permeability: &Coefficient,
    regional: Option<&RegionalPermeability>,
    gradient: impl Fn(&[f64]) -> [f64; 3],
) -> f64 {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let mut share = vec![0.0; complex.cell_count(n - 1)];
    let mut side = vec![usize::MAX; complex.cell_count(n - 1)];
    let by_cell = complex.boundary_csc(n);
    for c in 0..complex.cell_count(n) {
        if let Some(col) = by_cell.outer_view(c) {
            for (f, _) in col.iter() {
                share[f] += complex.measure(n)[c] / col.nnz() as f64;
                side[f] = side[f].min(c);
            }
        }
    }
    let normal = complex.normal();
    let mut sum = 0.0;
    for (f, w) in share.iter().enumerate() {
        let c = side[f];
        if c == usize::MAX {
            continue;
        }
        let mut x = complex.centroid_of(n - 1, f).to_vec();
        if regional.is_some() {
            let centre = complex.centroid_of(n, c);
            for (a, c) in x.iter_mut().zip(centre) {
                *a += 1e-6 * (c - *a);
            }
        }
        let g = gradient(&x);
        let k = tensor_in(permeability, regional, c, &x, d);
        let exact: f64 = (0..d)
            .map(|i| -(0..d).map(|j| k[i][j] * g[j]).sum::<f64>() * normal[f * d + i])
            .sum();
        let area = complex.measure(n - 1)[f];
        sum += w * (solution.flux[f] / area - exact).powi(2);
    }
    sum.sqrt()
}

/// The permeability, the source and the boundary values evaluated where
/// the solve evaluates them, without solving.
pub(super) fn check(case: &Case, spec: &DarcySpec, complex: &Complex) -> Result<(), RunError> {
    let n = complex.dim();
    if n == 0 || n != complex.embedding_dim() {
        return Ok(());
    }
    // Positive definite as the assembly will demand: a negative constant
    // permeability is refused here, not after `hasse check` said ok.
    let regional = regional_permeability(case, &spec.permeability, complex)?;
    let permeability = tensors(case, &spec.permeability, regional.as_ref(), complex)?;
    crate::metric::check_tensors(&permeability, complex.cell_count(n), n)
        .map_err(|e| run_error(case, DarcyError::Metric(e)))?;
    source_integrals(case, spec, complex)?;
    conditions(case, spec, complex).map(|_| ())
}
