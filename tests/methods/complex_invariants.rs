//! Invariants of the complex crate across every way of making a mesh:
//! generators in 1D–3D, hand-built polytopal cells, Gmsh imports.
//! Expected values are derived by hand in the comments, never read back
//! from the code under test.

use approx::{assert_abs_diff_eq, assert_relative_eq};
use hasse_complex::{generate, gmsh, Complex, TopCells, Vertices};
use sprs::CsMat;
use std::path::PathBuf;

fn cases(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../cases")
        .join(name)
}

/// A mesh of convex polygons that are neither all triangles nor quads: the
/// unit square with its corners cut off (an octagon and four triangles) and a
/// unit square on its right whose left side carries two hanging vertices (a
/// hexagon with straight angles, as SPLIT produces). Area 2, χ = 14 − 19 + 6 = 1.
fn polygon_mesh() -> Complex {
    let t = 1.0 / 3.0;
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [t, 0.0],
        [2.0 * t, 0.0],
        [1.0, 0.0],
        [1.0, t],
        [1.0, 2.0 * t],
        [1.0, 1.0],
        [2.0 * t, 1.0],
        [t, 1.0],
        [0.0, 1.0],
        [0.0, 2.0 * t],
        [0.0, t],
        [2.0, 0.0],
        [2.0, 1.0],
    ])
    .unwrap();
    Complex::build(
        v,
        TopCells::polygons([
            vec![1, 2, 4, 5, 7, 8, 10, 11],
            vec![0, 1, 11],
            vec![2, 3, 4],
            vec![5, 6, 7],
            vec![8, 9, 10],
            vec![3, 12, 13, 6, 5, 4],
        ]),
    )
    .unwrap()
}

/// Two unit cubes side by side given as polyhedra (faces listed cyclically).
fn polyhedron_mesh() -> Complex {
    let mut points = Vec::new();
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..3 {
                points.push([x as f64, y as f64, z as f64]);
            }
        }
    }
    let id = |x: usize, y: usize, z: usize| x + 3 * y + 6 * z;
    let cube = |x0: usize| -> Vec<Vec<usize>> {
        let x1 = x0 + 1;
        vec![
            vec![id(x0, 0, 0), id(x1, 0, 0), id(x1, 1, 0), id(x0, 1, 0)],
            vec![id(x0, 0, 1), id(x1, 0, 1), id(x1, 1, 1), id(x0, 1, 1)],
            vec![id(x0, 0, 0), id(x1, 0, 0), id(x1, 0, 1), id(x0, 0, 1)],
            vec![id(x0, 1, 0), id(x1, 1, 0), id(x1, 1, 1), id(x0, 1, 1)],
            vec![id(x0, 0, 0), id(x0, 1, 0), id(x0, 1, 1), id(x0, 0, 1)],
            vec![id(x1, 0, 0), id(x1, 1, 0), id(x1, 1, 1), id(x1, 0, 1)],
        ]
    };
    Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::polyhedra([cube(0), cube(1)]),
    )
    .unwrap()
}

fn every_mesh() -> Vec<(&'static str, Complex)> {
    let axis = |n| generate::uniform_axis(n, 0.0, 1.0).unwrap();
    let mut meshes = vec![
        ("interval", generate::interval(7, 0.0, 2.0).unwrap()),
        (
            "graded interval",
            generate::grid(&[generate::graded_axis(6, 0.0, 1.0, 1.3).unwrap()]).unwrap(),
        ),
        (
            "quads",
            generate::rectangle(5, 4, [0.0, 1.0], [0.0, 2.0]).unwrap(),
        ),
        (
            "kuhn triangles",
            generate::kuhn(&[axis(5), axis(3)]).unwrap(),
        ),
        (
            "delaunay",
            generate::delaunay(&[
                [0.0, 0.0],
                [1.0, 0.1],
                [2.1, 0.0],
                [0.2, 1.0],
                [1.3, 1.2],
                [2.0, 0.9],
                [0.9, 2.0],
                [1.7, 2.2],
            ])
            .unwrap(),
        ),
        ("annulus", generate::annulus(0.5, 1.0, 3, 12).unwrap()),
        ("torus", generate::torus(2.0, 0.5, 12, 6).unwrap()),
        ("sphere", generate::sphere(1.0, 1).unwrap()),
        (
            "hexes",
            generate::box3(3, 2, 4, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
        ),
        (
            "kuhn tetrahedra",
            generate::kuhn(&[axis(2), axis(3), axis(2)]).unwrap(),
        ),
        ("hollow box", generate::hollow_box(4, [1, 2]).unwrap()),
        ("polygons", polygon_mesh()),
        ("polyhedra", polyhedron_mesh()),
        (
            "l-shape.msh",
            gmsh::read_msh(&cases("l-shape.msh")).unwrap(),
        ),
    ];
    let quads = generate::rectangle(6, 6, [0.0, 1.0], [0.0, 1.0]).unwrap();
    meshes.push((
        "perturbed quads",
        generate::perturb(&quads, 0.3, 11).unwrap(),
    ));
    let hexes = generate::box3(3, 3, 3, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    meshes.push((
        "perturbed hexes",
        generate::perturb(&hexes, 0.3, 5).unwrap(),
    ));
    meshes
}

fn is_zero(m: &CsMat<i8>) -> bool {
    m.data().iter().all(|&x| x == 0)
}

#[test]
fn boundary_of_boundary_vanishes_on_every_mesh_type() {
    for (name, k) in every_mesh() {
        for p in 2..=k.dim() {
            let product = &**k.boundary(p - 1) * &**k.boundary(p);
            assert!(is_zero(&product), "{name}: ∂{}∂{p} ≠ 0", p - 1);
        }
        // Every boundary matrix has entries ±1 only.
        for p in 1..=k.dim() {
            assert!(
                k.boundary(p).data().iter().all(|x| x.abs() == 1),
                "{name}: ∂{p} has an entry other than ±1"
            );
        }
    }
}

#[test]
fn interior_faces_have_opposite_signs_and_boundary_faces_one_cell() {
    for (name, k) in every_mesh() {
        let n = k.dim();
        for (f, row) in k.boundary(n).outer_iterator().enumerate() {
            match row.nnz() {
                1 => {}
                2 => assert_eq!(row.data()[0], -row.data()[1], "{name}: face {f}"),
                m => panic!("{name}: face {f} bounds {m} top cells"),
            }
        }
    }
}

#[test]
fn hasse_matrix_shape_gives_the_euler_characteristic() {
    for (name, k) in every_mesh() {
        let (rows, cols) = k.hasse_matrix().shape();
        assert_eq!(
            cols as i64 - rows as i64,
            k.euler_characteristic(),
            "{name}"
        );
    }
}

#[test]
fn hasse_matrix_of_a_single_cube() {
    // One cube: k = (8, 12, 6, 1). Rows K1 ∪ K3 = 13, columns K0 ∪ K2 = 14, χ = 1.
    let cube = generate::box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    let h = cube.hasse_matrix();
    assert_eq!(h.shape(), (13, 14));
    assert_eq!(cube.euler_characteristic(), 1);
    // Each edge row: 2 vertices + 2 faces; the cube row: 6 faces.
    for (r, row) in h.outer_iterator().enumerate() {
        assert_eq!(row.nnz(), if r < 12 { 4 } else { 6 }, "row {r}");
    }
}

#[test]
fn thesis_two_tetrahedra_adjacency_matrices() {
    // Thesis appendix: two tetrahedra sharing a face, apexes v1 and v5 around
    // the triangle v2 v3 v4 (here 0-based: apexes 0 and 4).
    let v = Vertices::from_points(&[
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [-0.5, 0.9, 0.0],
        [-0.5, -0.9, 0.0],
        [0.0, 0.0, -1.0],
    ])
    .unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3], [4, 1, 2, 3]])).unwrap();
    assert_eq!(k.cell_counts(), vec![5, 9, 7, 2]);
    // [∂1][δ0] = ∂1 ∂1ᵀ: the graph Laplacian, printed in the thesis.
    let d1 = k.boundary(1).map(|&x| i32::from(x));
    let laplacian = (&d1 * &d1.transpose_view().to_csr()).to_dense();
    let printed = [
        [3, -1, -1, -1, 0],
        [-1, 4, -1, -1, -1],
        [-1, -1, 4, -1, -1],
        [-1, -1, -1, 4, -1],
        [0, -1, -1, -1, 3],
    ];
    for i in 0..5 {
        for j in 0..5 {
            assert_eq!(laplacian[[i, j]], printed[i][j], "({i},{j})");
        }
    }
    // [δ2][∂3] = ∂3ᵀ ∂3 = [[4, −1], [−1, 4]]: four faces each, the shared one
    // with opposite orientations.
    let d3 = k.boundary(3).map(|&x| i32::from(x));
    let gram = (&d3.transpose_view().to_csr() * &d3).to_dense();
    assert_eq!(
        (gram[[0, 0]], gram[[0, 1]], gram[[1, 0]], gram[[1, 1]]),
        (4, -1, -1, 4)
    );
    assert_eq!(k.betti_numbers(), vec![1, 0, 0, 0]);
}

#[test]
fn numbering_is_deterministic_and_independent_of_thread_count() {
    let build = || {
        let quads = generate::rectangle(9, 7, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let k = generate::perturb(&quads, 0.25, 3).unwrap();
        let tets = generate::kuhn(&[
            generate::uniform_axis(4, 0.0, 1.0).unwrap(),
            generate::uniform_axis(3, 0.0, 1.0).unwrap(),
            generate::uniform_axis(5, 0.0, 1.0).unwrap(),
        ])
        .unwrap();
        (k, tets)
    };
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(build);
    let parallel = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap()
        .install(build);
    for (a, b) in [(&single.0, &parallel.0), (&single.1, &parallel.1)] {
        assert_eq!(a, b);
        for p in 1..=a.dim() {
            assert_eq!(a.boundary(p), b.boundary(p));
            assert_eq!(
                a.lar().characteristic(p).unwrap(),
                b.lar().characteristic(p).unwrap()
            );
        }
        for p in 0..=a.dim() {
            let bits = |k: &Complex| k.measure(p).iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(a), bits(b), "measure({p})");
        }
    }
}

#[test]
fn measures_sum_to_the_domain_measure() {
    let tol = 1e-12;
    let quads = generate::rectangle(7, 5, [0.0, 2.0], [-1.0, 0.5]).unwrap();
    let total: f64 = quads.measure(2).iter().sum();
    assert_relative_eq!(total, 3.0, epsilon = 0.0, max_relative = tol);
    let perturbed = generate::perturb(&quads, 0.3, 9).unwrap();
    let total: f64 = perturbed.measure(2).iter().sum();
    assert_relative_eq!(total, 3.0, epsilon = 0.0, max_relative = tol);
    let tets = generate::kuhn(&[
        generate::uniform_axis(3, 0.0, 1.0).unwrap(),
        generate::uniform_axis(2, 0.0, 2.0).unwrap(),
        generate::graded_axis(4, 0.0, 3.0, 1.5).unwrap(),
    ])
    .unwrap();
    let total: f64 = tets.measure(3).iter().sum();
    assert_relative_eq!(total, 6.0, epsilon = 0.0, max_relative = tol);
    // Polygonal annulus with m sectors: m/2 · sin(2π/m) · (R² − r²).
    let m = 16;
    let annulus = generate::annulus(0.5, 1.0, 4, m).unwrap();
    let exact = m as f64 / 2.0 * (2.0 * std::f64::consts::PI / m as f64).sin() * (1.0 - 0.25);
    let total: f64 = annulus.measure(2).iter().sum();
    assert_abs_diff_eq!(total, exact, epsilon = tol);
    // The cavity range is half-open: cells 1 and 2 in each direction, a
    // 2×2×2 block of cells of side 1/5.
    let hollow = generate::hollow_box(5, [1, 3]).unwrap();
    let total: f64 = hollow.measure(3).iter().sum();
    assert_abs_diff_eq!(total, 1.0 - 8.0 / 125.0, epsilon = tol);
}

#[test]
fn closed_cells_have_zero_total_flux_of_the_normal() {
    // Σ_f ∂(f,c) |f| n_f = 0 for every top cell of a flat complex.
    let quads = generate::perturb(
        &generate::rectangle(5, 5, [0.0, 1.0], [0.0, 1.0]).unwrap(),
        0.3,
        1,
    )
    .unwrap();
    // Hexes must keep planar faces for |F| n_F to be the vector area: shear
    // the grid by a linear map instead of perturbing vertices independently.
    let grid = generate::box3(3, 3, 3, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    let sheared: Vec<f64> = grid
        .vertices()
        .as_slice()
        .chunks(3)
        .flat_map(|x| {
            [
                x[0] + 0.3 * x[1] - 0.2 * x[2],
                0.9 * x[1] + 0.4 * x[2],
                1.1 * x[2] + 0.1 * x[0],
            ]
        })
        .collect();
    let hexes = grid
        .with_vertices(hasse_complex::Vertices::new(3, sheared).unwrap())
        .unwrap();
    for k in [quads, hexes, polygon_mesh(), polyhedron_mesh()] {
        let n = k.dim();
        let d = k.embedding_dim();
        let area = k.measure(n - 1);
        let normal = k.normal();
        let columns = k.boundary_csc(n);
        for (c, col) in columns.outer_iterator().enumerate() {
            let mut sum = vec![0.0; d];
            for (f, &s) in col.iter() {
                for a in 0..d {
                    sum[a] += f64::from(s) * area[f] * normal[f * d + a];
                }
            }
            let scale: f64 = col.iter().map(|(f, _)| area[f]).sum();
            assert!(
                sum.iter().all(|x| x.abs() < 1e-13 * scale),
                "cell {c}: {sum:?}"
            );
        }
    }
}

#[test]
fn polygon_mesh_counts_and_area() {
    let k = polygon_mesh();
    assert_eq!(k.cell_counts(), vec![14, 19, 6]);
    assert_eq!(k.betti_numbers(), vec![1, 0, 0]);
    let total: f64 = k.measure(2).iter().sum();
    assert_abs_diff_eq!(total, 2.0, epsilon = 1e-14);
    // Octagon: unit square minus four corner triangles of area 1/18.
    assert_abs_diff_eq!(k.measure(2)[0], 1.0 - 4.0 / 18.0, epsilon = 1e-14);
}

#[test]
fn bad_input_is_reported_with_the_cell() {
    let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    let err = Complex::build(v.clone(), TopCells::simplices([[0, 1, 5]])).unwrap_err();
    assert!(err.to_string().contains("vertex 5"), "{err}");
    let err = Complex::build(v.clone(), TopCells::simplices([[0, 1, 1]])).unwrap_err();
    assert!(err.to_string().contains("more than once"), "{err}");
    let err = Complex::build(v, TopCells::cuboids([[0, 1, 2]])).unwrap_err();
    assert!(err.to_string().contains("cuboid with 3 vertices"), "{err}");
    let err = Vertices::new(2, vec![0.0, f64::INFINITY]).unwrap_err();
    assert!(err.to_string().contains("vertex 0"), "{err}");
}
