//! # hasse-solver
//!
//! Every operator of hasse is the canonical form **M = Aᵀ Ω A** (δΩ∂): A
//! an exact integer incidence matrix of a cell complex (pure topology), Ω
//! a metric that carries every length, material and method. Finite
//! differences, finite elements, finite volumes and DEC are different Ω on
//! the same A; a problem with several fields is a block system of such
//! operators.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::metric::{fe, fv};
//! use hasse_solver::operator::Canonical;
//! let k = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
//! // Nodal Q1 elements: A = δ⁰ (edges × vertices), Ω one block per cell.
//! let stiffness = Canonical::new(k.coboundary(0), fe::stiffness_metric(&k, &[1.0; 64]).unwrap()).unwrap();
//! // Cell-centred two-point finite volumes: A = ∂₂ (edges × cells), Ω diagonal.
//! let tpfa = Canonical::new(k.boundary(2), fv::two_point(&k, &[1.0; 64]).unwrap()).unwrap();
//! // The FE rows of A are differences along edges: constants are the
//! // kernel of the (Neumann) operator.
//! assert!(stiffness.apply(&vec![1.0; 81]).iter().all(|v| v.abs() < 1e-12));
//! // ∂₂ keeps the 32 boundary edges as rows: a ghost value 0 behind each,
//! // with σ = |F| / (h/2) = 2, so a constant 1 loses 2 through each of them.
//! let loss: f64 = tpfa.apply(&vec![1.0; 64]).iter().sum();
//! assert!((loss - 64.0).abs() < 1e-12);
//! ```
//!
//! ## Layers
//!
//! The crate is layered; each layer may use the layers before it and
//! never one after it:
//!
//! ```text
//! la  ←  multigrid, operator  ←  metric  ←  physics  ←  refine, study, distributed  ←  frontend
//! ```
//!
//! - [`la`]: linear algebra: direct factorisations (faer) and their
//!   orderings, conjugate gradients on row-stored matrices, eigenpairs,
//!   and [`la::fixed`], the one place where unknowns held at known values
//!   are eliminated and lifted back.
//! - [`multigrid`]: V-cycles and smoothed aggregation as CG
//!   preconditioners; only its transfers know the complex.
//! - [`operator`]: [`operator::Canonical`] (the pattern of Aᵀ Ω A built
//!   once, values many times; coupling blocks Aᵀ Ω B; sums), the Ω storage
//!   [`operator::BlockMetric`], and [`operator::block::BlockSystem`].
//! - [`metric`]: one module per method (FD, FE, FV, DEC) building Ω, the
//!   methods' names ([`metric::Method`]) and the one check of the
//!   coefficients.
//! - [`physics`]: each problem as canonical operators plus its data:
//!   diffusion, transient heat, mixed Darcy, Maxwell cavities, linear
//!   elasticity, coupled fields, normal gradients, and the k-form layer
//!   [`physics::forms`] (d, ⋆, δ, the Hodge Laplacian Δ_k, harmonic
//!   forms from cohomology generators, the Hodge decomposition, and the
//!   de Rham and Whitney maps between fields and cochains).
//! - [`refine`] (re-solving on SPLIT-refined meshes) and [`study`]
//!   (convergence orders and their tables).
//! - [`distributed`]: the partitioned complex (owned top cells and their
//!   ghost star) and, with the cargo feature `mpi`, distributed solves on
//!   PETSc over MPI.
//! - [`frontend`]: case files, running them, output files, and the
//!   `hasse` command line (`main.rs`); nothing in the library depends on
//!   it.
//!
//! The rule is checked by the test `tests/methods/layers.rs`: it fails when a
//! lower layer names a higher one.
//!
//! ## Using it as a library
//!
//! [`prelude`] brings the common names in with one `use`; `sprs`, `faer`
//! and `hasse_complex` are re-exported so that a program names the
//! versions hasse was built with. The front end (case files, HDF5
//! output, the command line, convergence plots) is the default cargo
//! feature `cli`; a program that only builds operators and solves can
//! leave it and its dependencies out:
//!
//! ```toml
//! hasse-solver = { path = "…/solver", default-features = false }
//! ```
//!
//! Accessors of the complex return shared matrices: `k.boundary(p)` and
//! `k.coboundary(p)` are `&Arc<CsMat<i8>>`, read through deref and handed
//! to operators without a copy; `try_boundary`/`try_coboundary` return an
//! error instead of panicking for a degree out of range. Products of them
//! dereference explicitly (`&**k.boundary(1) * &**k.boundary(2)`), since
//! `sprs` multiplies matrices, not pointers to them.

#![warn(missing_docs)]

// The crates whose types appear in hasse's public API, so that a user
// names the same versions: `hasse_solver::sprs::CsMat`,
// `hasse_solver::faer::Mat`, `hasse_solver::complex::Complex`.
pub use faer;
pub use hasse_complex as complex;
pub use sprs;

pub mod distributed;
#[cfg(feature = "cli")]
pub mod frontend;
pub mod la;
pub mod metric;
pub mod multigrid;
pub mod operator;
pub mod physics;
pub mod prelude;
pub mod refine;
pub mod study;

/// The README's Rust examples, compiled and run as doctests so that they
/// stay true.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
struct ReadmeExamples;

/// The Rust examples of the solver and performance notes, run the same way.
#[cfg(doctest)]
#[doc = include_str!("../../benches/README.md")]
struct SolverNotesExamples;
