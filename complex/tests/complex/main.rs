//! Integration tests of hasse-complex, one test binary (each binary is
//! linked separately, and links dominate the build): generators, geometry,
//! reading and writing, the Euler make and kill operators, and SPLIT. Run one module with
//! `cargo test -p hasse-complex --test complex split::`.
//!
//! The proptest regressions of `split` live in
//! `../proptest-regressions/split.txt`: proptest's default persistence
//! looks for the `main.rs` above a test source and keeps its seeds in a
//! `proptest-regressions` directory beside that directory.

mod coarsen;
mod euler;
mod generators;
mod geometry;
mod io;
mod lar_format;
mod makes;
mod seeds;
mod split;
