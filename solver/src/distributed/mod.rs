//! Distributed solves on PETSc over MPI, with a partitioned complex.
//!
//! The top cells are partitioned among the ranks (METIS k-way on the dual
//! graph read off ∂ₙ: [`partition_top_cells`]). Each rank builds a
//! [`LocalComplex`]: its owned top cells and the LAR star around them
//! (every top cell sharing a vertex with an owned one), with the global id
//! and owner rank of every cell. Because the star is complete around every
//! owned unknown, the serial assembly of Aᵀ Ω A on the local complex gives
//! the exact global rows of the owned unknowns: the distributed operator
//! is the same canonical form, by the same metric code, as the serial one.
//!
//! The partition and the local complexes need no MPI and are always built;
//! the PETSc binding and the solve need the cargo feature `mpi`
//! (`cargo build --release --features mpi`, with Debian's `petsc-dev` and
//! `libopenmpi-dev`: `scripts/setup --mpi`).

mod local;
mod partition;
#[cfg(feature = "mpi")]
pub mod petsc;
#[cfg(feature = "mpi")]
mod solve;

pub use local::LocalComplex;
pub use partition::partition_top_cells;
#[cfg(feature = "mpi")]
pub use solve::{solve_diffusion, DistributedSolve};

use crate::physics::diffusion::DiffusionError;
use hasse_complex::ComplexError;

/// Why a distributed solve could not be made.
#[derive(Debug, thiserror::Error)]
pub enum DistributedError {
    /// More ranks than top cells (or none): some rank would own nothing.
    #[error("{ranks} ranks for {cells} top cells: every rank must own at least one top cell; run on at most {cells} ranks")]
    TooManyRanks {
        /// Ranks asked for.
        ranks: usize,
        /// Top cells of the mesh.
        cells: usize,
    },
    /// The partition or the ownership of unknowns is inconsistent.
    #[error("partition: {0}")]
    Partition(String),
    /// The local complex could not be built.
    #[error("local complex: {0}")]
    Complex(#[from] ComplexError),
    /// The local assembly failed.
    #[error(transparent)]
    Diffusion(#[from] DiffusionError),
    /// A problem without Dirichlet or Robin boundary (singular) on the
    /// distributed path.
    #[error("pure Neumann problems (no Dirichlet or Robin boundary) are not solved on the petsc path yet: give a Dirichlet or Robin condition, or use another solver.type")]
    PureNeumann,
    /// More unknowns than PETSc's 32-bit indices hold.
    #[error("{unknowns} unknowns exceed PETSc's 32-bit indices (this PETSc was built without 64-bit indices)")]
    TooLarge {
        /// The global number of unknowns.
        unknowns: usize,
    },
    /// A PETSc call failed.
    #[cfg(feature = "mpi")]
    #[error(transparent)]
    Petsc(#[from] petsc::PetscError),
    /// KSP stopped without converging.
    #[cfg(feature = "mpi")]
    #[error("PETSc {} + {} did not converge: reason {} after {} iterations (residual norm {:e}); see KSPConvergedReason, or ask for a direct solve with solver.factorization", .0.ksp, .0.pc, .0.reason, .0.iterations, .0.residual_norm)]
    Diverged(petsc::KspReport),
}
