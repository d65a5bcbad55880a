//! The canonical form M = δ Ω ∂ = Aᵀ Ω A.
//!
//! A is an exact integer incidence matrix (rows: the cells that carry
//! fluxes, columns: the unknowns); Ω is the metric, a sum of small dense
//! blocks Σ_b E_{R_b}ᵀ W_b E_{S_b} over row sets R_b, S_b of A. A diagonal Ω
//! has one 1×1 block per row, a finite-element Ω one block per cell over the
//! cell's edges, a user-given sparse Ω one 1×1 block per entry.
//!
//! Assembly is split like a sparse factorisation: the sparsity pattern of
//! M, and how values reach it, are built once ([`Canonical::new`]);
//! numeric assembly ([`Canonical::assemble`]) can then be repeated with new
//! values of the same pattern ([`Canonical::set_metric`]). No map from
//! local entries to M is kept: M is formed column by column in parallel.
//! For a general Ω column j gathers column j of each local matrix
//! A_{R_b}ᵀ W_b A_{S_b} whose block touches j (blocks indexed by unknown
//! with the pattern); for a diagonal Ω (two-point fluxes, diagonal Hodge
//! stars) column j is Σ_r w_r a_rj A_r over the rows of A touching j,
//! from A stored by columns.
//!
//! The operator is split like its assembly: [`BlockMetric`] stores Ω,
//! `pattern` builds the sparsity of M once, `values` forms M's values, and
//! [`block`] places several operators in one block system.

pub mod block;
mod block_metric;
mod canonical;
mod pattern;
#[cfg(test)]
mod tests;
mod values;

pub use block_metric::BlockMetric;
pub use canonical::{metric_from_matrix, Canonical};
pub(crate) use pattern::{clique_pattern, diagonal_pattern};

/// Errors in building a canonical operator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CanonicalError {
    #[error("metric has size {metric} but the incidence matrix has {rows} rows")]
    SizeMismatch { metric: usize, rows: usize },
    #[error("metric block {block} refers to row {row}, beyond the {size} rows of A")]
    RowOutOfRange {
        block: usize,
        row: usize,
        size: usize,
    },
    #[error("metric block {block} has {found} values for a {rows}×{cols} block")]
    BlockShape {
        block: usize,
        rows: usize,
        cols: usize,
        found: usize,
    },
    #[error("metric block {block} has a non-finite value")]
    NonFinite { block: usize },
    #[error("new metric values do not have the pattern the operator was built with")]
    PatternChanged,
    #[error(
        "a sum of operators needs square terms over the same unknowns: {unknowns} and {found}"
    )]
    SumMismatch { unknowns: usize, found: usize },
}
