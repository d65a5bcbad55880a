//! Linear algebra: direct factorisations and their orderings, the
//! row-stored matrix and conjugate gradients, eigenpairs.

#![warn(missing_docs)]

pub mod direct;
pub(crate) mod disjoint;
pub mod eigen;
pub mod fixed;
pub mod iterative;
pub mod krylov;
pub mod ordering;
pub(crate) mod parallel;
