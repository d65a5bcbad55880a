//! The canonical operator M = Aᵀ Ω A and block systems of such operators.

pub mod block;
mod canonical;

pub(crate) use canonical::{clique_pattern, diagonal_pattern, ranges, split_at_ranges, zeroed};
pub use canonical::{metric_from_matrix, BlockMetric, Canonical, CanonicalError};
