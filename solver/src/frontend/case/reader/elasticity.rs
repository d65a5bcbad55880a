//! The [problem] table of kind = "elasticity" and its boundary conditions.

use super::*;
use crate::frontend::case::expr::Scope;
use crate::frontend::case::{
    ElasticBoundaryKind, ElasticBoundarySpec, ElasticitySpec, MaterialSpec, Problem,
};
use crate::physics::elasticity::PlaneModel;
use std::ops::Range;
use toml_edit::{Item, TableLike};

pub(super) const ELASTIC_TYPES: &[&str] = &["displacement", "traction"];

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
        let plane = self.choice(
            table,
            "plane",
            &PlaneModel::ALL,
            PlaneModel::name,
            "plane model",
            None,
            Some(PlaneModel::Strain),
        );
        let boundary = self.elastic_boundary(root, scope);
        Some(Problem::Elasticity(ElasticitySpec {
            material: material?,
            body_force: body_force?,
            plane: plane?,
            boundary,
        }))
    }

    pub(super) fn required_expression(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<crate::frontend::case::expr::Expression> {
        match self.entry(table, "problem", key) {
            Some(_) => self.expression_or_regions_at(table, "problem", key, scope),
            None => {
                self.error(header, &join("problem", key), "missing", None);
                None
            }
        }
    }

    pub(super) fn elastic_boundary(
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
