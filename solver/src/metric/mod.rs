//! The metrics Ω, one module per method. Each builds a [`BlockMetric`]
//! over the rows of a topological incidence matrix A:
//!
//! | method | unknowns | A | rows of Ω |
//! |---|---|---|---|
//! | FE (P1, Q1, VEM) | vertices | δ⁰ = ∂₁ᵀ | edges |
//! | DEC | vertices | δ⁰ = ∂₁ᵀ | edges |
//! | FV two-point | top cells | ∂ₙ | (n−1)-cells |
//! | FD five/seven-point | top cells | ∂ₙ | (n−1)-cells |
//! | FV mimetic (hybrid) | top cells and (n−1)-cells | half-face incidence | half-faces |
//!
//! Coefficients arrive as one symmetric tensor per top cell (a scalar λ is
//! λ·I), already evaluated by the problem layer.
//!
//! [`BlockMetric`]: crate::canonical::BlockMetric

pub mod dec;
pub mod fd;
pub mod fe;
pub mod fv;

use hasse_complex::ComplexError;
use rayon::prelude::*;

/// A symmetric tensor; the leading d×d block is used in R^d.
pub type Tensor = [[f64; 3]; 3];

/// λ·I as a tensor.
pub fn isotropic(lambda: f64) -> Tensor {
    [[lambda, 0.0, 0.0], [0.0, lambda, 0.0], [0.0, 0.0, lambda]]
}

/// Why a metric could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricError {
    #[error("{method} needs {needs}; top cell {cell} is not one")]
    UnsupportedCell {
        method: &'static str,
        needs: &'static str,
        cell: usize,
    },
    #[error("{method} needs {needs}: {detail}")]
    UnsupportedMesh {
        method: &'static str,
        needs: &'static str,
        detail: String,
    },
    #[error("coefficient in top cell {cell} is not symmetric positive definite (eigenvalue estimate {value:e}); diffusion coefficients must be > 0")]
    NotPositive { cell: usize, value: f64 },
    #[error("coefficient in top cell {cell} is not finite")]
    NonFinite { cell: usize },
    #[error("{count} coefficients given for {cells} top cells")]
    CoefficientCount { count: usize, cells: usize },
    #[error(transparent)]
    Geometry(#[from] ComplexError),
}

/// Check one tensor per top cell, symmetric positive definite in R^d.
pub fn check_tensors(tensors: &[Tensor], cells: usize, d: usize) -> Result<(), MetricError> {
    if tensors.len() != cells {
        return Err(MetricError::CoefficientCount {
            count: tensors.len(),
            cells,
        });
    }
    // In parallel; the first bad cell in cell order is the one reported.
    match tensors
        .par_iter()
        .enumerate()
        .find_map_first(|(cell, t)| tensor_problem(t, cell, d))
    {
        Some(problem) => Err(problem),
        None => Ok(()),
    }
}

/// Why tensor `t` of `cell` is not symmetric positive definite in R^d, if
/// it is not.
fn tensor_problem(t: &Tensor, cell: usize, d: usize) -> Option<MetricError> {
    if t.iter().flatten().any(|v| !v.is_finite()) {
        return Some(MetricError::NonFinite { cell });
    }
    // Leading principal minors > 0 (Sylvester) on the symmetric part,
    // scaled to unit size first: the minors of a valid K = 1e-200·I
    // would otherwise underflow to zero.
    let scale = t[..d]
        .iter()
        .flat_map(|row| row[..d].iter())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let m = |i: usize, j: usize| 0.5 * (t[i][j] + t[j][i]) / scale;
    let minors = [
        m(0, 0),
        m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0),
        m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
            - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
            + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0)),
    ];
    minors[..d]
        .iter()
        .find(|&&v| v <= 0.0)
        .map(|&bad| MetricError::NotPositive {
            cell,
            value: bad * scale,
        })
}
