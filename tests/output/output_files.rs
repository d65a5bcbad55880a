//! `output::write_run` read back with the `hdf5` crate: every array is
//! compared exactly with the complex it came from or with the analytic
//! formula the cochain was filled with, the XDMF texts (one file per
//! cochain degree grid) are checked for the grids and topology arrays a
//! reader needs, and failed writes are shown to leave no file behind and an
//! older output untouched.

use crate::scratch::Scratch;
use approx::assert_abs_diff_eq;
use hasse_complex::generate::{box3, kuhn, rectangle, uniform_axis};
use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::frontend::output::{
    write_mesh_series, write_mesh_series_with, write_run, write_run_with, Cochain, ComplexLayout,
    MeshStep, OutputError, OutputFiles, Provenance, RunOutput, SeriesOutput, Step,
};
use hdf5::types::VarLenUnicode;
use sprs::CsMat;
use std::path::Path;

/// This test's scratch directory (not created), removed when the test passes.
fn scratch(name: &str) -> Scratch {
    Scratch::new(&format!("output_files-{name}"))
}

/// Open a file this test wrote, for reading, without HDF5's file lock.
///
/// HDF5 opens files without close-on-exec and locks them with flock(2),
/// whose lock belongs to the open file description. A child process
/// spawned by another test of this binary (output_python runs Python)
/// while one of our writes has its file open inherits the descriptor and
/// keeps the writer's exclusive lock for its whole life, after the writer
/// closed the file and renamed it into place; an ordinary open of the
/// renamed file then fails with "unable to lock file" (EAGAIN). Nothing
/// else writes these files, so reading them unlocked is safe.
fn open(path: &Path) -> hdf5::File {
    hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

fn point(k: &Complex, v: usize) -> [f64; 3] {
    let mut p = [0.0; 3];
    p[..k.embedding_dim()].copy_from_slice(k.vertices().point(v));
    p
}

/// x + 2y − z at every vertex.
fn linear(k: &Complex) -> Vec<f64> {
    (0..k.cell_count(0))
        .map(|v| {
            let p = point(k, v);
            p[0] + 2.0 * p[1] - p[2]
        })
        .collect()
}

fn index_cochain(k: &Complex, p: usize) -> Vec<f64> {
    (0..k.cell_count(p)).map(|i| i as f64).collect()
}

fn run<'a>(k: &'a Complex, steps: Vec<Step>) -> RunOutput<'a> {
    RunOutput {
        complex: k,
        steps,
        provenance: Provenance {
            case_text: Some("[mesh]\nkind = \"test\" # ünïcode\n".into()),
            case_path: Some("cases/test.toml".into()),
            hasse_version: "9.9.9-test".into(),
            report: serde_json::json!({"iterations": 7, "residual": 1e-12}),
        },
    }
}

fn steady(k: &Complex, cochains: Vec<Cochain>) -> RunOutput<'_> {
    run(
        k,
        vec![Step {
            time: 0.0,
            cochains,
        }],
    )
}

fn read_u64(f: &hdf5::File, path: &str) -> Vec<u64> {
    f.dataset(path).unwrap().read_raw::<u64>().unwrap()
}

fn read_f64(f: &hdf5::File, path: &str) -> Vec<f64> {
    f.dataset(path).unwrap().read_raw::<f64>().unwrap()
}

fn read_i64(f: &hdf5::File, path: &str) -> Vec<i64> {
    f.dataset(path).unwrap().read_raw::<i64>().unwrap()
}

fn str_attr(loc: &hdf5::Location, name: &str) -> String {
    loc.attr(name)
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap()
        .as_str()
        .to_string()
}

/// The tests that compare every M_p and ∂_p with the complex write the
/// full layout (`[output] complex = "full"`); `complex_layout.rs` tests
/// the default one.
fn write_full_run(stem: &Path, run: &RunOutput) -> Result<OutputFiles, OutputError> {
    write_run_with(stem, run, ComplexLayout::Full)
}

fn write_full_series(stem: &Path, series: &SeriesOutput) -> Result<OutputFiles, OutputError> {
    write_mesh_series_with(stem, series, ComplexLayout::Full)
}

fn usizes(v: &[u64]) -> Vec<usize> {
    v.iter().map(|&x| x as usize).collect()
}

/// The mesh part of the file equals the complex: coordinates, every M_p and
/// every ∂_p rebuilt as a `CsMat` and compared with `complex.boundary(p)`.
fn check_mesh(f: &hdf5::File, k: &Complex) {
    check_mesh_at(f, "mesh", k);
}

/// [`check_mesh`] for the mesh stored in group `group` (`mesh`, or
/// `steps/<k>/mesh` in a series).
fn check_mesh_at(f: &hdf5::File, group: &str, k: &Complex) {
    let n = k.dim();
    let mesh = f.group(group).unwrap();
    assert_eq!(
        mesh.attr("dim").unwrap().read_scalar::<u64>().unwrap(),
        n as u64
    );
    assert_eq!(
        mesh.attr("complex")
            .unwrap()
            .read_scalar::<VarLenUnicode>()
            .unwrap()
            .as_str(),
        "full"
    );
    let vertices = f.dataset(&format!("{group}/vertices")).unwrap();
    assert_eq!(vertices.shape(), vec![k.cell_count(0), 3]);
    let xyz = vertices.read_raw::<f64>().unwrap();
    for v in 0..k.cell_count(0) {
        assert_eq!(&xyz[3 * v..3 * v + 3], &point(k, v));
    }
    for p in 0..=n {
        let indptr = usizes(&read_u64(f, &format!("{group}/cells/{p}/indptr")));
        let indices = usizes(&read_u64(f, &format!("{group}/cells/{p}/indices")));
        assert_eq!(indptr.len(), k.cell_count(p) + 1);
        for i in 0..k.cell_count(p) {
            assert_eq!(&indices[indptr[i]..indptr[i + 1]], k.cell_vertices(p, i));
        }
    }
    for p in 1..=n {
        let g = format!("{group}/boundary/{p}");
        let shape: Vec<u64> = f
            .group(&g)
            .unwrap()
            .attr("shape")
            .unwrap()
            .read_raw()
            .unwrap();
        let data = f
            .dataset(&format!("{g}/data"))
            .unwrap()
            .read_raw::<i8>()
            .unwrap();
        let m = CsMat::new(
            (shape[0] as usize, shape[1] as usize),
            usizes(&read_u64(f, &format!("{g}/indptr"))),
            usizes(&read_u64(f, &format!("{g}/indices"))),
            data,
        );
        assert_eq!(&m, &**k.boundary(p));
        assert_eq!((m.rows(), m.cols()), (k.cell_count(p - 1), k.cell_count(p)));
    }
    for (name, tag) in k.tags().iter() {
        let ds = f.dataset(&format!("{group}/tags/{name}")).unwrap();
        assert_eq!(usizes(&ds.read_raw::<u64>().unwrap()), tag.cells);
        assert_eq!(
            ds.attr("dim").unwrap().read_scalar::<u64>().unwrap(),
            tag.dim as u64
        );
    }
}

fn shoelace(points: &[[f64; 3]]) -> f64 {
    (0..points.len())
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % points.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

fn vol6(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let (u, v, w) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
        [d[0] - a[0], d[1] - a[1], d[2] - a[2]],
    );
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
        + u[2] * (v[0] * w[1] - v[1] * w[0])
}

/// Tags are balanced and every opened element is closed in order.
fn assert_well_formed(xml: &str) {
    assert!(xml.starts_with("<?xml version=\"1.0\""));
    let mut stack: Vec<String> = Vec::new();
    let mut rest = xml;
    while let Some(start) = rest.find('<') {
        let end = rest[start..].find('>').expect("unclosed tag") + start;
        let tag = &rest[start + 1..end];
        rest = &rest[end + 1..];
        if tag.starts_with('?') {
            continue;
        }
        let name: String = tag
            .trim_start_matches('/')
            .chars()
            .take_while(|c| c.is_alphanumeric())
            .collect();
        if tag.starts_with('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.as_str()),
                "mismatched </{name}>"
            );
        } else if !tag.ends_with('/') {
            stack.push(name);
        }
        assert!(!tag.contains('<'), "'<' inside a tag");
    }
    assert!(stack.is_empty(), "unclosed elements {stack:?}");
}

#[test]
fn quad_grid_round_trips_exactly() {
    let k = rectangle(3, 2, [0.0, 3.0], [0.0, 2.0]).unwrap();
    let dir = scratch("quad");
    let u = Cochain::new("u", 0, linear(&k))
        .with_units("K")
        .with_method("fe")
        .with_description("x + 2y");
    let q = Cochain::new("flux", 1, index_cochain(&k, 1));
    let c = Cochain::new("cell id", 2, index_cochain(&k, 2));
    let files = write_full_run(&dir.join("quad"), &steady(&k, vec![u, q, c])).unwrap();
    assert_eq!(files.hdf5, dir.join("quad.h5"));
    assert_eq!(files.xdmf, dir.join("quad.xdmf"));
    assert_eq!(files.extra_xdmf, [dir.join("quad.edges.xdmf")]);
    assert_eq!(files_in(&dir), ["quad.edges.xdmf", "quad.h5", "quad.xdmf"]);

    let f = open(&files.hdf5);
    check_mesh(&f, &k);
    assert_eq!(
        f.attr("step_count").unwrap().read_scalar::<u64>().unwrap(),
        1
    );
    assert_eq!(f.attr("times").unwrap().read_raw::<f64>().unwrap(), [0.0]);
    // One mesh for all steps: the version-1 layout, flagged for readers.
    let root_u64 = |name: &str| f.attr(name).unwrap().read_scalar::<u64>().unwrap();
    assert_eq!(root_u64("mesh_changes"), 0);
    assert_eq!(root_u64("format_version"), 1);
    assert!(f.group("steps/0/mesh").is_err());
    let step = f.group("steps/0").unwrap();
    assert_eq!(
        step.attr("time").unwrap().read_scalar::<f64>().unwrap(),
        0.0
    );
    let xyz = read_f64(&f, "mesh/vertices");
    let expected: Vec<f64> = xyz.chunks(3).map(|p| p[0] + 2.0 * p[1]).collect();
    assert_eq!(read_f64(&f, "steps/0/u"), expected);
    // Vertex 11 is the corner (3, 2) in x-fastest numbering: 3 + 2·2.
    assert_eq!(read_f64(&f, "steps/0/u")[11], 7.0);
    let u = f.dataset("steps/0/u").unwrap();
    assert_eq!(u.attr("dim").unwrap().read_scalar::<u64>().unwrap(), 0);
    assert_eq!(str_attr(&u, "units"), "K");
    assert_eq!(str_attr(&u, "method"), "fe");
    assert_eq!(str_attr(&u, "description"), "x + 2y");
    assert_eq!(
        read_f64(&f, "steps/0/cell id"),
        [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    );
    let flux = f.dataset("steps/0/flux").unwrap();
    assert!(flux.attr("units").is_err());
    assert_eq!(flux.read_raw::<f64>().unwrap().len(), 17);

    // Tags are compared by `check_mesh`; the 3×2 grid has 10 boundary edges.
    assert_eq!(read_u64(&f, "mesh/tags/boundary").len(), 10);

    let prov = f.group("provenance").unwrap();
    assert_eq!(str_attr(&prov, "hasse_version"), "9.9.9-test");
    assert_eq!(str_attr(&prov, "case_path"), "cases/test.toml");
    let written = str_attr(&prov, "written_at");
    assert_eq!(written.len(), 20);
    assert!(written.ends_with('Z') && written.as_bytes()[10] == b'T');
    let text = f
        .dataset("provenance/case_text")
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap();
    assert_eq!(text.as_str(), "[mesh]\nkind = \"test\" # ünïcode\n");
    let report = f
        .dataset("provenance/report")
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap();
    let report: serde_json::Value = serde_json::from_str(report.as_str()).unwrap();
    assert_eq!(report["iterations"], 7);

    // Quads are cyclic and counter-clockwise (positive area 1 each).
    let quads = f.dataset("xdmf/2/topology").unwrap();
    assert_eq!(quads.shape(), vec![6, 4]);
    let quads = read_i64(&f, "xdmf/2/topology");
    for q in quads.chunks(4) {
        let pts: Vec<[f64; 3]> = q.iter().map(|&v| point(&k, v as usize)).collect();
        assert_eq!(shoelace(&pts), 1.0);
    }
    let edges = read_i64(&f, "xdmf/1/topology");
    assert_eq!(edges.len(), 2 * 17);
    for (e, pair) in edges.chunks(2).enumerate() {
        let mut pair = usizes(&[pair[0] as u64, pair[1] as u64]);
        pair.sort_unstable();
        assert_eq!(pair, k.cell_vertices(1, e));
    }

    // The main file: the quads alone, as one uniform grid meshio can read.
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    assert!(xml.contains("<Xdmf Version=\"3.0\">"));
    assert!(!xml.contains("Collection"));
    assert_eq!(xml.matches("<Grid ").count(), 1);
    assert!(xml.contains("<Grid Name=\"cells\" GridType=\"Uniform\">"));
    assert!(xml.contains("TopologyType=\"Quadrilateral\" NumberOfElements=\"6\""));
    assert!(xml.contains(">quad.h5:/mesh/vertices<"));
    assert!(xml.contains("<Attribute Name=\"u\" AttributeType=\"Scalar\" Center=\"Node\">"));
    assert!(xml.contains("<Attribute Name=\"cell id\" AttributeType=\"Scalar\" Center=\"Cell\">"));
    assert!(!xml.contains("flux") && !xml.contains("Polyline"));
    // The edges file: 17 = 3·3 horizontal + 4·2 vertical edges of the 3×2 grid.
    let edges = std::fs::read_to_string(&files.extra_xdmf[0]).unwrap();
    assert_well_formed(&edges);
    assert!(!edges.contains("Collection"));
    assert_eq!(edges.matches("<Grid ").count(), 1);
    assert!(edges.contains("<Grid Name=\"edges\" GridType=\"Uniform\">"));
    assert!(
        edges.contains("TopologyType=\"Polyline\" NumberOfElements=\"17\" NodesPerElement=\"2\"")
    );
    assert!(edges.contains(">quad.h5:/xdmf/1/topology<"));
    assert!(edges.contains("Dimensions=\"12 3\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">quad.h5:/mesh/vertices<"));
    assert!(edges.contains("<Attribute Name=\"flux\" AttributeType=\"Scalar\" Center=\"Cell\">"));
    assert!(edges.contains("Dimensions=\"17\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">quad.h5:/steps/0/flux<"));
    assert_eq!(edges.matches("<Attribute ").count(), 1);
}

#[test]
fn triangles_and_hexes_get_reader_vertex_order() {
    let x = uniform_axis(3, 0.0, 1.5).unwrap();
    let tri = kuhn(&[x.clone(), x]).unwrap();
    let dir = scratch("tri-hex");
    let files = write_full_run(
        &dir.join("tri"),
        &steady(&tri, vec![Cochain::new("id", 2, index_cochain(&tri, 2))]),
    )
    .unwrap();
    let f = open(&files.hdf5);
    check_mesh(&f, &tri);
    let t = read_i64(&f, "xdmf/2/topology");
    assert_eq!(t.len(), 3 * 18);
    for tri_vertices in t.chunks(3) {
        let pts: Vec<[f64; 3]> = tri_vertices
            .iter()
            .map(|&v| point(&tri, v as usize))
            .collect();
        assert_abs_diff_eq!(shoelace(&pts), 0.125, epsilon = 1e-15);
    }
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert!(xml.contains("TopologyType=\"Triangle\" NumberOfElements=\"18\" NodesPerElement=\"3\""));
    assert!(!xml.contains("Collection"));
    assert!(files.extra_xdmf.is_empty());

    let hex = box3(2, 1, 2, [0.0, 2.0], [0.0, 1.0], [0.0, 4.0]).unwrap();
    let cochains = vec![
        Cochain::new("u", 0, linear(&hex)),
        Cochain::new("face", 2, index_cochain(&hex, 2)),
        Cochain::new("id", 3, index_cochain(&hex, 3)),
    ];
    let files = write_full_run(&dir.join("hex"), &steady(&hex, cochains)).unwrap();
    let f = open(&files.hdf5);
    check_mesh(&f, &hex);
    let h = read_i64(&f, "xdmf/3/topology");
    assert_eq!(h.len(), 8 * 4);
    for cell in h.chunks(8) {
        let p: Vec<[f64; 3]> = cell.iter().map(|&v| point(&hex, v as usize)).collect();
        // VTK hexahedron: the five-tetrahedron split has all volumes positive
        // and sums to the cell volume 1·1·2.
        let tets = [
            [0, 1, 3, 4],
            [1, 2, 3, 6],
            [1, 4, 5, 6],
            [3, 6, 7, 4],
            [1, 3, 4, 6],
        ];
        let mut total = 0.0;
        for t in tets {
            let v = vol6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
            assert!(v > 0.0);
            total += v / 6.0;
        }
        assert_abs_diff_eq!(total, 2.0, epsilon = 1e-12);
    }
    // Faces: every 2-cell of a box is a quad with area of its axis-aligned sides.
    let faces = f.dataset("xdmf/2/topology").unwrap();
    assert_eq!(faces.shape(), vec![hex.cell_count(2), 4]);
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    assert_eq!(xml.matches("<Grid ").count(), 1);
    assert!(
        xml.contains("TopologyType=\"Hexahedron\" NumberOfElements=\"4\" NodesPerElement=\"8\"")
    );
    assert!(!xml.contains("Name=\"face\""));
    // A face cochain and no edge cochain: hex.faces.xdmf only. The 2×1×2 box
    // has 3·1·2 x-normal + 2·2·2 y-normal + 2·1·3 z-normal = 20 faces.
    assert_eq!(files.extra_xdmf, [dir.join("hex.faces.xdmf")]);
    assert!(!dir.join("hex.edges.xdmf").exists());
    let faces = std::fs::read_to_string(&files.extra_xdmf[0]).unwrap();
    assert_well_formed(&faces);
    assert!(faces.contains(
        "<Grid Name=\"faces\" GridType=\"Uniform\">\n      <Topology TopologyType=\"Quadrilateral\" NumberOfElements=\"20\" NodesPerElement=\"4\">"
    ));
    assert!(faces.contains(
        "Dimensions=\"20\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">hex.h5:/steps/0/face<"
    ));
    assert!(!faces.contains("Name=\"u\"") && !faces.contains("Name=\"id\""));
}

#[test]
fn polygons_mix_in_one_topology_array() {
    // Pentagon, quad and triangle around the point (2, 1).
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 2.0],
        [0.0, 1.0],
        [4.0, 0.0],
        [4.0, 2.0],
        [2.5, 2.5],
    ])
    .unwrap();
    let cells = TopCells::polygons([vec![0, 1, 2, 3, 4], vec![1, 5, 6, 2], vec![2, 6, 7]]);
    let k = Complex::build(v, cells).unwrap();
    let dir = scratch("polygons");
    let files = write_full_run(
        &dir.join("poly"),
        &steady(&k, vec![Cochain::new("id", 2, index_cochain(&k, 2))]),
    )
    .unwrap();
    let f = open(&files.hdf5);
    check_mesh(&f, &k);
    let mixed = read_i64(&f, "xdmf/2/topology");
    assert_eq!(mixed.len(), (2 + 5) + (1 + 4) + (1 + 3));
    // Walk the array as a reader does; each cell must enclose its own area.
    // By hand: pentagon = 2x1 rectangle + triangle of area 1; quad = trapezoid
    // of parallel sides 2 and 1 at distance 2; triangle = |(2,1)×(0.5,1.5)|/2.
    let areas = [3.0, 3.0, 1.25];
    let mut r = 0;
    let mut cell = 0;
    while r < mixed.len() {
        let (count, start) = match mixed[r] {
            3 => (mixed[r + 1] as usize, r + 2),
            4 => (3, r + 1),
            5 => (4, r + 1),
            other => panic!("unexpected code {other}"),
        };
        let pts: Vec<[f64; 3]> = mixed[start..start + count]
            .iter()
            .map(|&v| point(&k, v as usize))
            .collect();
        let mut ids: Vec<usize> = mixed[start..start + count]
            .iter()
            .map(|&v| v as usize)
            .collect();
        ids.sort_unstable();
        assert_eq!(ids, k.cell_vertices(2, cell));
        let expected = match count {
            5 => areas[0],
            4 => areas[1],
            _ => areas[2],
        };
        assert_abs_diff_eq!(shoelace(&pts), expected, epsilon = 1e-12);
        r = start + count;
        cell += 1;
    }
    assert_eq!(cell, 3);
    let codes: Vec<i64> = vec![mixed[0], mixed[7], mixed[12]];
    let mut sorted = codes.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, [3, 4, 5]);
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert!(xml.contains("<Topology TopologyType=\"Mixed\" NumberOfElements=\"3\">"));
    assert!(xml.contains("<DataItem Dimensions=\"16\" DataType=\"Int\""));
}

#[test]
fn polyhedra_are_written_as_tetrahedra_with_their_cell_ids() {
    // A cube split into two triangular prisms by the plane x = y.
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
    let k = Complex::build(v, TopCells::polyhedra([prism(0, 1, 2), prism(0, 2, 3)])).unwrap();
    let dir = scratch("polyhedra");
    let values = vec![10.0, 20.0];
    let files = write_run(
        &dir.join("prisms"),
        &steady(&k, vec![Cochain::new("p", 3, values.clone())]),
    )
    .unwrap();
    let f = open(&files.hdf5);
    let ids = usizes(&read_u64(&f, "xdmf/3/cell_ids"));
    let tets = read_i64(&f, "xdmf/3/topology");
    assert_eq!(tets.len(), 4 * ids.len());
    let mut volume = [0.0; 2];
    for (t, &cell) in tets.chunks(4).zip(&ids) {
        let p: Vec<[f64; 3]> = t.iter().map(|&v| point(&k, v as usize)).collect();
        let v6 = vol6(p[0], p[1], p[2], p[3]);
        assert!(v6 > 0.0);
        volume[cell] += v6 / 6.0;
        let mut verts: Vec<usize> = t.iter().map(|&v| v as usize).collect();
        verts.retain(|v| k.cell_vertices(3, cell).contains(v));
        assert_eq!(verts.len(), 4);
    }
    assert_abs_diff_eq!(volume[0], 0.5, epsilon = 1e-12);
    assert_abs_diff_eq!(volume[1], 0.5, epsilon = 1e-12);
    let expanded = read_f64(&f, "xdmf/3/steps/0/p");
    let expected: Vec<f64> = ids.iter().map(|&c| values[c]).collect();
    assert_eq!(expanded, expected);
    assert_eq!(read_f64(&f, "steps/0/p"), values);
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert!(xml.contains(&format!(
        "TopologyType=\"Tetrahedron\" NumberOfElements=\"{}\"",
        ids.len()
    )));
    assert!(xml.contains("prisms.h5:/xdmf/3/steps/0/p<"));
}

#[test]
fn time_series_stores_every_level() {
    let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let times = [0.0, 0.5, 1.25];
    let steps: Vec<Step> = times
        .iter()
        .map(|&t| Step {
            time: t,
            cochains: vec![Cochain::new(
                "u",
                0,
                linear(&k).iter().map(|u| u * (1.0 + t)).collect(),
            )],
        })
        .collect();
    let dir = scratch("series");
    let files = write_run(&dir.join("heat"), &run(&k, steps)).unwrap();
    let f = open(&files.hdf5);
    assert_eq!(
        f.attr("step_count").unwrap().read_scalar::<u64>().unwrap(),
        3
    );
    assert_eq!(f.attr("times").unwrap().read_raw::<f64>().unwrap(), times);
    for (i, &t) in times.iter().enumerate() {
        let g = f.group(&format!("steps/{i}")).unwrap();
        assert_eq!(g.attr("time").unwrap().read_scalar::<f64>().unwrap(), t);
        let expected: Vec<f64> = linear(&k).iter().map(|u| u * (1.0 + t)).collect();
        assert_eq!(read_f64(&f, &format!("steps/{i}/u")), expected);
    }
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    assert_eq!(xml.matches("CollectionType=\"Temporal\"").count(), 1);
    for t in ["0.0", "0.5", "1.25"] {
        assert!(xml.contains(&format!("<Time Value=\"{t}\"/>")));
    }
    assert!(xml.contains("heat.h5:/steps/2/u<"));
    assert!(files.extra_xdmf.is_empty());
    assert_eq!(files_in(&dir), ["heat.h5", "heat.xdmf"]);
}

#[test]
fn a_3d_time_series_writes_one_temporal_file_per_degree() {
    // 1×1×1 cube: 8 vertices, 12 edges, 6 faces, 1 hexahedron.
    let k = box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    let times = [0.0, 2.0];
    let steps: Vec<Step> = times
        .iter()
        .map(|&t| Step {
            time: t,
            cochains: vec![
                Cochain::new("u", 0, vec![t; 8]),
                Cochain::new("q", 1, vec![t; 12]),
                Cochain::new("f", 2, vec![t; 6]),
                Cochain::new("c", 3, vec![t]),
            ],
        })
        .collect();
    let dir = scratch("series-3d");
    let files = write_run(&dir.join("cube"), &run(&k, steps)).unwrap();
    assert_eq!(
        files.extra_xdmf,
        [dir.join("cube.edges.xdmf"), dir.join("cube.faces.xdmf")]
    );
    assert_eq!(
        files_in(&dir),
        ["cube.edges.xdmf", "cube.faces.xdmf", "cube.h5", "cube.xdmf"]
    );
    let expect = [
        (&files.xdmf, "cells", "Hexahedron", 1, 8, &["u", "c"][..]),
        (&files.extra_xdmf[0], "edges", "Polyline", 12, 2, &["q"][..]),
        (
            &files.extra_xdmf[1],
            "faces",
            "Quadrilateral",
            6,
            4,
            &["f"][..],
        ),
    ];
    for (path, name, kind, count, nodes, fields) in expect {
        let xml = std::fs::read_to_string(path).unwrap();
        assert_well_formed(&xml);
        // One temporal collection holding one uniform grid per level.
        assert_eq!(
            xml.matches("CollectionType=\"Temporal\"").count(),
            1,
            "{name}"
        );
        assert!(xml.contains(&format!(
            "<Grid Name=\"{name}\" GridType=\"Collection\" CollectionType=\"Temporal\">"
        )));
        assert_eq!(
            xml.matches(&format!("<Grid Name=\"{name}\" GridType=\"Uniform\">"))
                .count(),
            2
        );
        assert_eq!(xml.matches("<Time Value=\"0.0\"/>").count(), 1);
        assert_eq!(xml.matches("<Time Value=\"2.0\"/>").count(), 1);
        assert_eq!(
            xml.matches(&format!(
                "TopologyType=\"{kind}\" NumberOfElements=\"{count}\" NodesPerElement=\"{nodes}\""
            ))
            .count(),
            2
        );
        assert_eq!(xml.matches("<Attribute ").count(), 2 * fields.len());
        for field in fields {
            assert!(
                xml.contains(&format!("cube.h5:/steps/1/{field}<")),
                "{name} {field}"
            );
        }
    }
}

#[test]
fn bad_cochains_are_rejected_before_anything_is_written() {
    let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let dir = scratch("bad");
    let short = steady(&k, vec![Cochain::new("u", 0, vec![1.0; 5])]);
    match write_run(&dir.join("run"), &short) {
        Err(OutputError::Shape {
            step: 0,
            name,
            dim: 0,
            expected: 6,
            got: 5,
        }) => assert_eq!(name, "u"),
        other => panic!("expected a shape error, got {other:?}"),
    }
    assert!(
        !dir.exists(),
        "a rejected run must not even create the directory"
    );

    let mut values = linear(&k);
    values[4] = f64::NAN;
    values[5] = f64::INFINITY;
    let err = write_run(
        &dir.join("run"),
        &steady(&k, vec![Cochain::new("T", 0, values)]),
    )
    .unwrap_err();
    assert!(matches!(err, OutputError::NonFinite { cell: 4, .. }));
    let message = err.to_string();
    assert!(
        message.contains("'T'") && message.contains("0-cell 4"),
        "{message}"
    );

    let twice = steady(
        &k,
        vec![
            Cochain::new("u", 0, linear(&k)),
            Cochain::new("u", 2, vec![0.0; 2]),
        ],
    );
    assert!(matches!(
        write_run(&dir.join("run"), &twice),
        Err(OutputError::DuplicateName { step: 0, .. })
    ));
    let high = steady(&k, vec![Cochain::new("w", 3, vec![])]);
    assert!(matches!(
        write_run(&dir.join("run"), &high),
        Err(OutputError::Degree {
            dim: 3,
            complex_dim: 2,
            ..
        })
    ));
    let backwards = run(
        &k,
        vec![
            Step {
                time: 1.0,
                cochains: vec![],
            },
            Step {
                time: 1.0,
                cochains: vec![],
            },
        ],
    );
    assert!(matches!(
        write_run(&dir.join("run"), &backwards),
        Err(OutputError::Time { step: 1, .. })
    ));
    assert!(!dir.exists());
}

#[test]
fn an_older_output_is_replaced_only_by_a_complete_one() {
    let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let dir = scratch("replace");
    let stem = dir.join("nested").join("run");
    let first = write_run(
        &stem,
        &steady(
            &k,
            vec![
                Cochain::new("u", 0, linear(&k)),
                Cochain::new("flux", 1, index_cochain(&k, 1)),
            ],
        ),
    )
    .unwrap();
    assert_eq!(
        first.extra_xdmf,
        [dir.join("nested").join("run.edges.xdmf")]
    );
    let old_h5 = std::fs::read(&first.hdf5).unwrap();
    let old_xdmf = std::fs::read(&first.xdmf).unwrap();
    let old_edges = std::fs::read(&first.extra_xdmf[0]).unwrap();
    let all_three = ["run.edges.xdmf", "run.h5", "run.xdmf"];

    // Fails validation.
    let bad = steady(&k, vec![Cochain::new("u", 2, vec![1.0; 3])]);
    assert!(write_run(&stem, &bad).is_err());
    // Passes validation but the provenance cannot be stored (NUL in an HDF5
    // string), so the failure happens halfway through the h5 file, with the
    // edges file still to come: none of them may appear, and
    // no temporary (`.run.*.tmp-*`, which `files_in` would list) is left.
    let mut late = steady(
        &k,
        vec![
            Cochain::new("v", 0, linear(&k)),
            Cochain::new("flux", 1, vec![0.5; 7]),
        ],
    );
    late.provenance.case_text = Some("a\0b".into());
    assert!(matches!(
        write_run(&stem, &late),
        Err(OutputError::Text { .. })
    ));
    assert_eq!(std::fs::read(&first.hdf5).unwrap(), old_h5);
    assert_eq!(std::fs::read(&first.xdmf).unwrap(), old_xdmf);
    assert_eq!(std::fs::read(&first.extra_xdmf[0]).unwrap(), old_edges);
    assert_eq!(files_in(&dir.join("nested")), all_three);

    let second = write_run(
        &stem,
        &run(
            &k,
            vec![
                Step {
                    time: 0.0,
                    cochains: vec![Cochain::new("w", 2, vec![1.0, 2.0])],
                },
                Step {
                    time: 1.0,
                    cochains: vec![Cochain::new("w", 2, vec![3.0, 4.0])],
                },
            ],
        ),
    )
    .unwrap();
    assert_eq!((&second.hdf5, &second.xdmf), (&first.hdf5, &first.xdmf));
    // The new output has no edge cochain: the old run.edges.xdmf would point
    // at /steps/0/flux and /xdmf/1, which the new h5 lacks, so it is gone.
    assert!(second.extra_xdmf.is_empty());
    let f = open(&second.hdf5);
    assert_eq!(
        f.attr("step_count").unwrap().read_scalar::<u64>().unwrap(),
        2
    );
    assert_eq!(read_f64(&f, "steps/1/w"), [3.0, 4.0]);
    assert!(f.dataset("steps/0/u").is_err());
    assert_eq!(files_in(&dir.join("nested")), ["run.h5", "run.xdmf"]);
}

#[test]
fn a_1d_complex_is_one_polyline_grid() {
    let k = hasse_complex::generate::interval(4, 0.0, 2.0).unwrap();
    let dir = scratch("interval");
    let cochains = vec![
        Cochain::new("u", 0, linear(&k)),
        Cochain::new("q", 1, index_cochain(&k, 1)),
    ];
    let files = write_full_run(&dir.join("line"), &steady(&k, cochains)).unwrap();
    let f = open(&files.hdf5);
    check_mesh(&f, &k);
    // (N, 3) with y = z = 0 padding and the embedding dimension kept.
    let vertices = f.dataset("mesh/vertices").unwrap();
    assert_eq!(
        vertices
            .attr("embedding_dim")
            .unwrap()
            .read_scalar::<u64>()
            .unwrap(),
        1
    );
    assert_eq!(read_f64(&f, "mesh/vertices")[6..9], [1.0, 0.0, 0.0]);
    assert_eq!(read_i64(&f, "xdmf/1/topology"), [0, 1, 1, 2, 2, 3, 3, 4]);
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    assert_eq!(xml.matches("<Grid ").count(), 1);
    assert!(xml.contains("<Grid Name=\"cells\" GridType=\"Uniform\">"));
    assert!(xml.contains("TopologyType=\"Polyline\" NumberOfElements=\"4\" NodesPerElement=\"2\""));
    assert!(xml.contains("Name=\"u\" AttributeType=\"Scalar\" Center=\"Node\""));
    assert!(xml.contains("Name=\"q\" AttributeType=\"Scalar\" Center=\"Cell\""));
}

#[test]
fn stems_that_cannot_name_the_files_are_rejected() {
    let k = hasse_complex::generate::interval(1, 0.0, 1.0).unwrap();
    let empty = steady(&k, vec![]);
    let dir = scratch("stems");
    assert!(matches!(
        write_run(&dir.join("a:b"), &empty),
        Err(OutputError::Stem { .. })
    ));
    assert!(matches!(
        write_run(Path::new("/"), &empty),
        Err(OutputError::Stem { .. })
    ));
    assert!(!dir.exists());
    // A stem whose name has a dot keeps it: run.v2 → run.v2.h5.
    let files = write_run(&dir.join("run.v2"), &empty).unwrap();
    assert_eq!(files.hdf5, dir.join("run.v2.h5"));
    assert_eq!(files_in(&dir), ["run.v2.h5", "run.v2.xdmf"]);

    // No step at all: the mesh alone, an empty `times`, a grid without attributes.
    let mesh_only = run(&k, vec![]);
    let files = write_full_run(&dir.join("mesh"), &mesh_only).unwrap();
    let f = open(&files.hdf5);
    assert_eq!(
        f.attr("step_count").unwrap().read_scalar::<u64>().unwrap(),
        0
    );
    assert!(f
        .attr("times")
        .unwrap()
        .read_raw::<f64>()
        .unwrap()
        .is_empty());
    check_mesh(&f, &k);
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    assert!(!xml.contains("<Attribute"));
    assert!(files.extra_xdmf.is_empty());

    // Only an edge cochain: the top grid is still written, as the bare mesh
    // (2×1 quads), and the edge field goes to edges-only.edges.xdmf.
    let quads = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let files = write_run(
        &dir.join("edges-only"),
        &steady(&quads, vec![Cochain::new("q", 1, vec![1.5; 7])]),
    )
    .unwrap();
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    assert!(xml.contains("<Grid Name=\"cells\" GridType=\"Uniform\">"));
    assert!(xml.contains("TopologyType=\"Quadrilateral\" NumberOfElements=\"2\""));
    assert!(!xml.contains("<Attribute"));
    assert_eq!(files.extra_xdmf, [dir.join("edges-only.edges.xdmf")]);
    let edges = std::fs::read_to_string(&files.extra_xdmf[0]).unwrap();
    assert!(edges.contains("TopologyType=\"Polyline\" NumberOfElements=\"7\""));
    assert!(edges.contains("edges-only.h5:/steps/0/q<"));
}

/// Mean of the vertices of p-cell i (exact for the dyadic grids used here).
fn centroid(k: &Complex, p: usize, i: usize) -> [f64; 3] {
    let vs = k.cell_vertices(p, i);
    let mut c = [0.0; 3];
    for &v in vs {
        for (a, b) in c.iter_mut().zip(point(k, v)) {
            *a += b;
        }
    }
    c.map(|a| a / vs.len() as f64)
}

/// u = (1 + t)(x + 2y − z) on vertices, q = x + y of the edge midpoint + t,
/// c = x − y of the cell centroid + 10t: analytic on every complex.
fn analytic_cochains(k: &Complex, t: f64) -> Vec<Cochain> {
    let n = k.dim();
    let q = (0..k.cell_count(1))
        .map(|e| {
            let m = centroid(k, 1, e);
            m[0] + m[1] + t
        })
        .collect();
    let c = (0..k.cell_count(n))
        .map(|i| {
            let m = centroid(k, n, i);
            m[0] - m[1] + 10.0 * t
        })
        .collect();
    vec![
        Cochain::new("u", 0, linear(k).iter().map(|u| (1.0 + t) * u).collect()).with_units("K"),
        Cochain::new("q", 1, q),
        Cochain::new("c", n, c),
    ]
}

fn series<'a>(levels: &[(f64, &'a Complex)]) -> SeriesOutput<'a> {
    SeriesOutput {
        steps: levels
            .iter()
            .map(|&(time, complex)| MeshStep {
                time,
                complex,
                cochains: analytic_cochains(complex, time),
            })
            .collect(),
        provenance: run(levels[0].1, vec![]).provenance,
    }
}

/// `(Dimensions, text)` of the one DataItem inside `<tag …>…</tag>` of `grid`.
fn data_item<'x>(grid: &'x str, tag: &str) -> (&'x str, &'x str) {
    let start = grid.find(&format!("<{tag} ")).expect(tag);
    let end = grid[start..].find(&format!("</{tag}>")).expect(tag) + start;
    let section = &grid[start..end];
    let item = section.find("<DataItem ").expect("DataItem");
    let dims = &section[item..];
    let dims = &dims[dims.find("Dimensions=\"").unwrap() + 12..];
    let dims = &dims[..dims.find('"').unwrap()];
    let text = &section[item..];
    let text = &text[text.find('>').unwrap() + 1..text.find("</DataItem>").unwrap()];
    (dims, text)
}

/// The uniform grids of a document, in order: those that say so, and in
/// a series whose mesh changes those that leave `GridType` at its default
/// (Uniform).
fn uniform_grids<'x>(xml: &'x str, name: &str) -> Vec<&'x str> {
    let open = format!("<Grid Name=\"{name}\"");
    xml.split(open.as_str())
        .skip(1)
        .filter_map(|g| {
            g.strip_prefix(" GridType=\"Uniform\">")
                .or_else(|| g.strip_prefix('>'))
        })
        .map(|g| &g[..g.find("</Grid>").unwrap()])
        .collect()
}

#[test]
fn a_refinement_series_stores_each_mesh_with_its_step() {
    let grids: Vec<Complex> = [2, 4, 8]
        .iter()
        .map(|&m| rectangle(m, m, [0.0, 1.0], [0.0, 1.0]).unwrap())
        .collect();
    let times = [0.0, 0.5, 1.25];
    let levels: Vec<(f64, &Complex)> = times.iter().copied().zip(&grids).collect();
    let dir = scratch("mesh-series");
    let files = write_full_series(&dir.join("refine"), &series(&levels)).unwrap();
    assert_eq!(files.hdf5, dir.join("refine.h5"));
    assert_eq!(files.xdmf, dir.join("refine.xdmf"));
    assert_eq!(files.extra_xdmf, [dir.join("refine.edges.xdmf")]);
    // Besides the series, each level alone, its top cells and its edges.
    let mut names: Vec<String> = ["refine.edges.xdmf", "refine.h5", "refine.xdmf"]
        .map(String::from)
        .to_vec();
    for k in 0..3 {
        let top = format!("refine.level-{k}.xdmf");
        let edges = format!("refine.level-{k}.edges.xdmf");
        assert_eq!(files.levels[k], [dir.join(&top), dir.join(&edges)]);
        names.extend([top, edges]);
    }
    names.sort();
    assert_eq!(files_in(&dir), names);

    let f = open(&files.hdf5);
    let root_u64 = |name: &str| f.attr(name).unwrap().read_scalar::<u64>().unwrap();
    assert_eq!(root_u64("mesh_changes"), 1);
    assert_eq!(root_u64("format_version"), 2);
    assert_eq!(root_u64("step_count"), 3);
    assert_eq!(f.attr("times").unwrap().read_raw::<f64>().unwrap(), times);
    // No shared mesh: a reader that ignores `mesh_changes` fails loudly.
    assert!(f.group("mesh").is_err() && f.group("xdmf").is_err());
    for (k, (&t, grid)) in times.iter().zip(&grids).enumerate() {
        let m = 2usize << k;
        check_mesh_at(&f, &format!("steps/{k}/mesh"), grid);
        assert_eq!(grid.cell_count(0), (m + 1) * (m + 1));
        let g = f.group(&format!("steps/{k}")).unwrap();
        assert_eq!(g.attr("time").unwrap().read_scalar::<f64>().unwrap(), t);
        // The analytic values, recomputed from the coordinates read back.
        let xyz = read_f64(&f, &format!("steps/{k}/mesh/vertices"));
        let u: Vec<f64> = xyz
            .chunks(3)
            .map(|p| (1.0 + t) * (p[0] + 2.0 * p[1] - p[2]))
            .collect();
        assert_eq!(read_f64(&f, &format!("steps/{k}/u")), u);
        let u_ds = f.dataset(&format!("steps/{k}/u")).unwrap();
        assert_eq!(str_attr(&u_ds, "units"), "K");
        for (name, values) in analytic_cochains(grid, t)
            .into_iter()
            .map(|c| (c.name, c.values))
        {
            assert_eq!(read_f64(&f, &format!("steps/{k}/{name}")), values, "{name}");
        }
        // The corner (1, 1) is the last vertex: u = (1 + t)·3.
        assert_eq!(
            *read_f64(&f, &format!("steps/{k}/u")).last().unwrap(),
            3.0 * (1.0 + t)
        );
        // Quads of side 1/m, counter-clockwise; 2m(m + 1) edges.
        let quads = f
            .dataset(&format!("steps/{k}/mesh/xdmf/2/topology"))
            .unwrap();
        assert_eq!(quads.shape(), vec![m * m, 4]);
        for q in quads.read_raw::<i64>().unwrap().chunks(4) {
            let pts: Vec<[f64; 3]> = q.iter().map(|&v| point(grid, v as usize)).collect();
            assert_eq!(shoelace(&pts), 1.0 / (m * m) as f64);
        }
        let edges = f
            .dataset(&format!("steps/{k}/mesh/xdmf/1/topology"))
            .unwrap();
        assert_eq!(edges.shape(), vec![2 * m * (m + 1), 2]);
    }

    // Every XDMF file: one temporal collection of three grids, grid k
    // taking geometry, topology and values from step k.
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    let edges_xml = std::fs::read_to_string(&files.extra_xdmf[0]).unwrap();
    for (text, name) in [(&xml, "cells"), (&edges_xml, "edges")] {
        assert_well_formed(text);
        assert_eq!(text.matches("CollectionType=\"Temporal\"").count(), 1);
        assert_eq!(text.matches("<Grid ").count(), 1 + 3);
        assert_eq!(uniform_grids(text, name).len(), 3, "{name}");
    }
    for (k, (grid_xml, edge_xml)) in uniform_grids(&xml, "cells")
        .into_iter()
        .zip(uniform_grids(&edges_xml, "edges"))
        .enumerate()
    {
        let m = 2usize << k;
        let nv = (m + 1) * (m + 1);
        assert!(grid_xml.contains(&format!("<Time Value=\"{:?}\"/>", times[k])));
        assert!(grid_xml.contains(&format!(
            "TopologyType=\"Quadrilateral\" NumberOfElements=\"{}\" NodesPerElement=\"4\"",
            m * m
        )));
        let topology = format!("refine.h5:/steps/{k}/mesh/xdmf/2/topology");
        assert_eq!(
            data_item(grid_xml, "Topology"),
            (format!("{} 4", m * m).as_str(), topology.as_str())
        );
        let geometry = format!("refine.h5:/steps/{k}/mesh/vertices");
        let nv3 = format!("{nv} 3");
        assert_eq!(
            data_item(grid_xml, "Geometry"),
            (nv3.as_str(), geometry.as_str())
        );
        assert!(grid_xml.contains(&format!(
            "Dimensions=\"{nv}\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">refine.h5:/steps/{k}/u<"
        )));
        assert!(grid_xml.contains(&format!(
            "Dimensions=\"{}\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">refine.h5:/steps/{k}/c<",
            m * m
        )));
        assert!(!grid_xml.contains("/q<"));

        let ne = 2 * m * (m + 1);
        assert!(edge_xml.contains(&format!(
            "TopologyType=\"Polyline\" NumberOfElements=\"{ne}\" NodesPerElement=\"2\""
        )));
        let topology = format!("refine.h5:/steps/{k}/mesh/xdmf/1/topology");
        assert_eq!(data_item(edge_xml, "Topology").1, topology);
        assert_eq!(
            data_item(edge_xml, "Geometry"),
            (nv3.as_str(), geometry.as_str())
        );
        assert!(edge_xml.contains(&format!(
            "Dimensions=\"{ne}\" DataType=\"Float\" Precision=\"8\" Format=\"HDF\">refine.h5:/steps/{k}/q<"
        )));
        assert_eq!(edge_xml.matches("<Attribute ").count(), 1);
    }
}

#[test]
fn a_series_with_split_polyhedra_keeps_the_expanded_values_with_each_mesh() {
    // Step 0: a cube of two prisms (written as tetrahedra); step 1: two hexahedra.
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
    let prisms = Complex::build(v, TopCells::polyhedra([prism(0, 1, 2), prism(0, 2, 3)])).unwrap();
    let hexes = box3(2, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    fn step(time: f64, complex: &Complex, p: Vec<f64>) -> MeshStep<'_> {
        MeshStep {
            time,
            complex,
            cochains: vec![Cochain::new("p", 3, p)],
        }
    }
    let out = SeriesOutput {
        steps: vec![
            step(0.0, &prisms, vec![10.0, 20.0]),
            step(1.0, &hexes, vec![30.0, 40.0]),
        ],
        provenance: Provenance::new(serde_json::Value::Null),
    };
    let dir = scratch("mesh-series-split");
    let files = write_full_series(&dir.join("split"), &out).unwrap();
    assert!(files.extra_xdmf.is_empty());
    let f = open(&files.hdf5);
    check_mesh_at(&f, "steps/0/mesh", &prisms);
    check_mesh_at(&f, "steps/1/mesh", &hexes);
    let ids = usizes(&read_u64(&f, "steps/0/mesh/xdmf/3/cell_ids"));
    assert_eq!(ids.len(), 6);
    let expected: Vec<f64> = ids.iter().map(|&c| [10.0, 20.0][c]).collect();
    assert_eq!(read_f64(&f, "steps/0/mesh/xdmf/3/steps/0/p"), expected);
    // Hexahedra need no expansion.
    assert!(f.dataset("steps/1/mesh/xdmf/3/cell_ids").is_err());
    assert_eq!(read_f64(&f, "steps/1/p"), [30.0, 40.0]);
    let xml = std::fs::read_to_string(&files.xdmf).unwrap();
    assert_well_formed(&xml);
    let grids = uniform_grids(&xml, "cells");
    assert_eq!(grids.len(), 2);
    assert!(grids[0].contains("TopologyType=\"Tetrahedron\" NumberOfElements=\"6\""));
    assert!(grids[0].contains(">split.h5:/steps/0/mesh/xdmf/3/steps/0/p<"));
    assert!(grids[1].contains("TopologyType=\"Hexahedron\" NumberOfElements=\"2\""));
    assert!(grids[1].contains(">split.h5:/steps/1/p<"));
}

#[test]
fn a_bad_mesh_series_is_rejected_before_anything_is_written() {
    let coarse = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let fine = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let dir = scratch("mesh-series-bad");
    let stem = dir.join("bad");
    let good = || series(&[(0.0, &coarse), (1.0, &fine)]);

    // Step 1's u sized for step 0's mesh: checked against step 1's complex.
    let mut s = good();
    s.steps[1].cochains[0].values = linear(&coarse);
    match write_mesh_series(&stem, &s) {
        Err(OutputError::Shape {
            step: 1,
            name,
            dim: 0,
            expected: 25,
            got: 9,
        }) => assert_eq!(name, "u"),
        other => panic!("expected a shape error, got {other:?}"),
    }
    let mut s = good();
    s.steps[1].cochains[2].values[3] = f64::NAN;
    assert!(matches!(
        write_mesh_series(&stem, &s),
        Err(OutputError::NonFinite {
            step: 1,
            dim: 2,
            cell: 3,
            ..
        })
    ));
    let mut s = good();
    let copy = s.steps[1].cochains[1].clone();
    s.steps[1].cochains.push(copy);
    assert!(matches!(
        write_mesh_series(&stem, &s),
        Err(OutputError::DuplicateName { step: 1, .. })
    ));
    let mut s = good();
    s.steps[1].time = 0.0;
    assert!(matches!(
        write_mesh_series(&stem, &s),
        Err(OutputError::Time { step: 1, .. })
    ));
    let mut s = good();
    s.steps[0].cochains.push(Cochain::new("w", 3, vec![]));
    assert!(matches!(
        write_mesh_series(&stem, &s),
        Err(OutputError::Degree {
            step: 0,
            dim: 3,
            complex_dim: 2,
            ..
        })
    ));
    // A cochain may not take the name of the step's mesh group.
    let mut s = good();
    s.steps[0]
        .cochains
        .push(Cochain::new("mesh", 0, vec![0.0; 9]));
    assert!(matches!(
        write_mesh_series(&stem, &s),
        Err(OutputError::InvalidName { .. })
    ));
    let line = hasse_complex::generate::interval(2, 0.0, 1.0).unwrap();
    let mixed = series(&[(0.0, &coarse), (1.0, &line)]);
    assert!(matches!(
        write_mesh_series(&stem, &mixed),
        Err(OutputError::MeshDimension {
            step: 1,
            dim: 1,
            expected: 2
        })
    ));
    let empty = SeriesOutput {
        steps: vec![],
        provenance: Provenance::new(serde_json::Value::Null),
    };
    assert!(matches!(
        write_mesh_series(&stem, &empty),
        Err(OutputError::EmptySeries)
    ));
    assert!(
        !dir.exists(),
        "a rejected series must not create the directory"
    );

    // An older output survives a series that fails halfway through the h5
    // (NUL in the case text), and no temporary is left.
    let first = write_run(
        &stem,
        &steady(&coarse, vec![Cochain::new("q", 1, vec![0.5; 12])]),
    )
    .unwrap();
    let before: Vec<Vec<u8>> = [&first.hdf5, &first.xdmf, &first.extra_xdmf[0]]
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    let mut late = good();
    late.provenance.case_text = Some("a\0b".into());
    assert!(matches!(
        write_mesh_series(&stem, &late),
        Err(OutputError::Text { .. })
    ));
    let after: Vec<Vec<u8>> = [&first.hdf5, &first.xdmf, &first.extra_xdmf[0]]
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    assert!(before == after);
    assert_eq!(files_in(&dir), ["bad.edges.xdmf", "bad.h5", "bad.xdmf"]);

    // A complete series then replaces it.
    let files = write_mesh_series(&stem, &good()).unwrap();
    assert_eq!(files.extra_xdmf, [dir.join("bad.edges.xdmf")]);
    let f = open(&files.hdf5);
    assert_eq!(
        f.attr("mesh_changes")
            .unwrap()
            .read_scalar::<u64>()
            .unwrap(),
        1
    );
    assert_eq!(
        files_in(&dir),
        [
            "bad.edges.xdmf",
            "bad.h5",
            "bad.level-0.edges.xdmf",
            "bad.level-0.xdmf",
            "bad.level-1.edges.xdmf",
            "bad.level-1.xdmf",
            "bad.xdmf"
        ]
    );
}
