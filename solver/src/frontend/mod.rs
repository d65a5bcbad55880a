//! The front end: case files, running them, output files.

pub mod case;
pub mod converge;
pub mod info;
mod mesh_defects;
pub mod mesh_spec;
pub mod output;
pub mod run;
