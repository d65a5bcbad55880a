//! The `[mesh]` and `[problem]` tables and the boundary conditions: what a
//! case solves and on which cells.

use super::*;

impl Reader {
    pub(super) fn mesh(
        &mut self,
        root: &dyn TableLike,
        text: &str,
    ) -> (Option<MeshSpec>, BTreeMap<String, Range<usize>>) {
        let mut spans = BTreeMap::new();
        let Some((table, entry)) = self.subtable(root, "", "mesh") else {
            if root.get("mesh").is_none() {
                self.error(None, "mesh", "no [mesh] table", Some("add [mesh] with `generator = \"rectangle\"` and `n = [16, 16]`, or `file = \"mesh.msh\"`".into()));
            }
            return (None, spans);
        };
        spans.insert(String::new(), entry.span().unwrap_or(0..0));
        let before = self.collector.diagnostics.len();
        self.check_keys(table, "mesh", MeshSpec::keys());
        for (key, item) in table.iter() {
            if let Some(span) = item
                .span()
                .or_else(|| table.get_key_value(key).and_then(|(k, _)| k.span()))
            {
                spans.insert(key.to_string(), span);
            }
        }
        if self.collector.diagnostics.len() > before {
            return (None, spans);
        }
        // The keys are known: let serde check the types, through toml (which
        // reports the line and column of a bad value).
        #[derive(serde::Deserialize)]
        struct MeshOnly {
            mesh: MeshSpec,
        }
        match toml::from_str::<toml::Table>(text).map(|mut t| t.remove("mesh")) {
            Ok(Some(value)) => {
                let mut wrapper = toml::Table::new();
                wrapper.insert("mesh".into(), value);
                match toml::Value::Table(wrapper).try_into::<MeshOnly>() {
                    Ok(m) => return (Some(m.mesh), spans),
                    Err(e) => {
                        // Find which key the message is about to point at it.
                        let message = e.message().trim().to_string();
                        let key = MeshSpec::keys().iter().find(|k| {
                            message.contains(&format!("mesh.{k}"))
                                || message.contains(&format!("`{k}`"))
                        });
                        let span = key
                            .and_then(|k| spans.get(*k).cloned())
                            .or_else(|| entry.span());
                        let name = key.map_or("mesh".to_string(), |k| format!("mesh.{k}"));
                        self.error(span, &name, message, None);
                    }
                }
            }
            _ => self.error(entry.span(), "mesh", "cannot read the [mesh] table", None),
        }
        (None, spans)
    }

    /// `problem.neumann` ("check", the default, or "project") and
    /// `problem.neumann_tolerance` (in (0, 1]): how much imbalance of
    /// pure-Neumann data is projected away rather than refused.
    fn neumann_tolerance(&mut self, table: &dyn TableLike) -> f64 {
        const DEFAULT: f64 = 1e-2;
        let project = match self.string_at(table, "problem", "neumann").as_deref() {
            None | Some("check") => false,
            Some("project") => true,
            Some(other) => {
                let span = self
                    .entry(table, "problem", "neumann")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "problem.neumann",
                    format!("unknown Neumann treatment \"{other}\""),
                    Some("use \"check\" (refuse data whose imbalance exceeds `neumann_tolerance`) or \"project\" (remove any imbalance and report it)".into()),
                );
                false
            }
        };
        let tolerance = match self.number_at(table, "problem", "neumann_tolerance") {
            None => DEFAULT,
            Some(t) if t > 0.0 && t <= 1.0 => t,
            Some(t) => {
                let span = self
                    .entry(table, "problem", "neumann_tolerance")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "problem.neumann_tolerance",
                    format!("{t} is not in (0, 1]"),
                    Some("it is the largest |∫f + ∮g| / Σ|terms| that is projected away, e.g. 0.05; `neumann = \"project\"` removes any imbalance".into()),
                );
                DEFAULT
            }
        };
        if project {
            f64::INFINITY
        } else {
            tolerance
        }
    }

    pub(super) fn problem(&mut self, root: &dyn TableLike, scope: &Scope) -> Option<Problem> {
        let Some((table, problem_entry)) = self.subtable(root, "", "problem") else {
            if root.get("problem").is_none() {
                self.error(
                    None,
                    "problem",
                    "no [problem] table",
                    Some("add [problem] with `method = \"fe\"` and `source = ...`".into()),
                );
            }
            return None;
        };
        self.check_keys(table, "problem", PROBLEM_KEYS);
        let kind = self
            .string_at(table, "problem", "kind")
            .unwrap_or_else(|| "diffusion".into());
        self.check_kind_keys(root, table, &kind);
        match kind.as_str() {
            "diffusion" if form_degree(root).is_some() => {
                self.form_diffusion(root, table, problem_entry.span(), scope)
            }
            "diffusion" => {
                if table.get("degree").is_some() {
                    // Degree 0 is this problem (functions); anything else
                    // that is not an integer ≥ 1 is refused here.
                    self.count(
                        table,
                        "degree",
                        0,
                        None,
                        "the degree k of the unknown: 0 (functions, ordinary diffusion) or 1 to the mesh's dimension (Δ_k u = f for k-forms)",
                    );
                }
                let method = self.method(table, problem_entry.span());
                let (conductivity, reaction) = self.conductivity_and_reaction(table, scope);
                let source = match self.entry(table, "problem", "source") {
                    Some(_) => self.expression_or_regions_at(table, "problem", "source", scope),
                    None => scope.parse("0").ok(),
                };
                let boundary = self.boundary(root, scope, Conditions::Steady);
                let circumcentres = match self.string_at(table, "problem", "cell_points").as_deref()
                {
                    None | Some("centroids") => false,
                    Some("circumcentres") => true,
                    Some(other) => {
                        let span = self
                            .entry(table, "problem", "cell_points")
                            .and_then(|e| e.span());
                        self.error(span, "problem.cell_points", format!("unknown cell points \"{other}\""), Some("use \"centroids\" (default) or \"circumcentres\" (Delaunay triangulations)".into()));
                        false
                    }
                };
                if circumcentres && method.is_some_and(|m| m != Method::Fv) {
                    let span = self
                        .entry(table, "problem", "cell_points")
                        .and_then(|e| e.span());
                    self.error(span, "problem.cell_points", "only the two-point flux (method = \"fv\") places its unknowns at other cell points", None);
                }
                let neumann_tolerance = self.neumann_tolerance(table);
                let spec = DiffusionSpec {
                    method: method?,
                    conductivity: conductivity?,
                    source: source?,
                    boundary,
                    circumcentres,
                    neumann_tolerance,
                    reaction: reaction?,
                };
                if spec.is_nonlinear() {
                    self.check_nonlinear(root, table, &spec);
                }
                Some(Problem::Diffusion(spec))
            }
            "heat" => self.heat(root, table, problem_entry.span(), scope),
            "darcy" => self.darcy(root, table, problem_entry.span(), scope),
            "maxwell" => self.maxwell(root, table, problem_entry.span()),
            "hodge-laplacian" => self.hodge(root, table, problem_entry.span()),
            "cohomology" => self.cohomology(root, table, problem_entry.span()),
            "hodge-decomposition" => self.decomposition(root, table, problem_entry.span(), scope),
            "elasticity" => self.elasticity(root, table, problem_entry.span(), scope),
            "coupled" => self.coupled(root, table, problem_entry.span(), scope),
            "transport" => self.transport(root, table, problem_entry.span(), scope),
            "growth" => self.growth(root, table, problem_entry.span(), scope),
            "gradient" => {
                if let Some(e) = self.entry(root, "", "boundary") {
                    self.error(
                        e.key_span.clone(),
                        "boundary",
                        "a gradient problem has no boundary conditions",
                        None,
                    );
                }
                let field = match self.entry(table, "problem", "field") {
                    Some(_) => self.expression_at(table, "problem", "field", scope),
                    None => {
                        self.error(
                            problem_entry.span(),
                            "problem.field",
                            "missing: the cell field whose gradient is computed",
                            Some("e.g. field = \"sin(pi*x)\"".into()),
                        );
                        None
                    }
                };
                let metric = self.gradient_metric(table);
                Some(Problem::Gradient(GradientSpec {
                    field: field?,
                    metric: metric?,
                }))
            }
            other => {
                let span = self.entry(table, "problem", "kind").and_then(|e| e.span());
                self.error(
                    span,
                    "problem.kind",
                    format!("unknown problem kind \"{other}\""),
                    Some(kind_help(other)),
                );
                None
            }
        }
    }

    /// What a nonlinear problem (steady or heat) does not have: a solver
    /// type other than the direct LU its Newton steps reuse, and
    /// quantities or probes.
    pub(super) fn refuse_nonlinear_solver_and_output(&mut self, root: &dyn TableLike) {
        // Newton's steps are solved by one LU analysis reused over the
        // steps; the iterative and distributed solvers are not wired in.
        if let Some((solver, kind)) = root
            .get("solver")
            .and_then(Item::as_table_like)
            .and_then(|t| t.get_key_value("type"))
        {
            if kind.as_str().is_some_and(|k| k != "direct") {
                self.error(
                    kind.span().or_else(|| solver.span()),
                    "solver.type",
                    "a nonlinear problem solves its Newton steps with a direct LU factorisation; other solver types are not available for it",
                    Some("remove solver.type (or set it to \"direct\")".into()),
                );
            }
        }
        let output = root.get("output").and_then(Item::as_table_like);
        for name in ["quantity", "probe"] {
            if let Some((key, _)) = output.and_then(|o| o.get_key_value(name)) {
                self.error(
                    key.span(),
                    &format!("output.{name}"),
                    format!("output.{name} is not evaluated for a nonlinear problem"),
                    Some(format!(
                        "remove [[output.{name}]]; the field u is in the output"
                    )),
                );
            }
        }
    }

    /// `problem.conductivity` and `problem.reaction` of diffusion and heat:
    /// both may use the solution u (which makes the problem nonlinear),
    /// k(u, x) then one differentiable scalar, r(u, x) differentiable.
    #[allow(clippy::type_complexity)]
    pub(super) fn conductivity_and_reaction(
        &mut self,
        table: &dyn TableLike,
        scope: &Scope,
    ) -> (Option<Coefficient>, Option<Option<Expression>>) {
        let with_u = scope.with_solution();
        let conductivity = self
            .coefficient(table, "conductivity", &with_u)
            .and_then(|k| self.nonlinear_conductivity(table, k));
        let reaction = match self.entry(table, "problem", "reaction") {
            Some(_) => self
                .expression_at(table, "problem", "reaction", &with_u)
                .and_then(|r| self.differentiable(table, "reaction", r))
                .map(Some),
            None => Some(None),
        };
        (conductivity, reaction)
    }

    /// A conductivity that uses u must be one scalar expression whose
    /// derivative exmex can form.
    pub(super) fn nonlinear_conductivity(
        &mut self,
        table: &dyn TableLike,
        k: Coefficient,
    ) -> Option<Coefficient> {
        let span = || {
            table
                .get_key_value("conductivity")
                .and_then(|(_, item)| item.span())
        };
        match k {
            Coefficient::Tensor(rows) if rows.iter().flatten().any(|e| e.uses_solution()) => {
                self.error(
                    span(),
                    "problem.conductivity",
                    "a conductivity that depends on u must be a scalar",
                    Some("write k(u, x) as one expression, e.g. \"1 + u^2\"".into()),
                );
                None
            }
            Coefficient::Scalar(e) if e.uses_solution() && e.regions().is_some() => {
                self.error(
                    span(),
                    "problem.conductivity",
                    "a conductivity that depends on u cannot be given per region",
                    Some("write one expression; select regions by position with if(…) outside the u-dependence".into()),
                );
                None
            }
            Coefficient::Scalar(e) if e.uses_solution() => self
                .differentiable(table, "conductivity", e)
                .map(Coefficient::Scalar),
            other => Some(other),
        }
    }

    /// `e` (at `problem.<key>`) if its derivative with respect to u exists.
    pub(super) fn differentiable(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        e: Expression,
    ) -> Option<Expression> {
        match e.derivative_u() {
            Ok(_) => Some(e),
            Err(error) => {
                let span = table.get_key_value(key).and_then(|(_, item)| item.span());
                let help = expression_help(&error, &Scope::new());
                self.error(span, &join("problem", key), error.to_string(), Some(help));
                None
            }
        }
    }

    /// What a nonlinear diffusion case cannot combine with, found from the
    /// input alone: the hybrid mimetic method, circumcentre cell points,
    /// Robin conditions, `[refine]`, quantities and probes.
    fn check_nonlinear(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        spec: &DiffusionSpec,
    ) {
        let span_of =
            |t: &dyn TableLike, key: &str| t.get_key_value(key).and_then(|(_, i)| i.span());
        if spec.method == Method::FvMimetic {
            self.error(
                span_of(table, "method"),
                "problem.method",
                "a nonlinear problem (conductivity with u, or a reaction) needs a diagonal Ω; fv-mimetic couples the faces of a cell",
                Some("use fv, fd, fe (simplices) or dec".into()),
            );
        }
        if spec.circumcentres {
            self.error(
                span_of(table, "cell_points"),
                "problem.cell_points",
                "a nonlinear problem keeps the cell values at the centroids",
                Some("remove problem.cell_points".into()),
            );
        }
        for b in &spec.boundary {
            if matches!(b.kind, BoundaryKindSpec::Robin { .. }) {
                self.error(
                    b.tag_span.clone(),
                    &format!("{}.type", b.key),
                    "Robin conditions are not supported with a u-dependent conductivity or a reaction",
                    Some("use dirichlet or neumann".into()),
                );
            }
        }
        self.refuse_nonlinear_solver_and_output(root);
        if let Some((key, _)) = root.get_key_value("refine") {
            self.error(
                key.span(),
                "refine",
                "refinement studies re-solve linear problems; this case is nonlinear",
                Some("remove [refine], or run the meshes one by one".into()),
            );
        }
    }

    pub(super) fn method(
        &mut self,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
    ) -> Option<Method> {
        self.method_in(table, "problem", header)
    }

    /// `method` of the table at `prefix` (`problem`, or `field[i]`).
    pub(super) fn method_in(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        header: Option<Range<usize>>,
    ) -> Option<Method> {
        let methods = Method::names().join(", ");
        let Some(entry) = self.entry(table, prefix, "method") else {
            self.error(
                header,
                &join(prefix, "method"),
                "missing: which discretisation to use",
                Some(format!("one of {methods}")),
            );
            return None;
        };
        let Some(name) = entry.item.as_str() else {
            self.type_error(&entry, "a string");
            return None;
        };
        match name.parse::<Method>() {
            Ok(method) => Some(method),
            Err(_) => {
                let owned: Vec<String> = Method::names().iter().map(|s| s.to_string()).collect();
                let help = match closest(name, &owned) {
                    Some(s) => format!("did you mean \"{s}\"? methods: {methods}"),
                    None => format!("methods: {methods}"),
                };
                self.error(
                    entry.span(),
                    &entry.name,
                    format!("unknown method \"{name}\""),
                    Some(help),
                );
                None
            }
        }
    }

    pub(super) fn boundary(
        &mut self,
        root: &dyn TableLike,
        scope: &Scope,
        conditions: Conditions,
    ) -> Vec<BoundarySpec> {
        self.boundary_in(root, "", scope, conditions)
    }

    /// The `[[boundary]]` tables under `parent` (the document, or a
    /// `[[field]]` of a coupled problem).
    pub(super) fn boundary_in(
        &mut self,
        parent: &dyn TableLike,
        parent_prefix: &str,
        scope: &Scope,
        conditions: Conditions,
    ) -> Vec<BoundarySpec> {
        let names = conditions.names();
        let mut out = Vec::new();
        let Some(entry) = self.entry(parent, parent_prefix, "boundary") else {
            return out;
        };
        let Some(array) = entry.item.as_array_of_tables() else {
            self.error(
                entry.span(),
                "boundary",
                "expected [[boundary]] tables",
                Some(
                    "write each condition as a [[boundary]] table with tag, type and value".into(),
                ),
            );
            return out;
        };
        for (i, table) in array.iter().enumerate() {
            let prefix = format!("{}[{i}]", join(parent_prefix, "boundary"));
            self.check_keys(table, &prefix, BOUNDARY_KEYS);
            let header = table.span();
            let tag_entry = self.entry(table, &prefix, "tag");
            let tag_span = tag_entry.as_ref().and_then(|e| e.span());
            let tag = match tag_entry {
                Some(_) => self.string_at(table, &prefix, "tag"),
                None => {
                    self.error(header.clone(), &format!("{prefix}.tag"), "missing: the boundary region's tag", Some("generated meshes tag \"boundary\" and each side (\"xmin\", \"xmax\", ...)".into()));
                    None
                }
            };
            let kind_name = match self.entry(table, &prefix, "type") {
                Some(_) => self.string_at(table, &prefix, "type"),
                None => {
                    self.error(
                        header.clone(),
                        &format!("{prefix}.type"),
                        format!("missing: {}", names.join(", ")),
                        None,
                    );
                    None
                }
            };
            let value = match self.entry(table, &prefix, "value") {
                Some(_) => self.expression_at(table, &prefix, "value", scope),
                None => {
                    self.error(
                        header.clone(),
                        &format!("{prefix}.value"),
                        "missing: the boundary value (a number or an expression)",
                        None,
                    );
                    None
                }
            };
            let kind = match (conditions, kind_name.as_deref()) {
                (Conditions::Steady | Conditions::Transient, Some("dirichlet"))
                | (Conditions::Darcy, Some("pressure")) => value.map(BoundaryKindSpec::Dirichlet),
                (Conditions::Steady | Conditions::Transient, Some("neumann"))
                | (Conditions::Darcy, Some("flux")) => value.map(BoundaryKindSpec::Neumann),
                (Conditions::Steady | Conditions::Transient, Some("robin")) => {
                    let alpha = match self.entry(table, &prefix, "alpha") {
                        Some(_) => self.expression_at(table, &prefix, "alpha", scope),
                        None => {
                            self.error(
                                header.clone(),
                                &format!("{prefix}.alpha"),
                                "missing: a Robin condition K∇u·n + α u = g needs α",
                                None,
                            );
                            None
                        }
                    };
                    if conditions == Conditions::Transient
                        && alpha.as_ref().is_some_and(|a| a.uses_time())
                    {
                        let span = self.entry(table, &prefix, "alpha").and_then(|e| e.span());
                        self.error(span, &format!("{prefix}.alpha"), "a Robin coefficient α enters the matrix, which is factorised once: it may not depend on t", Some("the value g may depend on t".into()));
                    }
                    match (alpha, value) {
                        (Some(alpha), Some(value)) => {
                            Some(BoundaryKindSpec::Robin { alpha, value })
                        }
                        _ => None,
                    }
                }
                (_, Some(other)) => {
                    let span = self.entry(table, &prefix, "type").and_then(|e| e.span());
                    let kinds: Vec<String> = names.iter().map(|s| s.to_string()).collect();
                    let help = closest(other, &kinds).map_or_else(
                        || conditions.help().to_string(),
                        |s| format!("did you mean \"{s}\"? {}", conditions.help()),
                    );
                    self.error(
                        span,
                        &format!("{prefix}.type"),
                        format!("unknown boundary type \"{other}\""),
                        Some(help),
                    );
                    None
                }
                (_, None) => None,
            };
            if let Some(e) = self.entry(table, &prefix, "component") {
                self.error(
                    e.key_span.clone(),
                    &e.name,
                    "only an elasticity displacement condition takes component",
                    None,
                );
            }
            if kind_name.as_deref() != Some("robin") || conditions == Conditions::Darcy {
                if let Some(e) = self.entry(table, &prefix, "alpha") {
                    self.error(
                        e.key_span.clone(),
                        &e.name,
                        "only a robin condition takes alpha",
                        None,
                    );
                }
            }
            if let (Some(tag), Some(kind)) = (tag, kind) {
                out.push(BoundarySpec {
                    tag,
                    kind,
                    tag_span,
                    key: prefix,
                });
            }
        }
        out
    }

    pub(super) fn gradient_metric(&mut self, table: &dyn TableLike) -> Option<GradientMetric> {
        let Some((metric, entry)) = self.subtable(table, "problem", "metric") else {
            if table.get("metric").is_none() {
                self.error(
                    None,
                    "problem.metric",
                    "missing: the face metric Ω",
                    Some("e.g. metric = { type = \"diagonal\", value = 0.2 }".into()),
                );
            }
            return None;
        };
        self.check_keys(metric, "problem.metric", METRIC_KEYS);
        let kind = self.string_at(metric, "problem.metric", "type");
        match kind.as_deref() {
            Some("diagonal") => match self.number_at(metric, "problem.metric", "value") {
                Some(v) if v.is_finite() => Some(GradientMetric::Diagonal(v)),
                Some(v) => {
                    self.error(
                        entry.span(),
                        "problem.metric.value",
                        format!("not finite: {v}"),
                        None,
                    );
                    None
                }
                None => {
                    if metric.get("value").is_none() {
                        self.error(
                            entry.span(),
                            "problem.metric.value",
                            "missing: the diagonal value σ of Ω = σ I",
                            None,
                        );
                    }
                    None
                }
            },
            Some("file") => {
                let scale = self
                    .number_at(metric, "problem.metric", "scale")
                    .unwrap_or(1.0);
                let file = self.string_at(metric, "problem.metric", "file");
                let Some(file) = file else {
                    if metric.get("file").is_none() {
                        self.error(
                            entry.span(),
                            "problem.metric.file",
                            "missing: the file of `row column value` lines",
                            None,
                        );
                    }
                    return None;
                };
                let path = self.relative(&file);
                if !path.is_file() {
                    let span = self
                        .entry(metric, "problem.metric", "file")
                        .and_then(|e| e.span());
                    self.error(
                        span,
                        "problem.metric.file",
                        format!("no such file: {}", path.display()),
                        Some("paths are relative to the case file".into()),
                    );
                    return None;
                }
                Some(GradientMetric::File { path, scale })
            }
            Some("two-point") => Some(GradientMetric::TwoPoint),
            Some(other) => {
                let span = self
                    .entry(metric, "problem.metric", "type")
                    .and_then(|e| e.span());
                self.error(
                    span,
                    "problem.metric.type",
                    format!("unknown metric type \"{other}\""),
                    Some("use \"diagonal\", \"file\" or \"two-point\"".into()),
                );
                None
            }
            None => {
                if metric.get("type").is_none() {
                    self.error(
                        entry.span(),
                        "problem.metric.type",
                        "missing: \"diagonal\", \"file\" or \"two-point\"",
                        None,
                    );
                }
                None
            }
        }
    }

    pub(super) fn relative(&self, file: &str) -> PathBuf {
        Path::new(&self.file)
            .parent()
            .unwrap_or(Path::new("."))
            .join(file)
    }
}
