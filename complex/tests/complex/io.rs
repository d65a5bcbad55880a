//! Gmsh reader and JSON format, checked against hand-derived numbers: the
//! fixtures in `tests/data/` are small enough that every count, vertex
//! number, tag and cell measure below was worked out on paper from the file.
//! Measures are computed here from the boundary matrices alone (Green /
//! divergence theorem), independently of the geometry module.

use approx::abs_diff_eq;
use hasse_complex::gmsh::{read_msh, read_msh_bytes, GmshError};
use hasse_complex::json::{from_json_str, read_json, to_json, write_json, JsonError};
use hasse_complex::{Complex, TopCells, Vertices};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------- helpers

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn read(name: &str) -> Complex {
    read_msh(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn point3(k: &Complex, v: usize) -> [f64; 3] {
    let mut x = [0.0; 3];
    let p = k.vertices().point(v);
    x[..p.len()].copy_from_slice(p);
    x
}

/// Entries (row, value) of column `j` of ∂_p.
fn column(k: &Complex, p: usize, j: usize) -> Vec<(usize, i8)> {
    let csc = k.boundary_csc(p);
    csc.outer_view(j)
        .map(|c| c.iter().map(|(i, &v)| (i, v)).collect())
        .unwrap_or_default()
}

/// Oriented edge a→b with a < b (the simplex convention ∂[a,b] = b − a).
fn edge_ends(k: &Complex, e: usize) -> ([f64; 3], [f64; 3]) {
    let v = k.cell_vertices(1, e);
    (point3(k, v[0]), point3(k, v[1]))
}

/// Oriented area vector of a 2-cell: ½ Σ_e ∂₂[e,f] x_a × x_b.
fn area_vector(k: &Complex, f: usize) -> [f64; 3] {
    let mut s = [0.0; 3];
    for (e, sign) in column(k, 2, f) {
        let (a, b) = edge_ends(k, e);
        let c = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        for i in 0..3 {
            s[i] += 0.5 * f64::from(sign) * c[i];
        }
    }
    s
}

/// Signed area of a 2-cell in the plane (Green's theorem on its oriented boundary).
fn signed_area(k: &Complex, f: usize) -> f64 {
    area_vector(k, f)[2]
}

/// Signed volume of a 3-cell: ⅓ Σ_f ∂₃[f,c] x_f · A_f (divergence theorem),
/// x_f any vertex of the planar face f.
fn signed_volume(k: &Complex, c: usize) -> f64 {
    column(k, 3, c)
        .into_iter()
        .map(|(f, sign)| {
            let x = point3(k, k.cell_vertices(2, f)[0]);
            let a = area_vector(k, f);
            f64::from(sign) * (x[0] * a[0] + x[1] * a[1] + x[2] * a[2]) / 3.0
        })
        .sum()
}

/// ∂∂ = 0 at every level, every (n−1)-cell on one or two top cells, and
/// opposite signs across every interior face.
fn assert_chain_complex(k: &Complex) {
    let n = k.dim();
    for p in 2..=n {
        let dd = &**k.boundary(p - 1) * &**k.boundary(p);
        assert!(dd.data().iter().all(|&x| x == 0), "∂{}∂{} ≠ 0", p - 1, p);
    }
    for (face, row) in k.boundary(n).outer_iterator().enumerate() {
        match row.data() {
            [_] => {}
            [a, b] => assert_eq!(a + b, 0, "interior face {face} has signs {a}, {b}"),
            other => panic!("face {face} lies on {} top cells", other.len()),
        }
    }
}

/// The (n−1)-cells on exactly one top cell (rows of ∂_n with one entry)
/// whose vertices all satisfy `inside`.
fn boundary_faces(k: &Complex, inside: impl Fn(&[f64]) -> bool) -> Vec<usize> {
    let n = k.dim();
    k.boundary(n)
        .outer_iterator()
        .enumerate()
        .filter(|(f, row)| {
            row.nnz() == 1
                && k.cell_vertices(n - 1, *f)
                    .iter()
                    .all(|&v| inside(k.vertices().point(v)))
        })
        .map(|(f, _)| f)
        .collect()
}

fn assert_close(a: f64, b: f64) {
    assert!(abs_diff_eq!(a, b, epsilon = 1e-12), "{a} != {b}");
}

fn bits(k: &Complex) -> Vec<u64> {
    k.vertices()
        .as_slice()
        .iter()
        .map(|x| x.to_bits())
        .collect()
}

fn assert_identical(a: &Complex, b: &Complex) {
    assert_eq!(a, b);
    assert_eq!(bits(a), bits(b));
    assert_eq!(a.dim(), b.dim());
    for p in 1..=a.dim() {
        let (x, y) = (a.boundary(p), b.boundary(p));
        assert_eq!(x.shape(), y.shape());
        assert_eq!(x.indptr().raw_storage(), y.indptr().raw_storage());
        assert_eq!(x.indices(), y.indices());
        assert_eq!(x.data(), y.data());
    }
    assert_eq!(a.top_orientation(), b.top_orientation());
    assert_eq!(a.tags(), b.tags());
}

/// A fresh, empty directory under the system temp dir.
fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hasse-io-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn dir_entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

// ---------------------------------------------------------------- Gmsh fixtures

#[test]
fn square_of_two_quads() {
    // Nodes 1..6 in file order become vertices 0..5:
    // v0 (0,0), v1 (1,0), v2 (1,1), v3 (0,1), v4 (½,0), v5 (½,1).
    let k = read("square_quads.msh");
    assert_eq!(k.embedding_dim(), 2);
    assert_eq!(k.cell_counts(), vec![6, 7, 2]);
    assert_eq!(k.euler_characteristic(), 1);
    let expected = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [0.5, 0.0],
        [0.5, 1.0],
    ];
    for (v, x) in expected.iter().enumerate() {
        assert_eq!(k.vertices().point(v), x);
    }
    // Quads (1 5 6 4) and (5 2 3 6) → vertex sets {0,3,4,5} and {1,2,4,5}.
    assert_eq!(k.cell_vertices(2, 0), &[0, 3, 4, 5]);
    assert_eq!(k.cell_vertices(2, 1), &[1, 2, 4, 5]);
    // Edges sorted by vertex set: {0,3} {0,4} {1,2} {1,4} {2,5} {3,5} {4,5}.
    let edges: Vec<&[usize]> = (0..7).map(|e| k.cell_vertices(1, e)).collect();
    assert_eq!(
        edges,
        vec![
            &[0, 3][..],
            &[0, 4],
            &[1, 2],
            &[1, 4],
            &[2, 5],
            &[3, 5],
            &[4, 5]
        ]
    );
    // "left" is line (4 1) = edge {0,3}; "right" is line (2 3) = edge {1,2}.
    let left = k.tag("left").unwrap();
    assert_eq!((left.dim, left.cells.as_slice()), (1, &[0][..]));
    let right = k.tag("right").unwrap();
    assert_eq!((right.dim, right.cells.as_slice()), (1, &[2][..]));
    let domain = k.tag("domain").unwrap();
    assert_eq!((domain.dim, domain.cells.as_slice()), (2, &[0, 1][..]));
    assert_eq!(k.tags().len(), 3);
    // The cyclic Gmsh quads became proper counter-clockwise cells of area ½.
    assert_chain_complex(&k);
    assert_close(signed_area(&k, 0), 0.5);
    assert_close(signed_area(&k, 1), 0.5);
}

#[test]
fn two_tetrahedra_with_sparse_tags_and_an_unused_node() {
    // Node tags 50 30 40 10 20 (used) and 70 (only a point element) in file
    // order: vertices v0 (1,1,1), v1 (0,1,0), v2 (0,0,1), v3 (0,0,0), v4 (1,0,0).
    let k = read("two_tets.msh");
    assert_eq!(k.embedding_dim(), 3);
    assert_eq!(k.cell_counts(), vec![5, 9, 7, 2]);
    assert_eq!(k.euler_characteristic(), 1);
    assert_eq!(k.betti_numbers(), vec![1, 0, 0, 0]);
    let expected = [
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
    ];
    for (v, x) in expected.iter().enumerate() {
        assert_eq!(k.vertices().point(v), x);
    }
    // Tets (10 20 30 40) → {1,2,3,4}, (20 30 40 50) → {0,1,2,4}.
    assert_eq!(k.cell_vertices(3, 0), &[1, 2, 3, 4]);
    assert_eq!(k.cell_vertices(3, 1), &[0, 1, 2, 4]);
    // Faces sorted: {0,1,2} {0,1,4} {0,2,4} {1,2,3} {1,2,4} {1,3,4} {2,3,4};
    // "bottom" is triangle (10 20 30) = {1,3,4} = face 5.
    let bottom = k.tag("bottom").unwrap();
    assert_eq!((bottom.dim, bottom.cells.as_slice()), (2, &[5][..]));
    assert_eq!(k.cell_vertices(2, 5), &[1, 3, 4]);
    let solid = k.tag("solid").unwrap();
    assert_eq!((solid.dim, solid.cells.as_slice()), (3, &[0, 1][..]));
    assert_chain_complex(&k);
    // Corner tet 1/6; the other has |det[(−1,1,0),(−1,0,1),(0,1,1)]|/6 = 1/3.
    assert_close(signed_volume(&k, 0), 1.0 / 6.0);
    assert_close(signed_volume(&k, 1), 1.0 / 3.0);
}

#[test]
fn mixed_triangles_and_quads_without_names() {
    let k = read("mixed_2d.msh");
    assert_eq!(k.cell_counts(), vec![7, 10, 4]);
    assert_eq!(k.euler_characteristic(), 1);
    // Top cells in file order: quads (1 2 5 4), (2 3 6 5), triangles (4 5 7), (5 6 7).
    assert_eq!(k.cell_vertices(2, 0), &[0, 1, 3, 4]);
    assert_eq!(k.cell_vertices(2, 1), &[1, 2, 4, 5]);
    assert_eq!(k.cell_vertices(2, 2), &[3, 4, 6]);
    assert_eq!(k.cell_vertices(2, 3), &[4, 5, 6]);
    // Physical tag 7 has no $PhysicalNames entry.
    let tag = k.tag("physical:2:7").unwrap();
    assert_eq!((tag.dim, tag.cells.as_slice()), (2, &[0, 1, 2, 3][..]));
    assert_chain_complex(&k);
    for (f, area) in [1.0, 1.0, 0.5, 0.5].into_iter().enumerate() {
        assert_close(signed_area(&k, f), area);
    }
}

#[test]
fn binary_and_ascii_meshio_files_agree() {
    let binary = read("mixed_3d_binary.msh");
    let ascii = read("mixed_3d_ascii.msh");
    assert_identical(&binary, &ascii);
}

#[test]
fn mixed_hex_pyramid_prism_tet() {
    let k = read("mixed_3d_binary.msh");
    // 12 vertices; edges 12 (hex) + 4 (apex) + 5 (prism) + 3 (tet tip) = 24;
    // faces 6 + 4 + 4 + 3 = 17; χ = 12 − 24 + 17 − 4 = 1.
    assert_eq!(k.cell_counts(), vec![12, 24, 17, 4]);
    assert_eq!(k.euler_characteristic(), 1);
    assert_eq!(k.betti_numbers(), vec![1, 0, 0, 0]);
    // meshio grouped the nodes by entity, so the $Nodes section lists tags
    // 9, 10, 11, 1, 4, 2, 3, 5, 8, 6, 7, 12 although they are consecutive:
    // vertex 0 is the apex, 1 and 2 the prism's far edge, 3 the origin.
    assert_eq!(k.vertices().point(0), &[0.5, 0.5, 1.5]);
    assert_eq!(k.vertices().point(1), &[2.0, 0.0, 0.0]);
    assert_eq!(k.vertices().point(2), &[2.0, 1.0, 0.0]);
    assert_eq!(k.vertices().point(3), &[0.0, 0.0, 0.0]);
    assert_eq!(k.vertices().point(11), &[1.5, 0.5, 1.5]);
    assert_chain_complex(&k);
    // Hex 1, pyramid ⅓·1·½, prism ½·1, tet |det|/6 = ½/6.
    for (c, volume) in [1.0, 1.0 / 6.0, 0.5, 1.0 / 12.0].into_iter().enumerate() {
        assert_close(signed_volume(&k, c), volume);
    }
    let apex = k.tag("apex").unwrap();
    assert_eq!((apex.dim, apex.cells.as_slice()), (0, &[0][..]));
    let ridge = k.tag("ridge").unwrap();
    assert_eq!(ridge.dim, 1);
    assert_eq!(ridge.cells.len(), 1);
    assert_eq!(k.cell_vertices(1, ridge.cells[0]), &[1, 2]);
    let bottom = k.tag("bottom").unwrap();
    assert_eq!(bottom.dim, 2);
    assert_eq!(bottom.cells.len(), 2);
    for &f in &bottom.cells {
        assert_eq!(k.cell_vertices(2, f).len(), 4);
        for &v in k.cell_vertices(2, f) {
            assert_eq!(point3(&k, v)[2], 0.0);
        }
    }
    let solid = k.tag("solid").unwrap();
    assert_eq!((solid.dim, solid.cells.as_slice()), (3, &[0, 1, 2, 3][..]));
}

#[test]
fn l_shape_case_mesh() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/l-shape.msh");
    let k = read_msh(&path).unwrap();
    // 9×9 grid minus the 4×4 nodes with x, y > ½; 64 − 16 squares, two
    // triangles each; E = V + F − 1.
    assert_eq!(k.cell_counts(), vec![65, 160, 96]);
    assert_eq!(k.betti_numbers(), vec![1, 0, 0]);
    assert_chain_complex(&k);
    let total: f64 = (0..96).map(|f| signed_area(&k, f)).sum();
    assert_close(total, 0.75);
    // The Dirichlet group is the whole boundary: perimeter 4 in steps of ⅛.
    let dirichlet = k.tag("dirichlet").unwrap();
    assert_eq!(dirichlet.dim, 1);
    assert_eq!(dirichlet.cells.len(), 32);
    assert_eq!(dirichlet.cells, boundary_faces(&k, |_| true));
    let domain = k.tag("domain").unwrap();
    assert_eq!((domain.dim, domain.cells.len()), (2, 96));
}

// ---------------------------------------------------------------- Gmsh errors

fn message_names(err: &GmshError, name: &str) {
    let text = err.to_string();
    assert!(text.contains(name), "message does not name {name}: {text}");
}

#[test]
fn version_2_is_refused_with_a_hint() {
    let err = read_msh(&data("version_2_2.msh")).unwrap_err();
    assert!(
        matches!(&err, GmshError::UnsupportedVersion { found, .. } if found == "2.2"),
        "{err:?}"
    );
    message_names(&err, "version_2_2.msh");
    assert!(err.to_string().contains("Version 4"), "{err}");
}

#[test]
fn truncated_file_is_a_parse_error() {
    let err = read_msh(&data("truncated.msh")).unwrap_err();
    assert!(matches!(err, GmshError::Parse { .. }), "{err:?}");
    message_names(&err, "truncated.msh");
    assert!(err.to_string().contains("truncated"), "{err}");
}

#[test]
fn missing_node_names_element_and_node() {
    let err = read_msh(&data("missing_node.msh")).unwrap_err();
    assert!(
        matches!(
            err,
            GmshError::MissingNode {
                element: 4,
                node: 9,
                ..
            }
        ),
        "{err:?}"
    );
    message_names(&err, "missing_node.msh");
}

#[test]
fn missing_file_is_an_io_error() {
    let err = read_msh(&data("no_such_file.msh")).unwrap_err();
    assert!(matches!(err, GmshError::Io { .. }), "{err:?}");
    message_names(&err, "no_such_file.msh");
}

const HEADER: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";

/// Three nodes of the unit triangle, tags 1..3.
const TRIANGLE_NODES: &str = "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n";

fn msh(body: &str) -> String {
    format!("{HEADER}{body}")
}

#[test]
fn second_order_elements_are_refused() {
    let text = msh("$Nodes\n1 6 1 6\n2 1 0 6\n1\n2\n3\n4\n5\n6\n0 0 0\n1 0 0\n0 1 0\n0.5 0 0\n0.5 0.5 0\n0 0.5 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 9 1\n1 1 2 3 4 5 6\n$EndElements\n");
    let err = read_msh_bytes(text.as_bytes(), "p2.msh").unwrap_err();
    assert!(
        matches!(&err, GmshError::UnsupportedElement { element_type: 9, hint, .. } if hint.contains("first-order")),
        "{err:?}"
    );
    message_names(&err, "p2.msh");
}

#[test]
fn a_group_element_that_is_not_a_cell_is_reported() {
    // The diagonal (2 4) of quad (1 2 3 4) is not an edge of the mesh.
    let text = msh("$PhysicalNames\n1\n1 5 \"cut\"\n$EndPhysicalNames\n$Entities\n0 1 1 0\n1 0 0 0 1 1 0 1 5 0\n1 0 0 0 1 1 0 0 0\n$EndEntities\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n$Elements\n2 2 1 2\n1 1 1 1\n7 2 4\n2 1 3 1\n8 1 2 3 4\n$EndElements\n");
    let err = read_msh_bytes(text.as_bytes(), "diagonal.msh").unwrap_err();
    assert!(
        matches!(&err, GmshError::NotACell { element: 7, dim: 1, group, .. } if group == "cut"),
        "{err:?}"
    );
    message_names(&err, "diagonal.msh");
}

#[test]
fn files_without_a_mesh_are_empty() {
    let no_elements = msh(TRIANGLE_NODES);
    let only_points = msh(&format!(
        "{TRIANGLE_NODES}$Elements\n1 1 1 1\n0 1 15 1\n1 1\n$EndElements\n"
    ));
    let no_nodes = msh("$Nodes\n0 0 1 1\n$EndNodes\n");
    for (text, name) in [
        (no_elements, "no_elements.msh"),
        (only_points, "points.msh"),
        (no_nodes, "no_nodes.msh"),
    ] {
        let err = read_msh_bytes(text.as_bytes(), name).unwrap_err();
        assert!(matches!(err, GmshError::Empty { .. }), "{name}: {err:?}");
        message_names(&err, name);
        assert!(err.to_string().contains("gmsh -2"), "{err}");
    }
}

#[test]
fn non_gmsh_and_malformed_headers_are_parse_errors() {
    let cases = [
        ("Point(1) = {0, 0, 0, 1};\n", "model.geo"),
        ("$MeshFormat\n4.1 2 8\n$EndMeshFormat\n", "filetype.msh"),
        ("$MeshFormat\n4.1 0 3\n$EndMeshFormat\n", "datasize.msh"),
        ("$MeshFormat\n4.1 1 8\n", "binary_marker.msh"),
        ("", "empty.msh"),
    ];
    for (text, name) in cases {
        let err = read_msh_bytes(text.as_bytes(), name).unwrap_err();
        assert!(matches!(err, GmshError::Parse { .. }), "{name}: {err:?}");
        message_names(&err, name);
    }
    let err = read_msh_bytes(b"$MeshFormat\n4 0 8\n$EndMeshFormat\n", "v40.msh").unwrap_err();
    assert!(
        matches!(err, GmshError::UnsupportedVersion { .. }),
        "{err:?}"
    );
}

#[test]
fn degenerate_elements_are_traced_to_the_gmsh_element() {
    let text = msh("$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n2 0 0\n$EndNodes\n$Elements\n1 1 41 41\n2 1 2 1\n41 1 2 3\n$EndElements\n");
    let err = read_msh_bytes(text.as_bytes(), "flat.msh").unwrap_err();
    assert!(matches!(err, GmshError::Complex { .. }), "{err:?}");
    message_names(&err, "flat.msh");
    assert!(err.to_string().contains("Gmsh element 41"), "{err}");
}

#[test]
fn consecutive_node_tags_listed_out_of_order() {
    // Block 1 lists tags 3, 1; block 2 lists tag 2. The tags are consecutive,
    // so a reader that assumed "tag = position" would misplace every node.
    let text = msh("$Nodes\n2 3 1 3\n2 1 0 2\n3\n1\n0 1 0\n0 0 0\n2 2 0 1\n2\n1 0 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n");
    let k = read_msh_bytes(text.as_bytes(), "order.msh").unwrap();
    // Vertices in file order: tag 3 (0,1), tag 1 (0,0), tag 2 (1,0).
    assert_eq!(k.vertices().point(0), &[0.0, 1.0]);
    assert_eq!(k.vertices().point(1), &[0.0, 0.0]);
    assert_eq!(k.vertices().point(2), &[1.0, 0.0]);
    assert_close(signed_area(&k, 0), 0.5);
}

#[test]
fn embedding_dimension_follows_the_coordinates() {
    let lines = |coords: &str| {
        msh(&format!("$Nodes\n1 3 1 3\n1 1 0 3\n1\n2\n3\n{coords}$EndNodes\n$Elements\n1 2 1 2\n1 1 1 2\n1 1 2\n2 2 3\n$EndElements\n"))
    };
    let on_x = read_msh_bytes(lines("0 0 0\n1 0 0\n3 0 0\n").as_bytes(), "x.msh").unwrap();
    assert_eq!((on_x.dim(), on_x.embedding_dim()), (1, 1));
    assert_eq!(on_x.vertices().point(2), &[3.0]);
    let bent = read_msh_bytes(lines("0 0 0\n1 0 0\n1 1 0\n").as_bytes(), "y.msh").unwrap();
    assert_eq!((bent.dim(), bent.embedding_dim()), (1, 2));
    let lifted = read_msh_bytes(lines("0 0 0\n1 0 0\n1 0 2\n").as_bytes(), "z.msh").unwrap();
    assert_eq!((lifted.dim(), lifted.embedding_dim()), (1, 3));
    // A triangle in the plane z = 1 is a surface in R³.
    let text = msh("$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 1\n1 0 1\n0 1 1\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n");
    let surface = read_msh_bytes(text.as_bytes(), "surface.msh").unwrap();
    assert_eq!((surface.dim(), surface.embedding_dim()), (2, 3));
}

#[test]
fn a_single_gmsh_hexahedron() {
    // Gmsh order: bottom 1 2 3 4 and top 5 6 7 8, counter-clockwise.
    let text = msh("$Nodes\n1 8 1 8\n3 1 0 8\n1\n2\n3\n4\n5\n6\n7\n8\n0 0 0\n2 0 0\n2 1 0\n0 1 0\n0 0 3\n2 0 3\n2 1 3\n0 1 3\n$EndNodes\n$Elements\n1 1 1 1\n3 1 5 1\n1 1 2 3 4 5 6 7 8\n$EndElements\n");
    let k = read_msh_bytes(text.as_bytes(), "hex.msh").unwrap();
    assert_eq!(k.cell_counts(), vec![8, 12, 6, 1]);
    assert_chain_complex(&k);
    assert_close(signed_volume(&k, 0), 6.0);
    assert!(k.tags().is_empty());
}

// ---------------------------------------------------------------- JSON

fn triangles_with_tags() -> Complex {
    let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
    let mut k = Complex::build(v, TopCells::simplices([[0, 1, 2], [1, 3, 2]])).unwrap();
    k.set_tag("diagonal", 1, vec![2]).unwrap();
    k.set_tag("corner \"quoted\" ∂", 0, vec![0, 3]).unwrap();
    let bottom = boundary_faces(&k, |x| x[1] < 1e-9);
    k.set_tag("bottom", 1, bottom).unwrap();
    k
}

fn perturbed_quads(seed: u64) -> Complex {
    // A 4×3 grid of quads with every coordinate carrying a full mantissa.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (nx, ny) = (4, 3);
    let mut points = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let jitter = |rng: &mut ChaCha8Rng| rng.gen_range(-0.2..0.2) / 3.0;
            points.push([
                (i as f64 + jitter(&mut rng)) / 7.0,
                (j as f64 + jitter(&mut rng)) * std::f64::consts::PI,
            ]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut quads = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            quads.push([id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)]);
        }
    }
    let mut k = Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::cuboids(quads),
    )
    .unwrap();
    k.set_tag("middle", 2, vec![5, 6]).unwrap();
    k
}

fn two_hexes() -> Complex {
    let mut points = Vec::new();
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..3 {
                points.push([x as f64 * 0.1, y as f64 * 0.3, z as f64 * 1e-3]);
            }
        }
    }
    let id = |x: usize, y: usize, z: usize| z * 6 + y * 3 + x;
    let hex = |x: usize| {
        [
            id(x, 0, 0),
            id(x + 1, 0, 0),
            id(x, 1, 0),
            id(x + 1, 1, 0),
            id(x, 0, 1),
            id(x + 1, 0, 1),
            id(x, 1, 1),
            id(x + 1, 1, 1),
        ]
    };
    let mut k = Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::cuboids([hex(0), hex(1)]),
    )
    .unwrap();
    let left = boundary_faces(&k, |x| x[0] < 1e-12);
    assert_eq!(left.len(), 1);
    k.set_tag("left", 2, left).unwrap();
    k.set_tag("everything", 3, vec![0, 1]).unwrap();
    k
}

fn cube_and_pyramid_polyhedra() -> Complex {
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
        [0.5, 0.5, 1.0 + 1.0 / 3.0],
    ];
    let cube = vec![
        vec![0, 1, 2, 3],
        vec![4, 5, 6, 7],
        vec![0, 1, 5, 4],
        vec![1, 2, 6, 5],
        vec![2, 3, 7, 6],
        vec![3, 0, 4, 7],
    ];
    let pyramid = vec![
        vec![4, 5, 6, 7],
        vec![4, 5, 8],
        vec![5, 6, 8],
        vec![6, 7, 8],
        vec![7, 4, 8],
    ];
    let mut k = Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::polyhedra([cube, pyramid]),
    )
    .unwrap();
    k.set_tag("tip", 0, vec![8]).unwrap();
    k
}

fn interval() -> Complex {
    let v = Vertices::from_points(&[[0.0], [0.1], [0.30000000000000004], [1e-300 + 1.0]]).unwrap();
    Complex::build(v, TopCells::simplices([[0, 1], [1, 2], [2, 3]])).unwrap()
}

fn closed_surface_in_space() -> Complex {
    // The boundary of a tetrahedron: n = 2 in R³, oriented outward.
    let v = Vertices::from_points(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ])
    .unwrap();
    Complex::build(
        v,
        TopCells::simplices([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]),
    )
    .unwrap()
}

fn examples() -> Vec<(&'static str, Complex)> {
    vec![
        ("triangles", triangles_with_tags()),
        ("quads-1", perturbed_quads(1)),
        ("quads-2", perturbed_quads(2)),
        ("hexes", two_hexes()),
        ("polyhedra", cube_and_pyramid_polyhedra()),
        ("interval", interval()),
        ("surface", closed_surface_in_space()),
        ("gmsh", read("mixed_3d_ascii.msh")),
    ]
}

#[test]
fn json_round_trip_is_exact() {
    for (name, k) in examples() {
        let text = to_json(&k);
        let back = from_json_str(&text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_identical(&k, &back);
        // Writing the re-read complex gives the same text.
        assert_eq!(to_json(&back), text, "{name}");
    }
}

#[test]
fn json_text_follows_the_documented_layout() {
    let k = triangles_with_tags();
    let value: serde_json::Value = serde_json::from_str(&to_json(&k)).unwrap();
    assert_eq!(value["format"], "hasse-complex");
    assert_eq!(value["version"], 1);
    assert_eq!(value["embedding_dim"], 2);
    assert_eq!(
        value["vertices"],
        serde_json::json!([0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    );
    // Edges {0,1} {0,2} {1,2} {1,3} {2,3}; triangles {0,1,2} {1,2,3}.
    assert_eq!(
        value["cells"],
        serde_json::json!([
            [[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]],
            [[0, 1, 2], [1, 2, 3]]
        ])
    );
    assert_eq!(
        value["top_orientation"],
        serde_json::json!(k.top_orientation())
    );
    assert_eq!(
        value["tags"]["diagonal"],
        serde_json::json!({"dim": 1, "cells": [2]})
    );
    assert_eq!(
        value["tags"]["bottom"],
        serde_json::json!({"dim": 1, "cells": [0]})
    );
}

#[test]
fn json_files_round_trip_and_replace_atomically() {
    let dir = scratch_dir("roundtrip");
    let path = dir.join("mesh.json");
    let first = two_hexes();
    write_json(&first, &path).unwrap();
    assert_identical(&read_json(&path).unwrap(), &first);
    let second = cube_and_pyramid_polyhedra();
    write_json(&second, &path).unwrap();
    assert_identical(&read_json(&path).unwrap(), &second);
    // No temporary file is left next to the result.
    assert_eq!(dir_entries(&dir), vec!["mesh.json".to_string()]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn failed_writes_leave_nothing_behind() {
    let k = triangles_with_tags();
    // Missing directory: nothing is created.
    let dir = scratch_dir("missing");
    let missing = dir.join("no").join("such").join("dir");
    let err = write_json(&k, &missing.join("mesh.json")).unwrap_err();
    assert!(matches!(err, JsonError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("mesh.json"), "{err}");
    assert!(!dir.join("no").exists());

    // The final name is a non-empty directory: the rename fails after the
    // temporary file was written, and the temporary file is removed.
    let blocked = dir.join("mesh.json");
    std::fs::create_dir(&blocked).unwrap();
    std::fs::write(blocked.join("keep"), "x").unwrap();
    let err = write_json(&k, &blocked).unwrap_err();
    assert!(matches!(err, JsonError::Io { .. }), "{err:?}");
    assert_eq!(dir_entries(&dir), vec!["mesh.json".to_string()]);
    assert_eq!(dir_entries(&blocked), vec!["keep".to_string()]);

    // A read-only directory (not enforced for root, so probe first).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.join("readonly");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        let enforced = std::fs::write(ro.join("probe"), "x").is_err();
        let _ = std::fs::remove_file(ro.join("probe"));
        if enforced {
            let err = write_json(&k, &ro.join("mesh.json")).unwrap_err();
            assert!(matches!(err, JsonError::Io { .. }), "{err:?}");
            assert!(dir_entries(&ro).is_empty());
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn json_errors_are_specific() {
    let good: serde_json::Value = serde_json::from_str(&to_json(&triangles_with_tags())).unwrap();
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        f(&mut v);
        serde_json::to_string(&v).unwrap()
    };

    let err = from_json_str(
        "{\"format\": \"hasse-complex\",\n  \"version\": 1,,}",
        "broken.json",
    )
    .unwrap_err();
    assert!(matches!(err, JsonError::Syntax { line: 2, .. }), "{err:?}");
    assert!(err.to_string().contains("broken.json"), "{err}");

    let format_cases: Vec<(String, &str)> = vec![
        (edit(&|v| v["format"] = "other".into()), "\"format\""),
        (edit(&|v| v["version"] = 2.into()), "version 2"),
        (edit(&|v| v["embedding_dim"] = 4.into()), "embedding_dim"),
        (
            edit(&|v| {
                v.as_object_mut().unwrap().remove("tags");
            }),
            "\"tags\" is missing",
        ),
        (
            edit(&|v| v["colour"] = "red".into()),
            "unknown field \"colour\"",
        ),
        (
            edit(&|v| v["vertices"] = serde_json::json!([0.0, 0.0, 1.0])),
            "multiple",
        ),
        (
            edit(&|v| v["cells"][0][0] = serde_json::json!([0, 9])),
            "vertex 9",
        ),
        (
            edit(&|v| v["top_orientation"] = serde_json::json!([1, 0])),
            "top_orientation",
        ),
        (
            edit(&|v| v["tags"]["bad"] = serde_json::json!({"dim": 1})),
            "tag \"bad\"",
        ),
        // A flipped stored orientation.
        (
            edit(&|v| {
                let o = v["top_orientation"][0].as_i64().unwrap();
                v["top_orientation"][0] = (-o).into();
            }),
            "edited inconsistently",
        ),
    ];
    for (text, expected) in format_cases {
        let err = from_json_str(&text, "edited.json").unwrap_err();
        assert!(
            matches!(err, JsonError::Format { .. }),
            "{expected}: {err:?}"
        );
        let message = err.to_string();
        assert!(message.contains("edited.json"), "{message}");
        assert!(message.contains(expected), "{expected}: {message}");
    }

    // Moving a vertex of a lone triangle across the opposite edge flips it.
    let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    let lone = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&to_json(&lone)).unwrap();
    value["vertices"][0] = 1.0.into();
    value["vertices"][1] = 1.0.into();
    let err = from_json_str(&value.to_string(), "moved.json").unwrap_err();
    assert!(
        matches!(&err, JsonError::Format { message, .. } if message.contains("edited inconsistently")),
        "{err:?}"
    );

    // Dropping edge {1,3}: the remaining cells no longer form a complex.
    let text = edit(&|v| {
        v["cells"][0].as_array_mut().unwrap().remove(3);
        v["tags"] = serde_json::json!({});
    });
    let err = from_json_str(&text, "holey.json").unwrap_err();
    assert!(
        matches!(err, JsonError::Format { .. } | JsonError::Complex { .. }),
        "{err:?}"
    );

    // A tag naming a cell that does not exist.
    let text = edit(&|v| v["tags"]["far"] = serde_json::json!({"dim": 2, "cells": [7]}));
    let err = from_json_str(&text, "tags.json").unwrap_err();
    assert!(matches!(err, JsonError::Complex { .. }), "{err:?}");

    let err = read_json(Path::new("/nonexistent/dir/mesh.json")).unwrap_err();
    assert!(matches!(err, JsonError::Io { .. }), "{err:?}");
}

#[test]
fn json_reads_coordinates_with_correct_rounding() {
    // Values whose shortest representations need 17 digits; a parser that
    // multiplies the decimal significand by a power of ten rounds some of
    // them to a neighbouring double.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut points = Vec::new();
    for i in 0..200 {
        let x: f64 = rng.gen_range(0.0..1.0);
        points.push([i as f64 + x, (i as f64 + x) * 1e-5 + 1.0 / 3.0]);
    }
    let v = Vertices::from_points(&points).unwrap();
    let k = Complex::build(v, TopCells::simplices((0..199).map(|i| [i, i + 1])));
    // The points are not on a line, but the 1-complex is fine in R².
    let k = k.unwrap();
    let back = from_json_str(&to_json(&k), "floats.json").unwrap();
    assert_eq!(bits(&k), bits(&back));
}
