//! # hasse-solver
//!
//! The canonical form δΩ∂ = Aᵀ Ω A on cell complexes: the operator type,
//! the metrics Ω of FD, FE, FV and DEC, boundary conditions, faer solves,
//! case files, output and the `hasse` command line.

pub mod block;
pub mod canonical;
pub mod case;
pub mod converge;
pub mod coupled;
pub mod darcy;
pub mod diffusion;
pub mod eigen;
pub mod elasticity;
pub mod info;
pub mod iterative;
pub mod linear;
pub mod maxwell;
pub mod mesh_spec;
pub mod metric;
pub mod multigrid;
pub mod ordering;
pub mod output;
pub mod refinement;
pub mod run;
pub mod transient;
