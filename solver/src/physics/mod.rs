//! Physics: each problem is a block of canonical operators plus its data.
//!
//! The types every problem shares live here: functions of position that
//! carry coefficients, sources and boundary data, the kinds of scalar
//! boundary conditions, and the lookup of the boundary faces a tag names.

pub mod coupled;
pub mod darcy;
pub mod diffusion;
pub mod elasticity;
pub mod forms;
pub mod gradient;
pub mod heat;
pub mod maxwell;
pub mod nonlinear;
pub mod probe;
pub mod regions;
pub mod transport;

use crate::metric::Tensor;
use hasse_complex::Complex;
use std::sync::Arc;

/// A scalar function of position.
pub type ScalarFn = Arc<dyn Fn(&[f64]) -> f64 + Send + Sync>;

/// A tensor-valued function of position.
pub type TensorFn = Arc<dyn Fn(&[f64]) -> Tensor + Send + Sync>;

/// A vector-valued function of position (gradients of exact solutions).
pub type VectorFn = Arc<dyn Fn(&[f64]) -> [f64; 3] + Send + Sync>;

/// The diffusion coefficient K, a function of position evaluated once per
/// top cell (at its centroid).
///
/// A scalar λ stands for λI and is stored as one number a cell; a tensor
/// must be symmetric positive definite in its leading d×d block (checked
/// when a problem is assembled).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// // An anisotropic, rotated K with f = 0: every linear u solves
/// // ∇·(K∇u) = 0, and Q1 elements reproduce it exactly.
/// let k = Conductivity::Tensor(Arc::new(|_| [[2.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 1.0]]));
/// let u = |x: &[f64]| 1.0 + x[0] - 2.0 * x[1];
/// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let solution = Diffusion::new(Method::Fe, k, Arc::new(|_| 0.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(u)))
///     .solve(&mesh)
///     .unwrap();
/// for v in 0..mesh.cell_count(0) {
///     assert!((solution.values[v] - u(mesh.vertices().point(v))).abs() < 1e-12);
/// }
/// ```
#[derive(Clone)]
pub enum Conductivity {
    /// K = λ(x) I.
    Scalar(ScalarFn),
    /// A symmetric positive definite tensor field.
    Tensor(TensorFn),
    /// A conductivity per region of top cells ([`regions`]): each cell's
    /// is its region's, evaluated at the cell's centroid.
    Regional(Arc<regions::Regional<Conductivity>>),
}

/// A boundary condition's kind and data, functions of the position on the
/// boundary.
///
/// The normal n points out of the domain, so a Neumann value g > 0 is
/// heat flowing *into* the domain: K∇u·n = g means −K∇u·n, the outward
/// flux, is −g.
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// // −(2u′)′ = 0 on [0, 1], u(0) = 0. With K u′·n = g at x = 1 (n = +1),
/// // u = g x / K; with K u′·n + α u = g instead, u = g x / (K + α).
/// let mesh = interval(8, 0.0, 1.0).unwrap();
/// let problem = |right: BoundaryKind| {
///     Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 2.0)), Arc::new(|_| 0.0))
///         .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///         .with_boundary("xmax", right)
///         .solve(&mesh)
///         .unwrap()
/// };
/// let neumann = problem(BoundaryKind::Neumann(Arc::new(|_| 3.0)));
/// let robin = problem(BoundaryKind::Robin { alpha: Arc::new(|_| 1.0), value: Arc::new(|_| 3.0) });
/// for v in 0..mesh.cell_count(0) {
///     let x = mesh.vertices().point(v)[0];
///     assert!((neumann.values[v] - 1.5 * x).abs() < 1e-12);
///     assert!((robin.values[v] - x).abs() < 1e-12);
/// }
/// ```
#[derive(Clone)]
pub enum BoundaryKind {
    /// u = g.
    Dirichlet(ScalarFn),
    /// K∇u·n = g (n outward).
    Neumann(ScalarFn),
    /// K∇u·n + α u = g, α > 0: a heat-transfer (or leaky) boundary towards
    /// an exterior at u = g/α; α → ∞ approaches Dirichlet, α → 0 Neumann.
    Robin {
        /// The transfer coefficient α, positive everywhere on the faces.
        alpha: ScalarFn,
        /// g, the right-hand side of the condition.
        value: ScalarFn,
    },
}

/// A condition on the boundary faces carrying a tag.
///
/// A problem applies its conditions in order, so a later condition on a
/// face replaces an earlier one: a condition on `"boundary"` followed by
/// one on a side changes only that side.
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::{BoundaryCondition, BoundaryKind, Conductivity};
/// use std::sync::Arc;
/// let mesh = interval(4, 0.0, 1.0).unwrap();
/// let mut problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 0.0));
/// problem.boundary = vec![
///     BoundaryCondition { tag: "boundary".into(), kind: BoundaryKind::Dirichlet(Arc::new(|_| 1.0)) },
///     BoundaryCondition { tag: "xmax".into(), kind: BoundaryKind::Dirichlet(Arc::new(|_| 0.0)) },
/// ];
/// // u(0) = 1 from the first condition, u(1) = 0 from the second: u = 1 − x.
/// let u = problem.solve(&mesh).unwrap().values;
/// for v in 0..5 {
///     assert!((u[v] - (1.0 - mesh.vertices().point(v)[0])).abs() < 1e-12);
/// }
/// ```
#[derive(Clone)]
pub struct BoundaryCondition {
    /// The tag of the mesh naming the faces: (n−1)-cells on the boundary.
    pub tag: String,
    /// The condition and its data.
    pub kind: BoundaryKind,
}

/// Which input of a problem a value came from, so that an error about
/// the value can point back to where the input gave it (a front end maps
/// a datum to its key in a case file).
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::{Diffusion, DiffusionError};
/// use hasse_solver::physics::{BoundaryKind, Conductivity, Datum};
/// use std::sync::Arc;
/// let mesh = interval(4, 0.0, 1.0).unwrap();
/// let problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 0.0))
///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
///     .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| f64::NAN)));
/// let Err(DiffusionError::NonFinite { datum, .. }) = problem.solve(&mesh) else { panic!() };
/// assert_eq!(datum, Datum::BoundaryValue { condition: 1, kind: "Dirichlet" });
/// assert_eq!(datum.to_string(), "the Dirichlet value of boundary condition 1");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Datum {
    /// The source f.
    Source,
    /// The coefficient K (conductivity, permeability).
    Coefficient,
    /// The initial value of a transient problem.
    Initial,
    /// The value of boundary condition `condition` (its index among the
    /// problem's conditions, in the order they were given), of `kind`
    /// Dirichlet, Neumann or Robin.
    BoundaryValue {
        /// Index of the condition among the problem's conditions.
        condition: usize,
        /// `"Dirichlet"`, `"Neumann"` or `"Robin"`.
        kind: &'static str,
    },
    /// The Robin α of boundary condition `condition`.
    RobinAlpha {
        /// Index of the condition among the problem's conditions.
        condition: usize,
    },
    /// A named parameter: a material constant (λ, μ, E, ν) or a reaction
    /// coefficient (a, b, c).
    Parameter(&'static str),
    /// The body force of elasticity.
    BodyForce,
}

impl std::fmt::Display for Datum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Datum::Source => f.write_str("the source"),
            Datum::Coefficient => f.write_str("the coefficient K"),
            Datum::Initial => f.write_str("the initial value"),
            Datum::BoundaryValue { condition, kind } => {
                write!(f, "the {kind} value of boundary condition {condition}")
            }
            Datum::RobinAlpha { condition } => {
                write!(f, "the Robin α of boundary condition {condition}")
            }
            Datum::Parameter(name) => write!(f, "the parameter {name}"),
            Datum::BodyForce => f.write_str("the body force"),
        }
    }
}

/// A point written as `(x, y, z)` with its coordinates' shortest
/// round-trip digits, for messages.
///
/// ```
/// use hasse_solver::physics::point_text;
/// assert_eq!(point_text(&[0.375, 0.125]), "(0.375, 0.125)");
/// ```
pub fn point_text(x: &[f64]) -> String {
    let coordinates: Vec<String> = x.iter().map(|v| format!("{v}")).collect();
    format!("({})", coordinates.join(", "))
}

/// `value`'s kind of non-finiteness: NaN, ∞ or −∞.
pub(crate) fn non_finite_text(value: f64) -> &'static str {
    if value.is_nan() {
        "NaN"
    } else if value > 0.0 {
        "∞"
    } else {
        "−∞"
    }
}

/// Why the faces of a boundary tag could not be found.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TagError {
    /// The mesh has no tag of this name (a misspelt tag, or a generator
    /// that names its sides otherwise).
    #[error("boundary condition on tag '{tag}': no such tag in the mesh (tags: {available})")]
    UnknownTag {
        /// The tag as the condition names it.
        tag: String,
        /// The mesh's tags, comma-separated, or `none`.
        available: String,
    },
    /// The tag names cells of another dimension than the faces (e.g. a
    /// region of top cells, or edges of a 3D mesh).
    #[error("boundary condition on tag '{tag}': it tags {dim}-cells, but boundary conditions need (n−1)-cells (n = {n})")]
    TagDimension {
        /// The tag.
        tag: String,
        /// Dimension of the cells it tags.
        dim: usize,
        /// Dimension of the complex.
        n: usize,
    },
    /// The tag includes a face inside the domain (on two top cells), where
    /// a boundary condition means nothing.
    #[error("boundary condition on tag '{tag}': face {face} is not on the boundary")]
    InteriorFace {
        /// The tag.
        tag: String,
        /// The first interior (n−1)-cell it names.
        face: usize,
    },
}

/// (face, k) for every (n−1)-cell a tag names, in face order, with k the
/// index of the last such tag (in `tags` order), so later conditions
/// override earlier ones. Only boundary faces appear, so the list is short
/// next to the face count. Errors: a tag missing from the mesh, a tag of
/// cells of another dimension, a tagged interior face.
pub(crate) fn tagged_boundary_faces<'a>(
    complex: &Complex,
    tags: impl Iterator<Item = &'a str>,
) -> Result<Vec<(usize, usize)>, TagError> {
    let n = complex.dim();
    let top = complex.boundary(n);
    let mut condition: Vec<(usize, usize)> = Vec::new();
    for (k, name) in tags.enumerate() {
        let tag = complex.tag(name).ok_or_else(|| TagError::UnknownTag {
            tag: name.to_string(),
            available: {
                let names: Vec<&str> = complex.tags().names().collect();
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                }
            },
        })?;
        if tag.dim != n - 1 {
            return Err(TagError::TagDimension {
                tag: name.to_string(),
                dim: tag.dim,
                n,
            });
        }
        for &f in &tag.cells {
            if top.outer_view(f).map_or(0, |r| r.nnz()) != 1 {
                return Err(TagError::InteriorFace {
                    tag: name.to_string(),
                    face: f,
                });
            }
            condition.push((f, k));
        }
    }
    // Stable: a face's entries stay in tag order, and the last one wins.
    condition.sort_by_key(|&(f, _)| f);
    let mut last: Vec<(usize, usize)> = Vec::with_capacity(condition.len());
    for (f, k) in condition {
        match last.last_mut() {
            Some(previous) if previous.0 == f => previous.1 = k,
            _ => last.push((f, k)),
        }
    }
    Ok(last)
}
