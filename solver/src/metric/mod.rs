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
//! Non-convex cells (simple polygons, e.g. read from a LAR file): FE takes
//! any, through the virtual element, which is exact on linear fields on
//! any simple polygon (and stable on star-shaped ones). FV (two-point and
//! mimetic) and barycentric DEC place unknowns or half-resistances at cell
//! centroids: they take non-convex cells that are star-shaped about their
//! centroid and refuse the first other one by id ([`require_convex`]).
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

use hasse_complex::{Complex, ComplexError};

/// Refuse a mesh with a top cell that is not star-shaped about its
/// centroid (a non-convex polygon whose centroid lies outside some edge's
/// half-plane) for a method that places unknowns or half-resistances at
/// centroids, naming the first such cell. Convex cells, and non-convex
/// ones seen whole from their centroid (mildly distorted quads), pass.
pub(crate) fn require_convex(complex: &Complex, method: &'static str) -> Result<(), MetricError> {
    if complex.dim() != 2 || complex.embedding_dim() != 2 {
        return Ok(());
    }
    let by_cell = complex.boundary_csc(2);
    let centroids = complex.centroid(2);
    let lar = complex.lar();
    let outside = |cell: usize| {
        let c = &centroids[2 * cell..2 * cell + 2];
        let Some(column) = by_cell.outer_view(cell) else {
            return false;
        };
        let scale = complex.measure(2)[cell];
        column.iter().any(|(e, &r)| {
            let ends = lar.cell_vertices(1, e);
            let (mut a, mut b) = (lar.vertices().point(ends[0]), lar.vertices().point(ends[1]));
            if r < 0 {
                (a, b) = (b, a);
            }
            // The centroid must be left of every edge of the ccw boundary.
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 1e-12 * scale
        })
    };
    match complex.non_convex_cells().into_iter().find(|&cell| outside(cell)) {
        Some(cell) => Err(MetricError::UnsupportedCell {
            method,
            needs: "cells star-shaped about their centroid (fe takes any simple polygon, by its virtual elements)",
            cell,
        }),
        None => Ok(()),
    }
}

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
