//! Running a linear elasticity case: the vector displacement of
//! [`crate::physics::elasticity`] on the vertices, one field per component, errors
//! against an exact displacement.

use super::{check_residual, scalar_fn, RunError, RunResult};
use crate::frontend::case::expr::Expression;
use crate::frontend::case::{Case, ElasticBoundaryKind, ElasticitySpec, MaterialSpec};
use crate::frontend::output::Cochain;
use crate::physics::diffusion::Errors;
use crate::physics::elasticity::{
    Coefficient, ElasticBoundary, Elasticity, ElasticityError, Material,
};
use crate::physics::{Datum, VectorFn};
use hasse_complex::Complex;
use std::time::Instant;

fn vector_fn(components: &[Expression]) -> VectorFn {
    super::vector_fn(components)
}

fn problem(case: &Case, spec: &ElasticitySpec, complex: &Complex) -> Elasticity {
    // A parameter per region becomes a value per cell, its region's at the
    // centroid; regions that do not fit the mesh were refused when it was
    // built, so the NaN fallback only marks a library misuse.
    let coefficient = |e: &Expression| match super::regional_fn(e) {
        Some(regional) => {
            let n = complex.dim();
            let values: Vec<f64> = match regional.per_cell(complex) {
                Ok(per_cell) => per_cell
                    .iter()
                    .enumerate()
                    .map(|(c, f)| f(complex.centroid_of(n, c)))
                    .collect(),
                Err(_) => vec![f64::NAN; complex.cell_count(n)],
            };
            Coefficient::PerCell(values.into())
        }
        None => Coefficient::Function(scalar_fn(e)),
    };
    let material = match &spec.material {
        MaterialSpec::Lame { lambda, mu } => Material::Lame {
            lambda: coefficient(lambda),
            mu: coefficient(mu),
        },
        MaterialSpec::Young { young, poisson } => Material::Young {
            young: coefficient(young),
            poisson: coefficient(poisson),
        },
    };
    let mut problem = Elasticity::new(material, vector_fn(&spec.body_force)).with_plane(spec.plane);
    for b in &spec.boundary {
        let kind = match &b.kind {
            ElasticBoundaryKind::Displacement {
                component: Some(a),
                value,
            } => ElasticBoundary::Component {
                component: *a,
                value: scalar_fn(&value[0]),
            },
            ElasticBoundaryKind::Displacement {
                component: None,
                value,
            } => ElasticBoundary::Displacement(vector_fn(value)),
            ElasticBoundaryKind::Traction(value) => ElasticBoundary::Traction(vector_fn(value)),
        };
        problem = problem.with_boundary(&b.tag, kind);
    }
    if let Some(f) = case.solver.factorization {
        problem.factorization = f;
    }
    problem.ordering = case.solver.ordering;
    problem
}

fn run_error(case: &Case, spec: &ElasticitySpec, e: ElasticityError) -> RunError {
    let message = e.to_string();
    let material = |name: &str| match (name, &spec.material) {
        ("λ", _) => "problem.lambda",
        ("μ", _) => "problem.mu",
        ("E", _) => "problem.young",
        ("ν", _) => "problem.poisson",
        (_, MaterialSpec::Lame { .. }) => "problem.lambda",
        (_, MaterialSpec::Young { .. }) => "problem.young",
    };
    let help = Some(super::FINITE_HELP.to_string());
    let located = match &e {
        ElasticityError::Solve(_) | ElasticityError::Canonical(_) => {
            RunError::solve(case, message, None)
        }
        ElasticityError::NonFiniteMaterial { what, .. } => {
            RunError::input_at(case, material(what), message, help)
        }
        ElasticityError::Lame { mu, .. } => RunError::input_at(
            case,
            if *mu <= 0.0 {
                "problem.mu"
            } else {
                "problem.lambda"
            },
            message,
            None,
        ),
        ElasticityError::Young { .. } => RunError::input_at(case, "problem.young", message, None),
        ElasticityError::Poisson { .. } => {
            RunError::input_at(case, "problem.poisson", message, None)
        }
        ElasticityError::NonFinite { datum, .. } => {
            let key = match datum {
                Datum::BoundaryValue { condition, .. } => spec
                    .boundary
                    .get(*condition)
                    .map_or_else(|| "boundary".into(), |b| format!("{}.value", b.key)),
                _ => "problem.body_force".into(),
            };
            RunError::input_at(case, &key, message, help)
        }
        ElasticityError::Component { tag, .. } => {
            let key = spec
                .boundary
                .iter()
                .find(|b| &b.tag == tag)
                .map_or_else(|| "boundary".into(), |b| format!("{}.component", b.key));
            RunError::input_at(case, &key, message, None)
        }
        ElasticityError::RigidModes { .. } => RunError::input_at(
            case,
            "boundary",
            message,
            Some(
                "prescribe the displacement on enough of the boundary to hold every rigid motion"
                    .into(),
            ),
        ),
        _ => RunError::input(case, message),
    };
    located.because(e)
}

pub(super) fn solve(
    case: &Case,
    spec: &ElasticitySpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let d = complex.embedding_dim();
    let elasticity = problem(case, spec, complex);
    phase("assembling and solving");
    let started = Instant::now();
    let u = elasticity
        .solve(complex)
        .map_err(|e| run_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    let mut warnings = Vec::new();
    check_residual(case, u.report.relative_residual, &mut warnings)?;
    let axes = ["x", "y", "z"];
    let mut fields: Vec<Cochain> = (0..u.dim)
        .map(|a| {
            Cochain::new(format!("u_{}", axes[a]), 0, u.component(a).to_vec())
                .with_description(format!("displacement component {}", axes[a]))
        })
        .collect();
    let errors = match case.exact.as_ref().and_then(|e| e.displacement.as_ref()) {
        Some(exact) if exact.len() < d => {
            return Err(RunError::input_at(
                case,
                "exact.displacement",
                format!(
                    "{} components, but the mesh lives in {d} dimensions",
                    exact.len()
                ),
                Some(format!("give {d} expressions, one per coordinate")),
            ))
        }
        Some(exact) => {
            let exact_fn = vector_fn(exact);
            let (l2, max) = u.errors(complex, &exact_fn);
            for (a, axis) in axes.iter().enumerate().take(u.dim) {
                let difference: Vec<f64> = u
                    .component(a)
                    .iter()
                    .enumerate()
                    .map(|(v, value)| value - exact_fn(complex.vertices().point(v))[a])
                    .collect();
                fields.push(
                    Cochain::new(format!("error_{axis}"), 0, difference)
                        .with_description(format!("u_{axis} − exact")),
                );
            }
            Some(Errors::sampled(l2, max))
        }
        None => None,
    };
    let timings = vec![
        ("assembly".to_string(), u.assembly_seconds),
        (
            "factorisation".to_string(),
            u.report.symbolic_seconds + u.report.numeric_seconds,
        ),
        ("solve".to_string(), u.report.solve_seconds),
        ("assembly + solve".to_string(), total),
    ];
    Ok(RunResult {
        problem: "elasticity".into(),
        method: Some("fe".into()),
        unknowns: u.values.len(),
        fields,
        errors,
        flux_error: None,
        relative_residual: Some(u.report.relative_residual),
        factorization: Some(u.report.factorization),
        ordering: u.report.ordering,
        timings,
        warnings,
        pure_neumann: false,
        series: Vec::new(),
        notes: Vec::new(),
        report: serde_json::Map::new(),
    })
}

/// The material and the body force evaluated where the solve evaluates
/// them, without solving.
pub(super) fn check(case: &Case, spec: &ElasticitySpec, complex: &Complex) -> Result<(), RunError> {
    problem(case, spec, complex)
        .check_data(complex)
        .map_err(|e| run_error(case, spec, e))
}
