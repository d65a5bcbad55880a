//! Running a diffusion case: the problem from its spec, the solver it
//! asks for, the solve, and the fields and errors of the summary.

use super::*;
use crate::physics::diffusion::{self as physics, CellPoints};

pub(crate) fn diffusion_problem(case: &Case, spec: &DiffusionSpec) -> Diffusion {
    let conductivity = conductivity(&spec.conductivity);
    let mut problem = Diffusion::new(spec.method, conductivity, scalar_fn(&spec.source));
    if let Some(source) = regional_fn(&spec.source) {
        problem = problem.with_source_by_region(source);
    }
    for b in &spec.boundary {
        problem = problem.with_boundary(&b.tag, super::boundary_kind(&b.kind));
    }
    if let Some(f) = case.solver.factorization {
        problem.factorization = f;
    }
    problem.ordering = case.solver.ordering;
    if spec.circumcentres {
        problem.cell_points = CellPoints::Circumcentres;
    }
    problem.neumann_tolerance = spec.neumann_tolerance;
    problem
}

/// The case's `solver.type` as a [`crate::multigrid::SolverChoice`]:
/// `None` for a direct solve (or PETSc's), else multigrid-preconditioned
/// CG on the generator's grid levels or by smoothed aggregation, or the
/// automatic rule. Diffusion and heat choose alike.
pub(super) fn solver_choice(
    case: &Case,
) -> Result<Option<crate::multigrid::SolverChoice>, RunError> {
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
    Ok(Some(match case.solver.kind {
        // GMRES and BiCGStab are refused for diffusion and heat when the
        // case is read.
        SolverKind::Direct | SolverKind::Petsc | SolverKind::Gmres | SolverKind::Bicgstab => {
            return Ok(None)
        }
        SolverKind::Multigrid => match grid {
            Some(h) => SolverChoice::Multigrid(h),
            None => {
                return Err(RunError::input_at(
                    case,
                    "solver.type",
                    "\"multigrid\" needs the grid levels of a rectangle or box generator mesh",
                    Some("use \"amg\" for other meshes".into()),
                ))
            }
        },
        SolverKind::Amg => SolverChoice::Multigrid(Hierarchy::Algebraic),
        SolverKind::Auto => SolverChoice::Auto(grid),
    }))
}

/// The case's `solver.type`: multigrid-preconditioned CG instead of the
/// direct factorisation when asked for (or chosen by the automatic rule).
fn with_solver(case: &Case, problem: Diffusion, complex: &Complex) -> Result<Diffusion, RunError> {
    Ok(match solver_choice(case)? {
        None => problem,
        Some(choice) => problem
            .with_solver(choice, case.solver.tolerance, complex)
            .with_cell_prolongation(case.solver.cell_prolongation),
    })
}

pub(super) fn solve_diffusion(
    case: &Case,
    spec: &DiffusionSpec,
    complex: &Complex,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    let problem = with_solver(case, diffusion_problem(case, spec), complex)?;
    let mut warnings = super::consistency::diffusion_warnings(
        complex,
        spec.method,
        &spec.conductivity,
        spec.circumcentres,
    );
    phase("assembling and solving");
    let started = Instant::now();
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    };
    let (solution, petsc) = if case.solver.kind == crate::frontend::case::SolverKind::Petsc {
        let (solution, note) = super::petsc::solve(case, &problem, complex)?;
        (solution, Some(note))
    } else {
        let solution = problem
            .solve(complex)
            .map_err(|e| diffusion_error(case, &keys, e))?;
        (solution, None)
    };
    let total = started.elapsed().as_secs_f64();
    let report = &solution.report;
    // With CG the "numeric" phase builds the preconditioner, not a factor.
    let setup = if solution.iterations.is_some() {
        "preconditioner setup"
    } else if solution.analyzed_during_assembly {
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
    if solution.iterations.is_some() || petsc.is_some() {
        // CG stops at solver.tolerance: only the failure limit applies.
        if report.relative_residual.is_nan()
            || report.relative_residual > case.solver.residual_limit
        {
            check_residual(case, report.relative_residual, &mut warnings)?;
        }
    } else {
        check_residual(case, report.relative_residual, &mut warnings)?;
    }
    let mut notes = match &solution.iterations {
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
    if let Some(note) = &petsc {
        notes.push(("petsc".to_string(), note.clone()));
    }
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
    // One convention for every method: the physical flux −K∇u·n through
    // each (n−1)-cell along its orientation (OUTPUT.md).
    let outflow = problem
        .boundary_outflow(complex, &solution)
        .map_err(|e| diffusion_error(case, &keys, e))?;
    let oriented = problem
        .oriented_flux(complex, &solution, &outflow)
        .map_err(|e| diffusion_error(case, &keys, e))?;
    if let Some(flux) = oriented {
        let how = match solution.location {
            Location::Nodal => "interior cells: |F| times the mean of the two cells' −K∇u_h·n; boundary cells: the method's residual flux, which balances the sources",
            _ => "the method's own face flux, which balances the sources",
        };
        fields.push(Cochain::new("flux", n - 1, flux).with_description(format!(
            "−K∇u·n through each (n−1)-cell along its orientation ({how})"
        )));
    }
    fields.push(Cochain::new("outflow", n - 1, outflow.clone()).with_description(
        "−K∇u·n leaving the domain through each boundary (n−1)-cell (0 inside): the method's own flux; Σ over a tag is the flux out through it",
    ));
    if solution.location == Location::Nodal && n > 1 {
        fields.push(
            Cochain::new("edge_flux", 1, solution.flux.iter().map(|q| -q).collect())
                .with_description("−Ω A u: the flux across each edge's dual cell, along the edge (the method's conservative flux)"),
        );
    }
    let coefficients = problem
        .cell_coefficients(complex)
        .map_err(|e| diffusion_error(case, &keys, e))?;
    fields.extend(coefficient_fields(
        &coefficients,
        complex.embedding_dim(),
        n,
    ));
    let gradient = physics::reconstruct_gradient(complex, &solution);
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
            let errors = physics::errors(complex, &solution, &u, grad.as_ref());
            let flux_error = grad
                .as_ref()
                .and_then(|g| physics::flux_error(complex, &solution, &problem, g));
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
    let quantities =
        super::quantities::diffusion_quantities(case, &problem, complex, &solution, &outflow)
            .map_err(|e| diffusion_error(case, &keys, e))?;
    notes.extend(quantities.notes);
    warnings.extend(quantities.warnings);
    let mut run_report = quantities.report;
    let probed = super::probes::probe_values(
        case,
        complex,
        solution.location,
        &solution.values,
        solution.cell_points.as_deref(),
    );
    let (probe_notes, probes) = super::probes::probe_report(case, &[], &[probed]);
    notes.extend(probe_notes);
    if let Some(probes) = probes {
        run_report.insert("probes".into(), probes);
    }
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
        factorization: (solution.iterations.is_none() && petsc.is_none())
            .then_some(report.factorization),
        ordering: report.ordering,
        timings,
        warnings,
        pure_neumann: solution.pure_neumann,
        series: Vec::new(),
        notes,
        report: run_report,
    })
}

/// The conductivity as cell fields: `conductivity` for K = λI, else one
/// field per component of the upper triangle (`conductivity_xx`, `_xy`, …).
fn coefficient_fields(k: &physics::CellCoefficients, d: usize, n: usize) -> Vec<Cochain> {
    match k {
        physics::CellCoefficients::Scalar(values) => {
            vec![Cochain::new("conductivity", n, values.clone())
                .with_description("K = λI: λ per top cell (at its centroid)")]
        }
        physics::CellCoefficients::Tensor(tensors) => {
            let axes = ["x", "y", "z"];
            let mut fields = Vec::new();
            for a in 0..d {
                for b in a..d {
                    fields.push(
                        Cochain::new(
                            format!("conductivity_{}{}", axes[a], axes[b]),
                            n,
                            tensors.iter().map(|t| t[a][b]).collect(),
                        )
                        .with_description(format!(
                            "K_{}{} per top cell (at its centroid)",
                            axes[a], axes[b]
                        )),
                    );
                }
            }
            fields
        }
    }
}

/// The data of a diffusion case evaluated where its solve evaluates them,
/// without solving (see [`Diffusion::check_data`]).
pub(super) fn check(case: &Case, spec: &DiffusionSpec, complex: &Complex) -> Result<(), RunError> {
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &spec.boundary,
    };
    diffusion_problem(case, spec)
        .check_data(complex)
        .map_err(|e| diffusion_error(case, &keys, e))
}
