//! The output files read by real clients: `tests/python/check_output.py`
//! opens them with h5py and meshio (`meshio.read` on every file of a
//! steady run, the main `<stem>.xdmf` and the `<stem>.edges.xdmf` of edge
//! cochains; `meshio.xdmf.TimeSeriesReader` on both files of a time
//! series) and compares with the values this test computes from analytic
//! formulas. A series whose mesh changes (`write_mesh_series`) is read
//! with h5py step by step, its XDMF files are parsed with `xml.etree` to
//! check that grid k points at step k's mesh, `meshio.read` opens each
//! level's own files (`<stem>.level-<k>[.edges].xdmf`) with that level's
//! mesh and fields, and meshio's `TimeSeriesReader` refuses the series.
//!
//! The files are written with `[output] complex = "full"`, whose every
//! M_p and ∂_p the script compares (the default layout is read by
//! `tests/python/check_run.py` after a `hasse run`).
//!
//! Python runs in a private venv at `<target>/pyenv` (see
//! `tests/common/pyenv.rs`). Without network the test fails under `CI` and is
//! skipped loudly elsewhere.

use hasse_complex::generate::{box3, kuhn, rectangle, uniform_axis};
use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::frontend::output::{
    write_mesh_series_with, write_run_with, Cochain, ComplexLayout, MeshStep, Provenance,
    RunOutput, SeriesOutput, Step,
};
use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;

fn padded(k: &Complex) -> Vec<[f64; 3]> {
    (0..k.cell_count(0))
        .map(|v| {
            let mut p = [0.0; 3];
            p[..k.embedding_dim()].copy_from_slice(k.vertices().point(v));
            p
        })
        .collect()
}

/// u(x, y, z) = x + 2y + 3z at the vertices.
fn linear(k: &Complex) -> Vec<f64> {
    padded(k)
        .iter()
        .map(|p| p[0] + 2.0 * p[1] + 3.0 * p[2])
        .collect()
}

/// Cell-centred analytic values: 10 + 0.5 i on cell i.
fn per_cell(k: &Complex, p: usize) -> Vec<f64> {
    (0..k.cell_count(p))
        .map(|i| 10.0 + 0.5 * i as f64)
        .collect()
}

fn edge_series(k: &Complex, t: f64) -> Vec<f64> {
    per_edge(k).iter().map(|q| q + 2.0 * t).collect()
}

fn provenance() -> Provenance {
    Provenance {
        case_text: Some("[mesh]\n".into()),
        case_path: None,
        hasse_version: env!("CARGO_PKG_VERSION").into(),
        report: json!({"case": "python"}),
    }
}

/// Edge values of the cases with an edge cochain: 0.25 (i + 1) on edge i,
/// so no two edges agree and a reordering would show.
fn per_edge(k: &Complex) -> Vec<f64> {
    (0..k.cell_count(1))
        .map(|i| 0.25 * (i + 1) as f64)
        .collect()
}

/// Write one steady case and describe what a reader must find in it; with
/// `edges = Some(count)` (the edge count worked out by hand), also an edge
/// cochain `q` that must land in `<name>.edges.xdmf` and leave the main
/// file readable by `meshio.read`.
fn steady_case(
    dir: &Path,
    name: &str,
    k: &Complex,
    cell_counts: Value,
    split_cells: bool,
    edges: Option<usize>,
) -> Value {
    let n = k.dim();
    let u = linear(k);
    let c = per_cell(k, n);
    let mut cochains = vec![
        Cochain::new("u", 0, u.clone()),
        Cochain::new("c", n, c.clone()),
    ];
    if edges.is_some() {
        cochains.push(Cochain::new("q", 1, per_edge(k)));
    }
    let run = RunOutput {
        complex: k,
        steps: vec![Step {
            time: 0.0,
            cochains,
        }],
        provenance: provenance(),
    };
    let files = write_run_with(&dir.join(name), &run, ComplexLayout::Full).unwrap();
    let mut case = describe(name, k, &files.hdf5, &files.xdmf, &[0.0], cell_counts);
    case["datasets"] = json!({"steps/0/u": u, "steps/0/c": c});
    case["point_data"] = json!({ "u": u });
    case["cell_data"] = json!({ "c": c });
    if split_cells {
        case["cells_of"] = json!(n);
    }
    if let Some(count) = edges {
        assert_eq!(files.extra_xdmf, [dir.join(format!("{name}.edges.xdmf"))]);
        case["edges"] = json!({
            "xdmf": files.extra_xdmf[0],
            "count": count,
            "steps": [{ "q": per_edge(k) }],
        });
    } else {
        assert!(files.extra_xdmf.is_empty());
    }
    case
}

fn describe(
    name: &str,
    k: &Complex,
    h5: &Path,
    xdmf: &Path,
    times: &[f64],
    cell_counts: Value,
) -> Value {
    let shapes: serde_json::Map<String, Value> = (1..=k.dim())
        .map(|p| (p.to_string(), json!([k.cell_count(p - 1), k.cell_count(p)])))
        .collect();
    json!({
        "name": name,
        "h5": h5,
        "xdmf": xdmf,
        "dim": k.dim(),
        "vertices": padded(k),
        "boundary_shapes": shapes,
        "times": times,
        "cell_counts": cell_counts,
        "hasse_version": env!("CARGO_PKG_VERSION"),
        "report": {"case": "python"},
    })
}

fn prisms() -> Complex {
    let v = Vertices::from_points(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
    ])
    .unwrap();
    let prism = |a: usize, b: usize, c: usize| {
        vec![
            vec![a, b, c],
            vec![a + 4, b + 4, c + 4],
            vec![a, b, b + 4, a + 4],
            vec![b, c, c + 4, b + 4],
            vec![c, a, a + 4, c + 4],
        ]
    };
    Complex::build(v, TopCells::polyhedra([prism(0, 1, 2), prism(0, 2, 3)])).unwrap()
}

#[test]
fn h5py_and_meshio_read_the_output() {
    let Some(python) = crate::pyenv::python_or_skip("output_python") else {
        return;
    };
    let dir = crate::scratch::Scratch::new("output_python");

    let quad = rectangle(3, 2, [0.0, 1.5], [0.0, 1.0]).unwrap();
    let x = uniform_axis(2, 0.0, 1.0).unwrap();
    let tri = kuhn(&[x.clone(), x]).unwrap();
    let hex = box3(2, 2, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 0.5]).unwrap();
    let prisms = prisms();
    let mut cases = vec![
        steady_case(&dir, "quad", &quad, json!({"quad": 6}), false, None),
        steady_case(&dir, "tri", &tri, json!({"triangle": 8}), false, None),
        steady_case(&dir, "hex", &hex, json!({"hexahedron": 4}), false, None),
        // Each prism is three tetrahedra (the cone from its lowest vertex).
        steady_case(&dir, "prisms", &prisms, json!({"tetra": 6}), true, None),
        // The 3×2 quads with an edge cochain: the main file must still be one
        // uniform grid, the 3·3 + 4·2 = 17 edges in quad-edges.edges.xdmf.
        steady_case(
            &dir,
            "quad-edges",
            &quad,
            json!({"quad": 6}),
            false,
            Some(17),
        ),
        // The 2×2 Kuhn grid: 2·3 + 3·2 axis edges and 4 diagonals.
        steady_case(
            &dir,
            "tri-edges",
            &tri,
            json!({"triangle": 8}),
            false,
            Some(16),
        ),
    ];

    // Two levels of u(t) = (1 + t)(x + 2y), with an edge cochain
    // q(t) = 0.25 (i + 1) + 2t that lives in series.edges.xdmf.
    let times = [0.0, 0.75];
    let steps: Vec<Step> = times
        .iter()
        .map(|&t| Step {
            time: t,
            cochains: vec![
                Cochain::new(
                    "u",
                    0,
                    linear(&quad).iter().map(|u| (1.0 + t) * u).collect(),
                ),
                Cochain::new("c", 2, per_cell(&quad, 2).iter().map(|c| c + t).collect()),
                Cochain::new("q", 1, edge_series(&quad, t)),
            ],
        })
        .collect();
    let run = RunOutput {
        complex: &quad,
        steps,
        provenance: provenance(),
    };
    let files = write_run_with(&dir.join("series"), &run, ComplexLayout::Full).unwrap();
    let mut series = describe(
        "series",
        &quad,
        &files.hdf5,
        &files.xdmf,
        &times,
        json!({"quad": 6}),
    );
    let expected: Vec<Value> = times
        .iter()
        .map(|&t| {
            json!({
                "point_data": {"u": linear(&quad).iter().map(|u| (1.0 + t) * u).collect::<Vec<_>>()},
                "cell_data": {"c": per_cell(&quad, 2).iter().map(|c| c + t).collect::<Vec<_>>()},
            })
        })
        .collect();
    series["steps"] = json!(expected);
    series["datasets"] = json!({ "steps/1/q": edge_series(&quad, 0.75) });
    assert_eq!(files.extra_xdmf, [dir.join("series.edges.xdmf")]);
    series["edges"] = json!({
        "xdmf": files.extra_xdmf[0],
        "count": 17,
        "steps": times.iter().map(|&t| json!({ "q": edge_series(&quad, t) })).collect::<Vec<_>>(),
    });
    cases.push(series);

    let mesh_series = vec![mesh_series_case(&dir)];

    let manifest = dir.join("manifest.json");
    std::fs::write(
        &manifest,
        json!({ "cases": cases, "mesh_series": mesh_series }).to_string(),
    )
    .unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/python/check_output.py");
    let out = Command::new(&python)
        .arg(&script)
        .arg(&manifest)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "check_output.py failed:\n{stdout}\n{stderr}"
    );
    // One line per case (seven) and one per edges file read back (two
    // steady cases and the series), then for the series whose mesh
    // changes one line each for h5py, the two XDMF files and meshio.
    let ok: Vec<&str> = stdout.lines().filter(|l| l.starts_with("ok ")).collect();
    let changing = |l: &&&str| l.contains("mesh series");
    assert_eq!(
        ok.iter()
            .filter(|l| !l.contains("edges file") && !changing(l))
            .count(),
        7
    );
    assert_eq!(
        ok.iter()
            .filter(|l| l.contains("edges file") && !changing(l))
            .count(),
        3
    );
    assert_eq!(ok.iter().filter(changing).count(), 4);
}

/// A series whose mesh changes: the 2×2 and 4×4 quads, then the 4×4 Kuhn
/// triangulation, with u = (1 + t)(x + 2y + 3z) on vertices, the edge
/// values 0.25 (i + 1) + 2t and the cell values 10 + 0.5 i + t. The
/// manifest lists, per step, what h5py must find under `/steps/<k>` and
/// what grid k of each XDMF file must point at.
fn mesh_series_case(dir: &Path) -> Value {
    let x = uniform_axis(4, 0.0, 1.0).unwrap();
    let meshes = [
        (
            0.0,
            rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            "Quadrilateral",
            4,
        ),
        (
            0.5,
            rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            "Quadrilateral",
            4,
        ),
        (1.5, kuhn(&[x.clone(), x]).unwrap(), "Triangle", 3),
    ];
    let values = |k: &Complex, t: f64| {
        (
            linear(k).iter().map(|u| (1.0 + t) * u).collect::<Vec<_>>(),
            edge_series(k, t),
            per_cell(k, 2).iter().map(|c| c + t).collect::<Vec<_>>(),
        )
    };
    let series = SeriesOutput {
        steps: meshes
            .iter()
            .map(|(t, k, _, _)| {
                let (u, q, c) = values(k, *t);
                MeshStep {
                    time: *t,
                    complex: k,
                    cochains: vec![
                        Cochain::new("u", 0, u),
                        Cochain::new("q", 1, q),
                        Cochain::new("c", 2, c),
                    ],
                }
            })
            .collect(),
        provenance: provenance(),
    };
    let files = write_mesh_series_with(&dir.join("growing"), &series, ComplexLayout::Full).unwrap();
    assert_eq!(files.extra_xdmf, [dir.join("growing.edges.xdmf")]);
    // Each level alone: its top cells and its edges.
    let expected_levels: Vec<Vec<_>> = (0..meshes.len())
        .map(|k| {
            vec![
                dir.join(format!("growing.level-{k}.xdmf")),
                dir.join(format!("growing.level-{k}.edges.xdmf")),
            ]
        })
        .collect();
    assert_eq!(files.levels, expected_levels);
    let steps: Vec<Value> = meshes
        .iter()
        .map(|(t, k, kind, nodes)| {
            let (u, q, c) = values(k, *t);
            let shapes: serde_json::Map<String, Value> = (1..=k.dim())
                .map(|p| (p.to_string(), json!([k.cell_count(p - 1), k.cell_count(p)])))
                .collect();
            json!({
                "vertices": padded(k),
                "cell_counts": (0..=k.dim()).map(|p| k.cell_count(p)).collect::<Vec<_>>(),
                "boundary_shapes": shapes,
                "fields": {"u": u, "q": q, "c": c},
                "field_dims": {"u": 0, "q": 1, "c": 2},
                "top_type": kind,
                "top_nodes": nodes,
            })
        })
        .collect();
    json!({
        "name": "growing",
        "h5": files.hdf5,
        "xdmf": files.xdmf,
        "edges_xdmf": files.extra_xdmf[0],
        "levels": files.levels,
        "dim": 2,
        "times": meshes.iter().map(|m| m.0).collect::<Vec<_>>(),
        "steps": steps,
        "hasse_version": env!("CARGO_PKG_VERSION"),
    })
}
