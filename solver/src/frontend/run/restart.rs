//! Restarting a heat run from a saved level of an earlier run's output
//! (`problem.initial = { from = "run.h5", level = … }`): the level's
//! temperature becomes u⁰ and its time t₀, on the same mesh.

use super::RunError;
use crate::frontend::case::{Case, HeatSpec, RestartSpec};
use hasse_complex::Complex;

/// The state a restarted run starts from.
pub(super) struct RestartState {
    /// t₀: the saved level's time.
    pub time: f64,
    /// u⁰ on every unknown.
    pub field: Vec<f64>,
    /// Steps to take: `time.steps`, or up to `time.end` from t₀.
    pub steps: usize,
}

fn refuse(case: &Case, key: &str, message: String, help: Option<&str>) -> RunError {
    RunError::input_at(case, key, message, help.map(str::to_string))
}

/// Read and check the restart of `spec` against `complex`.
pub(super) fn read(
    case: &Case,
    spec: &HeatSpec,
    restart: &RestartSpec,
    complex: &Complex,
) -> Result<RestartState, RunError> {
    let shown = restart.from.display().to_string();
    let file = hdf5::File::open(&restart.from).map_err(|e| {
        refuse(
            case,
            "problem.initial.from",
            format!("cannot open {shown}: {e}"),
            Some("give the .h5 output of an earlier run, relative to the case file"),
        )
    })?;
    let h5 = |e: hdf5::Error| {
        refuse(
            case,
            "problem.initial.from",
            format!("{shown} is not the output of a hasse run on one mesh: {e}"),
            None,
        )
    };
    let levels = file
        .group("steps")
        .map_err(h5)?
        .member_names()
        .map_err(h5)?
        .len();
    let level = match restart.level {
        None if levels > 0 => levels - 1,
        Some(k) if k < levels => k,
        _ => {
            return Err(refuse(
                case,
                "problem.initial.level",
                format!(
                    "{shown} has {levels} saved levels (0 to {})",
                    levels.saturating_sub(1)
                ),
                None,
            ))
        }
    };
    // Same mesh: the same vertices, in the same order, and as many top
    // cells (a SPLIT refinement would need the chain map).
    // Stored as N × 3, zero-padded below three dimensions.
    let padded: Vec<f64> = file
        .dataset("mesh/vertices")
        .map_err(h5)?
        .read_raw()
        .map_err(h5)?;
    let d = complex.embedding_dim();
    let vertices: Vec<f64> = padded
        .chunks(3)
        .flat_map(|p| p[..d.min(p.len())].to_vec())
        .collect();
    let n = complex.dim();
    let ours = complex.vertices().as_slice();
    let cells = file
        .dataset(&format!("mesh/cells/{n}/indptr"))
        .map_err(h5)?
        .size()
        .saturating_sub(1);
    if vertices != ours || cells != complex.cell_count(n) {
        return Err(refuse(
            case,
            "problem.initial.from",
            format!(
                "{shown} was computed on another mesh ({} vertices; this case's mesh has {})",
                padded.len() / 3,
                complex.cell_count(0)
            ),
            Some("restart on the mesh the earlier run used"),
        ));
    }
    let step = file.group(&format!("steps/{level}")).map_err(h5)?;
    let time: f64 = step
        .attr("time")
        .and_then(|a| a.read_scalar())
        .map_err(h5)?;
    let field: Vec<f64> = step.dataset("u").and_then(|d| d.read_raw()).map_err(h5)?;
    let steps = match spec.time.end {
        None => spec.time.steps,
        Some(end) => {
            let exact = (end - time) / spec.time.dt;
            let steps = exact.round();
            if steps < 1.0 || (exact - steps).abs() > 1e-9 * exact.max(1.0) {
                return Err(refuse(
                    case,
                    "time.end",
                    format!(
                        "the restart is at t = {time}: time.end = {end} is not a whole number of steps dt = {} after it",
                        spec.time.dt
                    ),
                    Some("give time.steps, the number of steps after the restart"),
                ));
            }
            steps as usize
        }
    };
    Ok(RestartState { time, field, steps })
}
