//! The `[problem]` table of kind = "hodge-laplacian": eigenpairs of Δ_k.

use super::*;
use crate::frontend::case::{HodgeSpec, Problem};
use std::ops::Range;
use toml_edit::TableLike;

impl Reader {
    /// A nonnegative integer key of `[problem]` (`degree`, `modes`) with
    /// its span; `minimum` is its least value.
    pub(super) fn count(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        minimum: i64,
        header: Option<Range<usize>>,
        help: &str,
    ) -> Option<(usize, Option<Range<usize>>)> {
        let Some(e) = self.entry(table, "problem", key) else {
            self.error(
                header,
                &format!("problem.{key}"),
                "missing",
                Some(help.into()),
            );
            return None;
        };
        match e.item.as_value() {
            Some(Value::Integer(n)) if *n.value() >= minimum => {
                Some((*n.value() as usize, e.span()))
            }
            Some(Value::Integer(n)) => {
                self.error(
                    e.span(),
                    &format!("problem.{key}"),
                    format!("at least {minimum}, found {}", n.value()),
                    Some(help.into()),
                );
                None
            }
            _ => {
                self.type_error(&e, "an integer");
                None
            }
        }
    }

    pub(super) fn hodge(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
    ) -> Option<Problem> {
        let (method, method_span, stars) = self.star_method(table, header.clone());
        let boundary = self.form_boundary(table);
        let degree = self.count(
            table,
            "degree",
            0,
            header.clone(),
            "the degree k of the forms, 0 ≤ k ≤ the mesh's dimension (0: functions)",
        );
        let modes = self.count(
            table,
            "modes",
            1,
            header,
            "how many nonzero eigenvalues to compute, e.g. modes = 6",
        );
        if let Some((k, _)) = root.get_key_value("boundary") {
            self.error(
                k.span(),
                "boundary",
                "Δ_k takes its boundary condition from problem.boundary (\"natural\" or \"essential\"), not from [[boundary]] tables",
                Some("remove the [[boundary]] tables".into()),
            );
        }
        if let Some((span, name)) = self.refused_factorization(root, &["ldlt", "lblt", "lu", "llt"])
        {
            self.error(
                span,
                "solver.factorization",
                format!("the eigensolver chooses its own factorisation of K − σM; \"{name}\" is not used"),
                Some("remove solver.factorization".into()),
            );
        }
        let (degree, degree_span) = degree?;
        Some(Problem::Hodge(HodgeSpec {
            method: method?,
            method_span,
            stars: stars?,
            boundary: boundary?,
            degree,
            degree_span,
            modes: modes?.0,
        }))
    }
}
