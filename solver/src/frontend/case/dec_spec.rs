//! The specifications of the DEC kinds built on the k-form layer besides
//! the Hodge Laplacian: `kind = "cohomology"` and
//! `kind = "hodge-decomposition"`.

use super::expr::Expression;
use super::HodgeMethod;
use std::ops::Range;

/// A basis of harmonic k-forms from cohomology generators
/// (`kind = "cohomology"`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, HodgeMethod, Problem};
/// let text = r#"
/// [mesh]
/// generator = "torus"
/// n = [16, 8]
/// major_radius = 2.0
/// minor_radius = 0.7
/// [problem]
/// kind = "cohomology"
/// method = "dec-barycentric"
/// degree = 1
/// "#;
/// let case = Case::from_text("cohomology.toml", text, &[]).unwrap();
/// let Problem::Cohomology(spec) = &case.problem else { panic!() };
/// assert_eq!((spec.method, spec.degree), (HodgeMethod::DecBarycentric, 1));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CohomologySpec {
    /// The star (`problem.method`).
    pub method: HodgeMethod,
    /// Where `problem.method` is written.
    pub method_span: Option<Range<usize>>,
    /// The degree k (`problem.degree`).
    pub degree: usize,
    /// Where `problem.degree` is written, for the check against the mesh.
    pub degree_span: Option<Range<usize>>,
    /// `problem.boundary`: natural (absolute, default) or essential
    /// (relative: the forms vanish on the boundary; degree 1 on
    /// 2-dimensional meshes).
    pub boundary: crate::physics::forms::Boundary,
}

/// The Hodge decomposition of a k-cochain given as a field
/// (`kind = "hodge-decomposition"`): a vector field for k = 1 (line
/// integrals along the edges) and for k = 2 on 3-dimensional meshes
/// (fluxes through the faces), a scalar one for k = 0 (vertex values) and
/// k = n (integrals over the top cells).
///
/// ```
/// use hasse_solver::frontend::case::{Case, Problem};
/// let text = r#"
/// [mesh]
/// generator = "sphere"
/// subdivisions = 2
/// [problem]
/// kind = "hodge-decomposition"
/// method = "dec"
/// field = ["-y", "x", "x*z"]
/// "#;
/// let case = Case::from_text("split.toml", text, &[]).unwrap();
/// let Problem::Decomposition(spec) = &case.problem else { panic!() };
/// assert_eq!((spec.field.len(), spec.degree), (3, 1));
/// ```
#[derive(Clone, Debug)]
pub struct DecompositionSpec {
    /// The star (`problem.method`): diagonal (the coexact part eliminated)
    /// or Whitney (the mixed saddle-point solve).
    pub method: HodgeMethod,
    /// Where `problem.method` is written.
    pub method_span: Option<Range<usize>>,
    /// The degree k (`problem.degree`, default 1).
    pub degree: usize,
    /// Where `problem.degree` is written, for the check against the mesh.
    pub degree_span: Option<Range<usize>>,
    /// The field F (`problem.field`): one expression per coordinate for a
    /// vector proxy, one expression for a scalar one; ω = R_k F, its de
    /// Rham cochain.
    pub field: Vec<Expression>,
}
