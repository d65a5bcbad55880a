//! The `hasse` command line.

use clap::{Parser, Subcommand};
use hasse_solver::{info, mesh_spec};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// hasse: one canonical form δΩ∂ = AᵀΩA for FD, FE, FV and DEC on any cell complex.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Report on a mesh: cell counts per dimension, Euler characteristic,
    /// Betti numbers, boundary regions (tags) and cell quality.
    ///
    /// MESH may be a case file (.toml, its [mesh] table is used), a Gmsh
    /// file (.msh, version 4) or a hasse complex file (.json).
    ///
    /// Example: hasse info cases/torus.toml
    Info {
        /// Case file, Gmsh .msh v4 file or hasse .json complex.
        mesh: PathBuf,
        /// Compute Betti numbers even for large meshes.
        #[arg(long)]
        betti: bool,
        /// Also print the time taken to build the complex and its geometry,
        /// and the peak memory of the process.
        #[arg(long)]
        timing: bool,
    },
}

/// Exit code for bad input (case file, mesh file, parameters).
const EXIT_BAD_INPUT: u8 = 2;

fn load_timed(path: &Path, timing: bool) -> Result<hasse_complex::Complex, mesh_spec::MeshError> {
    let started = std::time::Instant::now();
    let complex = load(path)?;
    if timing {
        println!(
            "timing     mesh built in {:.3} s",
            started.elapsed().as_secs_f64()
        );
    }
    Ok(complex)
}

fn load(path: &Path) -> Result<hasse_complex::Complex, mesh_spec::MeshError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("msh") => Ok(hasse_complex::gmsh::read_msh(path)?),
        Some("json") => Ok(hasse_complex::json::read_json(path)?),
        _ => mesh_spec::read_case_mesh(path)?.build(path),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Info {
            mesh,
            betti,
            timing,
        } => match load_timed(&mesh, timing) {
            Ok(complex) => {
                let started = std::time::Instant::now();
                let report = info::report(&complex, &mesh.display().to_string(), betti);
                print!("{report}");
                if timing {
                    println!(
                        "timing     report {:.3} s; peak memory {}",
                        started.elapsed().as_secs_f64(),
                        info::peak_memory().unwrap_or_else(|| "unknown".into())
                    );
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(EXIT_BAD_INPUT)
            }
        },
    }
}
