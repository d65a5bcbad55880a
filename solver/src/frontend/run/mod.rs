//! Running a case: build the mesh, assemble and solve the problem, compute
//! errors against the exact solution, collect the cochains to write.
//!
//! ```
//! use hasse_solver::frontend::{case::Case, run};
//! let text = r#"
//! [mesh]
//! generator = "rectangle"
//! n = [8, 8]
//! [problem]
//! method = "fe"
//! source = "2*pi^2*sin(pi*x)*sin(pi*y)"
//! [[boundary]]
//! tag = "boundary"
//! type = "dirichlet"
//! value = 0
//! [exact]
//! solution = "sin(pi*x)*sin(pi*y)"
//! "#;
//! let case = Case::from_text("demo.toml", text, &[]).unwrap();
//! let complex = case.build_mesh().unwrap();
//! let result = run::solve(&case, &complex, &mut |_| {}).unwrap();
//! assert!(result.errors.unwrap().l2 < 0.02);
//! ```

use crate::frontend::case::{
    BoundaryKindSpec, Case, Coefficient, DiffusionSpec, GradientMetric, GradientSpec, Problem,
};
use crate::frontend::output::Cochain;
use crate::la::direct::Factorization;
use crate::la::ordering::Ordering;
use crate::metric::Location;
use crate::metric::Tensor;
use crate::physics::diffusion::{Diffusion, Errors};
use crate::physics::gradient::{normal_gradient, FaceMetric, NormalGradient};
use crate::physics::BoundaryKind;
use crate::physics::Conductivity;
use crate::physics::ScalarFn;
use crate::physics::TensorFn;
use crate::physics::VectorFn;
use hasse_complex::Complex;
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

mod consistency;
mod coupled;
mod darcy;
mod dec;
mod diffusion;
mod disk;
mod elasticity;
mod error;
mod form_diffusion;
mod gradient;
pub mod growth;
mod heat;
mod hodge;
mod maxwell;
mod nonlinear;
mod nonlinear_heat;
mod petsc;
pub(crate) mod probes;
mod quantities;
pub mod refine;
mod restart;
mod stars;
mod stream;
mod transport;

pub(crate) use diffusion::diffusion_problem;
use diffusion::solve_diffusion;
pub use disk::OutputEstimate;
pub(crate) use error::{diffusion_error, Keys, FINITE_HELP};
pub use error::{Failure, RunError};
pub use probes::{probes_csv, write_probes_csv, write_tables};
pub use quantities::{quantities_csv, write_quantities_csv};
pub use stream::{solve_streaming, unwritten_fields, write_levels, write_output, LevelStream};

/// What a run produced.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Short name of the problem and method, e.g. `diffusion/fe`.
    pub problem: String,
    /// The method's name, for problems that have one.
    pub method: Option<String>,
    /// Unknowns of the solved system.
    pub unknowns: usize,
    /// The cochains to write: the solution and, with an exact solution,
    /// its values and the error on the same cells; for a transient run,
    /// those of the last level.
    pub fields: Vec<Cochain>,
    /// Errors against the case's `[exact]` solution, when it has one.
    pub errors: Option<Errors>,
    /// L² error of face fluxes (cell-centred and hybrid methods).
    pub flux_error: Option<f64>,
    /// ‖b − Mx‖₂ / ‖b‖₂ of the (last) linear solve, when there is one.
    pub relative_residual: Option<f64>,
    /// The direct factorisation used, when one was.
    pub factorization: Option<Factorization>,
    /// The fill-reducing ordering of that factorisation, when it is one of
    /// [`Ordering`]'s (not for LU or a solver's own ordering).
    pub ordering: Option<Ordering>,
    /// Phase name and seconds.
    pub timings: Vec<(String, f64)>,
    /// Messages worth a user's attention (large residual, pure Neumann…).
    pub warnings: Vec<String>,
    /// The problem had no Dirichlet or Robin boundary (Darcy: no pressure
    /// face), so its solution is the one with zero mean and errors are
    /// measured with the mean removed.
    pub pure_neumann: bool,
    /// Saved time levels of a transient run, (t, fields) in order; the
    /// output writes them as a time series. Empty for steady problems,
    /// whose `fields` are the one step.
    pub series: Vec<(f64, Vec<Cochain>)>,
    /// Further summary lines (label, text), e.g. time stepping or modes.
    pub notes: Vec<(String, String)>,
    /// Problem-specific entries of the stored report (per-level errors,
    /// eigenvalues…), merged into [`RunResult::report_json`].
    pub report: serde_json::Map<String, serde_json::Value>,
}

/// A steady boundary condition of the case as the physics takes it:
/// diffusion, nonlinear diffusion and transport read `[[boundary]]` alike.
pub(crate) fn boundary_kind(spec: &BoundaryKindSpec) -> BoundaryKind {
    match spec {
        BoundaryKindSpec::Dirichlet(v) => BoundaryKind::Dirichlet(scalar_fn(v)),
        BoundaryKindSpec::Neumann(v) => BoundaryKind::Neumann(scalar_fn(v)),
        BoundaryKindSpec::Robin { alpha, value } => BoundaryKind::Robin {
            alpha: scalar_fn(alpha),
            value: scalar_fn(value),
        },
    }
}

pub(crate) fn scalar_fn(e: &crate::frontend::case::expr::Expression) -> ScalarFn {
    let e = e.clone();
    Arc::new(move |x: &[f64]| e.eval(x, 0.0))
}

/// A case datum given per region as the library takes it (evaluated at
/// t = 0); `None` for a datum given by one expression.
pub(crate) fn regional_fn(
    e: &crate::frontend::case::expr::Expression,
) -> Option<crate::physics::regions::Regional<ScalarFn>> {
    let regions = e.regions()?;
    Some(crate::physics::regions::Regional::new(
        regions
            .pieces
            .iter()
            .map(|(name, piece)| (name.clone(), scalar_fn(piece)))
            .collect(),
        regions.default.as_ref().map(scalar_fn),
    ))
}

/// Solve the case's problem on `complex`; `phase` is told when each long
/// phase starts (for progress display).
pub fn solve(
    case: &Case,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let mut result = match &case.problem {
        Problem::Diffusion(spec) if spec.is_nonlinear() => {
            nonlinear::solve(case, spec, complex, phase)
        }
        Problem::Diffusion(spec) => solve_diffusion(case, spec, complex, phase),
        Problem::FormDiffusion(spec) => form_diffusion::solve(case, spec, complex, phase),
        Problem::Gradient(spec) => gradient::solve(case, spec, complex, phase),
        Problem::Heat(spec) => heat::solve(case, spec, complex, phase),
        Problem::Darcy(spec) => darcy::solve(case, spec, complex, phase),
        Problem::Maxwell(spec) => maxwell::solve(case, spec, complex, phase),
        Problem::Hodge(spec) => hodge::solve(case, spec, complex, phase),
        Problem::Cohomology(spec) => dec::cohomology(case, spec, complex, phase),
        Problem::Decomposition(spec) => dec::decomposition(case, spec, complex, phase),
        Problem::Elasticity(spec) => elasticity::solve(case, spec, complex, phase),
        Problem::Coupled(spec) => coupled::solve(case, spec, complex, phase),
        Problem::Transport(spec) => transport::solve(case, spec, complex, phase),
        Problem::Growth(_) => growth::solve(case, complex, phase),
    }?;
    if let Some(k) = probes::form_degree(&case.problem) {
        probes::attach_form_probes(case, complex, k, &mut result)?;
    }
    Ok(result)
}

/// The case's data evaluated on `complex` where the solve evaluates them
/// (coefficients, sources, materials, a gradient's field), without
/// assembling or solving: `hasse check` refuses bad data with the errors
/// `hasse run` would give. Boundary values and problems of the whole
/// system (a floating part, incompatible Neumann data) need the solve.
///
/// ```
/// use hasse_solver::frontend::{case::Case, run};
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nmethod = \"fe\"\nconductivity = \"1 - 2*x\"\n";
/// let case = Case::from_text("regions.toml", text, &[]).unwrap();
/// let complex = case.build_mesh().unwrap();
/// let error = run::check_data(&case, &complex).unwrap_err();
/// // Negative where x > ½: the first such cell's centroid, at the key's line.
/// assert!(error.to_string().starts_with("regions.toml:6:16: `problem.conductivity`: the conductivity at (0.625, 0.125)"));
/// ```
pub fn check_data(case: &Case, complex: &Complex) -> Result<(), RunError> {
    match &case.problem {
        Problem::Diffusion(spec) if spec.is_nonlinear() => nonlinear::check(case, spec, complex),
        Problem::Diffusion(spec) => diffusion::check(case, spec, complex),
        Problem::FormDiffusion(spec) => form_diffusion::check(case, spec, complex),
        Problem::Gradient(spec) => gradient::check(case, spec, complex),
        Problem::Heat(spec) => heat::check(case, spec, complex),
        Problem::Darcy(spec) => darcy::check(case, spec, complex),
        Problem::Maxwell(_) => Ok(()),
        Problem::Hodge(spec) => stars::read_stars(case, &spec.stars, complex).map(|_| ()),
        Problem::Cohomology(spec) => stars::read_stars(case, &spec.stars, complex).map(|_| ()),
        Problem::Decomposition(spec) => dec::check(case, spec, complex),
        Problem::Elasticity(spec) => elasticity::check(case, spec, complex),
        Problem::Coupled(spec) => coupled::check(case, spec, complex),
        Problem::Transport(spec) => transport::check(case, spec, complex),
        Problem::Growth(spec) => growth::check(case, spec, complex),
    }
}

/// ∇u from one expression per coordinate.
pub(crate) fn vector_fn(components: &[crate::frontend::case::expr::Expression]) -> VectorFn {
    let g = components.to_vec();
    Arc::new(move |x: &[f64]| {
        let mut v = [0.0; 3];
        for (slot, e) in v.iter_mut().zip(&g) {
            *slot = e.eval(x, 0.0);
        }
        v
    })
}

/// A case coefficient as a conductivity of the library (evaluated at t = 0).
/// A coefficient per region (scalars, tensors or both) is one conductivity
/// per region, each cell's checked where the assembly evaluates it.
pub(crate) fn conductivity(coefficient: &Coefficient) -> Conductivity {
    if let Some(regional) = coefficient.by_region() {
        return Conductivity::Regional(Arc::new(regional.map(conductivity)));
    }
    match coefficient {
        Coefficient::Scalar(e) => Conductivity::Scalar(scalar_fn(e)),
        Coefficient::Tensor(rows) => {
            let rows = rows.clone();
            let f: TensorFn = Arc::new(move |x: &[f64]| {
                let mut t: Tensor = [[0.0; 3]; 3];
                for (i, row) in rows.iter().enumerate() {
                    for (j, e) in row.iter().enumerate() {
                        t[i][j] = e.eval(x, 0.0);
                    }
                }
                t
            });
            Conductivity::Tensor(f)
        }
    }
}

fn check_residual(case: &Case, residual: f64, warnings: &mut Vec<String>) -> Result<(), RunError> {
    // A NaN residual fails too.
    if residual.is_nan() || residual > case.solver.residual_limit {
        return Err(RunError::solve(
            case,
            format!(
                "relative residual {residual:.3e} exceeds solver.residual_limit = {:.1e}: the system is (nearly) singular or badly conditioned",
                case.solver.residual_limit
            ),
            Some("check the boundary conditions and coefficients; raise solver.residual_limit only if the loss of accuracy is acceptable".into()),
        ));
    }
    if residual > case.solver.residual_warning {
        warnings.push(format!(
            "relative residual {residual:.3e} is above solver.residual_warning = {:.1e}",
            case.solver.residual_warning
        ));
    }
    Ok(())
}

/// u − u_exact, its discrete L² norm with the given weights (lumped vertex
/// volumes or cell measures) and its largest absolute value.
pub(crate) fn weighted_errors(
    values: &[f64],
    exact: &[f64],
    weights: &[f64],
) -> (Vec<f64>, f64, f64) {
    let difference: Vec<f64> = values.iter().zip(exact).map(|(a, b)| a - b).collect();
    let l2 = difference
        .iter()
        .zip(weights)
        .map(|(e, w)| e * e * w)
        .sum::<f64>()
        .sqrt();
    let max = difference.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    (difference, l2, max)
}

/// Where the values of a `dim`-cochain are sampled: vertices or centroids.
pub(crate) fn field_points(complex: &Complex, dim: usize) -> Vec<Vec<f64>> {
    let d = complex.embedding_dim();
    if dim == 0 {
        (0..complex.cell_count(0))
            .map(|v| complex.vertices().point(v).to_vec())
            .collect()
    } else {
        complex
            .centroid(dim)
            .chunks(d)
            .map(<[f64]>::to_vec)
            .collect()
    }
}

impl fmt::Display for RunResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.method {
            Some(m) => writeln!(f, "problem    {} ({m})", self.problem)?,
            None => writeln!(f, "problem    {}", self.problem)?,
        }
        if self.unknowns > 0 {
            write!(f, "unknowns   {}", self.unknowns)?;
            if let Some(fact) = self.factorization {
                write!(f, ", solver {fact}")?;
                if let Some(ordering) = self.ordering {
                    write!(f, ", {ordering} ordering")?;
                }
            }
            if let Some(r) = self.relative_residual {
                write!(f, ", relative residual {r:.2e}")?;
            }
            writeln!(f)?;
        }
        if let Some(e) = &self.errors {
            write!(f, "error      L2 {:.6e}, max {:.6e}", e.l2, e.max)?;
            if e.gradient_l2.is_finite() {
                write!(f, ", gradient L2 {:.6e}", e.gradient_l2)?;
            }
            if e.quadrature {
                writeln!(
                    f,
                    " (L2 norms by quadrature of the method's field, max at the unknowns' points)"
                )?;
                write!(
                    f,
                    "sampled    L2 {:.6e} at the unknowns' points",
                    e.l2_sampled
                )?;
                if e.gradient_sampled.is_finite() {
                    write!(
                        f,
                        ", gradient L2 {:.6e} at the centroids",
                        e.gradient_sampled
                    )?;
                }
                writeln!(f)?;
            } else {
                writeln!(f, " (at the unknowns' points)")?;
            }
        }
        if let Some(q) = self.flux_error {
            writeln!(f, "flux error L2 {q:.6e}")?;
        }
        for (label, text) in &self.notes {
            for (i, line) in text.lines().enumerate() {
                let label = if i == 0 { label.as_str() } else { "" };
                writeln!(f, "{label:<10} {line}")?;
            }
        }
        let timing: Vec<String> = self
            .timings
            .iter()
            .map(|(name, s)| format!("{name} {s:.3} s"))
            .collect();
        writeln!(f, "timing     {}", timing.join(", "))?;
        for w in &self.warnings {
            writeln!(f, "warning    {w}")?;
        }
        Ok(())
    }
}

impl RunResult {
    /// The report stored with the output (and printed by `-v`), as JSON.
    pub fn report_json(&self, complex: &Complex) -> serde_json::Value {
        let errors = self.errors.map(|e| {
            serde_json::json!({
                "l2": e.l2,
                "max": e.max,
                "gradient_l2": e.gradient_l2.is_finite().then_some(e.gradient_l2),
                "by_quadrature": e.quadrature,
                "l2_sampled": e.l2_sampled,
                "gradient_sampled": e.gradient_sampled.is_finite().then_some(e.gradient_sampled),
            })
        });
        let timings: serde_json::Map<String, serde_json::Value> = self
            .timings
            .iter()
            .map(|(name, s)| (name.clone(), serde_json::json!(s)))
            .collect();
        let mut report = serde_json::json!({
            "problem": self.problem,
            "method": self.method,
            "cells_per_dimension": complex.cell_counts(),
            "unknowns": self.unknowns,
            "factorization": self.factorization.map(|f| f.to_string()),
            "ordering": self.ordering.map(|o| o.to_string()),
            "relative_residual": self.relative_residual,
            "errors": errors,
            "flux_error": self.flux_error,
            "pure_neumann": self.pure_neumann,
            "timings_seconds": timings,
            "warnings": self.warnings,
        });
        if let Some(map) = report.as_object_mut() {
            map.extend(self.report.clone());
        }
        report
    }
}
