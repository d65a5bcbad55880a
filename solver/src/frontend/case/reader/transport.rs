//! Reading `kind = "transport"`: advection–diffusion on cell-centred
//! finite volumes or on nodal finite elements (with or without SUPG),
//! steady or with `[time]`.

use super::kinds::Conditions;
use super::{join, Reader};
use crate::frontend::case::expr::Scope;
use crate::frontend::case::{BoundaryKindSpec, Coefficient, Problem, TransportSpec};
use crate::metric::Method;
use crate::physics::transport::nodal::Stabilisation;
use crate::physics::transport::Scheme;
use std::ops::Range;
use toml_edit::TableLike;

/// The spatial schemes by their case-file names.
const SCHEMES: [Scheme; 2] = [Scheme::Upwind, Scheme::Limited];

/// The stabilisations of nodal elements by their case-file names.
const STABILISATIONS: [Stabilisation; 2] = [Stabilisation::Supg, Stabilisation::None];

impl Reader {
    pub(super) fn transport(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let span_of = |key: &str| table.get_key_value(key).and_then(|(_, i)| i.span());
        let method = self.method(table, header.clone());
        if let Some(m) = method.filter(|m| !matches!(m, Method::Fv | Method::Fe)) {
            self.error(
                span_of("method"),
                "problem.method",
                format!(
                    "transport is discretised by cell-centred finite volumes (fv) or nodal finite elements (fe); method \"{}\" is not available",
                    m.name()
                ),
                Some("use method = \"fv\" (two-point diffusion, upwind or limited advection) or \"fe\" (P1/Q1, SUPG)".into()),
            );
        }
        let nodal = method == Some(Method::Fe);
        // SUPG is a nodal-element stabilisation: finite volumes upwind by
        // their face values (`scheme`) instead.
        let stabilisation = match (table.get("stabilisation"), nodal) {
            (Some(_), false) if method.is_some() => {
                self.error(
                    span_of("stabilisation"),
                    "problem.stabilisation",
                    "problem.stabilisation applies to nodal finite elements (method = \"fe\") only; finite volumes choose their face values with problem.scheme",
                    Some("remove stabilisation, or use method = \"fe\"".into()),
                );
                None
            }
            _ => self.choice(
                table,
                "stabilisation",
                &STABILISATIONS,
                Stabilisation::name,
                "stabilisation",
                None,
                Some(Stabilisation::Supg),
            ),
        };
        // The number 0 (or "0") means no diffusion: pure advection.
        let zero = table.get("conductivity").is_some_and(|item| {
            item.as_integer() == Some(0)
                || item.as_float() == Some(0.0)
                || item.as_str().is_some_and(|s| s.trim() == "0")
        });
        let conductivity = if zero {
            Some(None)
        } else {
            self.coefficient(table, "conductivity", scope).map(Some)
        };
        let velocity = match self.entry(table, "problem", "velocity") {
            Some(e) => self.expression_list(&e, scope),
            None => {
                self.error(
                    header.clone(),
                    "problem.velocity",
                    "missing: the advecting velocity, one expression per coordinate",
                    Some("e.g. velocity = [\"1\", \"0\"] or [\"-y\", \"x\"]".into()),
                );
                None
            }
        };
        let source = match self.entry(table, "problem", "source") {
            Some(_) => self.expression_at(table, "problem", "source", scope),
            None => scope.parse("0").ok(),
        };
        let scheme = self.choice(
            table,
            "scheme",
            &SCHEMES,
            Scheme::name,
            "transport scheme",
            None,
            Some(Scheme::Upwind),
        );
        let boundary = self.boundary(root, scope, Conditions::Steady);
        let transient = root.get("time").is_some();
        let time = if transient {
            self.time(root).map(Some)
        } else {
            Some(None)
        };
        let initial = match (self.entry(table, "problem", "initial"), transient) {
            (Some(_), true) => self
                .expression_at(table, "problem", "initial", scope)
                .map(Some),
            (None, true) => {
                self.error(
                    header.clone(),
                    "problem.initial",
                    "missing: u(x, y, z) at t = 0 of the transient run",
                    Some("e.g. initial = \"exp(-100*((x-0.3)^2 + (y-0.5)^2))\"".into()),
                );
                None
            }
            (Some(e), false) => {
                self.error(
                    e.span(),
                    "problem.initial",
                    "an initial value needs a [time] table (without it the problem is steady)",
                    Some("add [time] with dt and steps, or remove initial".into()),
                );
                None
            }
            (None, false) => Some(None),
        };
        if nodal {
            // The nodal path needs a diffusion part; in time it is the
            // θ-scheme of `[time]`, without a `scheme`.
            if zero {
                self.error(
                    span_of("conductivity"),
                    "problem.conductivity",
                    "nodal finite elements (method = \"fe\") need a positive conductivity: the Galerkin/SUPG operator of pure advection is not solved here",
                    Some("give conductivity > 0, or use method = \"fv\" for pure advection".into()),
                );
            }
            if table.get("scheme").is_some() {
                self.error(
                    span_of("scheme"),
                    "problem.scheme",
                    "problem.scheme chooses the face values of finite volumes; nodal elements (method = \"fe\") take problem.stabilisation",
                    Some("remove scheme, or write stabilisation = \"supg\" or \"none\"".into()),
                );
            }
        } else if scheme == Some(Scheme::Limited) && !transient {
            self.error(
                span_of("scheme"),
                "problem.scheme",
                "the limited scheme steps in time (explicitly); a steady problem is solved with upwind face values",
                Some("add [time], or remove scheme".into()),
            );
        }
        // Every datum is evaluated once: none may depend on t.
        let mut timed: Vec<(Option<Range<usize>>, String)> = Vec::new();
        if velocity.iter().flatten().any(|e| e.uses_time()) {
            timed.push((span_of("velocity"), "problem.velocity".into()));
        }
        if source.as_ref().is_some_and(|e| e.uses_time()) {
            timed.push((span_of("source"), "problem.source".into()));
        }
        if matches!(&conductivity, Some(Some(k)) if Coefficient::uses_time(k)) {
            timed.push((span_of("conductivity"), "problem.conductivity".into()));
        }
        for b in &boundary {
            let uses = match &b.kind {
                BoundaryKindSpec::Dirichlet(v) | BoundaryKindSpec::Neumann(v) => v.uses_time(),
                BoundaryKindSpec::Robin { alpha, value } => alpha.uses_time() || value.uses_time(),
            };
            if uses {
                timed.push((b.tag_span.clone(), join(&b.key, "value")));
            }
        }
        for (span, key) in timed {
            self.error(
                span,
                &key,
                "transport data are evaluated once (the operator is assembled and factorised once): it may not depend on t",
                Some("use x, y and z only".into()),
            );
        }
        let method = method.filter(|m| matches!(m, Method::Fv | Method::Fe))?;
        Some(Problem::Transport(TransportSpec {
            method,
            stabilisation: stabilisation?,
            conductivity: conductivity?,
            velocity: velocity?,
            source: source?,
            boundary,
            scheme: scheme?,
            initial: initial?,
            time: time?,
        }))
    }
}
