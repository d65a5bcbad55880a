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
