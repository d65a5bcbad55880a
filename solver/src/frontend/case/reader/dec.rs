//! The `[problem]` tables of kind = "cohomology" and kind =
//! "hodge-decomposition".

use super::*;
use crate::frontend::case::expr::Scope;
use crate::frontend::case::{CohomologySpec, DecompositionSpec, HodgeMethod, Problem};
use crate::physics::forms::Boundary;
use std::ops::Range;
use toml_edit::TableLike;

impl Reader {
    /// `problem.method` of a DEC kind, with its span.
    fn star_method(
        &mut self,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
    ) -> (Option<HodgeMethod>, Option<Range<usize>>) {
        let span = self
            .entry(table, "problem", "method")
            .and_then(|e| e.span());
        let method = self.choice(
            table,
            "method",
            &HodgeMethod::ALL,
            HodgeMethod::name,
            "Hodge star",
            header,
            None,
        );
        (method, span)
    }

    /// Refuse `[[boundary]]` tables (these kinds constrain no tagged
    /// boundary: cohomology takes its one condition from
    /// `problem.boundary`) and `[exact]` (nothing is compared with it).
    fn refuse_boundary_tables(&mut self, root: &dyn TableLike, kind: &str) {
        if let Some((k, _)) = root.get_key_value("exact") {
            self.error(
                k.span(),
                "exact",
                format!("kind = \"{kind}\" compares with no exact solution: its checks (closedness, co-closedness, orthogonality) need none"),
                Some("remove the [exact] table".into()),
            );
        }
        if let Some((k, _)) = root.get_key_value("boundary") {
            self.error(
                k.span(),
                "boundary",
                if kind == "cohomology" {
                    "kind = \"cohomology\" takes no [[boundary]] tables: its one condition holds on the whole boundary and is `problem.boundary` (natural: absolute, nothing constrained; essential: relative, the forms vanish on the boundary)".to_string()
                } else {
                    format!("kind = \"{kind}\" takes no boundary conditions (absolute conditions: no cochain is constrained)")
                },
                Some(if kind == "cohomology" {
                    "remove the [[boundary]] tables; for relative classes set boundary = \"essential\" under [problem]".into()
                } else {
                    "remove the [[boundary]] tables".into()
                }),
            );
        }
    }

    pub(super) fn cohomology(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
    ) -> Option<Problem> {
        let (method, method_span) = self.star_method(table, header.clone());
        let degree = self.count(
            table,
            "degree",
            0,
            header,
            "the degree k of the harmonic forms, 0 to the mesh's dimension (absolute or, with boundary = \"essential\", relative)",
        );
        let boundary = self.choice(
            table,
            "boundary",
            &[Boundary::Natural, Boundary::Essential],
            Boundary::name,
            "boundary condition",
            None,
            Some(Boundary::Natural),
        );
        self.refuse_boundary_tables(root, "cohomology");
        let (degree, degree_span) = degree?;
        Some(Problem::Cohomology(CohomologySpec {
            method: method?,
            method_span,
            degree,
            degree_span,
            boundary: boundary?,
        }))
    }

    pub(super) fn decomposition(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let (method, method_span) = self.star_method(table, header.clone());
        // Every star is accepted: a diagonal one has its coexact part
        // eliminated, the Whitney mass is solved in mixed form.
        let degree = if table.get("degree").is_some() {
            self.count(
                table,
                "degree",
                0,
                header.clone(),
                "the degree k of the cochain, 0 to the mesh's dimension",
            )
        } else {
            Some((1, None))
        };
        let field = match self.entry(table, "problem", "field") {
            Some(e) if e.item.as_array().is_some() => self.expression_list(&e, scope),
            Some(e) => self
                .expression_of(e.item, "problem.field", e.span(), scope)
                .map(|f| vec![f]),
            None => {
                self.error(
                    header,
                    "problem.field",
                    "missing: the field whose de Rham cochain is ω (line integrals along the edges for degree 1)",
                    Some("e.g. field = [\"-y\", \"x\"] (one expression per coordinate; one expression for degree 0 or the top degree)".into()),
                );
                None
            }
        };
        self.refuse_boundary_tables(root, "hodge-decomposition");
        let (degree, degree_span) = degree?;
        Some(Problem::Decomposition(DecompositionSpec {
            method: method?,
            method_span,
            degree,
            degree_span,
            field: field?,
        }))
    }
}
