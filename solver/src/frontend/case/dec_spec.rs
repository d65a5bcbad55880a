//! The specifications of the DEC kinds built on the k-form layer besides
//! the Hodge Laplacian: `kind = "cohomology"`,
//! `kind = "hodge-decomposition"` and the Poisson problem for k-forms
//! (`kind = "diffusion"` with `degree` ≥ 1).

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
    /// The star files of `method = "supplied"` (`problem.stars`), one per
    /// degree 0 … n; empty otherwise.
    pub stars: Vec<std::path::PathBuf>,
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
    /// The star files of `method = "supplied"` (`problem.stars`), one per
    /// degree 0 … n; empty otherwise.
    pub stars: Vec<std::path::PathBuf>,
    /// The degree k (`problem.degree`, default 1).
    pub degree: usize,
    /// Where `problem.degree` is written, for the check against the mesh.
    pub degree_span: Option<Range<usize>>,
    /// The field F (`problem.field`): one expression per coordinate for a
    /// vector proxy, one expression for a scalar one; ω = R_k F, its de
    /// Rham cochain. Empty when ω is read from `cochain`.
    pub field: Vec<Expression>,
    /// `problem.cochain`: a file holding ω itself, one value per k-cell
    /// in hasse's cell order (instead of `field`).
    pub cochain: Option<std::path::PathBuf>,
}

/// The Poisson problem for k-forms, Δ_k u = f with Δ_k = dδ + δd
/// (`kind = "diffusion"` with `degree` ≥ 1): the source and the exact
/// solution are fields given like [`DecompositionSpec::field`] (a vector
/// field for 1-forms and for 2-forms in 3D, a scalar for the top degree),
/// their de Rham cochains the data.
///
/// ```
/// use hasse_solver::frontend::case::{Case, HodgeMethod, Problem};
/// use hasse_solver::physics::forms::Boundary;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [8, 8]
/// [problem]
/// kind = "diffusion"
/// degree = 1
/// method = "dec-barycentric"
/// boundary = "essential"
/// source = ["2*pi^2*sin(pi*y)", "0"]
/// [exact]
/// solution = ["sin(pi*y)", "0"]
/// "#;
/// let case = Case::from_text("forms.toml", text, &[]).unwrap();
/// let Problem::FormDiffusion(spec) = &case.problem else { panic!() };
/// assert_eq!((spec.degree, spec.method, spec.boundary), (1, HodgeMethod::DecBarycentric, Boundary::Essential));
/// assert_eq!(case.exact.unwrap().form.unwrap().len(), 2);
/// ```
#[derive(Clone, Debug)]
pub struct FormDiffusionSpec {
    /// The star (`problem.method`).
    pub method: HodgeMethod,
    /// Where `problem.method` is written.
    pub method_span: Option<Range<usize>>,
    /// The star files of `method = "supplied"` (`problem.stars`), one per
    /// degree 0 … n; empty otherwise.
    pub stars: Vec<std::path::PathBuf>,
    /// The degree k ≥ 1 (`problem.degree`).
    pub degree: usize,
    /// Where `problem.degree` is written, for the check against the mesh.
    pub degree_span: Option<Range<usize>>,
    /// `problem.boundary`: natural (absolute, default) or essential
    /// (relative: u and δu have zero tangential trace).
    pub boundary: crate::physics::forms::Boundary,
    /// The source f (`problem.source`), one expression per coordinate for
    /// a vector proxy, one for a scalar one.
    pub source: Vec<Expression>,
}
