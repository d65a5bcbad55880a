//! `[solver] type = "petsc"`: one distributed solve on PETSc over MPI.
//!
//! Every rank of `mpirun -np N hasse run CASE` reads the case and builds
//! the mesh, then [`crate::distributed::solve_diffusion`] partitions it,
//! assembles the owned rows on each rank's local complex and solves with
//! KSP. The solution is gathered on rank 0, which alone post-processes and
//! writes the output (the same single HDF5 + XDMF as a serial run); the
//! other ranks exit quietly once MPI is finalised.

use super::*;
use crate::physics::diffusion::{Diffusion, Solution};

/// Solve `problem` on PETSc; on rank 0 returns the solution and the
/// summary's line about the solve. Other ranks exit the process (0 when
/// the solve succeeded).
#[cfg(feature = "mpi")]
pub(super) fn solve(
    case: &Case,
    problem: &Diffusion,
    complex: &Complex,
) -> Result<(Solution, String), RunError> {
    use crate::distributed::petsc::{Defaults, Petsc};
    use crate::distributed::{solve_diffusion, DistributedError};
    use crate::la::direct::Factorization;
    use mpi::traits::*;

    let Some(universe) = mpi::initialize() else {
        return Err(RunError::input_at(
            case,
            "solver.type",
            "MPI is already running in this process: one petsc solve per run",
            None,
        ));
    };
    let world = universe.world();
    let rank = world.rank();
    let defaults = match case.solver.factorization {
        Some(Factorization::Lu) => Defaults::Direct { cholesky: false },
        Some(_) => Defaults::Direct { cholesky: true },
        None => Defaults::Iterative {
            tolerance: case.solver.tolerance,
        },
    };
    let outcome = Petsc::initialize(world.as_raw(), &case.solver.petsc_options)
        .map_err(DistributedError::from)
        .and_then(|petsc| solve_diffusion(&world, &petsc, problem, complex, defaults));
    let solved = match outcome {
        Ok(solved) => solved,
        // Every rank finds these alike, before any rank waits on another:
        // all finalise MPI and rank 0 reports.
        Err(error @ (DistributedError::TooManyRanks { .. } | DistributedError::PureNeumann)) => {
            drop(universe);
            if rank != 0 {
                std::process::exit(1);
            }
            return Err(RunError::input_at(
                case,
                "solver.type",
                error.to_string(),
                None,
            ));
        }
        // A failure on one rank leaves the others waiting in a collective
        // call: abort them all (no output has been written).
        Err(error) => {
            eprintln!("error: rank {rank} of {}: {error}", world.size());
            world.abort(1);
        }
    };
    drop(universe);
    if rank != 0 {
        std::process::exit(0);
    }
    let ksp = &solved.ksp;
    let note = format!(
        "PETSc {} + {} on {} ranks: {} iterations (converged reason {}), residual norm {:.2e}; unknowns per rank {:?}; assembly {:.3} s, solve {:.3} s; gathered on rank 0 for the output",
        ksp.ksp,
        ksp.pc,
        solved.ranks,
        ksp.iterations,
        ksp.reason,
        ksp.residual_norm,
        solved.owned,
        solved.assembly_seconds,
        solved.solve_seconds,
    );
    let keys = Keys {
        prefix: "problem".into(),
        coefficient: "conductivity",
        boundary: &[],
    };
    let solution = problem
        .solution_from_values(complex, solved.values, solved.solve_seconds)
        .map_err(|e| diffusion_error(case, &keys, e))?;
    Ok((solution, note))
}

/// Without the feature `mpi`, `hasse check` refuses the case already; a
/// case built in code gets the same answer here.
#[cfg(not(feature = "mpi"))]
pub(super) fn solve(
    case: &Case,
    _problem: &Diffusion,
    _complex: &Complex,
) -> Result<(Solution, String), RunError> {
    Err(RunError::input_at(
        case,
        "solver.type",
        "\"petsc\" needs a hasse built with the cargo feature `mpi`",
        Some("scripts/setup --mpi && cargo build --release --features mpi".into()),
    ))
}
