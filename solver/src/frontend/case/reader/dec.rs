//! The `[problem]` tables of kind = "cohomology", kind =
//! "hodge-decomposition" and kind = "diffusion" with `degree` ≥ 1 (the
//! Poisson problem for k-forms).

use super::*;
use crate::frontend::case::expr::Scope;
use crate::frontend::case::{
    CohomologySpec, DecompositionSpec, FormDiffusionSpec, HodgeMethod, Problem,
};
use crate::physics::forms::Boundary;
use std::ops::Range;
use std::path::PathBuf;
use toml_edit::TableLike;

impl Reader {
    /// `problem.method` of a DEC kind, with its span and the star files of
    /// `method = "supplied"` (`problem.stars`).
    pub(super) fn star_method(
        &mut self,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
    ) -> (
        Option<HodgeMethod>,
        Option<Range<usize>>,
        Option<Vec<PathBuf>>,
    ) {
        let span = self
            .entry(table, "problem", "method")
            .and_then(|e| e.span());
        let method = self.choice(
            table,
            "method",
            &HodgeMethod::ALL,
            HodgeMethod::name,
            "Hodge star",
            header.clone(),
            None,
        );
        let stars = self.star_files(table, method, header);
        (method, span, stars)
    }

    /// `problem.boundary` of a DEC kind: natural (default) or essential.
    pub(super) fn form_boundary(&mut self, table: &dyn TableLike) -> Option<Boundary> {
        self.choice(
            table,
            "boundary",
            &[Boundary::Natural, Boundary::Essential],
            Boundary::name,
            "boundary condition",
            None,
            Some(Boundary::Natural),
        )
    }

    /// `problem.stars`: with `method = "supplied"`, one existing file per
    /// degree (relative to the case file); refused with any other method.
    fn star_files(
        &mut self,
        table: &dyn TableLike,
        method: Option<HodgeMethod>,
        header: Option<Range<usize>>,
    ) -> Option<Vec<PathBuf>> {
        let entry = self.entry(table, "problem", "stars");
        let help = "e.g. stars = [\"star0.txt\", \"star1.txt\", \"star2.txt\"]: for degree k one value per k-cell in hasse's cell order (whitespace-separated, `#` starts a comment), paths relative to the case file";
        match (method, entry) {
            (Some(HodgeMethod::Supplied), None) => {
                self.error(
                    header,
                    "problem.stars",
                    "missing: method = \"supplied\" reads the diagonal Hodge stars from files, one per degree 0 to n",
                    Some(help.into()),
                );
                None
            }
            (Some(HodgeMethod::Supplied), Some(e)) => {
                let Some(array) = e.item.as_array() else {
                    self.type_error(&e, "an array of file names, one per degree");
                    return None;
                };
                let mut files = Vec::new();
                for value in array.iter() {
                    let Some(name) = value.as_str() else {
                        self.error(
                            value.span(),
                            "problem.stars",
                            "a file name (a string)",
                            Some(help.into()),
                        );
                        return None;
                    };
                    let path = self.relative(name);
                    if !path.is_file() {
                        self.error(
                            value.span(),
                            "problem.stars",
                            format!("no such file: {}", path.display()),
                            Some("paths are relative to the case file".into()),
                        );
                        return None;
                    }
                    files.push(path);
                }
                Some(files)
            }
            (_, Some(e)) => {
                self.error(
                    e.key_span.clone(),
                    "problem.stars",
                    "star files are read only with method = \"supplied\"",
                    Some("remove problem.stars, or set method = \"supplied\"".into()),
                );
                None
            }
            (_, None) => Some(Vec::new()),
        }
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
        let (method, method_span, stars) = self.star_method(table, header.clone());
        let degree = self.count(
            table,
            "degree",
            0,
            header,
            "the degree k of the harmonic forms, 0 to the mesh's dimension (absolute or, with boundary = \"essential\", relative)",
        );
        let boundary = self.form_boundary(table);
        self.refuse_boundary_tables(root, "cohomology");
        let (degree, degree_span) = degree?;
        Some(Problem::Cohomology(CohomologySpec {
            method: method?,
            method_span,
            stars: stars?,
            degree,
            degree_span,
            boundary: boundary?,
        }))
    }

    /// A k-form given by its proxy field (`key` of `[problem]`): an array
    /// of expressions, one per coordinate, or one expression.
    fn proxy_field(
        &mut self,
        table: &dyn TableLike,
        key: &str,
        header: Option<Range<usize>>,
        what: &str,
        scope: &Scope,
    ) -> Option<Vec<Expression>> {
        match self.entry(table, "problem", key) {
            Some(e) if e.item.as_array().is_some() => self.expression_list(&e, scope),
            Some(e) => self
                .expression_of(e.item, &format!("problem.{key}"), e.span(), scope)
                .map(|f| vec![f]),
            None => {
                self.error(
                    header,
                    &format!("problem.{key}"),
                    format!("missing: {what}"),
                    Some(format!("e.g. {key} = [\"-y\", \"x\"] (one expression per coordinate; one expression for degree 0 or the top degree)")),
                );
                None
            }
        }
    }

    pub(super) fn decomposition(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let (method, method_span, stars) = self.star_method(table, header.clone());
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
        let cochain = match self.entry(table, "problem", "cochain") {
            None => Some(None),
            Some(e) => match e.item.as_str() {
                Some(name) => {
                    let path = self.relative(name);
                    if path.is_file() {
                        Some(Some(path))
                    } else {
                        self.error(
                            e.span(),
                            "problem.cochain",
                            format!("no such file: {}", path.display()),
                            Some("paths are relative to the case file".into()),
                        );
                        None
                    }
                }
                None => {
                    self.type_error(&e, "a file name");
                    None
                }
            },
        };
        let field = match (&cochain, self.entry(table, "problem", "field")) {
            (Some(Some(_)), Some(e)) => {
                self.error(
                    e.key_span.clone(),
                    "problem.field",
                    "give ω either as a field (its de Rham cochain) or as a cochain file, not both",
                    Some("remove problem.field or problem.cochain".into()),
                );
                None
            }
            (Some(Some(_)), None) => Some(Vec::new()),
            _ => self.proxy_field(
                table,
                "field",
                header,
                "the field whose de Rham cochain is ω (line integrals along the edges for degree 1), or `cochain = \"omega.txt\"`, a file of its values",
                scope,
            ),
        };
        self.refuse_boundary_tables(root, "hodge-decomposition");
        let (degree, degree_span) = degree?;
        Some(Problem::Decomposition(DecompositionSpec {
            method: method?,
            method_span,
            stars: stars?,
            degree,
            degree_span,
            field: field?,
            cochain: cochain?,
        }))
    }

    pub(super) fn form_diffusion(
        &mut self,
        root: &dyn TableLike,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        scope: &Scope,
    ) -> Option<Problem> {
        let (method, method_span, stars) = self.star_method(table, header.clone());
        let degree = self.count(
            table,
            "degree",
            1,
            header.clone(),
            "the degree k of the unknown form, 1 to the mesh's dimension",
        );
        let boundary = self.form_boundary(table);
        let source = self.proxy_field(
            table,
            "source",
            header,
            "the source f of Δ_k u = f as a field (a vector field for 1-forms, and for 2-forms in 3D; a scalar for the top degree)",
            scope,
        );
        if let Some((k, _)) = root.get_key_value("boundary") {
            self.error(
                k.span(),
                "boundary",
                "the Poisson problem for k-forms takes its one condition from problem.boundary (natural: absolute, u·n = 0 and rot u = 0 for 1-forms in 2D; essential: relative, u × n = 0 and div u = 0), not from [[boundary]] tables",
                Some("remove the [[boundary]] tables; set boundary = \"essential\" under [problem] for relative conditions".into()),
            );
        }
        let (degree, degree_span) = degree?;
        Some(Problem::FormDiffusion(FormDiffusionSpec {
            method: method?,
            method_span,
            stars: stars?,
            degree,
            degree_span,
            boundary: boundary?,
            source: source?,
        }))
    }
}
