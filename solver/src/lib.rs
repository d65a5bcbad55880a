//! # hasse-solver
//!
//! The canonical form δΩ∂ = Aᵀ Ω A on cell complexes: the operator type,
//! the metrics Ω of FD, FE, FV and DEC, boundary conditions, faer solves,
//! case files, output and the `hasse` command line.

pub mod frontend;
pub mod la;
pub mod metric;
pub mod multigrid;
pub mod operator;
pub mod physics;
pub mod refine;
pub mod study;
