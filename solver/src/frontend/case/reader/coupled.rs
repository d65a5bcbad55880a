//! The `[problem]` table of kind = "coupled" and its two `[[field]]` tables.

use super::kinds::Conditions;
use super::*;
use crate::frontend::case::expr::Scope;
use crate::frontend::case::{CoupledFieldSpec, CoupledSpec, Problem};
use crate::metric::Method;
use std::ops::Range;
use toml_edit::TableLike;

pub(super) const FIELD_KEYS: &[&str] = &[
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
            Some(_) => reader.expression_or_regions_at(table, "problem", key, scope),
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
    pub(super) fn fields(
        &mut self,
        root: &dyn TableLike,
        scope: &Scope,
    ) -> Option<Vec<CoupledFieldSpec>> {
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
                Some(_) => self.expression_or_regions_at(table, &prefix, "source", scope),
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
                            // Not read: the coupled block solve does not
                            // project Neumann data.
                            neumann_tolerance: 1e-2,
                            reaction: None,
                        },
                        exact,
                    }),
                _ => ok = false,
            }
        }
        ok.then_some(out)
    }
}
