//! The LAR file format (`lar_json`): what it reads, what it refuses (each
//! error names the key, the cell and the problem) and that writing and
//! reading back gives the same complex; the star operator and products of
//! complexes on meshes.

use hasse_complex::generate;
use hasse_complex::lar_json::{self, LarError};
use hasse_complex::product::CellProduct;
use hasse_complex::Complex;

type TestResult = Result<(), Box<dyn std::error::Error>>;

fn refused(text: &str) -> Result<LarError, String> {
    match lar_json::from_str(text) {
        Ok(k) => Err(format!("accepted, with counts {:?}", k.cell_counts())),
        Err(e) => Ok(e),
    }
}

#[test]
fn bad_input_is_refused_with_the_key_the_cell_and_the_problem() -> TestResult {
    let cases: Vec<(&str, LarError)> = vec![
        (r#"[1, 2]"#, LarError::NotAnObject),
        (r#"{"FV": [[0, 1, 2]]}"#, LarError::MissingVertices),
        (r#"{"V": [[0, 0]]}"#, LarError::NoCells),
        (
            r#"{"V": [[0, 0], [1, 0]], "EV": [[0, 1]], "VF": []}"#,
            LarError::UnknownKey("VF".into()),
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1, 2.5]]}"#,
            LarError::NonIntegerIndex {
                key: "FV",
                cell: 0,
                value: "2.5".into(),
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1, -2]]}"#,
            LarError::NonIntegerIndex {
                key: "FV",
                cell: 0,
                value: "-2".into(),
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1, 2], [1, 2, 3]]}"#,
            LarError::IndexOutOfRange {
                key: "FV",
                cell: 1,
                vertex: 3,
                vertex_count: 3,
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1]]}"#,
            LarError::TooFewVertices {
                key: "FV",
                cell: 0,
                p: 2,
                found: 2,
                needed: "at least 3",
            },
        ),
        (
            r#"{"V": [[0], [1], [2]], "EV": [[0, 1, 2]]}"#,
            LarError::TooFewVertices {
                key: "EV",
                cell: 0,
                p: 1,
                found: 3,
                needed: "exactly 2",
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1, 1]]}"#,
            LarError::RepeatedVertex {
                key: "FV",
                cell: 0,
                vertex: 1,
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0, 0], [0, 1]], "FV": [[0, 1, 2]]}"#,
            LarError::CoordinateDimension {
                vertex: 1,
                expected: 2,
                found: 3,
            },
        ),
        (
            r#"{"V": [[0, 0], [1, "x"], [0, 1]], "FV": [[0, 1, 2]]}"#,
            LarError::NonFiniteCoordinate {
                vertex: 1,
                axis: 1,
                value: "\"x\"".into(),
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1, 2], [2, 1, 0]]}"#,
            LarError::DuplicateCell {
                key: "FV",
                cell: 1,
                first: 0,
            },
        ),
        (
            r#"{"V": [[0], [1], [2]], "FV": [[0, 1, 2]]}"#,
            LarError::DimensionTooHigh {
                key: "FV",
                p: 2,
                embedding_dim: 1,
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1]], "FV": [[0, 1, 2]], "EV": [[0, 1], [0, 2]]}"#,
            LarError::MissingFacet {
                key: "EV",
                vertices: vec![1, 2],
                upper: "FV",
                upper_cell: 0,
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [0, 1], [1, 1]], "FV": [[0, 1, 2]], "EV": [[0, 1], [0, 2], [1, 2], [1, 3]]}"#,
            LarError::NotAFacet {
                key: "EV",
                cell: 3,
                vertices: vec![1, 3],
                upper: "FV",
            },
        ),
        (
            r#"{"V": [[0, 0], [1, 0], [2, 0]], "FV": [[0, 1, 2]]}"#,
            LarError::Degenerate { key: "FV", cell: 0 },
        ),
    ];
    for (text, expected) in cases {
        let err = refused(text)?;
        assert_eq!(err, expected, "{text}");
        // The message names the key and the cell.
        let message = err.to_string();
        if let Some(key) = ["EV", "FV", "CV"].iter().find(|k| text.contains(*k)) {
            if !matches!(err, LarError::UnknownKey(_) | LarError::NotAnObject) {
                assert!(message.contains(key) || message.contains('V'), "{message}");
            }
        }
    }
    // A skew quadrilateral: some vertex is off the plane of the others.
    let skew = refused(r#"{"V": [[0,0,0], [1,0,0], [1,1,0], [0,1,1]], "FV": [[0, 1, 2, 3]]}"#)?;
    assert!(
        matches!(
            skew,
            LarError::NotPlanar {
                key: "FV",
                cell: 0,
                ..
            }
        ),
        "{skew}"
    );
    // Non-finite numbers cannot be written in JSON; a huge one overflows.
    let huge = r#"{"V": [[0, 0], [1e999, 0], [0, 1]], "FV": [[0, 1, 2]]}"#;
    let err = lar_json::parse_str(huge).err().ok_or("accepted 1e999")?;
    assert!(matches!(err, LarError::Syntax { line: 1, .. }), "{err}");
    Ok(())
}

#[test]
fn files_report_syntax_errors_with_line_and_column() -> TestResult {
    let dir = std::env::temp_dir().join(format!("hasse-lar-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("broken.lar.json");
    std::fs::write(&path, "{\"V\": [[0, 0],\n  [1, 0]\n")?;
    let err = lar_json::read_lar_json(&path).err().ok_or("accepted")?;
    assert!(
        matches!(err, lar_json::LarFileError::Syntax { line: 3, .. }),
        "{err}"
    );
    let missing = lar_json::read_lar_json(&dir.join("none.lar.json"))
        .err()
        .ok_or("accepted")?;
    assert!(matches!(missing, lar_json::LarFileError::Io { .. }));
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

fn round_trip(k: &Complex) -> TestResult {
    let text = lar_json::to_lar_json(k);
    let back = lar_json::from_str(&text)?;
    assert_eq!(back.lar(), k.lar());
    for p in 1..=k.dim() {
        assert_eq!(back.boundary(p), k.boundary(p), "∂_{p}");
    }
    Ok(())
}

#[test]
fn written_files_read_back_to_the_same_complex() -> TestResult {
    round_trip(&generate::interval(4, 0.0, 1.0)?)?;
    round_trip(&generate::rectangle(3, 2, [0.0, 1.0], [0.0, 0.1 + 0.2])?)?;
    round_trip(&generate::kuhn(&[vec![0.0, 0.5, 1.0], vec![0.0, 1.0]])?)?;
    round_trip(&generate::box3(
        2,
        1,
        2,
        [0.0, 1.0],
        [0.0, 1.0],
        [0.0, 1.0],
    )?)?;
    round_trip(&generate::voronoi(10, [0.0, 1.0], [0.0, 1.0], 3, 1)?)?;
    round_trip(&generate::sphere(1.0, 1)?)?;
    Ok(())
}

#[test]
fn given_lower_cells_keep_their_numbering() -> TestResult {
    // A square split into two triangles, edges listed in reverse order.
    let text = r#"{"V": [[0, 0], [1, 0], [0, 1], [1, 1]],
        "FV": [[0, 1, 2], [1, 3, 2]],
        "EV": [[3, 2], [1, 3], [1, 2], [2, 0], [0, 1]]}"#;
    let k = lar_json::from_str(text)?;
    let edges: Vec<&[usize]> = (0..5).map(|e| k.cell_vertices(1, e)).collect();
    assert_eq!(edges, vec![&[2, 3][..], &[1, 3], &[1, 2], &[0, 2], &[0, 1]]);
    assert!((&**k.boundary(1) * &**k.boundary(2))
        .data()
        .iter()
        .all(|&x| x == 0));
    Ok(())
}

#[test]
fn one_and_three_dimensional_complexes() -> TestResult {
    // A path in the plane, given by EV alone.
    let path = lar_json::from_str(r#"{"V": [[0, 0], [1, 0], [1, 1]], "EV": [[1, 0], [2, 1]]}"#)?;
    assert_eq!(path.cell_counts(), vec![3, 2]);
    assert_eq!(path.betti_numbers(), vec![1, 0]);
    // A unit cube and a pyramid on its top face, each by CV alone.
    let text = r#"{"V": [[0,0,0],[1,0,0],[0,1,0],[1,1,0],[0,0,1],[1,0,1],[0,1,1],[1,1,1],[0.5,0.5,2]],
        "CV": [[7, 6, 5, 4, 3, 2, 1, 0], [8, 4, 5, 6, 7]]}"#;
    let k = lar_json::from_str(text)?;
    // Cube 8/12/6/1 and the pyramid's apex, 4 edges, 4 triangles.
    assert_eq!(k.cell_counts(), vec![9, 16, 10, 2]);
    let volume: f64 = k.measure(3).iter().sum();
    assert!((volume - 4.0 / 3.0).abs() < 1e-12, "{volume}");
    // A tetrahedron glued into the middle of a cube face is not a complex.
    let glued = r#"{"V": [[0,0,0],[1,0,0],[0,1,0],[1,1,0],[0,0,1],[1,0,1],[0,1,1],[1,1,1],[2,0,0]],
        "CV": [[0, 1, 2, 3, 4, 5, 6, 7], [1, 3, 5, 8]]}"#;
    assert!(lar_json::from_str(glued).is_err());
    assert_eq!(k.euler_characteristic(), 1);
    round_trip(&k)?;
    Ok(())
}

#[test]
fn the_star_of_a_cell_is_every_cell_sharing_a_vertex_with_it() -> TestResult {
    let k = generate::rectangle(3, 3, [0.0, 1.0], [0.0, 1.0])?;
    // The centre square touches all nine; a corner square four.
    let centre = k.lar().star(2, &[4])?;
    assert_eq!(centre[2], (0..9).collect::<Vec<_>>());
    // Its vertices are its own four; its edges, the 12 at those vertices.
    assert_eq!(centre[0].len(), 4);
    assert_eq!(centre[1].len(), 12);
    let corner = k.lar().star(2, &[0])?;
    assert_eq!(corner[2], vec![0, 1, 3, 4]);
    assert_eq!(corner[0].len(), 4);
    // The star of a vertex is its vertex star; the edges around it.
    let at_vertex = k.lar().star(0, &[0])?;
    assert_eq!(at_vertex[0], vec![0]);
    assert_eq!(at_vertex[1].len(), 2);
    assert_eq!(at_vertex[2], vec![0]);
    // The same set as the support of [λ]ᵀ M_p M_qᵀ.
    let product = k.lar().cell_product(2, 2)?;
    let row: Vec<usize> = product
        .outer_view(0)
        .ok_or("row 0")?
        .iter()
        .map(|(j, _)| j)
        .collect();
    assert_eq!(row, corner[2]);
    assert!(k.lar().star(2, &[9]).is_err());
    Ok(())
}

#[test]
fn a_plane_mesh_times_an_interval_is_a_layer_of_prisms() -> TestResult {
    let triangles = generate::kuhn(&[vec![0.0, 0.5, 1.0], vec![0.0, 1.0]])?;
    let layer = generate::interval(2, 0.0, 0.25)?;
    let product = CellProduct::new(triangles.lar(), layer.lar());
    let prisms = product.to_complex()?;
    let (t, l) = (triangles.cell_counts(), layer.cell_counts());
    assert_eq!(prisms.cell_count(3), t[2] * l[1]);
    assert_eq!(prisms.cell_count(0), t[0] * l[0]);
    assert_eq!(prisms.euler_characteristic(), 1);
    assert_eq!(prisms.betti_numbers(), vec![1, 0, 0, 0]);
    // Prisms have six vertices; the volumes add up to 1 × 1 × 0.25.
    assert!((0..prisms.cell_count(3)).all(|c| prisms.cell_vertices(3, c).len() == 6));
    let volume: f64 = prisms.measure(3).iter().sum();
    assert!((volume - 0.25).abs() < 1e-12, "{volume}");
    // The factors of every top cell are a triangle and a layer edge.
    assert_eq!(product.factors(3, 0), (2, 0, 1, 0));
    Ok(())
}
