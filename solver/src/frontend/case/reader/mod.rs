//! Reading a case file's TOML into a [`Case`], key by key, collecting every
//! problem with its position instead of stopping at the first (so `hasse
//! check` can list them all).

use super::diagnostic::{Collector, Diagnostics};
use super::expr::{closest, ExprError, Expression, Scope};
use super::{
    BoundaryKindSpec, BoundarySpec, Case, Coefficient, DiffusionSpec, ExactSpec, GradientMetric,
    GradientSpec, OutputSpec, Problem, SolverKind, SolverSpec,
};
use crate::frontend::mesh_spec::MeshSpec;
use crate::la::direct::Factorization;
use crate::la::ordering::Ordering;
use crate::metric::Method;
use crate::multigrid::CellProlongation;
use crate::refine::{RefineSpec, Strategy};
use hasse_complex::DualKind;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml_edit::{ImDocument, Item, TableLike, Value};

mod kinds;
use kinds::{kind_help, problem_kind, Conditions};

const TOP_KEYS: &[&str] = &[
    "title",
    "description",
    "constants",
    "definitions",
    "mesh",
    "problem",
    "boundary",
    "exact",
    "solver",
    "output",
    "refine",
    "time",
    "field",
];
const PROBLEM_KEYS: &[&str] = &[
    "kind",
    "method",
    "conductivity",
    "source",
    "field",
    "metric",
    "cell_points",
    "initial",
    "permeability",
    "mass",
    "modes",
    "lambda",
    "mu",
    "young",
    "poisson",
    "body_force",
    "plane",
    "a",
    "b",
    "c",
];
/// The `problem` keys each kind takes (besides `kind`).
const KIND_KEYS: &[(&str, &[&str])] = &[
    (
        "diffusion",
        &["method", "conductivity", "source", "cell_points"],
    ),
    ("gradient", &["field", "metric"]),
    ("heat", &["method", "conductivity", "source", "initial"]),
    ("darcy", &["method", "permeability", "source"]),
    ("maxwell", &["method", "mass", "modes"]),
    (
        "elasticity",
        &["lambda", "mu", "young", "poisson", "body_force", "plane"],
    ),
    ("coupled", &["a", "b", "c"]),
];
const BOUNDARY_KEYS: &[&str] = &["tag", "type", "value", "alpha", "component"];
const EXACT_KEYS: &[&str] = &["solution", "gradient", "eigenvalues", "displacement"];
const SOLVER_KEYS: &[&str] = &[
    "type",
    "tolerance",
    "factorization",
    "residual_warning",
    "residual_limit",
    "prolongation",
    "ordering",
];
const OUTPUT_KEYS: &[&str] = &["directory", "name", "write"];
const REFINE_KEYS: &[&str] = &["strategy", "steps", "theta", "tolerance"];
const STRATEGIES: &[&str] = &[
    "uniform",
    "adaptive",
    "divide-longest-axis",
    "divide-shortest-wall",
];
const METRIC_KEYS: &[&str] = &["type", "value", "file", "scale"];
const METHODS: &[&str] = &["fd", "fe", "fv", "fv-mimetic", "dec", "dec-barycentric"];

/// Apply `key.path=value` overrides to the case text. Values are TOML
/// (`n=[64,64]`, `problem.method="fv"`); a value that is not valid TOML is
/// taken as a string, so `problem.method=fv` works too.
pub(super) fn apply_overrides(
    file: &str,
    text: &str,
    overrides: &[String],
) -> Result<String, Diagnostics> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let mut collector = Collector::new(file, text);
    let mut doc: toml_edit::DocumentMut = match text.parse() {
        Ok(doc) => doc,
        // The syntax error is reported with its position by the reader.
        Err(_) => return Ok(text.to_string()),
    };
    for assignment in overrides {
        let Some((path, raw)) = assignment.split_once('=') else {
            collector.error(
                None,
                "",
                format!("--set {assignment}: expected KEY=VALUE"),
                Some("e.g. --set problem.method=fv or --set mesh.n=[64,64]".into()),
            );
            continue;
        };
        let value: Value = raw
            .trim()
            .parse()
            .unwrap_or_else(|_| Value::from(raw.trim()));
        let segments: Vec<&str> = path.trim().split('.').collect();
        if segments.iter().any(|s| s.is_empty()) || !set_path(doc.as_table_mut(), &segments, value)
        {
            collector.error(
                None,
                path.trim(),
                format!(
                    "--set {assignment}: `{}` does not name a value in this case file",
                    path.trim()
                ),
                Some("use dotted keys such as problem.method, mesh.n or boundary.0.value".into()),
            );
        }
    }
    if collector.diagnostics.is_empty() {
        Ok(doc.to_string())
    } else {
        Err(Diagnostics(collector.diagnostics))
    }
}

/// Set the value at a dotted path, creating tables on the way; a numeric
/// segment indexes an array of tables (`boundary.0.value`).
fn set_path(table: &mut dyn TableLike, segments: &[&str], value: Value) -> bool {
    let Some((head, rest)) = segments.split_first() else {
        return false;
    };
    if rest.is_empty() {
        table.insert(head, Item::Value(value));
        return true;
    }
    if table.get(head).is_none() {
        table.insert(head, Item::Table(toml_edit::Table::new()));
    }
    match table.get_mut(head) {
        Some(Item::ArrayOfTables(array)) => {
            let (Some(index), Some(rest)) = (rest[0].parse::<usize>().ok(), rest.get(1..)) else {
                return false;
            };
            match array.get_mut(index) {
                Some(t) if !rest.is_empty() => set_path(t, rest, value),
                _ => false,
            }
        }
        Some(item) => match item.as_table_like_mut() {
            Some(t) => set_path(t, rest, value),
            None => false,
        },
        None => false,
    }
}

/// Walks the parsed document and records what it finds.
pub(super) struct Reader {
    collector: Collector,
    file: String,
}

/// A key found in a table: its dotted name, the span of the key and the item.
struct Entry<'a> {
    name: String,
    key_span: Option<Range<usize>>,
    item: &'a Item,
}

impl Entry<'_> {
    fn span(&self) -> Option<Range<usize>> {
        self.item.span().or_else(|| self.key_span.clone())
    }
}

impl Reader {
    pub(super) fn read(file: &str, text: &str) -> Result<Case, Diagnostics> {
        let mut reader = Reader {
            collector: Collector::new(file, text),
            file: file.to_string(),
        };
        let doc = match ImDocument::parse(text.to_string()) {
            Ok(doc) => doc,
            Err(e) => {
                reader.collector.error(
                    e.span(),
                    "",
                    format!("not valid TOML: {}", e.message().trim()),
                    Some("see https://toml.io for the syntax".into()),
                );
                return Err(Diagnostics(reader.collector.diagnostics));
            }
        };
        let root = doc.as_table();
        reader.check_keys(root, "", TOP_KEYS);

        let title = reader.string_at(root, "", "title");
        let mut scope = Scope::new();
        let constants = reader.constants(root, &mut scope);
        reader.definitions(root, &mut scope);
        let (mesh, mesh_spans) = reader.mesh(root, text);
        let problem = reader.problem(root, &scope);
        let exact = reader.exact(root, &scope);
        let solver = reader.solver(root);
        let output = reader.output(root);
        let refine = reader.refine(root);
        if refine.is_some() && problem_kind(root) != "diffusion" {
            let span = root.get_key_value("refine").and_then(|(k, _)| k.span());
            reader.error(
                span,
                "refine",
                format!(
                    "[refine] is for diffusion problems; this case is kind = \"{}\"",
                    problem_kind(root)
                ),
                Some("remove [refine], or run `hasse converge` for a study".into()),
            );
        }

        if !reader.collector.diagnostics.is_empty() {
            return Err(Diagnostics(reader.collector.diagnostics));
        }
        match (mesh, problem) {
            (Some(mesh), Some(problem)) => Ok(Case {
                path: PathBuf::from(file),
                text: text.to_string(),
                title,
                constants,
                scope,
                mesh,
                problem,
                exact,
                solver,
                output,
                refine,
                collector: reader.collector,
                mesh_spans,
            }),
            // Every `None` above came with a diagnostic.
            _ => Err(Diagnostics(reader.collector.diagnostics)),
        }
    }

    fn error(
        &mut self,
        span: Option<Range<usize>>,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) {
        self.collector.error(span, key, message, help);
    }

    fn check_keys(&mut self, table: &dyn TableLike, prefix: &str, known: &[&str]) {
        let owned: Vec<String> = known.iter().map(|s| s.to_string()).collect();
        for (key, _) in table.iter() {
            if known.contains(&key) {
                continue;
            }
            let span = table.get_key_value(key).and_then(|(k, _)| k.span());
            let help = match closest(key, &owned) {
                Some(s) => format!("did you mean `{s}`?"),
                None => format!("known keys here: {}", known.join(", ")),
            };
            self.error(span, &join(prefix, key), "unknown key", Some(help));
        }
    }

    fn entry<'a>(&self, table: &'a dyn TableLike, prefix: &str, key: &str) -> Option<Entry<'a>> {
        table.get_key_value(key).map(|(k, item)| Entry {
            name: join(prefix, key),
            key_span: k.span(),
            item,
        })
    }

    fn type_error(&mut self, entry: &Entry, expected: &str) {
        let found = describe(entry.item);
        self.error(
            entry.span(),
            &entry.name,
            format!("expected {expected}, found {found}"),
            None,
        );
    }

    fn string_at(&mut self, table: &dyn TableLike, prefix: &str, key: &str) -> Option<String> {
        let entry = self.entry(table, prefix, key)?;
        match entry.item.as_str() {
            Some(s) => Some(s.to_string()),
            None => {
                self.type_error(&entry, "a string");
                None
            }
        }
    }

    fn number(&mut self, entry: &Entry) -> Option<f64> {
        match entry.item.as_value() {
            Some(Value::Float(f)) => Some(*f.value()),
            Some(Value::Integer(i)) => Some(*i.value() as f64),
            _ => {
                self.type_error(entry, "a number");
                None
            }
        }
    }

    fn number_at(&mut self, table: &dyn TableLike, prefix: &str, key: &str) -> Option<f64> {
        let entry = self.entry(table, prefix, key)?;
        self.number(&entry)
    }

    fn expression_of(
        &mut self,
        item: &Item,
        name: &str,
        span: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Expression> {
        let text = match item.as_value() {
            Some(Value::String(s)) => s.value().clone(),
            Some(Value::Float(f)) => format_number(*f.value()),
            Some(Value::Integer(i)) => i.value().to_string(),
            _ => {
                let found = describe(item);
                self.error(
                    span,
                    name,
                    format!("expected a number or an expression string, found {found}"),
                    None,
                );
                return None;
            }
        };
        match scope.parse(&text) {
            // A constant is evaluated once here, so NaN or ±∞ is found at its
            // line rather than at the first point the solver samples.
            Ok(e) if e.is_constant() && !e.eval(&[], 0.0).is_finite() => {
                self.error(
                    span,
                    name,
                    format!("`{text}` evaluates to {}", e.eval(&[], 0.0)),
                    Some(
                        "give a finite value (check square roots, logarithms and divisions)".into(),
                    ),
                );
                None
            }
            Ok(e) => Some(e),
            Err(e) => {
                let help = expression_help(&e, scope);
                self.error(span, name, e.to_string(), Some(help));
                None
            }
        }
    }

    fn expression_at(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
        scope: &Scope,
    ) -> Option<Expression> {
        let entry = self.entry(table, prefix, key)?;
        self.expression_of(entry.item, &entry.name, entry.span(), scope)
    }

    fn subtable<'a>(
        &mut self,
        table: &'a dyn TableLike,
        prefix: &str,
        key: &str,
    ) -> Option<(&'a dyn TableLike, Entry<'a>)> {
        let entry = self.entry(table, prefix, key)?;
        match entry.item.as_table_like() {
            Some(t) => Some((t, entry)),
            None => {
                self.type_error(&entry, "a table");
                None
            }
        }
    }

    fn constants(&mut self, root: &dyn TableLike, scope: &mut Scope) -> BTreeMap<String, f64> {
        let mut out = BTreeMap::new();
        let Some((table, _)) = self.subtable(root, "", "constants") else {
            return out;
        };
        for (key, _) in table.iter() {
            let Some(entry) = self.entry(table, "constants", key) else {
                continue;
            };
            // A constant may be a number or an expression of earlier constants.
            let value = match entry.item.as_value() {
                Some(Value::String(_)) => self
                    .expression_of(entry.item, &entry.name, entry.span(), scope)
                    .and_then(|e| {
                        if e.is_constant() {
                            Some(e.eval(&[], 0.0))
                        } else {
                            self.error(
                                entry.span(),
                                &entry.name,
                                "a constant may not depend on x, y, z or t",
                                Some("move it to [definitions]".into()),
                            );
                            None
                        }
                    }),
                _ => self.number(&entry),
            };
            if let Some(v) = value {
                match scope.add_constant(key, v) {
                    Ok(()) => {
                        out.insert(key.to_string(), v);
                    }
                    Err(e) => self.error(entry.key_span.clone(), &entry.name, e.to_string(), None),
                }
            }
        }
        out
    }

    fn definitions(&mut self, root: &dyn TableLike, scope: &mut Scope) {
        let Some((table, _)) = self.subtable(root, "", "definitions") else {
            return;
        };
        for (key, item) in table.iter() {
            let Some(entry) = self.entry(table, "definitions", key) else {
                continue;
            };
            let Some(text) = item.as_str() else {
                self.type_error(&entry, "an expression string");
                continue;
            };
            if let Err(e) = scope.add_definition(key, text) {
                let span = match e {
                    ExprError::ReservedName { .. } => entry.key_span.clone(),
                    _ => entry.span(),
                };
                let help = expression_help(&e, scope);
                self.error(span, &entry.name, e.to_string(), Some(help));
            }
        }
    }

    fn mesh(
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

    fn problem(&mut self, root: &dyn TableLike, scope: &Scope) -> Option<Problem> {
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
            "diffusion" => {
                let method = self.method(table, problem_entry.span());
                let conductivity = self.coefficient(table, "conductivity", scope);
                let source = match self.entry(table, "problem", "source") {
                    Some(_) => self.expression_at(table, "problem", "source", scope),
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
                Some(Problem::Diffusion(DiffusionSpec {
                    method: method?,
                    conductivity: conductivity?,
                    source: source?,
                    boundary,
                    circumcentres,
                }))
            }
            "heat" => self.heat(root, table, problem_entry.span(), scope),
            "darcy" => self.darcy(root, table, problem_entry.span(), scope),
            "maxwell" => self.maxwell(root, table, problem_entry.span()),
            "elasticity" => self.elasticity(root, table, problem_entry.span(), scope),
            "coupled" => self.coupled(root, table, problem_entry.span(), scope),
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

    fn method(&mut self, table: &dyn TableLike, header: Option<Range<usize>>) -> Option<Method> {
        self.method_in(table, "problem", header)
    }

    /// `method` of the table at `prefix` (`problem`, or `field[i]`).
    fn method_in(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        header: Option<Range<usize>>,
    ) -> Option<Method> {
        let Some(entry) = self.entry(table, prefix, "method") else {
            self.error(
                header,
                &join(prefix, "method"),
                "missing: which discretisation to use",
                Some(format!("one of {}", METHODS.join(", "))),
            );
            return None;
        };
        let name = entry.item.as_str().map(str::to_string);
        let method = match name.as_deref() {
            Some("fd") => Method::Fd,
            Some("fe") => Method::Fe,
            Some("fv") => Method::Fv,
            Some("fv-mimetic") => Method::FvMimetic,
            Some("dec") => Method::Dec(DualKind::Circumcentric),
            Some("dec-barycentric") => Method::Dec(DualKind::Barycentric),
            Some(other) => {
                let owned: Vec<String> = METHODS.iter().map(|s| s.to_string()).collect();
                let help = match closest(other, &owned) {
                    Some(s) => format!("did you mean \"{s}\"? methods: {}", METHODS.join(", ")),
                    None => format!("methods: {}", METHODS.join(", ")),
                };
                self.error(
                    entry.span(),
                    &entry.name,
                    format!("unknown method \"{other}\""),
                    Some(help),
                );
                return None;
            }
            None => {
                self.type_error(&entry, "a string");
                return None;
            }
        };
        Some(method)
    }

    /// A scalar or tensor coefficient under `problem.<key>` (default 1).
    fn coefficient(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        scope: &Scope,
    ) -> Option<Coefficient> {
        self.coefficient_in(table, "problem", key, scope)
    }

    /// A scalar or tensor coefficient `<prefix>.<key>` (default 1).
    fn coefficient_in(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
        scope: &Scope,
    ) -> Option<Coefficient> {
        let Some(entry) = self.entry(table, prefix, key) else {
            return scope.parse("1").ok().map(Coefficient::Scalar);
        };
        let Some(Value::Array(rows)) = entry.item.as_value() else {
            return self
                .expression_of(entry.item, &entry.name, entry.span(), scope)
                .map(Coefficient::Scalar);
        };
        let size = rows.len();
        if !(1..=3).contains(&size) {
            self.error(
                entry.span(),
                &entry.name,
                format!("a tensor has 1 to 3 rows, found {size}"),
                None,
            );
            return None;
        }
        let mut tensor = Vec::with_capacity(size);
        let mut ok = true;
        for (i, row) in rows.iter().enumerate() {
            let name = format!("{}[{i}]", entry.name);
            let Value::Array(cols) = row else {
                self.error(
                    row.span(),
                    &name,
                    "expected a row (an array)",
                    Some("write the tensor as [[kxx, kxy], [kxy, kyy]]".into()),
                );
                ok = false;
                continue;
            };
            if cols.len() != size {
                self.error(
                    row.span(),
                    &name,
                    format!(
                        "row has {} entries; the tensor is {size}×{size}",
                        cols.len()
                    ),
                    None,
                );
                ok = false;
                continue;
            }
            let mut parsed = Vec::with_capacity(size);
            for (j, v) in cols.iter().enumerate() {
                let item = Item::Value(v.clone());
                match self.expression_of(&item, &format!("{name}[{j}]"), v.span(), scope) {
                    Some(e) => parsed.push(e),
                    None => ok = false,
                }
            }
            tensor.push(parsed);
        }
        if !ok {
            return None;
        }
        // Symmetry can be checked textually for constant entries here; entries
        // that vary are checked where they are evaluated.
        for (i, row) in tensor.iter().enumerate() {
            for (j, a) in row.iter().enumerate().take(i) {
                let b = &tensor[j][i];
                if a.is_constant() && b.is_constant() && a.eval(&[], 0.0) != b.eval(&[], 0.0) {
                    self.error(entry.span(), &entry.name, format!("the tensor is not symmetric: entry [{i}][{j}] = {} but [{j}][{i}] = {}", a.text(), b.text()), Some("a diffusion or permeability tensor is symmetric positive definite".into()));
                    return None;
                }
            }
        }
        Some(Coefficient::Tensor(tensor))
    }

    fn boundary(
        &mut self,
        root: &dyn TableLike,
        scope: &Scope,
        conditions: Conditions,
    ) -> Vec<BoundarySpec> {
        self.boundary_in(root, "", scope, conditions)
    }

    /// The `[[boundary]]` tables under `parent` (the document, or a
    /// `[[field]]` of a coupled problem).
    fn boundary_in(
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

    fn gradient_metric(&mut self, table: &dyn TableLike) -> Option<GradientMetric> {
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

    fn relative(&self, file: &str) -> PathBuf {
        Path::new(&self.file)
            .parent()
            .unwrap_or(Path::new("."))
            .join(file)
    }

    fn exact(&mut self, root: &dyn TableLike, scope: &Scope) -> Option<ExactSpec> {
        if problem_kind(root) == "coupled" {
            // Exact fields go in the [[field]] tables; `coupled` says so.
            return None;
        }
        let (table, entry) = self.subtable(root, "", "exact")?;
        self.check_keys(table, "exact", EXACT_KEYS);
        let eigenproblem = problem_kind(root) == "maxwell";
        let elastic = problem_kind(root) == "elasticity";
        let solution = match self.entry(table, "exact", "solution") {
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
                    "only an eigenproblem (kind = \"maxwell\") has eigenvalues",
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
        Some(ExactSpec {
            solution: if eigenproblem || elastic {
                None
            } else {
                Some(solution?)
            },
            gradient,
            eigenvalues,
            displacement,
        })
    }

    fn solver(&mut self, root: &dyn TableLike) -> SolverSpec {
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
                other => {
                    let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                    self.error(
                        span,
                        "solver.type",
                        format!("unknown solver type \"{other}\""),
                        Some("\"direct\" (faer LLᵀ/LDLᵀ/LU), \"multigrid\" (CG with a V-cycle on the generator's grid levels), \"amg\" (CG with smoothed aggregation, any mesh) or \"auto\"".into()),
                    );
                    SolverKind::Direct
                }
            };
            if spec.kind != SolverKind::Direct && problem_kind(root) != "diffusion" {
                let span = self.entry(table, "solver", "type").and_then(|e| e.span());
                self.error(
                    span,
                    "solver.type",
                    format!("the iterative solvers serve diffusion problems; this case is kind = \"{}\"", problem_kind(root)),
                    Some("remove solver.type (direct)".into()),
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
        spec
    }

    fn refine(&mut self, root: &dyn TableLike) -> Option<RefineSpec> {
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
        match self.string_at(table, "refine", "strategy").as_deref() {
            None | Some("uniform") => {}
            Some("adaptive") => {
                spec.strategy = Strategy::Adaptive {
                    theta: theta.unwrap_or(0.5),
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
        if theta.is_some() && !matches!(spec.strategy, Strategy::Adaptive { .. }) {
            let span = self
                .entry(table, "refine", "theta")
                .and_then(|e| e.key_span.clone());
            self.error(
                span,
                "refine.theta",
                "only the adaptive strategy marks cells",
                None,
            );
        }
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

    fn output(&mut self, root: &dyn TableLike) -> OutputSpec {
        let stem = Path::new(&self.file)
            .file_stem()
            .map_or("hasse".to_string(), |s| s.to_string_lossy().into_owned());
        let mut spec = OutputSpec {
            directory: PathBuf::from("."),
            name: stem,
            write: true,
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
        spec
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

fn describe(item: &Item) -> &'static str {
    match item {
        Item::None => "nothing",
        Item::Table(_) => "a table",
        Item::ArrayOfTables(_) => "an array of tables",
        Item::Value(v) => match v {
            Value::String(_) => "a string",
            Value::Integer(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Boolean(_) => "a boolean",
            Value::Datetime(_) => "a date",
            Value::Array(_) => "an array",
            Value::InlineTable(_) => "an inline table",
        },
    }
}

/// A number as expression text that parses back to the same f64.
fn format_number(v: f64) -> String {
    if v.is_finite() {
        format!("{v:?}")
    } else {
        v.to_string()
    }
}

fn expression_help(e: &ExprError, scope: &Scope) -> String {
    match e {
        ExprError::UnknownVariable { .. } => format!(
            "expressions may use {}; add other names under [constants] or [definitions]",
            scope.names().join(", ")
        ),
        ExprError::Syntax { .. } => "operators: + - * / ^; functions: sin cos tan exp ln sqrt abs min max atan2 ...; write powers as x^2".into(),
        ExprError::ReservedName { .. } => "choose another name".into(),
        ExprError::NonFiniteConstant { .. } => "give a finite number".into(),
    }
}
