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

#![warn(missing_docs)]

mod coefficient;
pub mod dec;
pub mod fd;
pub mod fe;
pub mod fv;
pub mod mass;
mod method;
pub mod whitney;

pub use coefficient::{check_tensors, isotropic, CellTensors, Tensor};
pub use method::{Location, Method, UnknownMethod};

use hasse_complex::ComplexError;

/// Why a metric could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricError {
    /// A top cell has a shape the method has no formula for (e.g. a
    /// polygon for circumcentric DEC, a folded quadrilateral for Q1).
    #[error("{method} needs {needs}; top cell {cell} is not one")]
    UnsupportedCell {
        /// The method, as the user would name it.
        method: &'static str,
        /// The kind of cell it needs.
        needs: &'static str,
        /// The first top cell that is not one.
        cell: usize,
    },
    /// The mesh as a whole does not fit the method (e.g. five-point
    /// differences on a grid that is not axis-aligned).
    #[error("{method} needs {needs}: {detail}")]
    UnsupportedMesh {
        /// The method, as the user would name it.
        method: &'static str,
        /// What it needs of the mesh.
        needs: &'static str,
        /// Where the mesh fails it.
        detail: String,
    },
    /// A coefficient is not symmetric positive definite in R^d, so the
    /// diffusion problem is not well posed there.
    #[error("coefficient in top cell {cell} is not symmetric positive definite (eigenvalue estimate {value:e}); diffusion coefficients must be > 0")]
    NotPositive {
        /// The first such top cell.
        cell: usize,
        /// The first leading principal minor of the symmetric part that is
        /// ≤ 0, brought to the units of K (λ itself for K = λ·I): about the
        /// smallest eigenvalue when the others are of the tensor's size.
        value: f64,
    },
    /// A coefficient holds NaN or ±∞.
    #[error("coefficient in top cell {cell} is not finite")]
    NonFinite {
        /// The first such top cell.
        cell: usize,
    },
    /// The source (right-hand side) evaluated to NaN or ±∞ where a load
    /// needs it.
    #[error("the source is {value} at {point:?} (in top cell {cell})")]
    NonFiniteSource {
        /// The top cell whose load needed the value.
        cell: usize,
        /// Where the source was evaluated.
        point: Vec<f64>,
        /// What it gave.
        value: f64,
    },
    /// The coefficients are not one per top cell.
    #[error("{count} coefficients given for {cells} top cells")]
    CoefficientCount {
        /// Coefficients given.
        count: usize,
        /// Top cells of the complex.
        cells: usize,
    },
    /// The complex could not give a boundary matrix, measure or dual the
    /// method needs.
    #[error(transparent)]
    Geometry(#[from] ComplexError),
}
