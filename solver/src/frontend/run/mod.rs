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
use crate::physics::diffusion::{self, Diffusion, DiffusionError, Errors};
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

mod coupled;
mod darcy;
mod elasticity;
mod heat;
mod maxwell;
pub mod refine;

/// What a run produced.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Short name of the problem and method, e.g. `diffusion/fe`.
    pub problem: String,
    pub method: Option<String>,
    pub unknowns: usize,
    pub fields: Vec<Cochain>,
    pub errors: Option<Errors>,
    /// L² error of face fluxes (cell-centred and hybrid methods).
    pub flux_error: Option<f64>,
    pub relative_residual: Option<f64>,
    pub factorization: Option<Factorization>,
    /// The fill-reducing ordering of that factorisation, when it is one of
    /// [`Ordering`]'s (not for LU or a solver's own ordering).
    pub ordering: Option<Ordering>,
    /// Phase name and seconds.
    pub timings: Vec<(String, f64)>,
    /// Messages worth a user's attention (large residual, pure Neumann…).
    pub warnings: Vec<String>,
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

/// Why a run failed after the case was read.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Bad data discovered while evaluating or assembling (exit code 2).
    #[error("{0}")]
    Input(String),
    /// The solve failed or is not trustworthy (exit code 1).
    #[error("{0}")]
    Solve(String),
}

impl RunError {
    /// Whether the user's input is at fault (as opposed to the numerics).
    pub fn is_input(&self) -> bool {
        matches!(self, RunError::Input(_))
    }
}

pub(crate) fn scalar_fn(e: &crate::frontend::case::expr::Expression) -> ScalarFn {
    let e = e.clone();
    Arc::new(move |x: &[f64]| e.eval(x, 0.0))
}

/// Solve the case's problem on `complex`; `phase` is told when each long
/// phase starts (for progress display).
pub fn solve(
    case: &Case,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    match &case.problem {
        Problem::Diffusion(spec) => solve_diffusion(case, spec, complex, phase),
        Problem::Gradient(spec) => gradient(case, spec, complex, phase),
        Problem::Heat(spec) => heat::solve(case, spec, complex, phase),
        Problem::Darcy(spec) => darcy::solve(case, spec, complex, phase),
        Problem::Maxwell(spec) => maxwell::solve(case, spec, complex, phase),
        Problem::Elasticity(spec) => elasticity::solve(case, spec, complex, phase),
        Problem::Coupled(spec) => coupled::solve(case, spec, complex, phase),
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
pub(crate) fn conductivity(coefficient: &Coefficient) -> Conductivity {
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

pub(crate) fn diffusion_problem(case: &Case, spec: &DiffusionSpec) -> Diffusion {
    let conductivity = conductivity(&spec.conductivity);
    let mut problem = Diffusion::new(spec.method, conductivity, scalar_fn(&spec.source));
    for b in &spec.boundary {
        let kind = match &b.kind {
            BoundaryKindSpec::Dirichlet(v) => BoundaryKind::Dirichlet(scalar_fn(v)),
            BoundaryKindSpec::Neumann(v) => BoundaryKind::Neumann(scalar_fn(v)),
            BoundaryKindSpec::Robin { alpha, value } => BoundaryKind::Robin {
                alpha: scalar_fn(alpha),
                value: scalar_fn(value),
            },
        };
        problem = problem.with_boundary(&b.tag, kind);
    }
    if let Some(f) = case.solver.factorization {
        problem.factorization = f;
    }
    problem.ordering = case.solver.ordering;
    if spec.circumcentres {
        problem.cell_points = diffusion::CellPoints::Circumcentres;
    }
    problem
}

/// The case's `solver.type`: multigrid-preconditioned CG instead of the
/// direct factorisation when asked for (or chosen by the automatic rule).
fn with_solver(case: &Case, problem: Diffusion, complex: &Complex) -> Result<Diffusion, RunError> {
    use crate::frontend::case::SolverKind;
    use crate::multigrid::{Hierarchy, SolverChoice};
    // Grid levels exist for the rectangle and box generators: coarser grids
    // halve n, which the prolongation checks.
    let grid = match (&case.mesh.generator, &case.mesh.n) {
        (Some(g), Some(n)) if g == "rectangle" || g == "box" || g == "interval" => {
            Some(Hierarchy::Grid { cells: n.clone() })
        }
        _ => None,
    };
    let choice = match case.solver.kind {
        SolverKind::Direct => return Ok(problem),
        SolverKind::Multigrid => match grid {
            Some(h) => SolverChoice::Multigrid(h),
            None => {
                return Err(RunError::Input(
                    "solver.type = \"multigrid\" needs the grid levels of a rectangle or box generator mesh; use \"amg\" for other meshes".into(),
                ))
            }
        },
        SolverKind::Amg => SolverChoice::Multigrid(Hierarchy::Algebraic),
        SolverKind::Auto => SolverChoice::Auto(grid),
    };
    Ok(problem
        .with_solver(choice, case.solver.tolerance, complex)
        .with_cell_prolongation(case.solver.cell_prolongation))
}

fn is_input_error(e: &DiffusionError) -> bool {
    !matches!(
        e,
        DiffusionError::Solve(_) | DiffusionError::Canonical(_) | DiffusionError::Iterative(_)
    )
}

fn solve_diffusion(
    case: &Case,
    spec: &DiffusionSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let problem = with_solver(case, diffusion_problem(case, spec), complex)?;
    let mut warnings = Vec::new();
    if let (crate::metric::Method::Fv, Coefficient::Tensor(rows)) =
        (spec.method, &spec.conductivity)
    {
        let off_diagonal_zero = rows.iter().enumerate().all(|(i, row)| {
            row.iter()
                .enumerate()
                .all(|(j, e)| i == j || (e.is_constant() && e.eval(&[], 0.0) == 0.0))
        });
        if !off_diagonal_zero {
            warnings.push(
                "the two-point flux (fv) sees only n·K·n: with off-diagonal K it is inconsistent; use fv-mimetic or fe".into(),
            );
        }
    }
    phase("assembling and solving");
    let started = Instant::now();
    let solution = problem.solve(complex).map_err(|e| {
        if is_input_error(&e) {
            RunError::Input(e.to_string())
        } else {
            RunError::Solve(e.to_string())
        }
    })?;
    let total = started.elapsed().as_secs_f64();
    let report = &solution.report;
    // With CG the "numeric" phase builds the preconditioner, not a factor.
    let setup = if solution.iterations.is_some() {
        "preconditioner setup"
    } else if solution.analysed_during_assembly {
        // Its analysis overlapped the assembly: the rows add up to more
        // than "assembly + solve".
        "factorisation (analysis beside assembly)"
    } else {
        "factorisation"
    };
    let mut timings = vec![
        ("assembly".to_string(), solution.assembly_seconds),
        (
            setup.to_string(),
            report.symbolic_seconds + report.numeric_seconds,
        ),
        ("solve".to_string(), report.solve_seconds),
    ];
    if solution.pure_neumann {
        warnings.push(format!(
            "pure Neumann problem: solved with zero mean (data imbalance {:.2e} removed)",
            solution.neumann_imbalance
        ));
    }
    if solution.iterations.is_some() {
        // CG stops at solver.tolerance: only the failure limit applies.
        if report.relative_residual.is_nan()
            || report.relative_residual > case.solver.residual_limit
        {
            check_residual(case, report.relative_residual, &mut warnings)?;
        }
    } else {
        check_residual(case, report.relative_residual, &mut warnings)?;
    }
    let notes = match &solution.iterations {
        Some(cg) => vec![(
            "iterative".to_string(),
            format!(
                "multigrid-preconditioned CG ({}): {} iterations to relative residual {:.2e} (tolerance {:.1e}), {:.3} s",
                match case.solver.kind {
                    crate::frontend::case::SolverKind::Amg => "smoothed aggregation",
                    _ => "grid levels",
                },
                cg.iterations,
                cg.relative_residual,
                case.solver.tolerance,
                cg.seconds
            ),
        )],
        None => Vec::new(),
    };
    if solution.condition_bound > 1e12 {
        warnings.push(format!("the system's condition number is at least {:.1e} (largest / smallest diagonal entry): expect to lose about {:.0} of 16 digits; check coefficients and cell sizes that span many orders of magnitude", solution.condition_bound, solution.condition_bound.log10()));
    }

    phase("post-processing");
    let post = Instant::now();
    let n = complex.dim();
    let field_dim = match solution.location {
        Location::Nodal => 0,
        _ => n,
    };
    let field = solution.field(complex).to_vec();
    let mut fields =
        vec![Cochain::new("u", field_dim, field.clone()).with_description("the solution")];
    match solution.location {
        Location::Nodal => fields.push(
            Cochain::new("flux", 1, solution.flux.clone())
                .with_description("edge cochain Ω A u (the discrete flux along edges)"),
        ),
        Location::CellCentred => fields.push(
            Cochain::new("flux", n - 1, solution.flux.clone())
                .with_description("flux through each (n−1)-cell along its orientation"),
        ),
        // Half-face fluxes have no cells of their own to live on.
        Location::Hybrid => {}
    }
    let gradient = diffusion::reconstruct_gradient(complex, &solution);
    // The reconstruction needs cells that fill their space; on a surface in
    // R³ it is undefined (NaN) and left out.
    let gradient_defined = gradient.iter().all(|g| g.iter().all(|v| v.is_finite()));
    for (axis, name) in ["x", "y", "z"]
        .iter()
        .enumerate()
        .take(if gradient_defined {
            complex.embedding_dim()
        } else {
            0
        })
    {
        fields.push(
            Cochain::new(
                format!("grad_{name}"),
                n,
                gradient.iter().map(|g| g[axis]).collect(),
            )
            .with_description(format!("∂u/∂{name} reconstructed per cell")),
        );
    }
    let exact = case
        .exact
        .as_ref()
        .and_then(|e| Some((e.solution.as_ref()?, e)));
    let (errors, flux_error) = match exact {
        None => (None, None),
        Some((solution_fn, exact)) => {
            let u = scalar_fn(solution_fn);
            let grad: Option<VectorFn> = exact.gradient.as_ref().map(|g| vector_fn(g));
            let errors = diffusion::errors(complex, &solution, &u, grad.as_ref());
            let flux_error = grad
                .as_ref()
                .and_then(|g| diffusion::flux_error(complex, &solution, &problem, g));
            let points = match &solution.cell_points {
                Some(given) => given
                    .chunks(complex.embedding_dim())
                    .map(<[f64]>::to_vec)
                    .collect(),
                None => field_points(complex, field_dim),
            };
            let exact_values: Vec<f64> = points.iter().map(|x| u(x)).collect();
            let mut difference: Vec<f64> = field
                .iter()
                .zip(&exact_values)
                .map(|(a, b)| a - b)
                .collect();
            if solution.pure_neumann {
                // u is defined up to a constant: compare with the mean removed,
                // as `errors` does.
                let mean = difference.iter().sum::<f64>() / difference.len().max(1) as f64;
                difference.iter_mut().for_each(|d| *d -= mean);
            }
            fields.push(
                Cochain::new("u_exact", field_dim, exact_values)
                    .with_description("the exact solution at the unknowns' points"),
            );
            fields
                .push(Cochain::new("error", field_dim, difference).with_description("u − u_exact"));
            (Some(errors), flux_error)
        }
    };
    timings.push(("post-processing".into(), post.elapsed().as_secs_f64()));
    timings.push(("assembly + solve".into(), total));
    Ok(RunResult {
        problem: "diffusion".into(),
        method: Some(spec.method.name().into()),
        unknowns: solution.unknowns(),
        fields,
        errors,
        flux_error,
        relative_residual: Some(report.relative_residual),
        factorization: solution
            .iterations
            .is_none()
            .then_some(report.factorization),
        ordering: report.ordering,
        timings,
        warnings,
        pure_neumann: solution.pure_neumann,
        series: Vec::new(),
        notes,
        report: serde_json::Map::new(),
    })
}

fn check_residual(case: &Case, residual: f64, warnings: &mut Vec<String>) -> Result<(), RunError> {
    // A NaN residual fails too.
    if residual.is_nan() || residual > case.solver.residual_limit {
        return Err(RunError::Solve(format!(
            "relative residual {residual:.3e} exceeds solver.residual_limit = {:.1e}: the system is (nearly) singular or badly conditioned",
            case.solver.residual_limit
        )));
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

/// Read a metric file: `row column value` per line, `#` comments.
fn read_metric_file(path: &PathBuf, faces: usize) -> Result<Vec<(usize, usize, f64)>, RunError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| RunError::Input(format!("{}: cannot read: {e}", path.display())))?;
    let mut entries = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let bad =
            |what: String| RunError::Input(format!("{}:{}: {what}", path.display(), number + 1));
        let parts: Vec<&str> = line.split_whitespace().collect();
        if parts.len() != 3 {
            return Err(bad(format!(
                "expected `row column value`, found {} fields",
                parts.len()
            )));
        }
        let index = |s: &str| -> Result<usize, RunError> {
            let i: usize = s
                .parse()
                .map_err(|_| bad(format!("`{s}` is not a face index")))?;
            if i >= faces {
                return Err(bad(format!(
                    "face {i} does not exist (the mesh has {faces} faces, numbered from 0)"
                )));
            }
            Ok(i)
        };
        let value: f64 = parts[2]
            .parse()
            .map_err(|_| bad(format!("`{}` is not a number", parts[2])))?;
        if !value.is_finite() {
            return Err(bad(format!("value {value} is not finite")));
        }
        entries.push((index(parts[0])?, index(parts[1])?, value));
    }
    Ok(entries)
}

/// g = −Ω ∂_nᵀ f: for an interior face F between cells c₁ (F oriented
/// outward of c₁) and c₂, (∂_nᵀ f)_F = f(c₁) − f(c₂), so −∂_nᵀ f is the
/// jump of f along F's normal and g approximates ∇f·n_F once Ω carries
/// 1/distance. Boundary faces (one cell) get no row: g = 0 there.
fn gradient(
    case: &Case,
    spec: &GradientSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let _ = case;
    phase("sampling and applying Ω δ");
    let started = Instant::now();
    let n = complex.dim();
    if n == 0 {
        return Err(RunError::Input(
            "a gradient problem needs a mesh of dimension ≥ 1".into(),
        ));
    }
    let points = field_points(complex, n);
    let f: Vec<f64> = points.iter().map(|x| spec.field.eval(x, 0.0)).collect();
    if let Some(c) = f.iter().position(|v| !v.is_finite()) {
        return Err(RunError::Input(format!(
            "problem.field is not finite ({}) at cell {c}, centroid {:?}",
            f[c], points[c]
        )));
    }
    let faces = complex.cell_count(n - 1);
    let metric = match &spec.metric {
        GradientMetric::Diagonal(sigma) => FaceMetric::Diagonal(*sigma),
        GradientMetric::TwoPoint => FaceMetric::TwoPoint,
        GradientMetric::File { path, scale } => FaceMetric::Entries(
            read_metric_file(path, faces)?
                .into_iter()
                .map(|(row, column, value)| (row, column, scale * value))
                .collect(),
        ),
    };
    let NormalGradient { jump, gradient: g } =
        normal_gradient(complex, &f, &metric).map_err(|e| RunError::Input(e.to_string()))?;
    let seconds = started.elapsed().as_secs_f64();
    Ok(RunResult {
        problem: "gradient".into(),
        method: None,
        unknowns: 0,
        fields: vec![
            Cochain::new("f", n, f).with_description("the field sampled at cell centroids"),
            Cochain::new("jump", n - 1, jump).with_description(
                "−∂ᵀ f: the jump of f across each interior face along its normal",
            ),
            Cochain::new("normal_gradient", n - 1, g)
                .with_description("Ω (−∂ᵀ f): the normal gradient as a face cochain"),
        ],
        errors: None,
        flux_error: None,
        relative_residual: None,
        factorization: None,
        ordering: None,
        timings: vec![("sample + Ω δ".into(), seconds)],
        warnings: Vec::new(),
        pure_neumann: false,
        series: Vec::new(),
        notes: Vec::new(),
        report: serde_json::Map::new(),
    })
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
            writeln!(f)?;
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

/// The run's cochains, each marked with the method that computed it.
fn cochains(fields: &[Cochain], method: Option<&str>) -> Vec<Cochain> {
    fields
        .iter()
        .map(|c| match method {
            Some(m) => c.clone().with_method(m),
            None => c.clone(),
        })
        .collect()
}

/// The provenance of a run of `case` with `report`.
fn provenance(case: &Case, report: serde_json::Value) -> crate::frontend::output::Provenance {
    let mut provenance = crate::frontend::output::Provenance::new(report);
    provenance.case_text = Some(case.text.clone());
    provenance.case_path = Some(case.path.display().to_string());
    provenance
}

/// What [`write_output`] writes for `result`.
fn run_output<'c>(
    case: &Case,
    complex: &'c Complex,
    result: &RunResult,
) -> crate::frontend::output::RunOutput<'c> {
    use crate::frontend::output::Step;
    let method = result.method.as_deref();
    let steps = if result.series.is_empty() {
        vec![Step {
            time: 0.0,
            cochains: cochains(&result.fields, method),
        }]
    } else {
        result
            .series
            .iter()
            .map(|(time, fields)| Step {
                time: *time,
                cochains: cochains(fields, method),
            })
            .collect()
    };
    crate::frontend::output::RunOutput {
        complex,
        steps,
        provenance: provenance(case, result.report_json(complex)),
    }
}

/// Write the run's fields, mesh and provenance to `<stem>.h5`,
/// `<stem>.xdmf` and, for edge or face fields, `<stem>.edges.xdmf` /
/// `<stem>.faces.xdmf` (atomically: nothing appears under those names
/// unless all were written completely).
pub fn write_output(
    case: &Case,
    complex: &Complex,
    result: &RunResult,
    stem: &std::path::Path,
) -> Result<crate::frontend::output::OutputFiles, crate::frontend::output::OutputError> {
    crate::frontend::output::write_run(stem, &run_output(case, complex, result))
}

/// Write a refinement study as a time series whose mesh changes: level k
/// at "time" k, each with its own complex (see `cases/OUTPUT.md`).
pub fn write_levels(
    case: &Case,
    levels: &[(Complex, Vec<Cochain>)],
    report: serde_json::Value,
    stem: &std::path::Path,
) -> Result<crate::frontend::output::OutputFiles, crate::frontend::output::OutputError> {
    use crate::frontend::output::{MeshStep, SeriesOutput};
    let method = case.method().map(|m| m.name());
    let steps = levels
        .iter()
        .enumerate()
        .map(|(k, (complex, fields))| MeshStep {
            time: k as f64,
            complex,
            cochains: cochains(fields, method),
        })
        .collect();
    crate::frontend::output::write_mesh_series(
        stem,
        &SeriesOutput {
            steps,
            provenance: provenance(case, report),
        },
    )
}

/// Solve as [`solve`]; a transient (heat) run also hands each saved level,
/// as soon as it is computed, to `stream`, which writes it to the partial
/// output of its stem (see [`crate::frontend::output::PartialOutput`]), so that an
/// interrupted or failed run keeps its completed levels. Other problems
/// ignore `stream`.
pub fn solve_streaming<'a>(
    case: &'a Case,
    complex: &'a Complex,
    stream: Option<&mut LevelStream<'a>>,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    match (&case.problem, stream) {
        (Problem::Heat(spec), Some(stream)) => {
            heat::solve_streaming(case, spec, complex, phase, Some(stream))
        }
        _ => solve(case, complex, phase),
    }
}

/// The output of one `hasse run` under one stem: the partial output of a
/// transient run while it goes on, then the final output.
///
/// The partial output is started by the first level (so steady runs write
/// none) and stops for good at the first level it cannot write: a level
/// with a non-finite value (the run fails anyway and says why) or an I/O
/// error ([`stopped`](Self::stopped); the run goes on, since the final
/// output may still succeed).
///
/// ```
/// use hasse_solver::frontend::{case::Case, run};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [4, 4]
/// [problem]
/// kind = "heat"
/// method = "fe"
/// initial = "x"
/// [time]
/// dt = 0.01
/// end = 0.04
/// "#;
/// let case = Case::from_text("cool.toml", text, &[]).unwrap();
/// let complex = case.build_mesh().unwrap();
/// let dir = std::env::temp_dir().join(format!("hasse-doc-stream-{}", std::process::id()));
/// let mut stream = run::LevelStream::new(&case, &dir.join("cool"));
/// let mut result = run::solve_streaming(&case, &complex, Some(&mut stream), &mut |_| {}).unwrap();
/// // Every saved level is in the partial output until the final one is written.
/// assert_eq!(stream.partial().unwrap().len(), result.series.len());
/// assert!(dir.join("cool.partial.xdmf").exists());
/// let files = stream.finish(&complex, &mut result).unwrap();
/// assert!(files.xdmf.exists() && !dir.join("cool.partial.xdmf").exists());
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub struct LevelStream<'a> {
    case: &'a Case,
    stem: PathBuf,
    partial: Option<crate::frontend::output::PartialOutput<'a>>,
    /// Levels are no longer written (see the type's documentation).
    closed: bool,
    stopped: Option<crate::frontend::output::OutputError>,
}

impl<'a> LevelStream<'a> {
    /// A stream to the output of `case` under `stem`; nothing is written
    /// before the first level.
    pub fn new(case: &'a Case, stem: &std::path::Path) -> Self {
        Self {
            case,
            stem: stem.to_path_buf(),
            partial: None,
            closed: false,
            stopped: None,
        }
    }

    /// Write saved level `time` with `fields` (on `complex`), starting the
    /// partial output at the first one; `phase` is told when it starts.
    pub(crate) fn level(
        &mut self,
        complex: &'a Complex,
        time: f64,
        fields: &[Cochain],
        method: Option<&str>,
        phase: &mut dyn FnMut(&str),
    ) {
        use crate::frontend::output::{OutputError, PartialOutput, Step};
        if self.closed {
            return;
        }
        if self.partial.is_none() {
            let report = serde_json::json!({ "partial": "written level by level during the run" });
            match PartialOutput::create(&self.stem, complex, &provenance(self.case, report)) {
                Ok(partial) => {
                    if partial.removed_stale() {
                        phase(&format!(
                            "removed the partial output of an earlier run, {}",
                            partial.xdmf().display()
                        ));
                    }
                    self.partial = Some(partial);
                }
                Err(e) => {
                    self.closed = true;
                    self.stopped = Some(e);
                    return;
                }
            }
        }
        let Some(partial) = self.partial.as_mut() else {
            return;
        };
        let step = Step {
            time,
            cochains: cochains(fields, method),
        };
        match partial.push(&step) {
            Ok(()) => {}
            Err(OutputError::NonFinite { .. }) => self.closed = true,
            Err(e) => {
                self.closed = true;
                self.stopped = Some(e);
            }
        }
    }

    /// The partial output, once started.
    pub fn partial(&self) -> Option<&crate::frontend::output::PartialOutput<'a>> {
        self.partial.as_ref()
    }

    /// Why the partial output stopped before the run ended, if an error
    /// stopped it.
    pub fn stopped(&self) -> Option<&crate::frontend::output::OutputError> {
        self.stopped.as_ref()
    }

    /// Which levels an interrupted or failed run left readable, and where,
    /// e.g. `completed levels 0..2 (t = 0, 0.01, 0.02) are readable in
    /// out/heat.partial.xdmf`; `None` when there are none.
    pub fn readable(&self) -> Option<String> {
        let partial = self.partial.as_ref().filter(|p| !p.is_empty())?;
        let times = partial.times();
        // Long runs save hundreds of levels: the first two and the last tell
        // the spacing and how far the run came.
        let shown: Vec<String> = if times.len() <= 5 {
            times.iter().map(|t| format!("{t}")).collect()
        } else {
            vec![
                format!("{}", times[0]),
                format!("{}", times[1]),
                "…".into(),
                format!("{}", times[times.len() - 1]),
            ]
        };
        Some(format!(
            "completed levels 0..{} (t = {}) are readable in {}",
            times.len() - 1,
            shown.join(", "),
            partial.xdmf().display()
        ))
    }

    /// Write the final output of `result` (as [`write_output`]) and then
    /// remove the partial output of the stem, this run's or an earlier
    /// one's. On an error the partial output stays. Once the final output
    /// is in place, a failure to remove the partial output does not undo
    /// it: it becomes a warning of `result`.
    pub fn finish(
        self,
        complex: &Complex,
        result: &mut RunResult,
    ) -> Result<crate::frontend::output::OutputFiles, crate::frontend::output::OutputError> {
        let run = run_output(self.case, complex, result);
        if let (Some(partial), false) = (&self.partial, self.closed) {
            // The partial output holds every level: the final one must
            // have the same.
            partial.check_run(&run)?;
        }
        let files = crate::frontend::output::write_run(&self.stem, &run)?;
        if let Err(e) = crate::frontend::output::remove_partial(&self.stem) {
            result.warnings.push(format!(
                "the output is complete, but the partial output could not be removed: {e}"
            ));
        }
        Ok(files)
    }
}
