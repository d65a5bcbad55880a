//! The specification of a `kind = "hodge-laplacian"` case.

use std::ops::Range;

/// The Hodge star of a `kind = "hodge-laplacian"` case (`problem.method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HodgeMethod {
    /// `dec`: the diagonal circumcentric star (simplices).
    Dec,
    /// `dec-barycentric`: the diagonal barycentric star (any convex cells).
    DecBarycentric,
    /// `whitney`: the Whitney (Galerkin) mass, the mixed block form
    /// (simplices).
    Whitney,
    /// `supplied`: diagonal stars read from files, one per degree
    /// (`problem.stars`), any cells.
    Supplied,
}

impl HodgeMethod {
    /// Every method, in the order help texts list them.
    pub const ALL: [HodgeMethod; 4] = [
        HodgeMethod::Dec,
        HodgeMethod::DecBarycentric,
        HodgeMethod::Whitney,
        HodgeMethod::Supplied,
    ];

    /// The name case files use.
    pub fn name(&self) -> &'static str {
        match self {
            HodgeMethod::Dec => "dec",
            HodgeMethod::DecBarycentric => "dec-barycentric",
            HodgeMethod::Whitney => "whitney",
            HodgeMethod::Supplied => "supplied",
        }
    }

    /// The star of the forms layer.
    pub fn star(&self) -> crate::physics::forms::Star {
        use crate::physics::forms::Star;
        match self {
            HodgeMethod::Dec => Star::Diagonal(hasse_complex::DualKind::Circumcentric),
            HodgeMethod::DecBarycentric => Star::Diagonal(hasse_complex::DualKind::Barycentric),
            HodgeMethod::Whitney => Star::Whitney,
            HodgeMethod::Supplied => Star::Supplied,
        }
    }
}

/// Eigenpairs of the Hodge Laplacian Δ_k on k-cochains
/// (`kind = "hodge-laplacian"`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, HodgeMethod, Problem};
/// use hasse_solver::physics::forms::Boundary;
/// let text = r#"
/// [mesh]
/// generator = "sphere"
/// subdivisions = 2
/// [problem]
/// kind = "hodge-laplacian"
/// method = "dec"
/// degree = 1
/// modes = 4
/// "#;
/// let case = Case::from_text("hodge.toml", text, &[]).unwrap();
/// let Problem::Hodge(spec) = &case.problem else { panic!() };
/// assert_eq!((spec.method, spec.degree, spec.modes, spec.boundary), (HodgeMethod::Dec, 1, 4, Boundary::Natural));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct HodgeSpec {
    /// The star (`problem.method`).
    pub method: HodgeMethod,
    /// Where `problem.method` is written.
    pub method_span: Option<Range<usize>>,
    /// The star files of `method = "supplied"` (`problem.stars`), one per
    /// degree 0 … n, relative to the working directory; empty otherwise.
    pub stars: Vec<std::path::PathBuf>,
    /// `problem.boundary`: natural (absolute, default) or essential
    /// (relative).
    pub boundary: crate::physics::forms::Boundary,
    /// The degree k (`problem.degree`).
    pub degree: usize,
    /// Where `problem.degree` is written, for the check against the mesh.
    pub degree_span: Option<Range<usize>>,
    /// How many nonzero eigenvalues to compute (`problem.modes`).
    pub modes: usize,
}
