//! The files of each level of a series whose mesh changes
//! (`<stem>.level-<k>[.<grid>].xdmf`, written by `write_mesh_series`): what
//! each holds, polygons written as triangles so that meshio reads them, and
//! which files of an earlier output under the same stem are removed.

use crate::scratch::Scratch;
use hasse_complex::generate::rectangle;
use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::frontend::output::{
    write_mesh_series, write_run, Cochain, MeshStep, Provenance, RunOutput, SeriesOutput, Step,
};
use std::path::Path;

/// Open an h5 file without HDF5's file locking: a child process that this
/// test binary spawns (Python, hasse) while another test writes an h5 file
/// inherits that writer's descriptor and lock (see `open` in
/// output_files.rs), and reading needs no lock, nothing else writing these.
fn open(path: &Path) -> hdf5::File {
    hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The unit square as a hexagon (hanging vertices in the middle of its
/// bottom and right sides) and the triangle beside its right side, cut
/// away from a neighbour as SPLIT leaves them.
fn hanging() -> Complex {
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [0.5, 0.0],
        [1.0, 0.0],
        [1.0, 0.5],
        [1.0, 1.0],
        [0.0, 1.0],
        [2.0, 0.0],
    ])
    .unwrap();
    Complex::build(
        v,
        TopCells::polygons([vec![0, 1, 2, 3, 4, 5], vec![2, 6, 3]]),
    )
    .unwrap()
}

fn step(time: f64, complex: &Complex, edges: bool) -> MeshStep<'_> {
    let x: Vec<f64> = (0..complex.cell_count(0))
        .map(|v| complex.vertices().point(v)[0])
        .collect();
    let mut cochains = vec![
        Cochain::new("x", 0, x),
        Cochain::new(
            "c",
            2,
            (0..complex.cell_count(2))
                .map(|i| 10.0 + i as f64)
                .collect(),
        ),
    ];
    if edges {
        cochains.push(Cochain::new("q", 1, vec![0.5; complex.cell_count(1)]));
    }
    MeshStep {
        time,
        complex,
        cochains,
    }
}

#[test]
fn each_level_file_is_one_uniform_grid_of_its_level() {
    let coarse = hanging();
    let fine = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let series = SeriesOutput {
        steps: vec![step(0.0, &coarse, false), step(1.0, &fine, false)],
        provenance: Provenance::new(serde_json::Value::Null),
    };
    let dir = Scratch::new("level-files");
    let files = write_mesh_series(&dir.join("grow"), &series).unwrap();
    assert!(files.extra_xdmf.is_empty());
    assert_eq!(
        files.levels,
        [
            [dir.join("grow.level-0.xdmf")],
            [dir.join("grow.level-1.xdmf")]
        ]
    );
    let level = |k: usize| std::fs::read_to_string(&files.levels[k][0]).unwrap();
    for k in 0..2 {
        let xml = level(k);
        // One grid and no <Time>: `meshio.read` rejects both a collection
        // and a <Time> section.
        assert_eq!(xml.matches("<Grid ").count(), 1, "{xml}");
        assert!(xml.contains("<Grid Name=\"cells\" GridType=\"Uniform\">"));
        assert!(
            !xml.contains("<Time") && !xml.contains("Collection"),
            "{xml}"
        );
        assert!(xml.contains(&format!(">grow.h5:/steps/{k}/mesh/vertices<")));
        assert!(xml.contains(&format!(">grow.h5:/steps/{k}/x<")));
        let other = 1 - k;
        assert!(!xml.contains(&format!("/steps/{other}/")), "{xml}");
    }
    // Level 0's hexagon is four triangles (meshio reads no polygon), its
    // cell value repeated on each through the expanded copy.
    let xml = level(0);
    assert!(
        xml.contains("TopologyType=\"Triangle\" NumberOfElements=\"5\" NodesPerElement=\"3\""),
        "{xml}"
    );
    assert!(
        xml.contains(">grow.h5:/steps/0/mesh/xdmf/2/steps/0/c<"),
        "{xml}"
    );
    let f = open(&files.hdf5);
    let read = |path: &str| f.dataset(path).unwrap();
    assert_eq!(
        read("steps/0/mesh/xdmf/2/cell_ids")
            .read_raw::<u64>()
            .unwrap(),
        [0, 0, 0, 0, 1]
    );
    assert_eq!(
        read("steps/0/mesh/xdmf/2/steps/0/c")
            .read_raw::<f64>()
            .unwrap(),
        [10.0, 10.0, 10.0, 10.0, 11.0]
    );
    // Level 1's quads need nothing of the sort.
    assert!(level(1).contains("TopologyType=\"Quadrilateral\" NumberOfElements=\"4\""));
    assert!(f.dataset("steps/1/mesh/xdmf/2/cell_ids").is_err());
    drop(f);

    // The same complex in a one-mesh run keeps its polygon, as it always
    // has, and has no level files.
    let run = RunOutput {
        complex: &coarse,
        steps: vec![Step {
            time: 0.0,
            cochains: series.steps[0].cochains.clone(),
        }],
        provenance: Provenance::new(serde_json::Value::Null),
    };
    let one = write_run(&dir.join("one"), &run).unwrap();
    assert!(one.levels.is_empty());
    let xml = std::fs::read_to_string(&one.xdmf).unwrap();
    assert!(xml.contains("<Topology TopologyType=\"Mixed\" NumberOfElements=\"2\">"));
    assert!(!names_in(&dir).iter().any(|n| n.starts_with("one.level-")));
}

/// An output under a stem replaces the level files of an earlier one: those
/// of levels or degrees it does not have go, and so do temporaries of
/// them left by a killed writer; files of other stems, or that only look
/// like level files, stay.
#[test]
fn stale_level_files_and_their_temporaries_are_removed() {
    let grids: Vec<Complex> = [1, 2, 4]
        .iter()
        .map(|&m| rectangle(m, m, [0.0, 1.0], [0.0, 1.0]).unwrap())
        .collect();
    let series = |count: usize, edges: bool| SeriesOutput {
        steps: grids[..count]
            .iter()
            .enumerate()
            .map(|(k, g)| step(k as f64, g, edges))
            .collect(),
        provenance: Provenance::new(serde_json::Value::Null),
    };
    let dir = Scratch::new("stale-levels");
    let stem = dir.join("grow");
    write_mesh_series(&stem, &series(3, true)).unwrap();
    assert_eq!(
        names_in(&dir)
            .iter()
            .filter(|n| n.starts_with("grow.level-"))
            .count(),
        6
    );
    // A temporary of a level file whose writer (no such process) was killed,
    // a stale faces file, and names that are not this stem's level files.
    let dead = ".grow.level-5.xdmf.tmp-999999999-0.xdmf";
    let kept = [
        "grow.level-x.xdmf",
        "grow.level-1.cells.xdmf",
        "other.level-0.xdmf",
    ];
    for name in kept.iter().chain(&[dead, "grow.level-7.faces.xdmf"]) {
        std::fs::write(dir.join(name), "").unwrap();
    }

    let files = write_mesh_series(&stem, &series(2, false)).unwrap();
    assert_eq!(
        files.levels,
        [
            [dir.join("grow.level-0.xdmf")],
            [dir.join("grow.level-1.xdmf")]
        ]
    );
    let mut expected: Vec<String> = [
        "grow.h5",
        "grow.level-0.xdmf",
        "grow.level-1.xdmf",
        "grow.xdmf",
    ]
    .iter()
    .chain(&kept)
    .map(|n| n.to_string())
    .collect();
    expected.sort();
    assert_eq!(names_in(&dir), expected);

    // A one-mesh run under the stem leaves no level file at all.
    let run = RunOutput {
        complex: &grids[0],
        steps: vec![],
        provenance: Provenance::new(serde_json::Value::Null),
    };
    write_run(&stem, &run).unwrap();
    let mut expected: Vec<String> = ["grow.h5", "grow.xdmf"]
        .iter()
        .chain(&kept)
        .map(|n| n.to_string())
        .collect();
    expected.sort();
    assert_eq!(names_in(&dir), expected);
}
