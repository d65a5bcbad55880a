//! Restarting a heat run from a saved level of an earlier run's output
//! (`problem.initial = { from = "run.h5", level = … }`): the level's
//! temperature becomes u⁰ and its time t₀, on the same mesh (the saved
//! values as they are, bit for bit) or on a refinement of it (the saved
//! field evaluated at the new unknowns' points the way the method
//! represents it, [`crate::physics::probe`]).

use super::RunError;
use crate::frontend::case::{Case, HeatSpec, RestartSpec};
use crate::frontend::output::read_mesh::read_mesh;
use crate::metric::Location;
use crate::physics::probe::{value_at, PointLocator};
use hasse_complex::Complex;
use hdf5::types::VarLenUnicode;
use serde_json::json;

/// The state a restarted run starts from.
pub(super) struct RestartState {
    /// t₀: the saved level's time.
    pub time: f64,
    /// u⁰ on every unknown.
    pub field: Vec<f64>,
    /// Steps to take: `time.steps`, or up to `time.end` from t₀.
    pub steps: usize,
    /// The summary's line: where u⁰ came from and how it reached this mesh.
    pub note: String,
    /// The same for the run report (`restart`).
    pub report: serde_json::Value,
}

fn refuse(case: &Case, key: &str, message: String, help: Option<&str>) -> RunError {
    RunError::input_at(case, key, message, help.map(str::to_string))
}

/// How the saved field reached this mesh's unknowns.
enum Mapping {
    /// The same mesh: the saved values as they are.
    Same,
    /// A refinement: `interpolated` of the values come from the P1/Q1
    /// interpolant inside a saved cell, the others from a saved vertex
    /// at the same place (nodal), or every value from the saved cell
    /// that holds the new cell's centroid (cell-centred).
    Refinement {
        location: Location,
        interpolated: usize,
        saved_cells: usize,
    },
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
    let step = file.group(&format!("steps/{level}")).map_err(h5)?;
    let time: f64 = step
        .attr("time")
        .and_then(|a| a.read_scalar())
        .map_err(h5)?;
    let u = step.dataset("u").map_err(h5)?;
    let dataset = format!("/steps/{level}/u");
    // Every heat run stamps its fields with the method; a file without
    // the stamp leaves the check to the count of values.
    if let Ok(attr) = u.attr("method") {
        let saved: VarLenUnicode = attr.read_scalar().map_err(h5)?;
        let ours = spec.method.name();
        if saved.as_str() != ours {
            return Err(refuse(
                case,
                "problem.method",
                format!(
                    "{shown} was computed with method \"{saved}\" (attribute `method` of {dataset}); this case uses \"{ours}\": a restart continues with the saved run's method"
                ),
                Some(&format!("set problem.method = \"{saved}\"")),
            ));
        }
    }
    let saved: Vec<f64> = u.read_raw().map_err(h5)?;
    // Same mesh: the same vertices, in the same order, and as many top
    // cells. Stored as N × 3, zero-padded below three dimensions.
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
    drop(file);
    let (field, mapping) = if vertices == ours && cells == complex.cell_count(n) {
        (saved, Mapping::Same)
    } else {
        let source = Source {
            case,
            restart,
            shown: &shown,
            dataset: &dataset,
        };
        source.onto_refinement(spec.method.location(), &saved, complex)?
    };
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
    let (note, report) = describe(&shown, level, time, field.len(), &mapping);
    Ok(RestartState {
        time,
        field,
        steps,
        note,
        report,
    })
}

/// The summary line and the report entry of a restart.
fn describe(
    shown: &str,
    level: usize,
    time: f64,
    unknowns: usize,
    mapping: &Mapping,
) -> (String, serde_json::Value) {
    let from = format!("from {shown} level {level} (t = {time})");
    match *mapping {
        Mapping::Same => (
            format!("{from} on the same mesh: {unknowns} values as saved"),
            json!({ "from": shown, "level": level, "time": time, "mesh": "same", "unknowns": unknowns }),
        ),
        Mapping::Refinement {
            location,
            interpolated,
            saved_cells,
        } => {
            let how = match location {
                Location::Nodal => format!(
                    "{interpolated} of {unknowns} values interpolated (P1/Q1 in the saved cell), {} at saved vertices",
                    unknowns - interpolated
                ),
                _ => format!(
                    "{unknowns} cell values from their parents ({saved_cells} saved cells)"
                ),
            };
            (
                format!("{from} on a refinement: {how}"),
                json!({
                    "from": shown,
                    "level": level,
                    "time": time,
                    "mesh": "refinement",
                    "unknowns": unknowns,
                    "interpolated": interpolated,
                    "saved_cells": saved_cells,
                }),
            )
        }
    }
}

/// The saved run a refinement restart reads, for its refusals.
struct Source<'a> {
    case: &'a Case,
    restart: &'a RestartSpec,
    shown: &'a str,
    dataset: &'a str,
}

/// Children of one saved cell may differ from it in measure by rounding
/// only: SPLIT cuts a convex cell into convex pieces whose measures add
/// up to the parent's to a few ulps (DESIGN.md's "refined measures sum to
/// coarse measures").
const NESTED: f64 = 1e-9;

impl Source<'_> {
    fn refuse(&self, message: String, help: &str) -> RunError {
        refuse(self.case, "problem.initial.from", message, Some(help))
    }

    fn not_a_refinement(&self, what: String) -> RunError {
        self.refuse(
            format!(
                "{} was computed on another mesh, of which this case's mesh is not a refinement: {what}",
                self.shown
            ),
            "restart on the saved run's mesh or on a refinement of it (SPLIT, or a finer grid nested in it)",
        )
    }

    /// `saved` (the values of [`Self::dataset`]) on `complex`, a refinement
    /// of the saved mesh: nodal values are the saved field's P1/Q1
    /// interpolant at each new vertex, cell values the value of the saved
    /// cell holding each new centroid (in a SPLIT refinement the parent:
    /// children inherit the parent's average, as through the chain map).
    fn onto_refinement(
        &self,
        location: Location,
        saved: &[f64],
        complex: &Complex,
    ) -> Result<(Vec<f64>, Mapping), RunError> {
        let coarse = read_mesh(&self.restart.from, "mesh").map_err(|e| {
            self.refuse(
                e.to_string(),
                "give the .h5 output of a hasse run on one mesh",
            )
        })?;
        let (n, d) = (coarse.dim(), coarse.embedding_dim());
        if (n, d) != (complex.dim(), complex.embedding_dim()) {
            return Err(self.not_a_refinement(format!(
                "its cells are {n}-dimensional in R^{d}, this mesh's {}-dimensional in R^{}",
                complex.dim(),
                complex.embedding_dim()
            )));
        }
        let (dim, unit) = match location {
            Location::Nodal => (0, "vertices"),
            Location::CellCentred => (n, "cells"),
            Location::Hybrid => {
                return Err(self.refuse(
                    format!(
                        "{} was computed on another mesh; a restart maps nodal or cell-centred unknowns onto a refinement, and this method has face unknowns too",
                        self.shown
                    ),
                    "restart on the saved run's mesh",
                ))
            }
        };
        if saved.len() != coarse.cell_count(dim) {
            return Err(self.refuse(
                format!(
                    "{}: {} has {} values, its mesh /mesh has {} {unit}",
                    self.shown,
                    self.dataset,
                    saved.len(),
                    coarse.cell_count(dim)
                ),
                "give the output of a heat run",
            ));
        }
        let locator = PointLocator::new(&coarse).map_err(|e| {
            self.refuse(
                format!("{}: cannot locate points in its mesh: {e}", self.shown),
                "restart on the saved run's mesh",
            )
        })?;
        let outside = |what: &str, i: usize, x: &[f64]| {
            self.not_a_refinement(format!(
                "{what} {i} of this mesh, at {x:?}, lies outside the saved mesh (/mesh/cells/{n} of {}), where {} has no value",
                self.shown, self.dataset
            ))
        };
        let points = super::field_points(complex, dim);
        // The unknowns' own points first, so that a vertex outside is the
        // point named.
        let holders: Vec<usize> = if dim == 0 {
            points
                .iter()
                .enumerate()
                .map(|(v, x)| locator.locate(x).ok_or_else(|| outside("vertex", v, x)))
                .collect::<Result<_, _>>()?
        } else {
            Vec::new()
        };
        // Each new top cell's parent: the saved cell holding its centroid.
        let parents: Vec<usize> = super::field_points(complex, n)
            .iter()
            .enumerate()
            .map(|(c, x)| {
                locator
                    .locate(x)
                    .ok_or_else(|| outside("the centroid of cell", c, x))
            })
            .collect::<Result<_, _>>()?;
        // Nested: the children of every saved cell fill it.
        let mut filled = vec![0.0; coarse.cell_count(n)];
        for (&p, &m) in parents.iter().zip(complex.measure(n)) {
            filled[p] += m;
        }
        let whole = coarse.measure(n);
        if let Some(p) =
            (0..whole.len()).find(|&p| (filled[p] - whole[p]).abs() > NESTED * whole[p])
        {
            return Err(self.not_a_refinement(format!(
                "the cells of this mesh whose centroids lie in saved cell {p} (centroid {:?}, measure {:.6e}) measure {:.6e} together, not its measure",
                coarse.centroid_of(n, p),
                whole[p],
                filled[p]
            )));
        }
        let saved_cells = coarse.cell_count(n);
        if dim == n {
            let field = parents.iter().map(|&p| saved[p]).collect();
            return Ok((
                field,
                Mapping::Refinement {
                    location,
                    interpolated: 0,
                    saved_cells,
                },
            ));
        }
        // A refinement keeps the saved vertices' coordinates bit for bit;
        // the count is for the summary ([`value_at`] takes a saved
        // vertex's value there as it is).
        let interpolated = points
            .iter()
            .zip(&holders)
            .filter(|&(x, &cell)| {
                !coarse
                    .cell_vertices(n, cell)
                    .iter()
                    .any(|&w| coarse.vertices().point(w) == x.as_slice())
            })
            .count();
        let field = points
            .iter()
            .zip(&holders)
            .map(|(x, &cell)| value_at(&coarse, Location::Nodal, saved, None, cell, x))
            .collect();
        Ok((
            field,
            Mapping::Refinement {
                location,
                interpolated,
                saved_cells,
            },
        ))
    }
}
