//! A case's `[refine]` table: the refinement study of its diffusion
//! problem ([`crate::refine`]), each level's fields for the output, and
//! the run result of the finest level.

use super::{
    diffusion_error, diffusion_problem, field_points, scalar_fn, vector_fn, Keys, RunError,
    RunResult,
};
use crate::frontend::case::{Case, Problem};
use crate::frontend::output::Cochain;
use crate::metric::Location;
use crate::physics::diffusion::Solution;
use crate::refine::{refine_and_solve, Exact, RefineError, RefineSpec, StepReport};
use hasse_complex::Complex;

/// The steps of a case's refinement, every level's mesh and fields, and
/// the run result on the finest mesh.
pub struct CaseRefinement {
    /// One report per level (the coarse solve first).
    pub steps: Vec<StepReport>,
    /// Every level's complex and fields (`u`, and `u_exact`, `error` when
    /// the case has an exact solution), for a time series whose mesh
    /// changes.
    pub levels: Vec<(Complex, Vec<Cochain>)>,
    /// The finest complex.
    pub complex: Complex,
    /// The case run on the finest complex.
    pub result: RunResult,
}

/// Solve the case on `complex`, refine `spec.steps` times and re-solve
/// after each step (see [`refine_and_solve`]); `phase` hears about each
/// step.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// use hasse_solver::frontend::run::refine::refine_case;
/// use hasse_solver::refine::{RefineSpec, Strategy};
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nmethod = \"fe\"\nsource = \"2*pi^2*sin(pi*x)*sin(pi*y)\"\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n[exact]\nsolution = \"sin(pi*x)*sin(pi*y)\"\n";
/// let case = Case::from_text("demo.toml", text, &[]).unwrap();
/// let complex = case.build_mesh().unwrap();
/// let spec = RefineSpec { strategy: Strategy::Uniform, steps: 2, ..RefineSpec::default() };
/// let study = refine_case(&case, &complex, &spec, &mut |_| {}).unwrap();
/// assert_eq!(study.steps.len(), 3); // the coarse solve and two refinements
/// assert_eq!(study.complex.cell_count(2), 16 * 16);
/// assert_eq!(study.levels[2].1[0].name, "u");
/// ```
pub fn refine_case(
    case: &Case,
    complex: &Complex,
    spec: &RefineSpec,
    phase: &mut dyn FnMut(&str),
) -> Result<CaseRefinement, RunError> {
    let problem = match &case.problem {
        Problem::Diffusion(spec) => diffusion_problem(case, spec),
        other => {
            return Err(RunError::input_at(
                case,
                "refine",
                format!(
                    "refinement re-solves diffusion problems; this case is kind = \"{}\"",
                    other.kind()
                ),
                None,
            ))
        }
    };
    let exact = case.exact.as_ref().and_then(|e| {
        Some(Exact {
            solution: scalar_fn(e.solution.as_ref()?),
            gradient: e.gradient.as_ref().map(|g| vector_fn(g)),
        })
    });
    let study = refine_and_solve(&problem, complex, spec, exact.as_ref(), phase).map_err(|e| {
        let located = match &e {
            RefineError::Refinement(message) => {
                RunError::input_at(case, "refine.strategy", message, None)
            }
            RefineError::Solve(d) => {
                let Problem::Diffusion(spec) = &case.problem else {
                    return RunError::input(case, e.to_string());
                };
                let keys = Keys {
                    prefix: "problem".into(),
                    coefficient: "conductivity",
                    boundary: &spec.boundary,
                };
                diffusion_error(case, &keys, d.clone())
            }
        };
        located.because(e)
    })?;
    let levels: Vec<(Complex, Vec<Cochain>)> = study
        .levels
        .into_iter()
        .map(|level| {
            let fields = level_fields(case, &level.complex, &level.solution);
            (level.complex, fields)
        })
        .collect();
    let finest = levels
        .last()
        .map(|(complex, _)| complex.clone())
        .unwrap_or_else(|| complex.clone());
    phase("post-processing the final mesh");
    let result = super::solve(case, &finest, &mut |_| {})?;
    Ok(CaseRefinement {
        steps: study.steps,
        levels,
        complex: finest,
        result,
    })
}

/// The primary field of a level and, with an exact solution, its error.
fn level_fields(case: &Case, complex: &Complex, solution: &Solution) -> Vec<Cochain> {
    let dim = match solution.location {
        Location::Nodal => 0,
        _ => complex.dim(),
    };
    let u = solution.field(complex).to_vec();
    let mut fields = Vec::new();
    if let Some(solution_fn) = case.exact.as_ref().and_then(|e| e.solution.as_ref()) {
        let points: Vec<Vec<f64>> = match &solution.cell_points {
            Some(given) => given
                .chunks(complex.embedding_dim())
                .map(<[f64]>::to_vec)
                .collect(),
            None => field_points(complex, dim),
        };
        let exact_values: Vec<f64> = points.iter().map(|x| solution_fn.eval(x, 0.0)).collect();
        let error = u.iter().zip(&exact_values).map(|(a, b)| a - b).collect();
        fields.push(
            Cochain::new("u_exact", dim, exact_values).with_description("the exact solution"),
        );
        fields.push(Cochain::new("error", dim, error).with_description("u − u_exact"));
    }
    fields.insert(
        0,
        Cochain::new("u", dim, u).with_description("the solution on this level"),
    );
    fields
}
