//! Integration tests of the complex and the methods: topology invariants,
//! the nodal and cell-centred metrics as Aᵀ Ω A, multigrid, property tests
//! over random meshes, and the layering of `solver/src`.
//!
//! One test binary per area (methods, physics, cli, output): each binary
//! links the whole library and HDF5, and links dominate the build. The
//! former test files are the modules below; run one of them with
//! `cargo test -p hasse-solver --test methods multigrid::`.

mod cell_metrics;
mod complex_invariants;
mod layers;
mod multigrid;
mod nodal_metrics;
mod partition;
mod properties;
