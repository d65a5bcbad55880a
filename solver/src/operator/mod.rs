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

#![warn(missing_docs)]

pub mod block;
mod block_metric;
mod canonical;
mod incidence;
mod pattern;
#[cfg(test)]
mod tests;
mod values;

pub use block_metric::BlockMetric;
pub use canonical::{metric_from_matrix, Canonical};
pub use incidence::IntoIncidence;
pub(crate) use pattern::{clique_pattern, diagonal_pattern};

/// Errors in building a canonical operator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CanonicalError {
    /// Ω is not square over the rows of A: A and Ω were built for
    /// different cells (e.g. a metric of the edges with an incidence
    /// matrix of the faces).
    #[error("metric has size {metric} but the incidence matrix has {rows} rows")]
    SizeMismatch {
        /// Rows (and columns) of Ω.
        metric: usize,
        /// Rows of A.
        rows: usize,
    },
    /// A block of Ω refers to a row that A does not have.
    #[error("metric block {block} refers to row {row}, beyond the {size} rows of A")]
    RowOutOfRange {
        /// The block, in the order the metric holds them.
        block: usize,
        /// The row it refers to.
        row: usize,
        /// Rows of A (and of Ω).
        size: usize,
    },
    /// A block of Ω does not have |rows| · |cols| values.
    #[error("metric block {block} has {found} values for a {rows}×{cols} block")]
    BlockShape {
        /// The block.
        block: usize,
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
        /// Values given.
        found: usize,
    },
    /// A block of Ω holds NaN or ±∞, typically from a degenerate cell or a
    /// coefficient that is not finite.
    #[error("metric block {block} has a non-finite value")]
    NonFinite {
        /// The first such block.
        block: usize,
    },
    /// [`Canonical::set_metric`] was given an Ω whose blocks sit elsewhere
    /// than those the assembly pattern was built for.
    #[error("new metric values do not have the pattern the operator was built with")]
    PatternChanged,
    /// A sum of operators mixed unknowns: the terms must all be Aᵀ Ω A
    /// over the same number of unknowns (not coupling blocks Aᵀ Ω B).
    #[error(
        "a sum of operators needs square terms over the same unknowns: {unknowns} and {found}"
    )]
    SumMismatch {
        /// Unknowns of the first term.
        unknowns: usize,
        /// Unknowns of the first term that differs (or of a coupling block).
        found: usize,
    },
}
