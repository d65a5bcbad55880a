//! Integration tests of the `hasse` binary as a user runs it: shipped
//! cases, physics kinds, `check`, `info`, the case documentation, bad
//! input, interrupted output and the replayed fuzz inputs.
//!
//! One test binary per area (methods, physics, cli, output); the former
//! test files are the modules below, e.g.
//! `cargo test -p hasse-solver --test cli bad_input::`. The tests of one
//! binary run on parallel threads of one process: each writes into its
//! own scratch directory (test name and process id) and hands environment
//! variables to the child `hasse` process, never to this one.

#[path = "../common/hasse.rs"]
mod hasse;
#[path = "../common/orders.rs"]
mod orders;
#[path = "../common/pyenv.rs"]
mod pyenv;
#[path = "../common/scratch.rs"]
mod scratch;

mod bad_input;
mod case_docs;
mod cli_cases;
mod cli_check;
mod cli_info;
mod cli_input;
mod cli_output;
mod cli_physics;
mod darcy_reports;
mod dec;
#[cfg(feature = "mpi")]
mod distributed;
mod doc_commands;
mod form_poisson;
mod fuzz_regressions;
mod growth;
mod heat_solvers;
mod hodge;
mod hodge_decomposition;
mod interrupted_output;
mod lar_files;
mod method_warnings;
mod nonlinear;
mod probes;
mod quantities;
mod refine_coarsen;
mod regions;
mod transport;
