//! Physics: each problem is a block of canonical operators plus its data.
//!
//! The types every problem shares live here: functions of position that
//! carry coefficients, sources and boundary data, the kinds of scalar
//! boundary conditions, and the lookup of the boundary faces a tag names.

pub mod coupled;
pub mod darcy;
pub mod diffusion;
pub mod elasticity;
pub mod gradient;
pub mod heat;
pub mod maxwell;

use crate::metric::Tensor;
use hasse_complex::Complex;
use std::sync::Arc;

/// A scalar function of position.
pub type ScalarFn = Arc<dyn Fn(&[f64]) -> f64 + Send + Sync>;

/// A tensor-valued function of position.
pub type TensorFn = Arc<dyn Fn(&[f64]) -> Tensor + Send + Sync>;

/// A vector-valued function of position (gradients of exact solutions).
pub type VectorFn = Arc<dyn Fn(&[f64]) -> [f64; 3] + Send + Sync>;

/// The diffusion coefficient K.
#[derive(Clone)]
pub enum Conductivity {
    /// K = λ(x) I.
    Scalar(ScalarFn),
    /// A symmetric positive definite tensor field.
    Tensor(TensorFn),
}

/// A boundary condition's kind and data.
#[derive(Clone)]
pub enum BoundaryKind {
    /// u = g.
    Dirichlet(ScalarFn),
    /// K∇u·n = g (n outward).
    Neumann(ScalarFn),
    /// K∇u·n + α u = g, α > 0.
    Robin { alpha: ScalarFn, value: ScalarFn },
}

/// A condition on the boundary faces carrying a tag.
#[derive(Clone)]
pub struct BoundaryCondition {
    pub tag: String,
    pub kind: BoundaryKind,
}

/// Which input of a problem a value came from, so that an error about
/// the value can point back to where the input gave it (a front end maps
/// a datum to its key in a case file).
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
        condition: usize,
        kind: &'static str,
    },
    /// The Robin α of boundary condition `condition`.
    RobinAlpha { condition: usize },
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
    #[error("boundary condition on tag '{tag}': no such tag in the mesh (tags: {available})")]
    UnknownTag { tag: String, available: String },
    #[error("boundary condition on tag '{tag}': it tags {dim}-cells, but boundary conditions need (n−1)-cells (n = {n})")]
    TagDimension { tag: String, dim: usize, n: usize },
    #[error("boundary condition on tag '{tag}': face {face} is not on the boundary")]
    InteriorFace { tag: String, face: usize },
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
