//! The specification of a `kind = "elasticity"` case: the material, the
//! body force and the displacement and traction conditions.

use super::expr::Expression;
use std::ops::Range;

/// The material of an elasticity problem (see [`ElasticitySpec`] for a
/// case).
///
/// ```
/// use hasse_solver::frontend::case::{Case, MaterialSpec, Problem};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "elasticity"
/// young = "200 + x"
/// poisson = 0.3
/// "#;
/// let case = Case::from_text("e.toml", text, &[]).unwrap();
/// let Problem::Elasticity(spec) = &case.problem else { panic!() };
/// let MaterialSpec::Young { young, poisson } = &spec.material else { panic!() };
/// assert_eq!((young.eval(&[1.0, 0.0], 0.0), poisson.text()), (201.0, "0.3"));
/// ```
#[derive(Clone, Debug)]
pub enum MaterialSpec {
    /// `lambda` and `mu`.
    Lame {
        /// λ.
        lambda: Expression,
        /// μ, the shear modulus.
        mu: Expression,
    },
    /// `young` and `poisson`.
    Young {
        /// Young's modulus E.
        young: Expression,
        /// Poisson's ratio ν.
        poisson: Expression,
    },
}

/// A boundary condition of an elasticity problem (see [`ElasticitySpec`]
/// for a case).
///
/// ```
/// use hasse_solver::frontend::case::{Case, ElasticBoundaryKind, Problem};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "elasticity"
/// lambda = 1
/// mu = 1
/// [[boundary]]
/// tag = "ymin"
/// type = "displacement"
/// component = 1
/// value = 0
/// "#;
/// let case = Case::from_text("e.toml", text, &[]).unwrap();
/// let Problem::Elasticity(spec) = &case.problem else { panic!() };
/// let ElasticBoundaryKind::Displacement { component, value } = &spec.boundary[0].kind else { panic!() };
/// assert_eq!((*component, value.len()), (Some(1), 1));
/// ```
#[derive(Clone, Debug)]
pub enum ElasticBoundaryKind {
    /// u = g (all components), or u_a = g for one component a
    /// (`type = "displacement"`).
    Displacement {
        /// `component`: a ∈ {0, 1, 2}, or `None` for every component.
        component: Option<usize>,
        /// `value`: d expressions, or one with a component.
        value: Vec<Expression>,
    },
    /// σ n = t, n outward (`type = "traction"`), one expression per
    /// coordinate.
    Traction(Vec<Expression>),
}

/// A tagged elasticity boundary condition: one `[[boundary]]` table of an
/// elasticity case (see [`ElasticitySpec`] for one).
#[derive(Clone, Debug)]
pub struct ElasticBoundarySpec {
    /// Tag of (n−1)-cells in the mesh.
    pub tag: String,
    /// The condition.
    pub kind: ElasticBoundaryKind,
    pub(crate) tag_span: Option<Range<usize>>,
    pub(crate) key: String,
}

/// Linear elasticity −∇·σ(u) = f, displacement on vertices
/// (`kind = "elasticity"`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, ElasticBoundaryKind, Problem};
/// use hasse_solver::physics::elasticity::PlaneModel;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// kind = "elasticity"
/// lambda = 1
/// mu = 1
/// plane = "stress"
/// body_force = [0, -1]
/// [[boundary]]
/// tag = "xmin"
/// type = "displacement"
/// value = [0, 0]
/// [[boundary]]
/// tag = "xmax"
/// type = "traction"
/// value = [1, 0]
/// "#;
/// let case = Case::from_text("e.toml", text, &[]).unwrap();
/// let Problem::Elasticity(spec) = &case.problem else { panic!() };
/// assert_eq!(spec.plane, PlaneModel::Stress);
/// assert_eq!(spec.body_force[1].eval(&[0.5, 0.5], 0.0), -1.0);
/// assert_eq!((spec.boundary[0].tag.as_str(), spec.boundary.len()), ("xmin", 2));
/// assert!(matches!(spec.boundary[1].kind, ElasticBoundaryKind::Traction(_)));
/// ```
#[derive(Clone, Debug)]
pub struct ElasticitySpec {
    /// λ and μ, or E and ν (`problem.lambda`, `mu` or `young`, `poisson`).
    pub material: MaterialSpec,
    /// f, one expression per coordinate.
    pub body_force: Vec<Expression>,
    /// `problem.plane` (2D only; default plane strain).
    pub plane: crate::physics::elasticity::PlaneModel,
    /// The `[[boundary]]` tables, in order; untagged faces are
    /// traction-free.
    pub boundary: Vec<ElasticBoundarySpec>,
}
