//! The XDMF 3 texts: one document per cochain degree grid, each pointing
//! into the same h5 file.

use super::topology::{grid_topology, GridTopology, Polygons};
use super::{Cochain, Levels, MeshAt, OutputError};
use std::fmt::Write;

/// The cochain degrees that get a grid (and a document), top cells first:
/// the top degree n always (it also carries the point data), then 1 ≤ p < n
/// in increasing order when a cochain of some level lives there.
pub(crate) fn degrees(levels: &Levels) -> Vec<usize> {
    let n = levels.dim();
    let used = |p: usize| {
        levels
            .steps
            .iter()
            .any(|s| s.cochains.iter().any(|c| c.dim == p))
    };
    let mut degrees = vec![n];
    degrees.extend((1..n).filter(|&p| used(p)));
    degrees
}

/// The grids of every mesh: `grids[m][i]` is the grid of the cells of
/// degree `degrees[i]` of `levels.meshes[m]`. In a series whose mesh
/// changes, polygons of five or more vertices are written as triangles:
/// each level has a file that `meshio.read` must open (see
/// [`level_document`]), and meshio reads no `Polygon` cell. A one-mesh
/// output keeps its polygons, as it always has.
pub(crate) fn grids(
    levels: &Levels,
    degrees: &[usize],
) -> Result<Vec<Vec<GridTopology>>, OutputError> {
    let polygons = if levels.mesh_changes {
        Polygons::Triangulate
    } else {
        Polygons::Keep
    };
    levels
        .meshes
        .iter()
        .map(|mesh| {
            degrees
                .iter()
                .map(|&p| grid_topology(mesh.complex, p, polygons))
                .collect()
        })
        .collect()
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
/// its copy expanded to the grid's elements when cells were split (kept
/// with the grid's other arrays under the mesh's XDMF group).
pub(crate) fn attribute_path(
    mesh: &MeshAt,
    grid: &GridTopology,
    step: usize,
    c: &Cochain,
    at: Center,
) -> String {
    match (at, &grid.cell_ids) {
        (Center::Cell, Some(_)) => format!(
            "/{}/{}/steps/{step}/{}",
            mesh.xdmf_group, grid.degree, c.name
        ),
        _ => format!("/steps/{step}/{}", c.name),
    }
}

/// Name of the grid of degree p in the XDMF text, also the middle part of
/// the file name `<stem>.<name>.xdmf` of a lower-degree grid.
pub(crate) fn grid_name(degree: usize, top_dim: usize) -> &'static str {
    match degree {
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

/// The h5 files an XDMF document reads, as paths relative to it.
pub(crate) struct Files<'a> {
    /// The file holding the mesh (`<group>/vertices`) and the XDMF arrays
    /// (`<xdmf_group>/<p>/topology`).
    pub mesh: &'a str,
    /// The file holding the cochains of level k, when not the mesh file;
    /// its levels are a time series even while there is only one of them.
    pub level: Option<&'a dyn Fn(usize) -> String>,
}

impl<'a> Files<'a> {
    /// Everything in one file: the layout of [`super::write_run`].
    pub fn one(h5_name: &'a str) -> Self {
        Files {
            mesh: h5_name,
            level: None,
        }
    }
}

const HEADER: &str =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n";
const FOOTER: &str = "  </Domain>\n</Xdmf>\n";

/// The XDMF document of the grid of degree `degrees[i]` (its grids are
/// `grids[m][i]`, see [`grids`]), reading `files`. One grid per document,
/// because `meshio.read` accepts only a domain holding a single uniform
/// grid and `TimeSeriesReader` only the last temporal collection: a plain
/// uniform grid for at most one time level of a single-file output, a
/// temporal collection otherwise, whose k-th grid takes its geometry and
/// topology from the mesh of level k.
pub(crate) fn document(
    levels: &Levels,
    grids: &[Vec<GridTopology>],
    i: usize,
    files: &Files,
) -> String {
    let mut out = String::from(HEADER);
    let grid = Grid {
        levels,
        grids,
        i,
        mesh_h5: escape(files.mesh),
        level_h5: files.level,
    };
    match (levels.steps.as_slice(), files.level) {
        ([], _) => grid.uniform(&mut out, 0, None, false, 4),
        ([only], None) => grid.uniform(&mut out, only.mesh, Some(0), false, 4),
        (steps, _) => {
            let name = grid_name(grids[0][i].degree, levels.dim());
            let _ = writeln!(
                out,
                "    <Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Temporal\">"
            );
            for (k, step) in steps.iter().enumerate() {
                grid.uniform(&mut out, step.mesh, Some(k), true, 6);
            }
            out.push_str("    </Grid>\n");
        }
    }
    out.push_str(FOOTER);
    out
}

/// The XDMF document of level `k` alone on the grid of degree
/// `degrees[i]`: one plain uniform grid (level k's mesh and fields),
/// without `<Time>`, which `meshio.read` rejects ("Unknown section"). The
/// file a reader without support for a changing mesh opens, one level at a
/// time.
pub(crate) fn level_document(
    levels: &Levels,
    grids: &[Vec<GridTopology>],
    i: usize,
    k: usize,
    files: &Files,
) -> String {
    let mut out = String::from(HEADER);
    let grid = Grid {
        levels,
        grids,
        i,
        mesh_h5: escape(files.mesh),
        level_h5: files.level,
    };
    let mesh = levels.steps.get(k).map_or(0, |s| s.mesh);
    grid.uniform(&mut out, mesh, Some(k), false, 4);
    out.push_str(FOOTER);
    out
}

/// Shortest text that parses back to the same f64 (Rust's `Display`).
fn float(x: f64) -> String {
    format!("{x:?}")
}

/// What every uniform grid of one document shares.
struct Grid<'a> {
    levels: &'a Levels<'a>,
    grids: &'a [Vec<GridTopology>],
    /// Index of the document's degree in `degrees`.
    i: usize,
    /// The escaped name of the h5 file with the meshes.
    mesh_h5: String,
    /// The (unescaped) name of the h5 file of level k, if not the mesh file.
    level_h5: Option<&'a dyn Fn(usize) -> String>,
}

impl Grid<'_> {
    /// The uniform grid of mesh `m`, with the attributes of level `step`
    /// (none for the bare mesh) and its `<Time>` when `timed`.
    fn uniform(&self, out: &mut String, m: usize, step: Option<usize>, timed: bool, indent: usize) {
        let (levels, h5) = (self.levels, self.mesh_h5.as_str());
        let mesh = &levels.meshes[m];
        let grid = &self.grids[m][self.i];
        let n = levels.dim();
        let pad = " ".repeat(indent);
        let name = grid_name(grid.degree, n);
        // The grids of a collection whose mesh changes leave `GridType` at
        // its default, Uniform: meshio's `TimeSeriesReader` looks for a grid
        // that names its type and, finding none, refuses the file ("Couldn't
        // find the mesh grid") instead of pairing every level's fields with
        // level 0's mesh. ParaView's XDMF readers follow the default.
        if timed && levels.mesh_changes {
            let _ = writeln!(out, "{pad}<Grid Name=\"{name}\">");
        } else {
            let _ = writeln!(out, "{pad}<Grid Name=\"{name}\" GridType=\"Uniform\">");
        }
        let level = step.and_then(|k| levels.steps.get(k).map(|s| (k, s)));
        if let (true, Some((_, s))) = (timed, level) {
            let _ = writeln!(out, "{pad}  <Time Value=\"{}\"/>", float(s.time));
        }
        let e = grid.element_count;
        let topology = format!("{h5}:/{}/{}/topology", mesh.xdmf_group, grid.degree);
        match grid.uniform {
            Some((kind, nodes)) => {
                let _ = writeln!(
                    out,
                    "{pad}  <Topology TopologyType=\"{kind}\" NumberOfElements=\"{e}\" NodesPerElement=\"{nodes}\">"
                );
                let _ = writeln!(
                    out,
                    "{pad}    <DataItem Dimensions=\"{e} {nodes}\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">{topology}</DataItem>"
                );
            }
            None => {
                let _ = writeln!(
                    out,
                    "{pad}  <Topology TopologyType=\"Mixed\" NumberOfElements=\"{e}\">"
                );
                let _ = writeln!(
                    out,
                    "{pad}    <DataItem Dimensions=\"{}\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">{topology}</DataItem>",
                    grid.connectivity.len(),
                );
            }
        }
        let _ = writeln!(out, "{pad}  </Topology>");
        let _ = writeln!(out, "{pad}  <Geometry GeometryType=\"XYZ\">");
        let _ = writeln!(
            out,
            "{pad}    <DataItem Dimensions=\"{} 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:/{}/vertices</DataItem>",
            mesh.complex.cell_count(0),
            mesh.group
        );
        let _ = writeln!(out, "{pad}  </Geometry>");
        if let Some((k, s)) = level {
            let level_h5 = match self.level_h5 {
                Some(name) => escape(&name(k)),
                None => h5.to_string(),
            };
            for c in s.cochains {
                let Some(at) = center(grid, n, c) else {
                    continue;
                };
                let (center_name, len) = match at {
                    Center::Node => ("Node", mesh.complex.cell_count(0)),
                    Center::Cell => ("Cell", e),
                };
                let _ = writeln!(
                    out,
                    "{pad}  <Attribute Name=\"{}\" AttributeType=\"Scalar\" Center=\"{center_name}\">",
                    escape(&c.name)
                );
                let _ = writeln!(
                    out,
                    "{pad}    <DataItem Dimensions=\"{len}\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">{level_h5}:{}</DataItem>",
                    escape(&attribute_path(mesh, grid, k, c, at))
                );
                let _ = writeln!(out, "{pad}  </Attribute>");
            }
        }
        let _ = writeln!(out, "{pad}</Grid>");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontend::output::{
        ComplexLayout, MeshStep, Provenance, RunOutput, SeriesOutput, Step,
    };

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
        let levels = Levels::of_run(&run, ComplexLayout::Minimal);
        let degrees = degrees(&levels);
        assert_eq!(degrees, [2, 1]);
        let grids = grids(&levels, &degrees).unwrap();
        assert_eq!(grids.len(), 1);
        assert_eq!(
            grids[0].iter().map(|g| g.degree).collect::<Vec<_>>(),
            [2, 1]
        );
        assert_eq!(grid_name(1, 2), "edges");

        let cells = document(&levels, &grids, 0, &Files::one("a&b.h5"));
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

        let edges = document(&levels, &grids, 1, &Files::one("a&b.h5"));
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
        let levels = Levels::of_run(&run, ComplexLayout::Minimal);
        let grids = grids(&levels, &degrees(&levels)).unwrap();
        let text = document(&levels, &grids, 0, &Files::one("r.h5"));
        assert_eq!(text.matches("<Grid ").count(), 1);
        assert!(!text.contains("Collection"));
        assert!(!text.contains("<Time"));
        assert!(!text.contains("Name=\"q\""));
        assert!(text.contains("<DataItem Dimensions=\"2 4\" DataType=\"Int\" Precision=\"8\" Format=\"HDF\">r.h5:/xdmf/2/topology</DataItem>"));
        // 2×1 quads have 7 edges: 2 rows of 2 horizontal ones and 3 vertical ones.
        let edges = document(&levels, &grids, 1, &Files::one("r.h5"));
        assert_eq!(edges.matches("<Grid ").count(), 1);
        assert!(!edges.contains("Collection"));
        assert!(edges.contains("<DataItem Dimensions=\"7\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">r.h5:/steps/0/q</DataItem>"));
        assert!(!edges.contains("Name=\"p\""));
    }

    #[test]
    fn series_grids_read_their_own_step_mesh() {
        let coarse = hasse_complex::generate::rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let fine = hasse_complex::generate::rectangle(2, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let one = SeriesOutput {
            steps: vec![MeshStep {
                time: 3.0,
                complex: &fine,
                cochains: vec![Cochain::new("c", 2, vec![1.0, 2.0])],
            }],
            provenance: Provenance::new(serde_json::Value::Null),
        };
        let levels = Levels::of_series(&one, ComplexLayout::Minimal);
        let meshes = grids(&levels, &degrees(&levels)).unwrap();
        let text = document(&levels, &meshes, 0, &Files::one("s.h5"));
        // One step: a plain uniform grid, still on the step's own mesh.
        assert!(!text.contains("Collection") && !text.contains("<Time"));
        assert!(text.contains(">s.h5:/steps/0/mesh/vertices<"));
        assert!(text.contains(">s.h5:/steps/0/mesh/xdmf/2/topology<"));
        assert!(text.contains(">s.h5:/steps/0/c<"));
        assert!(!text.contains(":/mesh/") && !text.contains(":/xdmf/"));

        let two = SeriesOutput {
            steps: vec![
                MeshStep {
                    time: 0.0,
                    complex: &coarse,
                    cochains: vec![],
                },
                MeshStep {
                    time: 1.0,
                    complex: &fine,
                    cochains: vec![],
                },
            ],
            provenance: Provenance::new(serde_json::Value::Null),
        };
        let levels = Levels::of_series(&two, ComplexLayout::Minimal);
        let meshes = grids(&levels, &degrees(&levels)).unwrap();
        assert_eq!(meshes.len(), 2);
        let text = document(&levels, &meshes, 0, &Files::one("s.h5"));
        assert_eq!(text.matches("CollectionType=\"Temporal\"").count(), 1);
        assert!(text.contains("NumberOfElements=\"1\" NodesPerElement=\"4\""));
        assert!(text.contains("NumberOfElements=\"2\" NodesPerElement=\"4\""));
        assert!(text.contains("Dimensions=\"4 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">s.h5:/steps/0/mesh/vertices<"));
        assert!(text.contains("Dimensions=\"6 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">s.h5:/steps/1/mesh/vertices<"));
        assert!(!text.contains("<Attribute"));
    }
}
