//! Reading a case file's TOML into a [`Case`], key by key, collecting every
//! problem with its position instead of stopping at the first (so `hasse
//! check` can list them all).

use super::diagnostic::{Collector, Diagnostics};
use super::expr::{closest, ExprError, Expression, Regions, Scope};
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
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml_edit::{ImDocument, Item, TableLike, Value};

mod coefficient;
mod coupled;
mod dec;
mod elasticity;
mod growth;
mod hodge;
mod kinds;
mod overrides;
mod problem;
mod quantities;
mod sections;
#[cfg(test)]
mod tests;
mod time;
mod transport;

use kinds::{form_degree, kind_help, problem_kind, Conditions};
pub(in crate::frontend::case) use overrides::apply_overrides;

pub(super) const TOP_KEYS: &[&str] = &[
    "title",
    "description",
    "constants",
    "definitions",
    "mesh",
    "regions",
    "problem",
    "boundary",
    "exact",
    "solver",
    "output",
    "refine",
    "time",
    "field",
    "growth",
];
pub(super) const PROBLEM_KEYS: &[&str] = &[
    "kind",
    "method",
    "conductivity",
    "source",
    "field",
    "metric",
    "cell_points",
    "neumann",
    "neumann_tolerance",
    "reaction",
    "initial",
    "permeability",
    "mass",
    "modes",
    "degree",
    "boundary",
    "lambda",
    "mu",
    "young",
    "poisson",
    "body_force",
    "plane",
    "a",
    "b",
    "c",
    "velocity",
    "scheme",
    "stabilisation",
    "stars",
    "cochain",
    "decay",
];
/// The `problem` keys each kind takes (besides `kind`).
pub(super) const KIND_KEYS: &[(&str, &[&str])] = &[
    (
        "diffusion",
        &[
            "method",
            "conductivity",
            "source",
            "cell_points",
            "neumann",
            "neumann_tolerance",
            "reaction",
            "degree",
        ],
    ),
    ("gradient", &["field", "metric"]),
    (
        "heat",
        &["method", "conductivity", "source", "initial", "reaction"],
    ),
    ("darcy", &["method", "permeability", "source"]),
    ("maxwell", &["method", "mass", "modes"]),
    (
        "hodge-laplacian",
        &["method", "degree", "modes", "boundary", "stars"],
    ),
    ("cohomology", &["method", "degree", "boundary", "stars"]),
    (
        "hodge-decomposition",
        &["method", "degree", "field", "cochain", "stars"],
    ),
    (
        "elasticity",
        &["lambda", "mu", "young", "poisson", "body_force", "plane"],
    ),
    ("coupled", &["a", "b", "c"]),
    (
        "growth",
        &["method", "conductivity", "source", "initial", "decay"],
    ),
    (
        "transport",
        &[
            "method",
            "conductivity",
            "source",
            "velocity",
            "initial",
            "scheme",
            "stabilisation",
        ],
    ),
];
pub(super) const BOUNDARY_KEYS: &[&str] = &["tag", "type", "value", "alpha", "component"];
pub(super) const EXACT_KEYS: &[&str] = &["solution", "gradient", "eigenvalues", "displacement"];
pub(super) const SOLVER_KEYS: &[&str] = &[
    "type",
    "tolerance",
    "factorization",
    "residual_warning",
    "residual_limit",
    "prolongation",
    "ordering",
    "petsc",
    "nonlinear",
    "preconditioner",
];
pub(super) const PETSC_KEYS: &[&str] = &["options"];
/// Keys of `[solver.nonlinear]`.
pub(super) const NONLINEAR_KEYS: &[&str] =
    &["method", "tolerance", "max_iterations", "monitor", "linear"];
pub(super) const OUTPUT_KEYS: &[&str] = &[
    "directory",
    "name",
    "write",
    "quantity",
    "probe",
    "fields",
    "partial",
    "complex",
];
pub(super) const REFINE_KEYS: &[&str] = &["strategy", "steps", "theta", "coarsen", "tolerance"];
pub(super) const STRATEGIES: &[&str] = &[
    "uniform",
    "adaptive",
    "divide-longest-axis",
    "divide-shortest-wall",
];
pub(super) const METRIC_KEYS: &[&str] = &["type", "value", "file", "scale"];

/// Walks the parsed document and records what it finds.
pub(super) struct Reader {
    collector: Collector,
    file: String,
}

/// A key found in a table: its dotted name, the span of the key and the item.
pub(super) struct Entry<'a> {
    name: String,
    key_span: Option<Range<usize>>,
    item: &'a Item,
}

impl Entry<'_> {
    pub(super) fn span(&self) -> Option<Range<usize>> {
        self.item.span().or_else(|| self.key_span.clone())
    }
}

impl Reader {
    pub(super) fn read(
        file: &str,
        text: &str,
        overrides: Vec<(String, String)>,
    ) -> Result<Case, Diagnostics> {
        let mut reader = Reader {
            collector: Collector::new(file, text).with_overrides(overrides),
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
        let regions = reader.regions(root, &scope);
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
        if refine.is_some() && solver.kind == SolverKind::Petsc {
            // One MPI run solves one system: MPI and PETSc start once per
            // process.
            let span = root.get_key_value("refine").and_then(|(k, _)| k.span());
            reader.error(
                span,
                "refine",
                "[refine] re-solves on refined meshes, which the petsc path does not do yet (one distributed solve per run)",
                Some("remove [refine], or use another solver.type".into()),
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
                regions,
                problem,
                exact,
                solver,
                output,
                refine,
                warnings: reader.collector.warnings.clone(),
                collector: reader.collector,
                mesh_spans,
            }),
            // Every `None` above came with a diagnostic.
            _ => Err(Diagnostics(reader.collector.diagnostics)),
        }
    }

    pub(super) fn error(
        &mut self,
        span: Option<Range<usize>>,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) {
        self.collector.error(span, key, message, help);
    }

    pub(super) fn check_keys(&mut self, table: &dyn TableLike, prefix: &str, known: &[&str]) {
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

    pub(super) fn entry<'a>(
        &self,
        table: &'a dyn TableLike,
        prefix: &str,
        key: &str,
    ) -> Option<Entry<'a>> {
        table.get_key_value(key).map(|(k, item)| {
            let entry = Entry {
                name: join(prefix, key),
                key_span: k.span(),
                item,
            };
            // Every key read is remembered, so that problems found after
            // reading (at run time) can still point at it.
            self.collector.record(&entry.name, entry.span());
            entry
        })
    }

    pub(super) fn type_error(&mut self, entry: &Entry, expected: &str) {
        let found = describe(entry.item);
        self.error(
            entry.span(),
            &entry.name,
            format!("expected {expected}, found {found}"),
            None,
        );
    }

    pub(super) fn string_at(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
    ) -> Option<String> {
        let entry = self.entry(table, prefix, key)?;
        match entry.item.as_str() {
            Some(s) => Some(s.to_string()),
            None => {
                self.type_error(&entry, "a string");
                None
            }
        }
    }

    pub(super) fn number(&mut self, entry: &Entry) -> Option<f64> {
        match entry.item.as_value() {
            Some(Value::Float(f)) => Some(*f.value()),
            Some(Value::Integer(i)) => Some(*i.value() as f64),
            _ => {
                self.type_error(entry, "a number");
                None
            }
        }
    }

    pub(super) fn number_at(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
    ) -> Option<f64> {
        let entry = self.entry(table, prefix, key)?;
        self.number(&entry)
    }

    pub(super) fn expression_of(
        &mut self,
        item: &Item,
        name: &str,
        span: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Expression> {
        let text = match item.as_value() {
            Some(Value::String(s)) => s.value().clone(),
            // TOML's nan and inf are numbers, but not values a coefficient
            // can take; said as such rather than as an unknown name `NaN`.
            Some(Value::Float(f)) if !f.value().is_finite() => {
                let written = match *f.value() {
                    v if v.is_nan() => "nan",
                    v if v > 0.0 => "inf",
                    _ => "-inf",
                };
                self.error(
                    span,
                    name,
                    format!("`{written}` is not a finite number"),
                    Some("give a finite value".into()),
                );
                return None;
            }
            Some(Value::Float(f)) => format_number(*f.value()),
            Some(Value::Integer(i)) => i.value().to_string(),
            _ if item.is_table_like() => {
                self.error(
                    span,
                    name,
                    "values per region (a table `{ region = value, default = value }`) are not accepted here".to_string(),
                    Some(format!("{REGIONAL_KEYS}; give `{name}` one expression (`if(…)` can tell places apart)")),
                );
                return None;
            }
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
                    {
                        let (head, tail) = super::expr::quote(&text, None);
                        format!("{head} evaluates to {}{tail}", e.eval(&[], 0.0))
                    },
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

    /// An expression `<prefix>.<key>` that may be given per region: a
    /// table of region names (tags of top cells) and an optional `default`,
    /// each an expression.
    pub(super) fn expression_or_regions_at(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
        scope: &Scope,
    ) -> Option<Expression> {
        let entry = self.entry(table, prefix, key)?;
        self.expression_or_regions(&entry, scope)
    }

    /// [`Reader::expression_or_regions_at`] of an entry already found.
    pub(super) fn expression_or_regions(
        &mut self,
        entry: &Entry,
        scope: &Scope,
    ) -> Option<Expression> {
        let Some(regions) = entry.item.as_table_like() else {
            return self.expression_of(entry.item, &entry.name, entry.span(), scope);
        };
        let mut pieces = Vec::new();
        let mut default = None;
        let mut ok = true;
        for (region, item) in regions.iter() {
            let name = format!("{}.{region}", entry.name);
            let span = item.span().or_else(|| entry.span());
            self.collector.record(&name, span.clone());
            match self.expression_of(item, &name, span, scope) {
                Some(e) if region == "default" => default = Some(e),
                Some(e) => pieces.push((region.to_string(), e)),
                None => ok = false,
            }
        }
        if ok && pieces.is_empty() {
            self.error(
                entry.span(),
                &entry.name,
                "a table of values per region names no region".to_string(),
                Some("write `{ region = value, …, default = value }` with tags of top cells as regions, or give one value".into()),
            );
            return None;
        }
        let text = entry.item.to_string().trim().to_string();
        ok.then(|| Expression::per_region(&text, Regions { pieces, default }))
    }

    pub(super) fn expression_at(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
        scope: &Scope,
    ) -> Option<Expression> {
        let entry = self.entry(table, prefix, key)?;
        self.expression_of(entry.item, &entry.name, entry.span(), scope)
    }

    pub(super) fn subtable<'a>(
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

    pub(super) fn constants(
        &mut self,
        root: &dyn TableLike,
        scope: &mut Scope,
    ) -> BTreeMap<String, f64> {
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

    pub(super) fn definitions(&mut self, root: &dyn TableLike, scope: &mut Scope) {
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
}

impl Reader {
    /// `[regions]`: tags defined by a condition on the centroid,
    /// `name = "x < 0.5"` (top cells) or `name = { faces = "x == 1" }`
    /// ((n−1)-cells), applied when the mesh is built.
    pub(super) fn regions(
        &mut self,
        root: &dyn TableLike,
        scope: &Scope,
    ) -> Vec<super::RegionSpec> {
        let Some((table, _)) = self.subtable(root, "", "regions") else {
            return Vec::new();
        };
        let mut regions = Vec::new();
        for (key, _) in table.iter() {
            let Some(entry) = self.entry(table, "regions", key) else {
                continue;
            };
            let (item, name, span, faces) = match entry.item.as_table_like() {
                Some(inner) => {
                    self.check_keys(inner, &entry.name, &["faces"]);
                    match self.entry(inner, &entry.name, "faces") {
                        Some(e) => (e.item, e.name.clone(), e.span(), true),
                        None => {
                            self.error(entry.span(), &entry.name, "a table here is `{ faces = \"condition\" }`", Some("give a condition string for a region of top cells, or faces = \"…\" for (n−1)-cells".into()));
                            continue;
                        }
                    }
                }
                None => (entry.item, entry.name.clone(), entry.span(), false),
            };
            if let Some(condition) = self.expression_of(item, &name, span, scope) {
                regions.push(super::RegionSpec {
                    name: key.to_string(),
                    condition,
                    faces,
                });
            }
        }
        regions
    }
}

pub(super) fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

pub(super) fn describe(item: &Item) -> &'static str {
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
pub(super) fn format_number(v: f64) -> String {
    if v.is_finite() {
        format!("{v:?}")
    } else {
        v.to_string()
    }
}

/// Where values per region are accepted, as messages say it.
pub(super) const REGIONAL_KEYS: &str = "values per region are accepted by the conductivity and source of diffusion and heat problems (and of coupled fields, and their reaction coefficients a, b, c), the permeability and source of Darcy problems and the Lamé parameters of elasticity";

pub(super) fn expression_help(e: &ExprError, scope: &Scope) -> String {
    match e {
        ExprError::UnknownVariable { name, .. } if name == "u" => format!(
            "the solution u may appear only in the conductivity and reaction of a diffusion or heat problem (which makes it nonlinear); here expressions may use {}",
            scope.names().join(", ")
        ),
        ExprError::UnknownVariable { .. } => format!(
            "expressions may use {}; add other names under [constants] or [definitions]",
            scope.names().join(", ")
        ),
        ExprError::NotDifferentiable { .. } => "Newton's method needs ∂/∂u: write the u-dependence with + - * / ^ and functions (sin, exp, ln, sqrt, …), without comparisons or if(…)".into(),
        ExprError::Syntax { .. } => "operators: + - * / ^; functions: sin cos tan exp ln sqrt abs min max atan2 ...; write powers as x^2".into(),
        ExprError::ReservedName { .. } => "choose another name".into(),
        ExprError::NonFiniteConstant { .. } => "give a finite number".into(),
    }
}
