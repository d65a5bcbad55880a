//! Integration tests of the physics through the library: diffusion by
//! every method, Darcy, Maxwell, transient heat, elasticity, coupled
//! fields, re-solving on refined meshes and convergence studies (of any
//! mesh, in space and in time).
//!
//! One test binary per area (methods, physics, cli, output); the former
//! test files are the modules below, e.g.
//! `cargo test -p hasse-solver --test physics darcy::`.

#[path = "../common/orders.rs"]
mod orders;

mod cohomology_3d;
mod cohomology_relative;
mod converge;
mod converge_any;
mod coupled;
mod darcy;
mod diffusion;
mod elasticity;
mod form_poisson;
mod forms;
mod forms_dec;
mod hodge_decomposition;
mod interface_flux;
mod maxwell;
mod nonlinear;
mod refinement;
mod transient;
mod transport;
mod transport_fe;
mod whitney_map;
