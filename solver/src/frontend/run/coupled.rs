//! Running a coupled two-field case: [`crate::physics::coupled`] assembles both
//! diffusion operators and the reaction blocks as one block system; each
//! field is written on its own cells and compared with its exact field.

use super::{
    diffusion_error, diffusion_problem, field_points, scalar_fn, Keys, RunError, RunResult,
};
use crate::frontend::case::{Case, CoupledSpec};
use crate::frontend::output::Cochain;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::Location;
use crate::physics::coupled::{Coupled, CoupledError, CoupledField, Reaction, RegionalReaction};
use hasse_complex::Complex;
use std::time::Instant;

fn run_error(case: &Case, spec: &CoupledSpec, e: CoupledError) -> RunError {
    let message = e.to_string();
    let located = match &e {
        CoupledError::Factorization { .. } | CoupledError::Solve(_) => RunError::solve(
            case,
            message,
            Some("check solver.factorization and the coupling b: LLᵀ needs a c > b²".into()),
        ),
        CoupledError::Field { name, source } => {
            let Some(i) = spec.fields.iter().position(|f| &f.name == name) else {
                return RunError::input(case, message).because(e);
            };
            let keys = Keys {
                prefix: format!("field[{i}]"),
                coefficient: "conductivity",
                boundary: &spec.fields[i].diffusion.boundary,
            };
            return diffusion_error(case, &keys, source.clone()).because(e);
        }
        CoupledError::NonFinite { what, .. } => RunError::input_at(
            case,
            &format!("problem.{what}"),
            message,
            Some(super::FINITE_HELP.into()),
        ),
        CoupledError::Region { what, .. } => {
            RunError::input_at(case, &format!("problem.{what}"), message, None)
        }
        _ => RunError::input(case, message),
    };
    located.because(e)
}

pub(super) fn solve(
    case: &Case,
    spec: &CoupledSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let fields = spec
        .fields
        .clone()
        .map(|f| CoupledField::new(&f.name, diffusion_problem(case, &f.diffusion)));
    let mut problem = Coupled::new(
        fields[0].clone(),
        fields[1].clone(),
        Reaction {
            a: scalar_fn(&spec.a),
            b: scalar_fn(&spec.b),
            c: scalar_fn(&spec.c),
        },
    );
    if [&spec.a, &spec.b, &spec.c]
        .iter()
        .any(|e| e.regions().is_some())
    {
        problem = problem.with_reaction_by_region(RegionalReaction {
            a: super::regional_fn(&spec.a),
            b: super::regional_fn(&spec.b),
            c: super::regional_fn(&spec.c),
        });
    }
    if let Some(f) = case.solver.factorization {
        problem.factorization = f;
    }
    phase("assembling the block system and solving");
    let started = Instant::now();
    let solution = problem
        .solve(complex)
        .map_err(|e| run_error(case, spec, e))?;
    let total = started.elapsed().as_secs_f64();
    let dim = match solution.location {
        Location::Nodal => 0,
        _ => complex.dim(),
    };
    let weights = if dim == 0 {
        lumped_vertex_volumes(complex)
    } else {
        complex.measure(dim).to_vec()
    };
    let points = field_points(complex, dim);
    let mut out = Vec::new();
    let mut notes = Vec::new();
    let mut report = serde_json::Map::new();
    for (field, values) in spec.fields.iter().zip(&solution.fields) {
        out.push(
            Cochain::new(field.name.clone(), dim, values.clone())
                .with_description(format!("coupled field {}", field.name)),
        );
        if let Some(exact) = &field.exact {
            let exact_values: Vec<f64> = points.iter().map(|x| exact.eval(x, 0.0)).collect();
            let (difference, l2, max) = super::weighted_errors(values, &exact_values, &weights);
            notes.push((
                format!("error {}", field.name),
                format!("L2 {l2:.6e}, max {max:.6e}"),
            ));
            report.insert(
                format!("errors_{}", field.name),
                serde_json::json!({ "l2": l2, "max": max }),
            );
            out.push(
                Cochain::new(format!("{}_exact", field.name), dim, exact_values)
                    .with_description(format!("the exact {}", field.name)),
            );
            out.push(
                Cochain::new(format!("{}_error", field.name), dim, difference)
                    .with_description(format!("{} − exact", field.name)),
            );
        }
    }
    let methods = format!(
        "{}/{}",
        spec.fields[0].diffusion.method.name(),
        spec.fields[1].diffusion.method.name()
    );
    Ok(RunResult {
        problem: "coupled".into(),
        method: Some(methods),
        unknowns: solution.fields.iter().map(Vec::len).sum(),
        fields: out,
        errors: None,
        flux_error: None,
        relative_residual: None,
        factorization: Some(problem.factorization),
        ordering: None,
        timings: vec![("assembly + solve".to_string(), total)],
        warnings: spec
            .fields
            .iter()
            .flat_map(|f| {
                super::consistency::diffusion_warnings(
                    complex,
                    f.diffusion.method,
                    &f.diffusion.conductivity,
                    f.diffusion.circumcentres,
                )
                .into_iter()
                .map(move |w| format!("field {}: {w}", f.name))
            })
            .collect(),
        pure_neumann: false,
        series: Vec::new(),
        notes,
        report,
    })
}

/// Each field's conductivity and source evaluated where the solve
/// evaluates them, without solving.
pub(super) fn check(case: &Case, spec: &CoupledSpec, complex: &Complex) -> Result<(), RunError> {
    for (i, field) in spec.fields.iter().enumerate() {
        let keys = Keys {
            prefix: format!("field[{i}]"),
            coefficient: "conductivity",
            boundary: &field.diffusion.boundary,
        };
        diffusion_problem(case, &field.diffusion)
            .check_data(complex)
            .map_err(|e| diffusion_error(case, &keys, e))?;
    }
    Ok(())
}
