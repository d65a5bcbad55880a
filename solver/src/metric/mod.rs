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
//! Coefficients arrive as one symmetric tensor per top cell, already
//! evaluated by the problem layer: [`CellTensors`], either one full tensor
//! per cell or one scalar λ per cell (K = λ·I, stored as 8 bytes a cell
//! instead of 72).
//!
//! [`BlockMetric`]: crate::operator::BlockMetric

mod coefficient;
pub mod dec;
pub mod fd;
pub mod fe;
pub mod fv;
pub mod mass;
mod method;

pub use coefficient::{check_tensors, isotropic, CellTensors, Tensor};
pub use method::{Location, Method, UnknownMethod};

use hasse_complex::ComplexError;

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
    /// The source (right-hand side) evaluated to NaN or ±∞ where a load
    /// needs it.
    #[error("the source is {value} at {point:?} (in top cell {cell})")]
    NonFiniteSource {
        cell: usize,
        point: Vec<f64>,
        value: f64,
    },
    #[error("{count} coefficients given for {cells} top cells")]
    CoefficientCount { count: usize, cells: usize },
    #[error(transparent)]
    Geometry(#[from] ComplexError),
}
