//! The `[exact]`, `[solver]`, `[refine]` and `[output]` tables.

use super::*;
use crate::frontend::case::NonlinearSolverSpec;
use crate::frontend::output::ComplexLayout;
use crate::physics::nonlinear::{Iteration, KrylovPreconditioner};

impl Reader {
    pub(super) fn exact(&mut self, root: &dyn TableLike, scope: &Scope) -> Option<ExactSpec> {
        if problem_kind(root) == "coupled" {
            // Exact fields go in the [[field]] tables; `coupled` says so.
            return None;
        }
        let (table, entry) = self.subtable(root, "", "exact")?;
        self.check_keys(table, "exact", EXACT_KEYS);
        let eigenproblem = matches!(problem_kind(root), "maxwell" | "hodge-laplacian");
        let elastic = problem_kind(root) == "elasticity";
        let forms = form_degree(root).is_some();
        let solution = match self.entry(table, "exact", "solution") {
            // A k-form's proxy: read below as `form`.
            Some(_) if forms => None,
            Some(e) if elastic => {
                self.error(
                    e.key_span.clone(),
                    "exact.solution",
                    "an elasticity problem's exact solution is a vector",
                    Some("give displacement = [\"u_x\", \"u_y\"(, \"u_z\")]".into()),
                );
                None
            }
            None if elastic => None,
            Some(e) if eigenproblem => {
                self.error(
                    e.key_span.clone(),
                    "exact.solution",
                    "an eigenproblem has no single solution",
                    Some("give the exact eigenvalues: eigenvalues = [...]".into()),
                );
                None
            }
            Some(_) => self.expression_at(table, "exact", "solution", scope),
            None if eigenproblem => None,
            None => {
                self.error(
                    entry.span(),
                    "exact.solution",
                    "missing: the exact solution u(x, y, z)",
                    None,
                );
                return None;
            }
        };
        let gradient = match self.entry(table, "exact", "gradient") {
            None => None,
            Some(g) => match g.item.as_array() {
                Some(array) if (1..=3).contains(&array.len()) => {
                    let mut parts = Vec::new();
                    for (i, v) in array.iter().enumerate() {
                        let item = Item::Value(v.clone());
                        if let Some(e) = self.expression_of(
                            &item,
                            &format!("exact.gradient[{i}]"),
                            v.span(),
                            scope,
                        ) {
                            parts.push(e);
                        }
                    }
                    (parts.len() == array.len()).then_some(parts)
                }
                _ => {
                    self.type_error(&g, "an array of 1 to 3 expressions (∂u/∂x, ∂u/∂y, ∂u/∂z)");
                    None
                }
            },
        };
        let eigenvalues = match self.entry(table, "exact", "eigenvalues") {
            None if eigenproblem => {
                self.error(
                    entry.span(),
                    "exact.eigenvalues",
                    "missing: the exact eigenvalues, ascending",
                    Some("e.g. eigenvalues = [\"pi^2\", \"pi^2\", \"2*pi^2\"]".into()),
                );
                return None;
            }
            None => Vec::new(),
            Some(e) if !eigenproblem => {
                self.error(
                    e.key_span.clone(),
                    "exact.eigenvalues",
                    "only an eigenproblem (kind = \"maxwell\" or \"hodge-laplacian\") has eigenvalues",
                    None,
                );
                Vec::new()
            }
            Some(e) => self.constant_list(&e, scope)?,
        };
        let displacement = match self.entry(table, "exact", "displacement") {
            None if elastic => {
                self.error(
                    entry.span(),
                    "exact.displacement",
                    "missing: the exact displacement, one expression per coordinate",
                    None,
                );
                return None;
            }
            None => None,
            Some(e) if !elastic => {
                self.error(
                    e.key_span.clone(),
                    "exact.displacement",
                    "only an elasticity problem has a displacement",
                    Some("give `solution` instead".into()),
                );
                None
            }
            Some(e) => Some(self.expression_list(&e, scope)?),
        };
        let form = match self.entry(table, "exact", "solution") {
            Some(e) if forms && e.item.as_array().is_some() => {
                Some(self.expression_list(&e, scope)?)
            }
            Some(e) if forms => Some(vec![self.expression_of(
                e.item,
                "exact.solution",
                e.span(),
                scope,
            )?]),
            _ => None,
        };
        if gradient.is_some() && forms {
            if let Some(e) = self.entry(table, "exact", "gradient") {
                self.error(
                    e.key_span.clone(),
                    "exact.gradient",
                    "a k-form's error is measured on its cochain; the gradient of a form is not used",
                    Some("remove exact.gradient".into()),
                );
            }
        }
        Some(ExactSpec {
            form,
            solution: if eigenproblem || elastic || forms {
                None
            } else {
                Some(solution?)
            },
            gradient,
            eigenvalues,
            displacement,
        })
    }

    pub(super) fn solver(&mut self, root: &dyn TableLike) -> SolverSpec {
        let mut spec = SolverSpec::default();
        let Some((table, _)) = self.subtable(root, "", "solver") else {
            return spec;
        };
        self.check_keys(table, "solver", SOLVER_KEYS);
        if let Some(kind) = self.string_at(table, "solver", "type") {
            spec.kind = match kind.as_str() {
                "direct" => SolverKind::Direct,
                "multigrid" => SolverKind::Multigrid,
                "amg" => SolverKind::Amg,
                "auto" => SolverKind::Auto,
                "gmres" => SolverKind::Gmres,
                "bicgstab" => SolverKind::Bicgstab,
                "petsc" => {
                    if !cfg!(feature = "mpi") {
                        let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                        self.error(
                            span,
                            "solver.type",
                            "\"petsc\" needs a hasse built with the cargo feature `mpi`, and this one was built without it",
                            Some("install MPI and PETSc with `scripts/setup --mpi`, build with `cargo build --release --features mpi`, and run with `mpirun -np N target/release/hasse run CASE`".into()),
                        );
                    }
                    SolverKind::Petsc
                }
                other => {
                    let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                    self.error(
                        span,
                        "solver.type",
                        format!("unknown solver type \"{other}\""),
                        Some("\"direct\" (faer LLᵀ/LDLᵀ/LU), \"multigrid\" (CG with a V-cycle on the generator's grid levels), \"amg\" (CG with smoothed aggregation, any mesh), \"auto\", \"petsc\" (PETSc over MPI), or for transport \"gmres\" / \"bicgstab\" (ILU(0)-preconditioned)".into()),
                    );
                    SolverKind::Direct
                }
            };
            let kind = problem_kind(root);
            let krylov = matches!(spec.kind, SolverKind::Gmres | SolverKind::Bicgstab);
            let serves = match spec.kind {
                SolverKind::Direct => true,
                SolverKind::Petsc => kind == "diffusion",
                SolverKind::Gmres | SolverKind::Bicgstab => kind == "transport",
                _ => matches!(kind, "diffusion" | "heat"),
            };
            if krylov && !serves {
                let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                self.error(
                    span,
                    "solver.type",
                    format!("GMRES and BiCGStab serve the nonsymmetric systems of kind = \"transport\"; this case is kind = \"{kind}\""),
                    Some("symmetric problems take \"direct\", \"multigrid\", \"amg\" or \"auto\"".into()),
                );
            } else if kind == "transport" && !serves {
                let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                self.error(
                    span,
                    "solver.type",
                    "a transport system is nonsymmetric: conjugate gradients (multigrid, amg, auto) and PETSc's CG do not apply",
                    Some("use \"direct\" (sparse LU), \"gmres\" or \"bicgstab\"".into()),
                );
            } else if !serves {
                let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                let served = if spec.kind == SolverKind::Petsc {
                    "PETSc serves steady diffusion problems"
                } else {
                    "the iterative solvers serve diffusion and heat problems"
                };
                self.error(
                    span,
                    "solver.type",
                    format!("{served}; this case is kind = \"{kind}\""),
                    Some("remove solver.type (direct)".into()),
                );
            }
        }
        if let Some(name) = self.string_at(table, "solver", "preconditioner") {
            let span = self
                .entry(table, "solver", "preconditioner")
                .and_then(|e| e.span());
            match name.as_str() {
                "ilu0" => {}
                "multigrid" => spec.multigrid_preconditioner = true,
                other => self.error(
                    span.clone(),
                    "solver.preconditioner",
                    format!("unknown preconditioner \"{other}\""),
                    Some("\"ilu0\" (incomplete LU of the whole matrix) or \"multigrid\" (a V-cycle of the diffusion part)".into()),
                ),
            }
            if !matches!(spec.kind, SolverKind::Gmres | SolverKind::Bicgstab) {
                self.error(
                    span,
                    "solver.preconditioner",
                    "a preconditioner is chosen for solver.type = \"gmres\" or \"bicgstab\" only",
                    Some("set solver.type, or remove solver.preconditioner".into()),
                );
            }
        }
        if let Some((petsc, entry)) = self.subtable(table, "solver", "petsc") {
            self.check_keys(petsc, "solver.petsc", PETSC_KEYS);
            if let Some(options) = self.string_at(petsc, "solver.petsc", "options") {
                spec.petsc_options = options;
            }
            if spec.kind != SolverKind::Petsc {
                self.error(
                    entry.span(),
                    "solver.petsc",
                    "PETSc options apply only to solver.type = \"petsc\"",
                    Some("set solver.type = \"petsc\" or remove [solver.petsc]".into()),
                );
            }
        }
        if let Some(t) = self.number_at(table, "solver", "tolerance") {
            if t > 0.0 && t < 1.0 {
                spec.tolerance = t;
            } else {
                let span = self
                    .entry(table, "solver", "tolerance")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "solver.tolerance",
                    format!("a relative residual in (0, 1), found {t}"),
                    None,
                );
            }
        }
        if let Some(name) = self.string_at(table, "solver", "factorization") {
            spec.factorization = match name.as_str() {
                "llt" | "cholesky" => Some(Factorization::Llt),
                "ldlt" => Some(Factorization::Ldlt),
                "lblt" => Some(Factorization::Lblt),
                "lu" => Some(Factorization::Lu),
                other => {
                    let span = self
                        .entry(table, "solver", "factorization")
                        .and_then(|e| e.span());
                    self.error(
                        span,
                        "solver.factorization",
                        format!("unknown factorisation \"{other}\""),
                        Some("use \"llt\", \"ldlt\", \"lblt\" or \"lu\"".into()),
                    );
                    None
                }
            };
        }
        if let Some(name) = self.string_at(table, "solver", "prolongation") {
            let span = self
                .entry(table, "solver", "prolongation")
                .and_then(|e| e.span());
            match name.as_str() {
                "smoothed" => spec.cell_prolongation = CellProlongation::Smoothed,
                // Twice the coarse correction undoes the Galerkin operator's
                // stiffness (see the multigrid module).
                "constant" => {
                    spec.cell_prolongation = CellProlongation::Constant { correction: 2.0 }
                }
                other => self.error(
                    span.clone(),
                    "solver.prolongation",
                    format!("unknown prolongation \"{other}\""),
                    Some("use \"smoothed\" (the default: mesh-independent iteration counts) or \"constant\" (cheaper setup, counts grow slowly with the mesh)".into()),
                ),
            }
            if !matches!(spec.kind, SolverKind::Multigrid | SolverKind::Auto) {
                self.error(
                    span,
                    "solver.prolongation",
                    "applies only to the grid levels of solver.type = \"multigrid\" (or \"auto\")",
                    Some("set solver.type = \"multigrid\" or remove solver.prolongation".into()),
                );
            }
        }
        if let Some(name) = self.string_at(table, "solver", "ordering") {
            let span = self
                .entry(table, "solver", "ordering")
                .and_then(|e| e.span());
            match name.as_str() {
                "auto" => spec.ordering = Ordering::Automatic,
                "amd" => spec.ordering = Ordering::Amd,
                "nested-dissection" => spec.ordering = Ordering::NestedDissection,
                "geometric" => spec.ordering = Ordering::Geometric,
                other => self.error(
                    span.clone(),
                    "solver.ordering",
                    format!("unknown ordering \"{other}\""),
                    Some("use \"auto\" (the default), \"amd\" (approximate minimum degree), \"nested-dissection\" (METIS) or \"geometric\" (nested dissection from the unknowns' positions)".into()),
                ),
            }
            let kind = problem_kind(root);
            if spec.ordering == Ordering::Geometric && kind != "diffusion" {
                self.error(
                    span.clone(),
                    "solver.ordering",
                    format!("\"geometric\" orders by the unknowns' positions, which only diffusion cases hand to the solver; kind = \"{kind}\" does not"),
                    Some("use \"auto\", \"amd\" or \"nested-dissection\"".into()),
                );
            } else if !matches!(kind, "diffusion" | "heat" | "elasticity") {
                self.error(
                    span,
                    "solver.ordering",
                    format!("applies to the direct solves of diffusion, heat and elasticity cases; kind = \"{kind}\" orders its systems itself"),
                    Some("remove solver.ordering".into()),
                );
            } else if matches!(spec.kind, SolverKind::Multigrid | SolverKind::Amg) {
                self.error(
                    span,
                    "solver.ordering",
                    "orders a direct factorisation; multigrid-preconditioned CG factorises nothing",
                    Some(
                        "set solver.type = \"direct\" (or \"auto\") or remove solver.ordering"
                            .into(),
                    ),
                );
            } else if spec.factorization == Some(Factorization::Lu) {
                self.error(
                    span,
                    "solver.ordering",
                    "LU orders its columns by COLAMD; the ordering applies to llt, ldlt and lblt",
                    Some("remove solver.ordering or choose another solver.factorization".into()),
                );
            }
        }
        for (key, slot) in [
            ("residual_warning", &mut spec.residual_warning),
            ("residual_limit", &mut spec.residual_limit),
        ] {
            if let Some(v) = self.number_at(table, "solver", key) {
                if v > 0.0 && v.is_finite() {
                    *slot = v;
                } else {
                    let span = self.entry(table, "solver", key).and_then(|e| e.span());
                    self.error(
                        span,
                        &format!("solver.{key}"),
                        format!("must be a positive number, found {v}"),
                        None,
                    );
                }
            }
        }
        if let Some((nonlinear, _)) = self.subtable(table, "solver", "nonlinear") {
            spec.nonlinear = self.nonlinear_solver(nonlinear);
        }
        spec
    }

    /// `[solver.nonlinear]`: method, tolerance, max_iterations, monitor.
    fn nonlinear_solver(&mut self, table: &dyn TableLike) -> NonlinearSolverSpec {
        const PREFIX: &str = "solver.nonlinear";
        self.check_keys(table, PREFIX, NONLINEAR_KEYS);
        let mut spec = NonlinearSolverSpec::default();
        if let Some(name) = self.string_at(table, PREFIX, "method") {
            match name.as_str() {
                "newton" => spec.iteration = Iteration::Newton,
                "picard" => spec.iteration = Iteration::Picard,
                other => {
                    let span = self.entry(table, PREFIX, "method").and_then(|e| e.span());
                    self.error(
                        span,
                        "solver.nonlinear.method",
                        format!("unknown nonlinear method \"{other}\""),
                        Some("use \"newton\" (default: quadratic convergence) or \"picard\" (the coefficient frozen at the last iterate: linear convergence)".into()),
                    );
                }
            }
        }
        if let Some(t) = self.number_at(table, PREFIX, "tolerance") {
            if t > 0.0 && t < 1.0 {
                spec.tolerance = t;
            } else {
                let span = self
                    .entry(table, PREFIX, "tolerance")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "solver.nonlinear.tolerance",
                    format!("a relative residual in (0, 1), found {t}"),
                    None,
                );
            }
        }
        if let Some(entry) = self.entry(table, PREFIX, "max_iterations") {
            match entry.item.as_integer() {
                Some(n) if n >= 1 => spec.max_iterations = n as usize,
                Some(n) => self.error(
                    entry.span(),
                    &entry.name,
                    format!("at least 1 iteration, found {n}"),
                    None,
                ),
                None => self.type_error(&entry, "an integer"),
            }
        }
        if let Some(entry) = self.entry(table, PREFIX, "monitor") {
            match entry.item.as_bool() {
                Some(b) => spec.monitor = b,
                None => self.type_error(&entry, "true or false"),
            }
        }
        if let Some(entry) = self.entry(table, PREFIX, "linear") {
            match entry.item.as_str() {
                Some("direct") => spec.krylov = false,
                Some("krylov") => spec.krylov = true,
                Some("krylov-multigrid") => {
                    spec.krylov = true;
                    spec.preconditioner = KrylovPreconditioner::Multigrid;
                }
                Some(other) => self.error(
                    entry.span(),
                    &entry.name,
                    format!("unknown linear solver \"{other}\" for the Newton steps"),
                    Some("use \"direct\" (an LU per step, default), \"krylov\" (GMRES preconditioned by an LLᵀ of the Jacobian's symmetric part) or \"krylov-multigrid\" (GMRES preconditioned by an algebraic multigrid V-cycle of it)".into()),
                ),
                None => self.type_error(&entry, "\"direct\", \"krylov\" or \"krylov-multigrid\""),
            }
        }
        spec
    }

    pub(super) fn refine(&mut self, root: &dyn TableLike) -> Option<RefineSpec> {
        let (table, entry) = self.subtable(root, "", "refine")?;
        self.check_keys(table, "refine", REFINE_KEYS);
        let mut spec = RefineSpec::default();
        let theta = self.number_at(table, "refine", "theta");
        if let Some(t) = theta {
            if !(t > 0.0 && t <= 1.0) {
                let span = self.entry(table, "refine", "theta").and_then(|e| e.span());
                self.error(
                    span,
                    "refine.theta",
                    format!("the Dörfler fraction must lie in (0, 1], found {t}"),
                    None,
                );
            }
        }
        let coarsen = self.number_at(table, "refine", "coarsen");
        if let Some(c) = coarsen {
            if !(0.0..1.0).contains(&c) {
                let span = self
                    .entry(table, "refine", "coarsen")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "refine.coarsen",
                    format!("the coarsening fraction of Σ η² must lie in [0, 1), found {c}"),
                    Some("e.g. `coarsen = 0.1` merges back the sibling groups holding at most a tenth of the squared indicator; 0 never coarsens".into()),
                );
            }
        }
        match self.string_at(table, "refine", "strategy").as_deref() {
            None | Some("uniform") => {}
            Some("adaptive") => {
                spec.strategy = Strategy::Adaptive {
                    theta: theta.unwrap_or(0.5),
                    coarsen: coarsen.filter(|c| (0.0..1.0).contains(c)).unwrap_or(0.0),
                }
            }
            Some("divide-longest-axis") => spec.strategy = Strategy::DivideLongestAxis,
            Some("divide-shortest-wall") => spec.strategy = Strategy::DivideShortestWall,
            Some(other) => {
                let span = self
                    .entry(table, "refine", "strategy")
                    .and_then(|e| e.span());
                let owned: Vec<String> = STRATEGIES.iter().map(|s| s.to_string()).collect();
                let help = closest(other, &owned)
                    .map_or(format!("strategies: {}", STRATEGIES.join(", ")), |s| {
                        format!("did you mean \"{s}\"?")
                    });
                self.error(
                    span,
                    "refine.strategy",
                    format!("unknown refinement strategy \"{other}\""),
                    Some(help),
                );
            }
        }
        for (key, value) in [("theta", theta), ("coarsen", coarsen)] {
            if value.is_some() {
                self.adaptive_only(table, key, &spec);
            }
        }
        self.refine_steps(table, entry, spec)
    }

    /// A key of the adaptive strategy (`theta`, `coarsen`) given with
    /// another strategy: an error when both come from the same place, a
    /// warning when the command line switched the strategy of an adaptive
    /// file.
    fn adaptive_only(&mut self, table: &dyn TableLike, key: &str, spec: &RefineSpec) {
        let name = format!("refine.{key}");
        let what = match key {
            "theta" => "marks cells",
            _ => "coarsens cells",
        };
        if !matches!(spec.strategy, Strategy::Adaptive { .. }) {
            let span = self
                .entry(table, "refine", key)
                .and_then(|e| e.key_span.clone());
            // A θ written in the file for its adaptive strategy is left
            // unused, not wrong, when the command line chose another
            // strategy (`--set refine.strategy=uniform`, `--strategy
            // uniform`): the file still reads as written. A θ and a
            // non-adaptive strategy from the same source contradict.
            let strategy_from_command_line =
                self.collector.is_set("refine.strategy") && !self.collector.is_set(&name);
            if strategy_from_command_line {
                let strategy = self
                    .string_at(table, "refine", "strategy")
                    .unwrap_or_default();
                self.collector.warning(
                    span,
                    &name,
                    format!(
                        "unused: the command line sets strategy \"{strategy}\", and only the adaptive strategy {what}"
                    ),
                    None,
                );
            } else {
                self.error(
                    span,
                    &name,
                    format!("only the adaptive strategy {what}"),
                    Some(format!("remove `{key}`, or set `strategy = \"adaptive\"`")),
                );
            }
        }
    }

    fn refine_steps(
        &mut self,
        table: &dyn TableLike,
        entry: Entry<'_>,
        mut spec: RefineSpec,
    ) -> Option<RefineSpec> {
        match self.entry(table, "refine", "steps") {
            Some(e) => match e.item.as_integer() {
                Some(n) if (0..=20).contains(&n) => spec.steps = n as usize,
                Some(n) => self.error(
                    e.span(),
                    &e.name,
                    format!("between 0 and 20 steps, found {n}"),
                    Some("each step multiplies the cell count by up to 2ⁿ".into()),
                ),
                None => self.type_error(&e, "an integer"),
            },
            None => self.error(
                entry.span(),
                "refine.steps",
                "missing: how many refinement steps",
                Some("e.g. steps = 3".into()),
            ),
        }
        if let Some(t) = self.number_at(table, "refine", "tolerance") {
            if t > 0.0 && t < 1.0 {
                spec.tolerance = t;
            } else {
                let span = self
                    .entry(table, "refine", "tolerance")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "refine.tolerance",
                    format!("a relative residual in (0, 1), found {t}"),
                    None,
                );
            }
        }
        Some(spec)
    }

    pub(super) fn output(&mut self, root: &dyn TableLike) -> OutputSpec {
        let stem = Path::new(&self.file)
            .file_stem()
            .map_or("hasse".to_string(), |s| s.to_string_lossy().into_owned());
        let mut spec = OutputSpec {
            directory: PathBuf::from("."),
            name: stem,
            write: true,
            quantities: Vec::new(),
            probes: Vec::new(),
            fields: None,
            partial: true,
            complex: ComplexLayout::default(),
        };
        let Some((table, _)) = self.subtable(root, "", "output") else {
            return spec;
        };
        self.check_keys(table, "output", OUTPUT_KEYS);
        if let Some(d) = self.string_at(table, "output", "directory") {
            spec.directory = PathBuf::from(d);
        }
        if let Some(n) = self.string_at(table, "output", "name") {
            if n.is_empty() || n.contains(['/', '\\']) {
                let span = self.entry(table, "output", "name").and_then(|e| e.span());
                self.error(
                    span,
                    "output.name",
                    "a file stem without directories",
                    Some("put directories in output.directory".into()),
                );
            } else {
                spec.name = n;
            }
        }
        if let Some(e) = self.entry(table, "output", "write") {
            match e.item.as_bool() {
                Some(b) => spec.write = b,
                None => self.type_error(&e, "true or false"),
            }
        }
        if let Some(e) = self.entry(table, "output", "partial") {
            match e.item.as_bool() {
                Some(b) => spec.partial = b,
                None => self.type_error(&e, "true or false"),
            }
        }
        if let Some(e) = self.entry(table, "output", "fields") {
            let names: Option<Vec<String>> = e
                .item
                .as_array()
                .and_then(|a| a.iter().map(|v| v.as_str().map(str::to_string)).collect());
            match names {
                Some(names) if !names.is_empty() => spec.fields = Some(names),
                _ => self.type_error(
                    &e,
                    "a non-empty array of field names, e.g. [\"u\", \"flux\"]",
                ),
            }
        }
        if let Some(layout) = self.choice_in(
            table,
            "output",
            "complex",
            &ComplexLayout::ALL,
            ComplexLayout::name,
            "layout of the complex",
            None,
            Some(ComplexLayout::default()),
        ) {
            spec.complex = layout;
        }
        spec.quantities = self.quantities(table);
        spec.probes = self.probes(table);
        spec
    }
}
