//! Integration tests of the output files: HDF5 + XDMF read back with the
//! `hdf5` crate, and by h5py and meshio as a user would.
//!
//! One test binary per area (methods, physics, cli, output); the former
//! test files are the modules below.

#[path = "../common/pyenv.rs"]
mod pyenv;
#[path = "../common/scratch.rs"]
mod scratch;

mod complex_layout;
mod flux_convention;
mod level_files;
mod output_files;
mod output_python;
mod output_selection;
mod refine_series;
mod restart;
