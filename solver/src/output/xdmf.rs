//! The XDMF 3 texts: one document per cochain degree grid, each pointing
//! into the same h5 file.

use super::topology::{grid_topology, GridTopology};
use super::{Cochain, OutputError, RunOutput};
use std::fmt::Write;

/// The grids a run needs, top cells first: the top grid always (it also
/// carries the point data), then edges and faces, in increasing degree,
/// only when cochains live there.
pub(crate) fn grids(run: &RunOutput) -> Result<Vec<GridTopology>, OutputError> {
    let n = run.complex.dim();
    let used = |p: usize| {
        run.steps
            .iter()
            .any(|s| s.cochains.iter().any(|c| c.dim == p))
    };
    let mut grids = vec![grid_topology(run.complex, n)?];
    for p in 1..n {
        if used(p) {
            grids.push(grid_topology(run.complex, p)?);
        }
    }
    Ok(grids)
}

/// How a cochain appears on a grid, if it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Center {
    Node,
    Cell,
}

pub(crate) fn center(grid: &GridTopology, top_dim: usize, c: &Cochain) -> Option<Center> {
    if c.dim == grid.degree {
        Some(Center::Cell)
    } else if c.dim == 0 && grid.degree == top_dim {
        Some(Center::Node)
    } else {
        None
    }
}

/// HDF5 path of the values an XDMF attribute reads: the cochain itself, or
/// its copy expanded to the grid's elements when cells were split.
pub(crate) fn attribute_path(grid: &GridTopology, step: usize, c: &Cochain, at: Center) -> String {
    match (at, &grid.cell_ids) {
        (Center::Cell, Some(_)) => format!("/xdmf/{}/steps/{step}/{}", grid.degree, c.name),
        _ => format!("/steps/{step}/{}", c.name),
    }
}

/// Name of the grid in the XDMF text, also the middle part of the file
/// name `<stem>.<name>.xdmf` of a lower-degree grid.
pub(crate) fn grid_name(grid: &GridTopology, top_dim: usize) -> &'static str {
    match grid.degree {
        p if p == top_dim => "cells",
        1 => "edges",
        _ => "faces",
    }
}

fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(ch),
        }
    }
    out
}

/// The XDMF document of one grid; `h5_name` is the h5 file name relative
/// to it. One grid per document, because `meshio.read` accepts only a
/// domain holding a single uniform grid and `TimeSeriesReader` only the
/// last temporal collection: a plain uniform grid for at most one time
/// level, a temporal collection for several.
pub(crate) fn document(run: &RunOutput, grid: &GridTopology, h5_name: &str) -> String {
    let h5 = escape(h5_name);
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    out.push_str("<Xdmf Version=\"3.0\">\n  <Domain>\n");
    if run.steps.len() <= 1 {
        uniform_grid(&mut out, run, grid, 0, None, &h5, 4);
    } else {
        let name = grid_name(grid, run.complex.dim());
        let _ = writeln!(
            out,
            "    <Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Temporal\">"
        );
        for (k, step) in run.steps.iter().enumerate() {
            uniform_grid(&mut out, run, grid, k, Some(step.time), &h5, 6);
        }
        out.push_str("    </Grid>\n");
    }
    out.push_str("  </Domain>\n</Xdmf>\n");
    out
}

/// Shortest text that parses back to the same f64 (Rust's `Display`).
fn float(x: f64) -> String {
    format!("{x:?}")
}

fn uniform_grid(
    out: &mut String,
    run: &RunOutput,
    grid: &GridTopology,
    step: usize,
    time: Option<f64>,
    h5: &str,
    indent: usize,
) {
    let n = run.complex.dim();
    let pad = " ".repeat(indent);
    let name = grid_name(grid, n);
    let _ = writeln!(out, "{pad}<Grid Name=\"{name}\" GridType=\"Uniform\">");
    if let Some(t) = time {
        let _ = writeln!(out, "{pad}  <Time Value=\"{}\"/>", float(t));
    }
    let e = grid.element_count;
    match grid.uniform {
        Some((kind, nodes)) => {
            let _ = writeln!(
                out,
                "{pad}  <Topology TopologyType=\"{kind}\" NumberOfElements=\"{e}\" NodesPerElement=\"{nodes}\">"
            );
            let _ = writeln!(
                out,
                "{pad}    <DataItem Dimensions=\"{e} {nodes}\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">{h5}:/xdmf/{}/topology</DataItem>",
                grid.degree
            );
        }
        None => {
            let _ = writeln!(
                out,
                "{pad}  <Topology TopologyType=\"Mixed\" NumberOfElements=\"{e}\">"
            );
            let _ = writeln!(
                out,
                "{pad}    <DataItem Dimensions=\"{}\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">{h5}:/xdmf/{}/topology</DataItem>",
                grid.connectivity.len(),
                grid.degree
            );
        }
    }
    let _ = writeln!(out, "{pad}  </Topology>");
    let _ = writeln!(out, "{pad}  <Geometry GeometryType=\"XYZ\">");
    let _ = writeln!(
        out,
        "{pad}    <DataItem Dimensions=\"{} 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:/mesh/vertices</DataItem>",
        run.complex.cell_count(0)
    );
    let _ = writeln!(out, "{pad}  </Geometry>");
    if let Some(s) = run.steps.get(step) {
        for c in &s.cochains {
            let Some(at) = center(grid, n, c) else {
                continue;
            };
            let (center_name, len) = match at {
                Center::Node => ("Node", run.complex.cell_count(0)),
                Center::Cell => ("Cell", e),
            };
            let _ = writeln!(
                out,
                "{pad}  <Attribute Name=\"{}\" AttributeType=\"Scalar\" Center=\"{center_name}\">",
                escape(&c.name)
            );
            let _ = writeln!(
                out,
                "{pad}    <DataItem Dimensions=\"{len}\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:{}</DataItem>",
                escape(&attribute_path(grid, step, c, at))
            );
            let _ = writeln!(out, "{pad}  </Attribute>");
        }
    }
    let _ = writeln!(out, "{pad}</Grid>");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{Provenance, Step};

    #[test]
    fn a_time_series_gives_one_temporal_collection_per_grid_document() {
        let k = hasse_complex::generate::rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let step = |t: f64| Step {
            time: t,
            cochains: vec![
                Cochain::new("u", 0, vec![t; 4]),
                Cochain::new("flux", 1, vec![t; 4]),
            ],
        };
        let run = RunOutput {
            complex: &k,
            steps: vec![step(0.0), step(0.25)],
            provenance: Provenance::new(serde_json::Value::Null),
        };
        let grids = grids(&run).unwrap();
        assert_eq!(grids.iter().map(|g| g.degree).collect::<Vec<_>>(), [2, 1]);
        assert_eq!(grid_name(&grids[1], 2), "edges");

        let cells = document(&run, &grids[0], "a&b.h5");
        assert_eq!(cells.matches("CollectionType=\"Temporal\"").count(), 1);
        assert!(cells
            .contains("<Grid Name=\"cells\" GridType=\"Collection\" CollectionType=\"Temporal\">"));
        assert_eq!(cells.matches("<Time Value=\"0.0\"/>").count(), 1);
        assert_eq!(cells.matches("<Time Value=\"0.25\"/>").count(), 1);
        // Point data on the top grid only, edge data on the edge grid only.
        assert_eq!(
            cells
                .matches("Name=\"u\" AttributeType=\"Scalar\" Center=\"Node\"")
                .count(),
            2
        );
        assert!(!cells.contains("flux"));
        assert_eq!(cells.matches("<Grid ").count(), 1 + 2);

        let edges = document(&run, &grids[1], "a&b.h5");
        assert!(edges
            .contains("<Grid Name=\"edges\" GridType=\"Collection\" CollectionType=\"Temporal\">"));
        assert_eq!(
            edges
                .matches("Name=\"flux\" AttributeType=\"Scalar\" Center=\"Cell\"")
                .count(),
            2
        );
        assert!(!edges.contains("Name=\"u\""));
        assert!(edges.contains("a&amp;b.h5:/steps/1/flux"));
        assert!(edges.contains(
            "<Topology TopologyType=\"Polyline\" NumberOfElements=\"4\" NodesPerElement=\"2\">"
        ));
        assert_eq!(edges.matches("<Grid ").count(), 1 + 2);
        assert_eq!(edges.matches("</Grid>").count(), 1 + 2);
    }

    #[test]
    fn one_step_gives_plain_uniform_grids() {
        let k = hasse_complex::generate::rectangle(2, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let run = RunOutput {
            complex: &k,
            steps: vec![Step {
                time: 0.0,
                cochains: vec![
                    Cochain::new("p", 2, vec![1.0, 2.0]),
                    Cochain::new("q", 1, vec![0.5; 7]),
                ],
            }],
            provenance: Provenance::new(serde_json::Value::Null),
        };
        let grids = grids(&run).unwrap();
        let text = document(&run, &grids[0], "r.h5");
        assert_eq!(text.matches("<Grid ").count(), 1);
        assert!(!text.contains("Collection"));
        assert!(!text.contains("<Time"));
        assert!(!text.contains("Name=\"q\""));
        assert!(text.contains("<DataItem Dimensions=\"2 4\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">r.h5:/xdmf/2/topology</DataItem>"));
        // 2×1 quads have 7 edges: 2 rows of 2 horizontal ones and 3 vertical ones.
        let edges = document(&run, &grids[1], "r.h5");
        assert_eq!(edges.matches("<Grid ").count(), 1);
        assert!(!edges.contains("Collection"));
        assert!(edges.contains("<DataItem Dimensions=\"7\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">r.h5:/steps/0/q</DataItem>"));
        assert!(!edges.contains("Name=\"p\""));
    }
}
