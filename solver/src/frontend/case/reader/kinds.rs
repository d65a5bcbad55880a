//! The problem kinds beyond steady diffusion and gradients: which `problem`
//! keys each kind takes, and reading transient heat (with its `[time]`
//! table), mixed Darcy and Maxwell cavity problems.

use super::{join, Reader, KIND_KEYS};
use crate::frontend::case::expr::{closest, Scope};
use crate::frontend::case::{
    CoupledFieldSpec, CoupledSpec, DarcySpec, ElasticBoundaryKind, ElasticBoundarySpec,
    ElasticitySpec, HeatSpec, MaterialSpec, MaxwellSpec, Problem, TimeSpec,
};
use crate::metric::fv::FluxMass;
use crate::metric::Method;
use crate::physics::elasticity::PlaneModel;
use crate::physics::maxwell::Mass;
use hasse_complex::DualKind;
use std::ops::Range;
use toml_edit::{Item, TableLike, Value};

const TIME_KEYS: &[&str] = &[
    "dt",
    "steps",
    "end",
    "start",
    "scheme",
    "theta",
    "save_every",
];
const SCHEMES: &[&str] = &["backward-euler", "crank-nicolson"];
const DARCY_METHODS: &[&str] = &["mimetic", "dec", "dec-barycentric"];
const MAXWELL_METHODS: &[&str] = &["dec", "dec-barycentric"];
const MAXWELL_MASSES: &[&str] = &["hodge", "whitney"];
/// More steps than this is almost certainly a typo in `dt` or `end`.
const MAX_STEPS: i64 = 10_000_000;

/// The kind a case's `problem.kind` names (default diffusion), read
/// directly from the document so other tables can depend on it.
pub(in crate::frontend::case) fn problem_kind(root: &dyn TableLike) -> &str {
    root.get("problem")
        .and_then(Item::as_table_like)
        .and_then(|p| p.get("kind"))
        .and_then(Item::as_str)
        .unwrap_or("diffusion")
}

/// The help line of an unknown `problem.kind`.
pub(in crate::frontend::case) fn kind_help(other: &str) -> String {
    let kinds: Vec<String> = KIND_KEYS.iter().map(|(k, _)| k.to_string()).collect();
    let list = kinds.join(", ");
    match closest(other, &kinds) {
        Some(s) => format!("did you mean \"{s}\"? kinds: {list} (default diffusion)"),
        None => format!("kinds: {list} (default diffusion)"),
    }
}

/// Which boundary condition types a problem kind accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::frontend::case) enum Conditions {
    /// Dirichlet, Neumann and Robin on a steady scalar problem.
    Steady,
    /// As `Steady`, with values that may depend on t (not the Robin α).
    Transient,
    /// Pressure (natural) and normal velocity (essential) on Darcy flow.
    Darcy,
}

impl Conditions {
    pub(in crate::frontend::case) fn names(self) -> &'static [&'static str] {
        match self {
            Conditions::Steady | Conditions::Transient => &["dirichlet", "neumann", "robin"],
            Conditions::Darcy => &["pressure", "flux"],
        }
    }

    pub(in crate::frontend::case) fn help(self) -> &'static str {
        match self {
            Conditions::Steady | Conditions::Transient => "use dirichlet, neumann or robin",
            Conditions::Darcy => "a Darcy boundary takes \"pressure\" (p given) or \"flux\" (outward normal velocity u·n given); untagged boundary faces are no-flow",
        }
    }
}

impl Reader {
    /// Report `problem` keys the kind does not use, and a `[time]` table
    /// on a steady problem.
    pub(super) fn check_kind_keys(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        kind: &str,
    ) {
        let Some((_, keys)) = KIND_KEYS.iter().find(|(k, _)| *k == kind) else {
            // An unknown kind is reported by the caller.
            return;
        };
        for (key, _) in table.iter() {
            if key == "kind" || keys.contains(&key) || !super::PROBLEM_KEYS.contains(&key) {
                continue;
            }
            let span = table.get_key_value(key).and_then(|(k, _)| k.span());
            let users: Vec<&str> = KIND_KEYS
                .iter()
                .filter(|(_, ks)| ks.contains(&key))
                .map(|(k, _)| *k)
                .collect();
            self.error(
                span,
                &join("problem", key),
                format!(
                    "not used by kind = \"{kind}\" (only by {})",
                    users.join(", ")
                ),
                Some(format!("a {kind} problem takes: {}", keys.join(", "))),
            );
        }
        if kind != "coupled" {
            if let Some((k, _)) = root.get_key_value("field") {
                self.error(
                    k.span(),
                    "field",
                    format!("[[field]] tables are for kind = \"coupled\"; this problem is {kind}"),
                    None,
                );
            }
        }
        if kind != "heat" {
            if let Some((k, _)) = root.get_key_value("time") {
                self.error(
                    k.span(),
                    "time",
                    format!("[time] is for kind = \"heat\"; this problem is {kind}"),
                    Some("remove [time], or set problem.kind = \"heat\"".into()),
                );
            }
        }
    }

    pub(super) fn heat(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let method = self.method(table, header.clone());
        if method == Some(Method::FvMimetic) {
            let span = self
                .entry(table, "problem", "method")
                .and_then(|e| e.span());
            self.error(
                span,
                "problem.method",
                "fv-mimetic has half-face unknowns, which carry no mass: it cannot step in time",
                Some("use fe, fv, fd, dec or dec-barycentric".into()),
            );
        }
        let conductivity = self.coefficient(table, "conductivity", scope);
        let source = match self.entry(table, "problem", "source") {
            Some(_) => self.expression_at(table, "problem", "source", scope),
            None => scope.parse("0").ok(),
        };
        let initial = match self.entry(table, "problem", "initial") {
            Some(_) => self.expression_at(table, "problem", "initial", scope),
            None => {
                self.error(
                    header,
                    "problem.initial",
                    "missing: the initial temperature u(x, y, z) at t₀",
                    Some("e.g. initial = \"sin(pi*x)*sin(pi*y)\"".into()),
                );
                None
            }
        };
        let boundary = self.boundary(root, scope, Conditions::Transient);
        let time = self.time(root);
        if method == Some(Method::FvMimetic) {
            return None;
        }
        Some(Problem::Heat(HeatSpec {
            method: method?,
            conductivity: conductivity?,
            source: source?,
            initial: initial?,
            boundary,
            time: time?,
        }))
    }

    /// The `[time]` table of a heat problem.
    fn time(&mut self, root: &dyn TableLike) -> Option<TimeSpec> {
        let Some((table, entry)) = self.subtable(root, "", "time") else {
            if root.get("time").is_none() {
                self.error(
                    None,
                    "time",
                    "no [time] table: a heat problem steps in time",
                    Some("add [time] with `dt = 0.01` and `steps = 100` (or `end = 1.0`)".into()),
                );
            }
            return None;
        };
        let header = entry.span();
        self.check_keys(table, "time", TIME_KEYS);
        let dt = match self.entry(table, "time", "dt") {
            None => {
                self.error(header.clone(), "time.dt", "missing: the time step Δt", None);
                None
            }
            Some(e) => match self.number(&e) {
                Some(v) if v > 0.0 && v.is_finite() => Some(v),
                Some(v) => {
                    self.error(
                        e.span(),
                        "time.dt",
                        format!("the time step must be positive and finite, found {v}"),
                        None,
                    );
                    None
                }
                None => None,
            },
        };
        let start = match self.number_at(table, "time", "start") {
            Some(v) if !v.is_finite() => {
                let span = self.entry(table, "time", "start").and_then(|e| e.span());
                self.error(span, "time.start", format!("not finite: {v}"), None);
                None
            }
            Some(v) => Some(v),
            None => Some(0.0),
        };
        let steps = self.step_count(table, header.clone(), dt, start);
        let theta = self.theta(table);
        let save_every = match self.entry(table, "time", "save_every") {
            None => Some(1),
            Some(e) => match e.item.as_integer() {
                Some(k) if k >= 0 => Some(k as usize),
                Some(k) => {
                    self.error(
                        e.span(),
                        "time.save_every",
                        format!("a step count ≥ 0, found {k}"),
                        Some("0 saves only the first and last levels".into()),
                    );
                    None
                }
                None => {
                    self.type_error(&e, "an integer");
                    None
                }
            },
        };
        Some(TimeSpec {
            dt: dt?,
            steps: steps?,
            start: start?,
            theta: theta?,
            save_every: save_every?,
        })
    }

    /// `steps`, or `end` turned into a whole number of steps of `dt`.
    fn step_count(
        &mut self,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        dt: Option<f64>,
        start: Option<f64>,
    ) -> Option<usize> {
        let steps = self.entry(table, "time", "steps");
        let end = self.entry(table, "time", "end");
        match (steps, end) {
            (Some(_), Some(e)) => {
                self.error(
                    e.key_span.clone(),
                    "time.end",
                    "give either steps or end, not both",
                    None,
                );
                None
            }
            (None, None) => {
                self.error(
                    header,
                    "time.steps",
                    "missing: how long to run",
                    Some("give `steps = 100` or `end = 1.0`".into()),
                );
                None
            }
            (Some(e), None) => match e.item.as_integer() {
                Some(n) if (1..=MAX_STEPS).contains(&n) => Some(n as usize),
                Some(n) => {
                    self.error(
                        e.span(),
                        "time.steps",
                        format!("between 1 and {MAX_STEPS} steps, found {n}"),
                        None,
                    );
                    None
                }
                None => {
                    self.type_error(&e, "an integer");
                    None
                }
            },
            (None, Some(e)) => {
                let end = self.number(&e)?;
                let (dt, start) = (dt?, start?);
                let span = e.span();
                if !(end.is_finite() && end > start) {
                    self.error(
                        span,
                        "time.end",
                        format!(
                            "the end time must be finite and after the start {start}, found {end}"
                        ),
                        None,
                    );
                    return None;
                }
                let exact = (end - start) / dt;
                let steps = exact.round();
                // Steps must tile [t₀, end] exactly, or the last level would
                // not be at `end` and errors there would be misleading.
                if (exact - steps).abs() > 1e-9 * exact.max(1.0) || steps < 1.0 {
                    self.error(
                        span,
                        "time.end",
                        format!("end − start = {} is not a whole number of steps dt = {dt} ({exact:.6} steps)", end - start),
                        Some("change dt or end, or give `steps` instead".into()),
                    );
                    return None;
                }
                if steps > MAX_STEPS as f64 {
                    self.error(
                        span,
                        "time.end",
                        format!("{steps} steps of dt = {dt}: more than {MAX_STEPS}"),
                        Some("check dt and end".into()),
                    );
                    return None;
                }
                Some(steps as usize)
            }
        }
    }

    /// θ from `scheme` or `theta` (default backward Euler, θ = 1).
    fn theta(&mut self, table: &dyn TableLike) -> Option<f64> {
        let scheme = self.entry(table, "time", "scheme");
        let theta = self.entry(table, "time", "theta");
        if let (Some(_), Some(t)) = (&scheme, &theta) {
            self.error(
                t.key_span.clone(),
                "time.theta",
                "give either scheme or theta, not both",
                None,
            );
            return None;
        }
        if let Some(t) = theta {
            let v = self.number(&t)?;
            if !(0.0..=1.0).contains(&v) {
                self.error(
                    t.span(),
                    "time.theta",
                    format!("θ must lie in [0, 1], found {v}"),
                    Some("1 is backward Euler, 0.5 Crank–Nicolson".into()),
                );
                return None;
            }
            return Some(v);
        }
        let Some(s) = scheme else {
            return Some(1.0);
        };
        match s.item.as_str() {
            Some("backward-euler") => Some(1.0),
            Some("crank-nicolson") => Some(0.5),
            Some(other) => {
                let owned: Vec<String> = SCHEMES.iter().map(|s| s.to_string()).collect();
                let help = closest(other, &owned).map_or_else(
                    || format!("schemes: {} (or theta = …)", SCHEMES.join(", ")),
                    |s| format!("did you mean \"{s}\"?"),
                );
                self.error(
                    s.span(),
                    "time.scheme",
                    format!("unknown time scheme \"{other}\""),
                    Some(help),
                );
                None
            }
            None => {
                self.type_error(&s, "a string");
                None
            }
        }
    }

    /// A string key of `problem` chosen from `choices`.
    fn choice(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        choices: &[&str],
        what: &str,
        header: Option<Range<usize>>,
        default: Option<&'static str>,
    ) -> Option<String> {
        let name = join("problem", key);
        let Some(entry) = self.entry(table, "problem", key) else {
            if default.is_none() {
                self.error(
                    header,
                    &name,
                    format!("missing: the {what}"),
                    Some(format!("one of {}", choices.join(", "))),
                );
            }
            return default.map(str::to_string);
        };
        match entry.item.as_str() {
            Some(s) if choices.contains(&s) => Some(s.to_string()),
            Some(other) => {
                let owned: Vec<String> = choices.iter().map(|s| s.to_string()).collect();
                let help = match closest(other, &owned) {
                    Some(s) => format!("did you mean \"{s}\"? choices: {}", choices.join(", ")),
                    None => format!("choices: {}", choices.join(", ")),
                };
                self.error(
                    entry.span(),
                    &name,
                    format!("unknown {what} \"{other}\""),
                    Some(help),
                );
                None
            }
            None => {
                self.type_error(&entry, "a string");
                None
            }
        }
    }

    /// `solver.factorization` if it is one of `refused`, with its span.
    fn refused_factorization(
        &self,
        root: &dyn TableLike,
        refused: &[&str],
    ) -> Option<(Option<Range<usize>>, String)> {
        let solver = root.get("solver")?.as_table_like()?;
        let (_, item) = solver.get_key_value("factorization")?;
        let name = item.as_str()?;
        refused
            .contains(&name)
            .then(|| (item.span(), name.to_string()))
    }

    pub(super) fn darcy(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let mass = self
            .choice(
                table,
                "method",
                DARCY_METHODS,
                "flux mass method",
                header,
                None,
            )
            .map(|m| match m.as_str() {
                "mimetic" => FluxMass::Mimetic,
                "dec-barycentric" => FluxMass::Dec(DualKind::Barycentric),
                _ => FluxMass::Dec(DualKind::Circumcentric),
            });
        let permeability = self.coefficient(table, "permeability", scope);
        let source = match self.entry(table, "problem", "source") {
            Some(_) => self.expression_at(table, "problem", "source", scope),
            None => scope.parse("0").ok(),
        };
        let boundary = self.boundary(root, scope, Conditions::Darcy);
        if let Some((span, name)) = self.refused_factorization(root, &["llt", "cholesky"]) {
            self.error(
                span,
                "solver.factorization",
                format!("the Darcy saddle-point matrix [[M, −∂], [−∂ᵀ, 0]] is indefinite: {name} (LLᵀ) cannot factorise it"),
                Some("leave it out (LDLᵀ in a saddle-point-safe order), or use \"ldlt\", \"lblt\" or \"lu\"".into()),
            );
        }
        Some(Problem::Darcy(DarcySpec {
            mass: mass?,
            permeability: permeability?,
            source: source?,
            boundary,
        }))
    }

    pub(super) fn maxwell(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
    ) -> Option<Problem> {
        let dual = self
            .choice(
                table,
                "method",
                MAXWELL_METHODS,
                "Hodge star (dual)",
                header.clone(),
                None,
            )
            .map(|m| match m.as_str() {
                "dec-barycentric" => DualKind::Barycentric,
                _ => DualKind::Circumcentric,
            });
        let mass = self
            .choice(
                table,
                "mass",
                MAXWELL_MASSES,
                "edge mass",
                None,
                Some("hodge"),
            )
            .map(|m| match m.as_str() {
                "whitney" => Mass::Whitney,
                _ => Mass::Hodge,
            });
        let modes = match self.entry(table, "problem", "modes") {
            None => {
                self.error(
                    header,
                    "problem.modes",
                    "missing: how many resonant modes to compute",
                    Some("e.g. modes = 6".into()),
                );
                None
            }
            Some(e) => match e.item.as_value() {
                Some(Value::Integer(n)) if *n.value() >= 1 => Some(*n.value() as usize),
                Some(Value::Integer(n)) => {
                    self.error(
                        e.span(),
                        "problem.modes",
                        format!("at least one mode, found {}", n.value()),
                        None,
                    );
                    None
                }
                _ => {
                    self.type_error(&e, "an integer");
                    None
                }
            },
        };
        if let Some((k, _)) = root.get_key_value("boundary") {
            self.error(
                k.span(),
                "boundary",
                "a cavity's walls are perfect conductors (tangential E = 0 on the whole boundary): it takes no [[boundary]] conditions",
                Some("remove the [[boundary]] tables".into()),
            );
        }
        if let Some((span, name)) = self.refused_factorization(root, &["ldlt", "lblt", "lu"]) {
            self.error(
                span,
                "solver.factorization",
                format!("the cavity's shift-invert uses LLᵀ of the positive definite K − σM; \"{name}\" is not used"),
                Some("remove solver.factorization".into()),
            );
        }
        Some(Problem::Maxwell(MaxwellSpec {
            dual: dual?,
            mass: mass?,
            modes: modes?,
        }))
    }

    /// A list of constant numbers or constant expressions (`exact.eigenvalues`).
    pub(super) fn constant_list(
        &mut self,
        entry: &super::Entry,
        scope: &Scope,
    ) -> Option<Vec<f64>> {
        let Some(array) = entry.item.as_array() else {
            self.type_error(entry, "an array of numbers or constant expressions");
            return None;
        };
        let mut values = Vec::with_capacity(array.len());
        let mut ok = true;
        for (i, v) in array.iter().enumerate() {
            let name = format!("{}[{i}]", entry.name);
            let item = Item::Value(v.clone());
            match self.expression_of(&item, &name, v.span(), scope) {
                Some(e) if e.is_constant() => {
                    let x = e.eval(&[], 0.0);
                    if x.is_finite() {
                        values.push(x);
                    } else {
                        self.error(v.span(), &name, format!("not finite: {x}"), None);
                        ok = false;
                    }
                }
                Some(_) => {
                    self.error(
                        v.span(),
                        &name,
                        "an eigenvalue is a number: it may not depend on x, y, z or t",
                        None,
                    );
                    ok = false;
                }
                None => ok = false,
            }
        }
        if ok && values.windows(2).any(|w| w[1] < w[0]) {
            self.error(
                entry.span(),
                &entry.name,
                "eigenvalues must be given in ascending order (they are compared with the computed ones in order)",
                None,
            );
            ok = false;
        }
        ok.then_some(values)
    }
}

const PLANES: &[&str] = &["strain", "stress"];
const ELASTIC_TYPES: &[&str] = &["displacement", "traction"];

impl Reader {
    /// An array of expressions (vectors: body forces, displacements).
    pub(super) fn expression_list(
        &mut self,
        entry: &super::Entry,
        scope: &Scope,
    ) -> Option<Vec<crate::frontend::case::expr::Expression>> {
        let Some(array) = entry.item.as_array().filter(|a| (1..=3).contains(&a.len())) else {
            self.type_error(entry, "an array of 1 to 3 expressions (x, y, z components)");
            return None;
        };
        let mut parts = Vec::with_capacity(array.len());
        for (i, v) in array.iter().enumerate() {
            let item = Item::Value(v.clone());
            parts.push(self.expression_of(&item, &format!("{}[{i}]", entry.name), v.span(), scope));
        }
        parts.into_iter().collect()
    }

    pub(super) fn elasticity(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let present = |key: &str| table.get(key).is_some();
        let material = match (
            present("lambda") || present("mu"),
            present("young") || present("poisson"),
        ) {
            (true, true) => {
                self.error(
                    header.clone(),
                    "problem.young",
                    "give the material either by lambda and mu or by young and poisson, not both",
                    None,
                );
                None
            }
            (false, false) => {
                self.error(
                    header.clone(),
                    "problem.young",
                    "missing: the material",
                    Some("give young = E and poisson = ν, or lambda and mu".into()),
                );
                None
            }
            (true, false) => {
                let lambda = self.required_expression(table, "lambda", header.clone(), scope);
                let mu = self.required_expression(table, "mu", header.clone(), scope);
                Some(MaterialSpec::Lame {
                    lambda: lambda?,
                    mu: mu?,
                })
            }
            (false, true) => {
                let young = self.required_expression(table, "young", header.clone(), scope);
                let poisson = self.required_expression(table, "poisson", header.clone(), scope);
                Some(MaterialSpec::Young {
                    young: young?,
                    poisson: poisson?,
                })
            }
        };
        let body_force = match self.entry(table, "problem", "body_force") {
            Some(e) => self.expression_list(&e, scope),
            None => scope.parse("0").ok().map(|z| vec![z.clone(), z.clone(), z]),
        };
        let plane = match self
            .choice(table, "plane", PLANES, "plane model", None, Some("strain"))
            .as_deref()
        {
            Some("stress") => Some(PlaneModel::Stress),
            Some(_) => Some(PlaneModel::Strain),
            None => None,
        };
        let boundary = self.elastic_boundary(root, scope);
        Some(Problem::Elasticity(ElasticitySpec {
            material: material?,
            body_force: body_force?,
            plane: plane?,
            boundary,
        }))
    }

    fn required_expression(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<crate::frontend::case::expr::Expression> {
        match self.entry(table, "problem", key) {
            Some(_) => self.expression_at(table, "problem", key, scope),
            None => {
                self.error(header, &join("problem", key), "missing", None);
                None
            }
        }
    }

    fn elastic_boundary(
        &mut self,
        root: &dyn TableLike,
        scope: &Scope,
    ) -> Vec<ElasticBoundarySpec> {
        let mut out = Vec::new();
        let Some(entry) = self.entry(root, "", "boundary") else {
            return out;
        };
        let Some(array) = entry.item.as_array_of_tables() else {
            self.error(
                entry.span(),
                "boundary",
                "expected [[boundary]] tables",
                None,
            );
            return out;
        };
        for (i, table) in array.iter().enumerate() {
            let prefix = format!("boundary[{i}]");
            self.check_keys(table, &prefix, super::BOUNDARY_KEYS);
            let header = table.span();
            if let Some(e) = self.entry(table, &prefix, "alpha") {
                self.error(
                    e.key_span.clone(),
                    &e.name,
                    "an elasticity boundary takes no alpha",
                    None,
                );
            }
            let tag_span = self.entry(table, &prefix, "tag").and_then(|e| e.span());
            let tag = match self.entry(table, &prefix, "tag") {
                Some(_) => self.string_at(table, &prefix, "tag"),
                None => {
                    self.error(
                        header.clone(),
                        &format!("{prefix}.tag"),
                        "missing: the boundary region's tag",
                        None,
                    );
                    None
                }
            };
            let kind = match self.entry(table, &prefix, "type") {
                None => {
                    self.error(
                        header.clone(),
                        &format!("{prefix}.type"),
                        "missing: displacement or traction",
                        None,
                    );
                    None
                }
                Some(e) => match e.item.as_str() {
                    Some(s) if ELASTIC_TYPES.contains(&s) => Some(s.to_string()),
                    Some(other) => {
                        self.error(
                            e.span(),
                            &e.name,
                            format!("unknown boundary type \"{other}\""),
                            Some("an elasticity boundary is \"displacement\" (u = value, or one `component` of it) or \"traction\" (σn = value); untagged faces are traction-free".into()),
                        );
                        None
                    }
                    None => {
                        self.type_error(&e, "a string");
                        None
                    }
                },
            };
            let component = match self.entry(table, &prefix, "component") {
                None => None,
                Some(e) => match e.item.as_integer() {
                    Some(c @ 0..=2) if kind.as_deref() == Some("displacement") => Some(c as usize),
                    Some(0..=2) => {
                        self.error(
                            e.key_span.clone(),
                            &e.name,
                            "only a displacement condition fixes one component",
                            None,
                        );
                        None
                    }
                    _ => {
                        self.error(
                            e.span(),
                            &e.name,
                            "a component index 0 (x), 1 (y) or 2 (z)",
                            None,
                        );
                        None
                    }
                },
            };
            let value = match self.entry(table, &prefix, "value") {
                None => {
                    self.error(
                        header.clone(),
                        &format!("{prefix}.value"),
                        "missing: the boundary value",
                        Some("a vector [gx, gy(, gz)], or one expression with `component`".into()),
                    );
                    None
                }
                Some(e) if component.is_some() => self
                    .expression_of(e.item, &e.name, e.span(), scope)
                    .map(|v| vec![v]),
                Some(e) => self.expression_list(&e, scope),
            };
            let kind = match (kind.as_deref(), value) {
                (Some("displacement"), Some(value)) => {
                    Some(ElasticBoundaryKind::Displacement { component, value })
                }
                (Some("traction"), Some(value)) => Some(ElasticBoundaryKind::Traction(value)),
                _ => None,
            };
            if let (Some(tag), Some(kind)) = (tag, kind) {
                out.push(ElasticBoundarySpec {
                    tag,
                    kind,
                    tag_span,
                    key: prefix,
                });
            }
        }
        out
    }
}

const FIELD_KEYS: &[&str] = &[
    "name",
    "method",
    "conductivity",
    "source",
    "exact",
    "boundary",
];

impl Reader {
    pub(super) fn coupled(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let coefficient = |reader: &mut Self, key: &str| match reader.entry(table, "problem", key) {
            Some(_) => reader.expression_at(table, "problem", key, scope),
            None => {
                reader.error(
                    header.clone(),
                    &join("problem", key),
                    format!("missing: the reaction coefficient {key}"),
                    Some("−∇·(D₁∇u) + a u − b v = f, −∇·(D₂∇v) − b u + c v = g".into()),
                );
                None
            }
        };
        let (a, b, c) = (
            coefficient(self, "a"),
            coefficient(self, "b"),
            coefficient(self, "c"),
        );
        for key in ["boundary", "exact"] {
            if let Some((k, _)) = root.get_key_value(key) {
                self.error(
                    k.span(),
                    key,
                    format!("a coupled problem gives `{key}` per field"),
                    Some(format!(
                        "move it into the [[field]] tables ([[field.{key}]] or `exact = ...`)"
                    )),
                );
            }
        }
        let fields = self.fields(root, scope);
        let [first, second]: [CoupledFieldSpec; 2] = fields?.try_into().ok()?;
        Some(Problem::Coupled(Box::new(CoupledSpec {
            fields: [first, second],
            a: a?,
            b: b?,
            c: c?,
        })))
    }

    /// The two `[[field]]` tables of a coupled problem.
    fn fields(&mut self, root: &dyn TableLike, scope: &Scope) -> Option<Vec<CoupledFieldSpec>> {
        let Some(entry) = self.entry(root, "", "field") else {
            self.error(
                None,
                "field",
                "missing: a coupled problem has two [[field]] tables",
                Some("each with name, method, conductivity, source and [[field.boundary]]".into()),
            );
            return None;
        };
        let Some(array) = entry.item.as_array_of_tables() else {
            self.type_error(&entry, "[[field]] tables");
            return None;
        };
        if array.len() != 2 {
            self.error(
                entry.key_span.clone(),
                "field",
                format!(
                    "a coupled problem has exactly two fields, found {}",
                    array.len()
                ),
                None,
            );
            return None;
        }
        let mut out = Vec::new();
        let mut ok = true;
        for (i, table) in array.iter().enumerate() {
            let prefix = format!("field[{i}]");
            self.check_keys(table, &prefix, FIELD_KEYS);
            let header = table.span();
            let name = match self.entry(table, &prefix, "name") {
                Some(_) => self.string_at(table, &prefix, "name"),
                None => {
                    self.error(
                        header.clone(),
                        &join(&prefix, "name"),
                        "missing: the field's name (used for its output)",
                        None,
                    );
                    None
                }
            };
            if let Some(n) = &name {
                let clash = out.iter().any(|f: &CoupledFieldSpec| &f.name == n);
                if clash || n.is_empty() || !n.chars().all(|ch| ch.is_alphanumeric() || ch == '_') {
                    let span = self.entry(table, &prefix, "name").and_then(|e| e.span());
                    self.error(span, &join(&prefix, "name"), format!("field name \"{n}\" must be a non-empty word (letters, digits, _) and differ from the other field's"), None);
                    ok = false;
                }
            }
            let method = self.method_in(table, &prefix, header.clone());
            if method == Some(Method::FvMimetic) {
                let span = self.entry(table, &prefix, "method").and_then(|e| e.span());
                self.error(
                    span,
                    &join(&prefix, "method"),
                    "fv-mimetic has half-face unknowns, which the reaction terms do not act on",
                    Some("use fe, fv, fd, dec or dec-barycentric".into()),
                );
                ok = false;
            }
            let conductivity = self.coefficient_in(table, &prefix, "conductivity", scope);
            let source = match self.entry(table, &prefix, "source") {
                Some(_) => self.expression_at(table, &prefix, "source", scope),
                None => scope.parse("0").ok(),
            };
            let exact = match self.entry(table, &prefix, "exact") {
                Some(_) => self.expression_at(table, &prefix, "exact", scope).map(Some),
                None => Some(None),
            };
            let boundary = self.boundary_in(table, &prefix, scope, Conditions::Steady);
            match (name, method, conductivity, source, exact) {
                (Some(name), Some(method), Some(conductivity), Some(source), Some(exact)) => out
                    .push(CoupledFieldSpec {
                        name,
                        diffusion: crate::frontend::case::DiffusionSpec {
                            method,
                            conductivity,
                            source,
                            boundary,
                            circumcentres: false,
                        },
                        exact,
                    }),
                _ => ok = false,
            }
        }
        ok.then_some(out)
    }
}
