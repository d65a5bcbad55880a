//! The problem kinds beyond steady diffusion and gradients: which `problem`
//! keys each kind takes, and reading transient heat (with its `[time]`
//! table), mixed Darcy and Maxwell cavity problems.

use super::{join, Reader, KIND_KEYS};
use crate::frontend::case::expr::{closest, Scope};
use crate::frontend::case::{Coefficient, DarcySpec, HeatSpec, MaxwellSpec, Problem};
use crate::metric::fv::FluxMass;
use crate::metric::Method;
use crate::physics::maxwell::Mass;
use hasse_complex::DualKind;
use std::ops::Range;
use toml_edit::{Item, TableLike, Value};

/// The kind a case's `problem.kind` names (default diffusion), read
/// directly from the document so other tables can depend on it.
pub(in crate::frontend::case) fn problem_kind(root: &dyn TableLike) -> &str {
    root.get("problem")
        .and_then(Item::as_table_like)
        .and_then(|p| p.get("kind"))
        .and_then(Item::as_str)
        .unwrap_or("diffusion")
}

/// The degree of a Poisson problem for k-forms: an integer
/// `problem.degree` other than 0 in a diffusion case, read directly from
/// the document (degree 0 is ordinary diffusion; a negative one is then
/// refused by the forms' reader, which asks for k ≥ 1).
pub(in crate::frontend::case) fn form_degree(root: &dyn TableLike) -> Option<i64> {
    if problem_kind(root) != "diffusion" {
        return None;
    }
    root.get("problem")
        .and_then(Item::as_table_like)
        .and_then(|p| p.get("degree"))
        .and_then(Item::as_integer)
        .filter(|&k| k != 0)
}

/// The `problem` keys of a Poisson problem for k-forms.
const FORM_DIFFUSION_KEYS: &[&str] = &["method", "degree", "boundary", "source", "stars"];

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
        let Some((_, kind_keys)) = KIND_KEYS.iter().find(|(k, _)| *k == kind) else {
            // An unknown kind is reported by the caller.
            return;
        };
        let forms = form_degree(root);
        let keys: &[&str] = if forms.is_some() {
            FORM_DIFFUSION_KEYS
        } else {
            kind_keys
        };
        let shown = match forms {
            Some(k) => format!("kind = \"{kind}\" with degree = {k} (Δ_{k} u = f for {k}-forms)"),
            None => format!("kind = \"{kind}\""),
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
            let mut users = users.join(", ");
            if forms.is_none() && FORM_DIFFUSION_KEYS.contains(&key) {
                users.push_str(", diffusion of k-forms (degree ≥ 1)");
            }
            self.error(
                span,
                &join("problem", key),
                format!("not used by {shown} (only by {users})"),
                Some(format!("this problem takes: {}", keys.join(", "))),
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
        if kind != "growth" {
            if let Some((k, _)) = root.get_key_value("growth") {
                self.error(
                    k.span(),
                    "growth",
                    format!("[growth] is for kind = \"growth\"; this problem is {kind}"),
                    Some("remove [growth], or set problem.kind = \"growth\"".into()),
                );
            }
        }
        if !["heat", "transport", "growth"].contains(&kind) {
            if let Some((k, _)) = root.get_key_value("time") {
                self.error(
                    k.span(),
                    "time",
                    format!(
                        "[time] is for kind = \"heat\", \"transport\" or \"growth\"; this problem is {kind}"
                    ),
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
        // k and r may use u (which makes the problem nonlinear: Newton in
        // every step); k(u, x) must then be one differentiable scalar.
        let (conductivity, reaction) = self.conductivity_and_reaction(table, scope);
        let nonlinear = reaction.as_ref().is_some_and(Option::is_some)
            || match &conductivity {
                Some(Coefficient::Scalar(e)) => e.uses_solution(),
                _ => false,
            };
        let span_of = |key: &str| table.get_key_value(key).and_then(|(_, i)| i.span());
        if conductivity.as_ref().is_some_and(Coefficient::uses_time) {
            // As for a Robin α: K enters the matrix, which is assembled
            // and factorised once; evaluating it at t = 0 would freeze it
            // silently (even when time.start ≠ 0). The nonlinear run
            // evaluates k(u, x) and r(u, x) without t.
            let message = if nonlinear {
                "a nonlinear heat problem evaluates k(u, x) and r(u, x) without t: the conductivity may not depend on t"
            } else {
                "the conductivity enters the matrix, which is assembled and factorised once: it may not depend on t"
            };
            self.error(
                span_of("conductivity"),
                "problem.conductivity",
                message,
                Some("the source and the boundary values may depend on t; the conductivity may vary with x, y and z".into()),
            );
        }
        if reaction
            .as_ref()
            .and_then(Option::as_ref)
            .is_some_and(|r| r.uses_time())
        {
            self.error(
                span_of("reaction"),
                "problem.reaction",
                "a nonlinear heat problem evaluates r(u, x) without t: the reaction may not depend on t",
                Some("put the part that depends on t in the source".into()),
            );
        }
        let source = match self.entry(table, "problem", "source") {
            Some(_) => self.expression_or_regions_at(table, "problem", "source", scope),
            None => scope.parse("0").ok(),
        };
        let mut restart = None;
        let initial = match self.entry(table, "problem", "initial") {
            Some(e) if e.item.is_table_like() => {
                restart = self.restart(&e);
                restart.as_ref()?;
                scope.parse("0").ok()
            }
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
        if nonlinear {
            self.check_nonlinear_heat(
                root,
                table,
                conductivity.as_ref(),
                &boundary,
                source.as_ref(),
                restart.is_some(),
            );
        }
        Some(Problem::Heat(HeatSpec {
            method: method?,
            conductivity: conductivity?,
            reaction: reaction?,
            source: source?,
            initial: initial?,
            boundary,
            time: time?,
            restart,
        }))
    }

    /// What a nonlinear heat case (k with u, or a reaction) cannot combine
    /// with, found from the input alone: Robin conditions, a source per
    /// region, a restart, adaptive steps, solvers other than the direct
    /// LU of Newton's steps, quantities and probes.
    fn check_nonlinear_heat(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        conductivity: Option<&Coefficient>,
        boundary: &[crate::frontend::case::BoundarySpec],
        source: Option<&crate::frontend::case::expr::Expression>,
        restart: bool,
    ) {
        let span_of =
            |t: &dyn TableLike, key: &str| t.get_key_value(key).and_then(|(_, i)| i.span());
        let message = match conductivity {
            Some(Coefficient::Tensor(_)) => Some("a nonlinear problem takes a scalar conductivity"),
            Some(Coefficient::Scalar(k)) if k.regions().is_some() => {
                Some("values per region are not supported in a nonlinear problem")
            }
            _ => None,
        };
        if let Some(message) = message {
            self.error(
                span_of(table, "conductivity"),
                "problem.conductivity",
                message,
                Some("write k(u, x) as one expression (if(…) selects by position)".into()),
            );
        }
        for b in boundary {
            if matches!(
                b.kind,
                crate::frontend::case::BoundaryKindSpec::Robin { .. }
            ) {
                self.error(
                    b.tag_span.clone(),
                    &format!("{}.type", b.key),
                    "Robin conditions are not supported with a u-dependent conductivity or a reaction",
                    Some("use dirichlet or neumann".into()),
                );
            }
        }
        if source.is_some_and(|f| f.regions().is_some()) {
            self.error(
                span_of(table, "source"),
                "problem.source",
                "values per region are not supported in a nonlinear problem",
                Some("write one expression (if(…) selects by position)".into()),
            );
        }
        if restart {
            self.error(
                span_of(table, "initial"),
                "problem.initial",
                "a nonlinear heat run cannot restart from a saved level",
                Some("give the initial temperature as an expression".into()),
            );
        }
        let time = root.get("time").and_then(Item::as_table_like);
        if let Some(adaptive) = time.and_then(|t| t.get_key_value("adaptive")) {
            self.error(
                adaptive.0.span(),
                "time.adaptive",
                "a nonlinear heat run takes constant steps: adaptive step sizes are not available for it",
                Some("remove time.adaptive and choose time.dt".into()),
            );
        }
        self.refuse_nonlinear_solver_and_output(root);
    }

    /// `problem.initial = { from = "run.h5", level = "last" | k }`.
    fn restart(&mut self, entry: &super::Entry) -> Option<crate::frontend::case::RestartSpec> {
        let table = entry.item.as_table_like()?;
        self.check_keys(table, "problem.initial", &["from", "level"]);
        let Some(from) = self.string_at(table, "problem.initial", "from") else {
            self.error(
                entry.span(),
                "problem.initial.from",
                "missing: the HDF5 output of the run to restart from",
                Some("initial = { from = \"run.h5\", level = \"last\" }".into()),
            );
            return None;
        };
        let level = match self.entry(table, "problem.initial", "level") {
            None => None,
            Some(e) => match (e.item.as_str(), e.item.as_integer()) {
                (Some("last"), _) => None,
                (_, Some(k)) if k >= 0 => Some(k as usize),
                _ => {
                    self.error(
                        e.span(),
                        "problem.initial.level",
                        "a saved level: \"last\" or its number k ≥ 0 (/steps/<k> of the file)",
                        None,
                    );
                    return None;
                }
            },
        };
        let base = std::path::Path::new(&self.file)
            .parent()
            .unwrap_or(std::path::Path::new("."));
        Some(crate::frontend::case::RestartSpec {
            from: base.join(from),
            level,
        })
    }

    /// A string key of `problem` chosen from `choices`.
    /// The value of `problem.<key>` among `values`, read by the names
    /// `name` gives them (the enum's own names: one mapping from names to
    /// values); `default` when the key is absent, or an error naming the
    /// choices.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn choice<T: Copy>(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        values: &[T],
        name: impl Fn(&T) -> &'static str,
        what: &str,
        header: Option<Range<usize>>,
        default: Option<T>,
    ) -> Option<T> {
        self.choice_in(table, "problem", key, values, name, what, header, default)
    }

    /// [`choice`](Self::choice) for the key `<prefix>.<key>` of any table
    /// (e.g. `output.complex`).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn choice_in<T: Copy>(
        &mut self,
        table: &dyn TableLike,
        prefix: &str,
        key: &str,
        values: &[T],
        name: impl Fn(&T) -> &'static str,
        what: &str,
        header: Option<Range<usize>>,
        default: Option<T>,
    ) -> Option<T> {
        let names: Vec<&str> = values.iter().map(&name).collect();
        let entry_name = join(prefix, key);
        let Some(entry) = self.entry(table, prefix, key) else {
            if default.is_none() {
                self.error(
                    header,
                    &entry_name,
                    format!("missing: the {what}"),
                    Some(format!("one of {}", names.join(", "))),
                );
            }
            return default;
        };
        match entry.item.as_str() {
            Some(s) => match values.iter().find(|v| name(v) == s) {
                Some(&value) => Some(value),
                None => {
                    let owned: Vec<String> = names.iter().map(|s| s.to_string()).collect();
                    let help = match closest(s, &owned) {
                        Some(c) => format!("did you mean \"{c}\"? choices: {}", names.join(", ")),
                        None => format!("choices: {}", names.join(", ")),
                    };
                    self.error(
                        entry.span(),
                        &entry_name,
                        format!("unknown {what} \"{s}\""),
                        Some(help),
                    );
                    None
                }
            },
            None => {
                self.type_error(&entry, "a string");
                None
            }
        }
    }

    /// `solver.factorization` if it is one of `refused`, with its span.
    pub(super) fn refused_factorization(
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
        let mass = self.choice(
            table,
            "method",
            &FluxMass::ALL,
            FluxMass::name,
            "flux mass method",
            header,
            None,
        );
        let permeability = self.coefficient(table, "permeability", scope);
        let source = match self.entry(table, "problem", "source") {
            Some(_) => self.expression_or_regions_at(table, "problem", "source", scope),
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
        // The dual of the Hodge stars, named as the DEC methods are.
        let duals = [DualKind::Circumcentric, DualKind::Barycentric];
        let dual = self.choice(
            table,
            "method",
            &duals,
            |&kind| Method::Dec(kind).name(),
            "Hodge star (dual)",
            header.clone(),
            None,
        );
        let mass = self.choice(
            table,
            "mass",
            &Mass::ALL,
            Mass::name,
            "edge mass",
            None,
            Some(Mass::Hodge),
        );
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
