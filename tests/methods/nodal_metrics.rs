//! Tests of the nodal metrics (FE: P1, Q1, VEM; DEC), all as δ⁰ᵀ Ω δ⁰.
//!
//! Expected values never come from the code under test: the P1 reference
//! stiffness is assembled here element by element from barycentric
//! gradients (K_c = |c| G K Gᵀ, G from the inverse of the simplex's
//! homogeneous coordinate matrix), the Q1 references are the textbook
//! stencils and their Kronecker-product construction, and the rest are
//! properties that hold for any correct method (linear patch test,
//! constants in the kernel, symmetry, exact integrals of linear loads).

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_abs_diff_ne, relative_eq};
use hasse_complex::dual::DualKind;
use hasse_complex::generate::{box3, delaunay, kuhn, perturb, rectangle, uniform_axis};
use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::metric::{dec, fe, isotropic, MetricError, Tensor};
use hasse_solver::operator::{BlockMetric, Canonical};
use nalgebra::DMatrix;
use std::collections::HashMap;

// ---------------------------------------------------------------- helpers

/// δ⁰ᵀ Ω δ⁰ as a dense matrix.
fn assemble(complex: &Complex, omega: BlockMetric) -> DMatrix<f64> {
    let m = Canonical::new(complex.coboundary(0), omega)
        .unwrap()
        .assemble()
        .to_dense();
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

fn largest(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// Every entry within `tol` times the largest entry.
fn assert_close(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64, what: &str) {
    assert_eq!(a.shape(), b.shape(), "{what}");
    let scale = largest(a).max(largest(b));
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            assert!(
                abs_diff_eq!(a[(i, j)], b[(i, j)], epsilon = tol * scale),
                "{what}: entry ({i}, {j}) is {} vs {}",
                a[(i, j)],
                b[(i, j)]
            );
        }
    }
}

/// Deterministic pseudo-random numbers in [0, 1) (xorshift64*).
struct Random(u64);

impl Random {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn top_cells(complex: &Complex) -> usize {
    complex.cell_count(complex.dim())
}

fn constant(complex: &Complex, k: Tensor) -> Vec<Tensor> {
    vec![k; top_cells(complex)]
}

/// A positive scalar coefficient that jumps from cell to cell.
fn jumping(complex: &Complex) -> Vec<Tensor> {
    (0..top_cells(complex))
        .map(|c| isotropic(1.0 + 9.0 * ((c * 7) % 5) as f64 / 4.0))
        .collect()
}

const ANISOTROPIC_2D: Tensor = [[2.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 1.0]];
const ANISOTROPIC_3D: Tensor = [[2.0, 0.5, 0.1], [0.5, 1.0, -0.2], [0.1, -0.2, 1.5]];

/// Measure and barycentric gradients (rows) of a full-dimensional simplex,
/// from the inverse of the homogeneous matrix P (rows (1, x_i)):
/// λ_i(x) = (1, x) · column i of P⁻¹.
fn barycentric(points: &[&[f64]]) -> (f64, DMatrix<f64>) {
    let n = points.len() - 1;
    let p = DMatrix::from_fn(
        n + 1,
        n + 1,
        |i, j| if j == 0 { 1.0 } else { points[i][j - 1] },
    );
    let factorial: f64 = (1..=n).map(|k| k as f64).product();
    let measure = p.determinant().abs() / factorial;
    let inverse = p.try_inverse().unwrap();
    // Row i: ∇λ_i.
    let gradients = DMatrix::from_fn(n + 1, n, |i, a| inverse[(a + 1, i)]);
    (measure, gradients)
}

/// P1 stiffness Σ_c |c| G K Gᵀ, assembled element by element.
fn p1_reference(complex: &Complex, tensors: &[Tensor]) -> DMatrix<f64> {
    let (n, nv) = (complex.dim(), complex.cell_count(0));
    let mut m = DMatrix::zeros(nv, nv);
    for (c, k) in tensors.iter().enumerate() {
        let cell = complex.cell_vertices(n, c);
        let points: Vec<&[f64]> = cell.iter().map(|&v| complex.vertices().point(v)).collect();
        let (measure, g) = barycentric(&points);
        let kn = DMatrix::from_fn(n, n, |i, j| k[i][j]);
        let local = &g * kn * g.transpose() * measure;
        for (i, &vi) in cell.iter().enumerate() {
            for (j, &vj) in cell.iter().enumerate() {
                m[(vi, vj)] += local[(i, j)];
            }
        }
    }
    m
}

fn boundary_vertices(complex: &Complex) -> Vec<bool> {
    let mut on = vec![false; complex.cell_count(0)];
    for &v in complex.boundary_subcomplex().cells(0) {
        on[v] = true;
    }
    on
}

/// M u = 0 at every interior vertex for u linear, and M 1 = 0 everywhere.
fn assert_patch_test(complex: &Complex, m: &DMatrix<f64>, what: &str) {
    let on_boundary = boundary_vertices(complex);
    assert!(on_boundary.iter().any(|b| !b), "{what}: no interior vertex");
    let coefficients = [1.7, -0.9, 0.4];
    let u = DMatrix::from_fn(complex.cell_count(0), 1, |v, _| {
        let x = complex.vertices().point(v);
        0.3 + x.iter().zip(coefficients).map(|(a, b)| a * b).sum::<f64>()
    });
    let mu = m * &u;
    let scale = largest(m) * largest(&u);
    for (v, &b) in on_boundary.iter().enumerate() {
        if !b {
            assert!(
                abs_diff_eq!(mu[v], 0.0, epsilon = 1e-12 * scale),
                "{what}: (M u)_{v} = {:e} for linear u",
                mu[v]
            );
        }
    }
    assert_kernel_and_symmetry(m, what);
}

fn assert_kernel_and_symmetry(m: &DMatrix<f64>, what: &str) {
    let scale = largest(m);
    let ones = DMatrix::from_element(m.ncols(), 1, 1.0);
    let m1 = m * ones;
    assert!(
        largest(&m1) <= 1e-13 * scale,
        "{what}: |M 1| = {:e}",
        largest(&m1)
    );
    assert_close(m, &m.transpose(), 1e-14, &format!("{what}: symmetry"));
}

// ---------------------------------------------------------------- meshes

/// Delaunay triangulation of the unit square's corners and random points.
fn random_delaunay(count: usize, seed: u64) -> Complex {
    let mut random = Random(seed);
    let mut points = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    points.extend((0..count).map(|_| [random.next(), random.next()]));
    delaunay(&points).unwrap()
}

/// Delaunay triangulation of a jittered (n+1)² lattice on the unit square
/// (boundary points stay on the boundary): random, but without the slivers
/// that uniform random points leave along the hull.
fn jittered_delaunay(n: usize, seed: u64) -> Complex {
    let mut random = Random(seed);
    let h = 1.0 / n as f64;
    let mut points = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let mut jitter = || 0.7 * h * (random.next() - 0.5);
            let (dx, dy) = (jitter(), jitter());
            let x = i as f64 * h + if i == 0 || i == n { 0.0 } else { dx };
            let y = j as f64 * h + if j == 0 || j == n { 0.0 } else { dy };
            points.push([x, y]);
        }
    }
    delaunay(&points).unwrap()
}

/// A triangulation of the diamond |x − 1|/2 + |y|/1.5 ≤ 1 whose edge AB has
/// two obtuse opposite angles (≈ 147° and 152°): its cotangent weight is
/// negative, so the mesh is not Delaunay.
fn non_delaunay() -> Complex {
    let points = [
        [0.0, 0.0],   // 0 A
        [2.0, 0.0],   // 1 B
        [1.0, 0.3],   // 2 C
        [1.1, -0.25], // 3 D
        [1.0, 1.5],   // 4 E
        [1.0, -1.5],  // 5 F
        [-1.0, 0.0],  // 6 G
        [3.0, 0.0],   // 7 H
    ];
    let triangles = [
        [0, 1, 2],
        [0, 1, 3],
        [0, 2, 4],
        [2, 1, 4],
        [0, 3, 5],
        [3, 1, 5],
        [6, 0, 4],
        [6, 0, 5],
        [1, 7, 4],
        [1, 7, 5],
    ];
    let v = Vertices::from_points(&points).unwrap();
    Complex::build(v, TopCells::simplices(triangles)).unwrap()
}

fn kuhn_cube(n: usize) -> Complex {
    let x = uniform_axis(n, 0.0, 1.0).unwrap();
    kuhn(&[x.clone(), x.clone(), x]).unwrap()
}

/// [0, 3]² cut into 3×3 unit squares, each interior grid vertex blown up
/// into a small diamond (half-diagonal ε, different at each vertex): corner
/// squares become pentagons, side squares hexagons, the centre an octagon.
/// 9 + 4 convex polygons.
fn cut_corner_polygons() -> Complex {
    let epsilon = |i: i64, j: i64| 0.15 + 0.05 * (i + 2 * j - 3) as f64;
    let interior = |i: i64, j: i64| (1..=2).contains(&i) && (1..=2).contains(&j);
    let mut index: HashMap<(i64, i64, i64, i64), usize> = HashMap::new();
    let mut points: Vec<[f64; 2]> = Vec::new();
    // A vertex is a grid point (i, j) moved by (dx, dy) · ε(i, j).
    let mut id = |i: i64, j: i64, dx: i64, dy: i64, points: &mut Vec<[f64; 2]>| {
        *index.entry((i, j, dx, dy)).or_insert_with(|| {
            let e = if dx == 0 && dy == 0 {
                0.0
            } else {
                epsilon(i, j)
            };
            points.push([i as f64 + e * dx as f64, j as f64 + e * dy as f64]);
            points.len() - 1
        })
    };
    let mut polygons: Vec<Vec<usize>> = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let mut polygon = Vec::new();
            for k in 0..4 {
                let (ci, cj) = corners[k];
                if interior(ci, cj) {
                    let (pi, pj) = corners[(k + 3) % 4];
                    let (ni, nj) = corners[(k + 1) % 4];
                    polygon.push(id(ci, cj, pi - ci, pj - cj, &mut points));
                    polygon.push(id(ci, cj, ni - ci, nj - cj, &mut points));
                } else {
                    polygon.push(id(ci, cj, 0, 0, &mut points));
                }
            }
            polygons.push(polygon);
        }
    }
    for (i, j) in [(1, 1), (2, 1), (2, 2), (1, 2)] {
        polygons.push(vec![
            id(i, j, 1, 0, &mut points),
            id(i, j, 0, 1, &mut points),
            id(i, j, -1, 0, &mut points),
            id(i, j, 0, -1, &mut points),
        ]);
    }
    let v = Vertices::from_points(&points).unwrap();
    Complex::build(v, TopCells::polygons(polygons)).unwrap()
}

/// Triangular prisms: a Delaunay triangulation of the unit square extruded
/// through the layers z = 0, 0.3, 1.
fn prisms() -> Complex {
    let base = random_delaunay(12, 99);
    let layers = [0.0, 0.3, 1.0];
    let nb = base.cell_count(0);
    let mut points = Vec::new();
    for &z in &layers {
        for v in 0..nb {
            let p = base.vertices().point(v);
            points.push([p[0], p[1], z]);
        }
    }
    let mut cells: Vec<Vec<Vec<usize>>> = Vec::new();
    for layer in 0..layers.len() - 1 {
        for t in 0..base.cell_count(2) {
            let tri = base.cell_vertices(2, t);
            let lo = |k: usize| tri[k] + layer * nb;
            let hi = |k: usize| tri[k] + (layer + 1) * nb;
            let mut faces = vec![vec![lo(0), lo(1), lo(2)], vec![hi(0), hi(1), hi(2)]];
            for k in 0..3 {
                let m = (k + 1) % 3;
                faces.push(vec![lo(k), lo(m), hi(m), hi(k)]);
            }
            cells.push(faces);
        }
    }
    let v = Vertices::from_points(&points).unwrap();
    Complex::build(v, TopCells::polyhedra(cells)).unwrap()
}

// ------------------------------------------------ DEC = P1 (the equivalence)

/// DEC and FE both reproduce the element-by-element P1 stiffness to 1e-12
/// of the largest entry: in 2D the diagonal circumcentric star (and the
/// Whitney star), in 3D the Whitney star (the diagonal one is not P1 there,
/// see `diagonal_circumcentric_star_in_3d_*`).
fn assert_dec_and_fe_are_p1(complex: &Complex, tensors: &[Tensor], what: &str) {
    let reference = p1_reference(complex, tensors);
    if complex.dim() == 2 {
        let dec = assemble(
            complex,
            dec::hodge_metric(complex, DualKind::Circumcentric, tensors).unwrap(),
        );
        assert_close(&dec, &reference, 1e-12, &format!("{what}: DEC vs P1"));
    }
    let whitney = assemble(complex, dec::whitney_metric(complex, tensors).unwrap());
    assert_close(
        &whitney,
        &reference,
        1e-12,
        &format!("{what}: Whitney vs P1"),
    );
    let fe = assemble(complex, fe::stiffness_metric(complex, tensors).unwrap());
    assert_close(&fe, &reference, 1e-12, &format!("{what}: FE vs P1"));
}

#[test]
fn dec_laplacian_equals_p1_on_a_delaunay_triangulation() {
    let k = random_delaunay(200, 7);
    assert_dec_and_fe_are_p1(&k, &constant(&k, isotropic(1.0)), "Delaunay");
}

#[test]
fn dec_laplacian_equals_p1_on_a_non_delaunay_triangulation() {
    let k = non_delaunay();
    let tensors = constant(&k, isotropic(1.0));
    let omega = dec::hodge_metric(&k, DualKind::Circumcentric, &tensors).unwrap();
    let ab = k.find_cell(1, &[0, 1]).unwrap();
    let weight = omega.to_dense()[ab][ab];
    // cot 146.6° + cot 151.9° < 0, worked out from the coordinates:
    // cot θ = (u·v)/|u×v| at C = (1, 0.3) and D = (1.1, −0.25).
    let cot = |c: [f64; 2]| {
        let (u, v) = ([0.0 - c[0], 0.0 - c[1]], [2.0 - c[0], 0.0 - c[1]]);
        (u[0] * v[0] + u[1] * v[1]) / (u[0] * v[1] - u[1] * v[0]).abs()
    };
    let expected = 0.5 * (cot([1.0, 0.3]) + cot([1.1, -0.25]));
    assert!(expected < -1.0);
    assert_abs_diff_eq!(weight, expected, epsilon = 1e-14);
    assert_dec_and_fe_are_p1(&k, &tensors, "non-Delaunay");
}

#[test]
fn whitney_dec_equals_p1_on_kuhn_boxes() {
    let k = kuhn_cube(3);
    assert_dec_and_fe_are_p1(&k, &constant(&k, isotropic(1.0)), "Kuhn box");
    let p = perturb(&k, 0.3, 11).unwrap();
    assert_dec_and_fe_are_p1(&p, &constant(&p, isotropic(1.0)), "perturbed Kuhn box");
}

#[test]
fn diagonal_circumcentric_star_in_3d_is_the_seven_point_stencil_inside_a_kuhn_box() {
    // The Voronoi cell of an interior grid vertex is the cube of side h
    // around it: weight h²/h = h on the six axis edges, 0 on the diagonals.
    // P1 on the Kuhn split gives the same interior rows.
    let n = 3;
    let h = 1.0 / n as f64;
    let k = kuhn_cube(n);
    let tensors = constant(&k, isotropic(1.0));
    let dec = assemble(
        &k,
        dec::hodge_metric(&k, DualKind::Circumcentric, &tensors).unwrap(),
    );
    let p1 = p1_reference(&k, &tensors);
    let side = n + 1;
    let on_boundary = boundary_vertices(&k);
    for (v, _) in on_boundary.iter().enumerate().filter(|(_, &b)| !b) {
        let at = [v % side, (v / side) % side, v / (side * side)];
        for w in 0..k.cell_count(0) {
            let other = [w % side, (w / side) % side, w / (side * side)];
            let steps: usize = (0..3).map(|a| at[a].abs_diff(other[a])).sum();
            let axis = (0..3).all(|a| at[a].abs_diff(other[a]) <= 1);
            let expected = match (steps, axis) {
                (0, _) => 6.0 * h,
                (1, true) => -h,
                _ => 0.0,
            };
            assert!(
                abs_diff_eq!(dec[(v, w)], expected, epsilon = 1e-14),
                "DEC ({v}, {w})"
            );
            assert!(
                abs_diff_eq!(p1[(v, w)], expected, epsilon = 1e-14),
                "P1 ({v}, {w})"
            );
        }
    }
    // Near the boundary, and on any perturbed grid, the two differ.
    assert_abs_diff_ne!(dec[(0, 0)], p1[(0, 0)], epsilon = 0.05);
    let p = perturb(&k, 0.3, 11).unwrap();
    let tensors = constant(&p, isotropic(1.0));
    let dec = assemble(
        &p,
        dec::hodge_metric(&p, DualKind::Circumcentric, &tensors).unwrap(),
    );
    assert!(largest(&(&dec - p1_reference(&p, &tensors))) > 1e-3 * largest(&dec));
}

#[test]
fn dec_laplacian_equals_p1_with_a_jumping_coefficient() {
    for (k, what) in [
        (random_delaunay(150, 3), "Delaunay"),
        (non_delaunay(), "non-Delaunay"),
        (
            perturb(&kuhn_cube(3), 0.25, 5).unwrap(),
            "perturbed Kuhn box",
        ),
    ] {
        assert_dec_and_fe_are_p1(&k, &jumping(&k), what);
    }
}

#[test]
fn hodge_weights_sum_to_the_dual_measures() {
    // Well-shaped meshes: on slivers the dual measures computed from far-away
    // circumcentres lose digits that the metric (which works from angles)
    // keeps, see `sliver_weights_keep_their_digits` in the dec module.
    for k in [jittered_delaunay(8, 1), non_delaunay()] {
        for kind in [DualKind::Circumcentric, DualKind::Barycentric] {
            let omega = dec::hodge_metric(&k, kind, &constant(&k, isotropic(1.0))).unwrap();
            let dense = omega.to_dense();
            for (e, s) in k.hodge_star(kind, 1).unwrap().iter().enumerate() {
                assert!(
                    relative_eq!(dense[e][e], s, epsilon = 1e-13, max_relative = 1e-13),
                    "{kind:?} {e}"
                );
            }
        }
    }
    let p = perturb(&kuhn_cube(2), 0.3, 2).unwrap();
    let q = perturb(
        &box3(2, 2, 2, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
        0.2,
        4,
    )
    .unwrap();
    for (k, kinds) in [
        (&p, &[DualKind::Circumcentric, DualKind::Barycentric][..]),
        (&q, &[DualKind::Barycentric][..]),
    ] {
        for &kind in kinds {
            let omega = dec::hodge_metric(k, kind, &constant(k, isotropic(1.0))).unwrap();
            let dense = omega.to_dense();
            for (e, s) in k.hodge_star(kind, 1).unwrap().iter().enumerate() {
                assert!(
                    relative_eq!(dense[e][e], s, epsilon = 1e-13, max_relative = 1e-13),
                    "3D {kind:?} {e}"
                );
            }
        }
    }
}

// ------------------------------------------------------------- tensors

#[test]
fn anisotropic_p1_from_fe_and_whitney_dec_match_the_element_assembly() {
    let k = random_delaunay(120, 21);
    let tensors = constant(&k, ANISOTROPIC_2D);
    let reference = p1_reference(&k, &tensors);
    let fe = assemble(&k, fe::stiffness_metric(&k, &tensors).unwrap());
    assert_close(&fe, &reference, 1e-12, "FE tensor 2D");
    for kind in [DualKind::Circumcentric, DualKind::Barycentric] {
        let omega = dec::hodge_metric(&k, kind, &tensors).unwrap();
        // One 3×3 Whitney block per triangle.
        assert_eq!(omega.block_count(), k.cell_count(2));
        let dec = assemble(&k, omega);
        assert_close(&dec, &reference, 1e-12, "Whitney tensor 2D");
    }
    let p = perturb(&kuhn_cube(2), 0.25, 8).unwrap();
    let tensors = constant(&p, ANISOTROPIC_3D);
    let reference = p1_reference(&p, &tensors);
    let fe = assemble(&p, fe::stiffness_metric(&p, &tensors).unwrap());
    assert_close(&fe, &reference, 1e-12, "FE tensor 3D");
    let dec = assemble(
        &p,
        dec::hodge_metric(&p, DualKind::Circumcentric, &tensors).unwrap(),
    );
    assert_close(&dec, &reference, 1e-12, "Whitney tensor 3D");
}

#[test]
fn mixed_scalar_and_tensor_cells_combine() {
    let k = random_delaunay(40, 13);
    let tensors: Vec<Tensor> = (0..k.cell_count(2))
        .map(|c| {
            if c % 2 == 0 {
                ANISOTROPIC_2D
            } else {
                isotropic(3.0)
            }
        })
        .collect();
    let reference = p1_reference(&k, &tensors);
    let dec = assemble(
        &k,
        dec::hodge_metric(&k, DualKind::Circumcentric, &tensors).unwrap(),
    );
    assert_close(&dec, &reference, 1e-12, "mixed coefficients");
}

// ------------------------------------------------------------------- Q1

#[test]
fn q1_on_a_uniform_grid_is_the_nine_point_stencil() {
    let n = 4;
    let k = rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let m = assemble(
        &k,
        fe::stiffness_metric(&k, &constant(&k, isotropic(1.0))).unwrap(),
    );
    let side = n + 1;
    for j in 1..n {
        for i in 1..n {
            let row = i + side * j;
            for col in 0..side * side {
                let (ci, cj) = (col % side, col / side);
                let expected = match (ci.abs_diff(i), cj.abs_diff(j)) {
                    (0, 0) => 8.0 / 3.0,
                    (0 | 1, 0 | 1) => -1.0 / 3.0,
                    _ => 0.0,
                };
                assert!(
                    abs_diff_eq!(m[(row, col)], expected, epsilon = 1e-14),
                    "row {row} col {col}: {} vs {expected}",
                    m[(row, col)]
                );
            }
        }
    }
}

/// 1D P1 stiffness and mass of a uniform axis (n cells of size h).
fn one_d(n: usize, h: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut k = DMatrix::zeros(n + 1, n + 1);
    let mut m = DMatrix::zeros(n + 1, n + 1);
    for e in 0..n {
        for (a, b) in [(e, e), (e + 1, e + 1)] {
            k[(a, b)] += 1.0 / h;
            m[(a, b)] += h / 3.0;
        }
        for (a, b) in [(e, e + 1), (e + 1, e)] {
            k[(a, b)] -= 1.0 / h;
            m[(a, b)] += h / 6.0;
        }
    }
    (k, m)
}

#[test]
fn q1_on_rectangular_grids_is_the_tensor_product_stiffness() {
    // Q1 stiffness = K_y ⊗ M_x + M_y ⊗ K_x with vertices numbered x fastest.
    let (nx, ny) = (3, 2);
    let k = rectangle(nx, ny, [0.0, 1.5], [0.0, 0.4]).unwrap();
    let m = assemble(
        &k,
        fe::stiffness_metric(&k, &constant(&k, isotropic(2.0))).unwrap(),
    );
    let (kx, mx) = one_d(nx, 0.5);
    let (ky, my) = one_d(ny, 0.2);
    let expected = (ky.kronecker(&mx) + my.kronecker(&kx)) * 2.0;
    assert_close(&m, &expected, 1e-13, "Q1 2D");

    let (nx, ny, nz) = (2, 3, 2);
    let k = box3(nx, ny, nz, [0.0, 1.0], [0.0, 0.6], [0.0, 2.0]).unwrap();
    let m = assemble(
        &k,
        fe::stiffness_metric(&k, &constant(&k, isotropic(1.0))).unwrap(),
    );
    let (kx, mx) = one_d(nx, 0.5);
    let (ky, my) = one_d(ny, 0.2);
    let (kz, mz) = one_d(nz, 1.0);
    let expected = kz.kronecker(&my.kronecker(&mx))
        + mz.kronecker(&ky.kronecker(&mx))
        + mz.kronecker(&my.kronecker(&kx));
    assert_close(&m, &expected, 1e-13, "Q1 3D");
    // The unit-cube element: 1/3 on the diagonal, 0 along edges, −1/12 across
    // faces and the body diagonal; the interior row of a unit grid sums them.
    let k = box3(2, 2, 2, [0.0, 2.0], [0.0, 2.0], [0.0, 2.0]).unwrap();
    let m = assemble(
        &k,
        fe::stiffness_metric(&k, &constant(&k, isotropic(1.0))).unwrap(),
    );
    let centre = 13;
    for col in 0..27 {
        let offsets = [col % 3, (col / 3) % 3, col / 9].map(|c: usize| c.abs_diff(1));
        let expected = match offsets.iter().sum::<usize>() {
            0 => 8.0 / 3.0,
            1 => 0.0,
            2 => -2.0 / 12.0,
            _ => -1.0 / 12.0,
        };
        assert!(
            abs_diff_eq!(m[(centre, col)], expected, epsilon = 1e-14),
            "col {col}"
        );
    }
}

// ------------------------------------------------------- patch tests

#[test]
fn p1_patch_test() {
    let k = random_delaunay(100, 17);
    for tensor in [isotropic(1.0), ANISOTROPIC_2D] {
        let m = assemble(&k, fe::stiffness_metric(&k, &constant(&k, tensor)).unwrap());
        assert_patch_test(&k, &m, "P1 Delaunay");
    }
    let p = perturb(&kuhn_cube(3), 0.3, 1).unwrap();
    for tensor in [isotropic(1.0), ANISOTROPIC_3D] {
        let m = assemble(&p, fe::stiffness_metric(&p, &constant(&p, tensor)).unwrap());
        assert_patch_test(&p, &m, "P1 perturbed Kuhn");
    }
}

#[test]
fn q1_patch_test_on_perturbed_quads_and_hexes() {
    let q = perturb(&rectangle(6, 5, [0.0, 2.0], [0.0, 1.0]).unwrap(), 0.3, 3).unwrap();
    let h = perturb(
        &box3(3, 3, 3, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
        0.25,
        9,
    )
    .unwrap();
    for (k, tensor) in [(&q, ANISOTROPIC_2D), (&h, ANISOTROPIC_3D)] {
        for tensor in [isotropic(1.0), tensor] {
            let omega = fe::stiffness_metric(k, &constant(k, tensor)).unwrap();
            // One dense block per cell (Q1), no diagonal part.
            assert_eq!(omega.block_count(), top_cells(k));
            assert!(omega.is_symmetric(0.0));
            assert_patch_test(k, &assemble(k, omega), "Q1 perturbed");
        }
    }
}

#[test]
fn vem_patch_test_on_polygons_polyhedra_and_distorted_grids() {
    let polygons = cut_corner_polygons();
    assert_eq!(polygons.cell_count(2), 13);
    let counts: Vec<usize> = (0..13)
        .map(|c| polygons.cell_vertices(2, c).len())
        .collect();
    assert_eq!(counts.iter().filter(|&&n| n == 5).count(), 4);
    assert_eq!(counts.iter().filter(|&&n| n == 8).count(), 1);
    let q = perturb(&rectangle(5, 5, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.3, 6).unwrap();
    let h = perturb(
        &box3(3, 3, 3, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
        0.25,
        4,
    )
    .unwrap();
    let prisms = prisms();
    let cases: [(&Complex, Tensor, &str); 4] = [
        (&polygons, ANISOTROPIC_2D, "VEM polygons"),
        (&q, ANISOTROPIC_2D, "VEM perturbed quads"),
        (&h, ANISOTROPIC_3D, "VEM perturbed hexes"),
        (&prisms, ANISOTROPIC_3D, "VEM prisms"),
    ];
    for (k, tensor, what) in cases {
        for tensor in [isotropic(1.0), tensor] {
            let omega = fe::vem_stiffness_metric(k, &constant(k, tensor)).unwrap();
            assert_patch_test(k, &assemble(k, omega), what);
        }
    }
    // Shape dispatch: prisms go to the virtual element; the polygon mesh
    // mixes Q1 (its diamonds) with virtual elements and still passes.
    let tensors = constant(&prisms, isotropic(1.0));
    let by_shape = assemble(&prisms, fe::stiffness_metric(&prisms, &tensors).unwrap());
    let vem = assemble(
        &prisms,
        fe::vem_stiffness_metric(&prisms, &tensors).unwrap(),
    );
    assert_close(&by_shape, &vem, 1e-14, "dispatch");
    let omega = fe::stiffness_metric(&polygons, &constant(&polygons, ANISOTROPIC_2D)).unwrap();
    assert_patch_test(&polygons, &assemble(&polygons, omega), "Q1 + VEM polygons");
}

#[test]
fn vem_on_simplices_is_p1() {
    let k = random_delaunay(30, 5);
    let tensors = constant(&k, ANISOTROPIC_2D);
    let vem = assemble(&k, fe::vem_stiffness_metric(&k, &tensors).unwrap());
    assert_close(&vem, &p1_reference(&k, &tensors), 1e-12, "VEM on triangles");
    let p = perturb(&kuhn_cube(2), 0.2, 3).unwrap();
    let tensors = constant(&p, ANISOTROPIC_3D);
    let vem = assemble(&p, fe::vem_stiffness_metric(&p, &tensors).unwrap());
    assert_close(
        &vem,
        &p1_reference(&p, &tensors),
        1e-12,
        "VEM on tetrahedra",
    );
}

#[test]
fn vem_on_parallelograms_is_exact_for_the_consistency_part() {
    // On a rectangle the virtual element is not Q1 (its stabilisation is not
    // the bilinear correction) but both are exact for linear u: they agree
    // on the linear functions.
    let k = rectangle(1, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let tensors = constant(&k, isotropic(1.0));
    let q1 = assemble(&k, fe::stiffness_metric(&k, &tensors).unwrap());
    let vem = assemble(&k, fe::vem_stiffness_metric(&k, &tensors).unwrap());
    for u in [
        [1.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0, 1.0],
        [1.0, 3.0, -1.0, 1.0],
    ] {
        let u = DMatrix::from_row_slice(4, 1, &u);
        let (a, b) = (&q1 * &u, &vem * &u);
        assert!((a - b).abs().max() < 1e-14);
    }
}

#[test]
fn dec_patch_test() {
    for (k, what) in [
        (random_delaunay(100, 23), "DEC Delaunay"),
        (non_delaunay(), "DEC non-Delaunay"),
        (
            perturb(&kuhn_cube(3), 0.3, 12).unwrap(),
            "DEC perturbed Kuhn",
        ),
    ] {
        let omega = dec::hodge_metric(&k, DualKind::Circumcentric, &constant(&k, isotropic(1.0)));
        assert_patch_test(&k, &assemble(&k, omega.unwrap()), what);
    }
    // The barycentric dual of a uniform grid is orthogonal: five- and
    // seven-point stencils, exact for linear u.
    let q = rectangle(4, 3, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let h = box3(3, 3, 3, [0.0, 1.0], [0.0, 1.5], [0.0, 1.0]).unwrap();
    for k in [&q, &h] {
        let omega = dec::hodge_metric(k, DualKind::Barycentric, &constant(k, isotropic(1.0)));
        assert_patch_test(k, &assemble(k, omega.unwrap()), "DEC barycentric grid");
    }
    // Five-point stencil entries: |⋆e| / |e| = h_y / h_x across a vertical dual edge.
    let m = assemble(
        &q,
        dec::hodge_metric(&q, DualKind::Barycentric, &constant(&q, isotropic(1.0))).unwrap(),
    );
    let centre = 1 + 5;
    let (hx, hy) = (0.5, 1.0 / 3.0);
    assert_abs_diff_eq!(
        m[(centre, centre)],
        2.0 * (hy / hx + hx / hy),
        epsilon = 1e-14
    );
    assert_abs_diff_eq!(m[(centre, centre + 1)], -(hy / hx), epsilon = 1e-14);
    assert_abs_diff_eq!(m[(centre, centre + 5)], -(hx / hy), epsilon = 1e-14);
    assert_abs_diff_eq!(m[(centre, centre + 6)], 0.0, epsilon = 1e-14);
}

#[test]
fn kernel_and_symmetry_of_every_method() {
    let polygons = cut_corner_polygons();
    let prisms = prisms();
    let q = perturb(&rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.3, 2).unwrap();
    let k = random_delaunay(50, 31);
    for (complex, what) in [
        (&polygons, "polygons"),
        (&prisms, "prisms"),
        (&q, "quads"),
        (&k, "triangles"),
    ] {
        let tensors = jumping(complex);
        let m = assemble(complex, fe::stiffness_metric(complex, &tensors).unwrap());
        assert_kernel_and_symmetry(&m, &format!("FE {what}"));
        let m = assemble(
            complex,
            fe::vem_stiffness_metric(complex, &tensors).unwrap(),
        );
        assert_kernel_and_symmetry(&m, &format!("VEM {what}"));
        let m = assemble(
            complex,
            dec::hodge_metric(complex, DualKind::Barycentric, &tensors).unwrap(),
        );
        assert_kernel_and_symmetry(&m, &format!("DEC barycentric {what}"));
    }
}

#[test]
fn embedded_triangles_give_the_surface_laplacian() {
    // A rotated copy of a planar triangulation in R³ has the same P1 and DEC
    // matrices as the planar one.
    let k = random_delaunay(40, 19);
    let (c, s) = (0.6f64, 0.8f64);
    let points: Vec<[f64; 3]> = (0..k.cell_count(0))
        .map(|v| {
            let p = k.vertices().point(v);
            [p[0], c * p[1], s * p[1]]
        })
        .collect();
    let cells: Vec<Vec<usize>> = (0..k.cell_count(2))
        .map(|t| k.cell_vertices(2, t).to_vec())
        .collect();
    let surface = Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::simplices(cells),
    )
    .unwrap();
    let planar = p1_reference(&k, &constant(&k, isotropic(1.0)));
    let tensors = constant(&surface, isotropic(1.0));
    let fe = assemble(&surface, fe::stiffness_metric(&surface, &tensors).unwrap());
    assert_close(&fe, &planar, 1e-12, "surface FE");
    let dec = assemble(
        &surface,
        dec::hodge_metric(&surface, DualKind::Circumcentric, &tensors).unwrap(),
    );
    assert_close(&dec, &planar, 1e-12, "surface DEC");
    // Q1 and VEM need cells that fill their space.
    let quads = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let lifted: Vec<[f64; 3]> = (0..4)
        .map(|v| {
            let p = quads.vertices().point(v);
            [p[0], p[1], 0.0]
        })
        .collect();
    let lifted = quads
        .with_vertices(Vertices::from_points(&lifted).unwrap())
        .unwrap();
    assert!(matches!(
        fe::stiffness_metric(&lifted, &[isotropic(1.0)]),
        Err(MetricError::UnsupportedMesh { .. })
    ));
}

// ------------------------------------------------------------------ load

/// ∫ f over every simplex of `k` for linear f: |τ| f(centroid), with |τ|
/// from the homogeneous determinant.
fn integral_over_simplices(k: &Complex, f: &dyn Fn(&[f64]) -> f64) -> f64 {
    let n = k.dim();
    (0..k.cell_count(n))
        .map(|c| {
            let cell = k.cell_vertices(n, c);
            let points: Vec<&[f64]> = cell.iter().map(|&v| k.vertices().point(v)).collect();
            let (measure, _) = barycentric(&points);
            let centroid: Vec<f64> = (0..n)
                .map(|a| points.iter().map(|p| p[a]).sum::<f64>() / (n + 1) as f64)
                .collect();
            measure * f(&centroid)
        })
        .sum()
}

fn assert_total(load: &[f64], expected: f64, what: &str) {
    let total: f64 = load.iter().sum();
    assert!(
        relative_eq!(total, expected, epsilon = 1e-13, max_relative = 1e-13),
        "{what}: Σ load = {total}, ∫ f = {expected}"
    );
}

fn one(_: &[f64]) -> f64 {
    1.0
}

fn linear(x: &[f64]) -> f64 {
    1.0 + 2.0 * x[0] - 3.0 * x[1] + x.get(2).map_or(0.0, |z| 0.5 * z)
}

#[test]
fn fe_load_integrates_constants_and_linear_functions() {
    let t = random_delaunay(80, 29);
    let p = perturb(&kuhn_cube(3), 0.3, 6).unwrap();
    for k in [&t, &p] {
        assert_total(
            &fe::load(k, &one).unwrap(),
            integral_over_simplices(k, &one),
            "P1 1",
        );
        assert_total(
            &fe::load(k, &linear).unwrap(),
            integral_over_simplices(k, &linear),
            "P1 linear",
        );
    }
    // Each vertex gets ∫ f φ_v = |T| (f_1 + f_2 + f_3 + f_v) / 12 for linear f.
    let v = Vertices::from_points(&[[0.2, 0.1], [1.5, 0.3], [0.4, 1.2]]).unwrap();
    let tri = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    let b = fe::load(&tri, &linear).unwrap();
    let values: Vec<f64> = (0..3).map(|v| linear(tri.vertices().point(v))).collect();
    let area = 0.5 * ((1.3f64) * 1.1 - 0.2 * 0.2);
    for (v, bv) in b.iter().enumerate() {
        let expected = area * (values.iter().sum::<f64>() + values[v]) / 12.0;
        assert!(
            abs_diff_eq!(*bv, expected, epsilon = 1e-14),
            "{v}: {bv} vs {expected}"
        );
    }
    // Q1 on distorted quads of [0, 2] × [0, 1] and hexes of the unit cube.
    let q = perturb(&rectangle(5, 4, [0.0, 2.0], [0.0, 1.0]).unwrap(), 0.3, 8).unwrap();
    assert_total(&fe::load(&q, &one).unwrap(), 2.0, "Q1 1");
    assert_total(
        &fe::load(&q, &linear).unwrap(),
        2.0 + 4.0 - 3.0,
        "Q1 linear",
    );
    let h = perturb(
        &box3(3, 2, 3, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
        0.25,
        8,
    )
    .unwrap();
    assert_total(&fe::load(&h, &one).unwrap(), 1.0, "Q1 hex 1");
    assert_total(
        &fe::load(&h, &linear).unwrap(),
        1.0 + 1.0 - 1.5 + 0.25,
        "Q1 hex linear",
    );
    // VEM: [0, 3]² and the unit cube.
    let polygons = cut_corner_polygons();
    assert_total(&fe::load(&polygons, &one).unwrap(), 9.0, "VEM 1");
    assert_total(
        &fe::load(&polygons, &linear).unwrap(),
        9.0 + 27.0 - 40.5,
        "VEM linear",
    );
    let prisms = prisms();
    assert_total(&fe::load(&prisms, &one).unwrap(), 1.0, "VEM prisms 1");
    assert_total(
        &fe::load(&prisms, &linear).unwrap(),
        1.0 + 1.0 - 1.5 + 0.25,
        "VEM prisms linear",
    );
}

#[test]
fn dec_load_integrates_constants_and_linear_functions_on_barycentric_duals() {
    let t = random_delaunay(80, 37);
    let p = perturb(&kuhn_cube(3), 0.3, 6).unwrap();
    for k in [&t, &p] {
        for kind in [DualKind::Circumcentric, DualKind::Barycentric] {
            assert_total(
                &dec::load(k, kind, &one).unwrap(),
                integral_over_simplices(k, &one),
                "DEC 1",
            );
        }
        assert_total(
            &dec::load(k, DualKind::Barycentric, &linear).unwrap(),
            integral_over_simplices(k, &linear),
            "DEC barycentric linear",
        );
    }
    let q = rectangle(4, 3, [0.0, 2.0], [0.0, 1.0]).unwrap();
    assert_total(
        &dec::load(&q, DualKind::Barycentric, &linear).unwrap(),
        3.0,
        "DEC grid",
    );
    assert!(matches!(
        dec::load(&q, DualKind::Circumcentric, &one),
        Err(MetricError::Geometry(_))
    ));
}

#[test]
fn one_dimensional_fe_and_dec_are_the_three_point_stencil() {
    // Graded axis: ω_e = λ/h_e for P1 and for DEC (the dual of an edge is a
    // point), and the load of f = x is ∫ x φ_v (exact: degree 2 with 2-point Gauss).
    let x = hasse_complex::generate::graded_axis(5, 0.0, 2.0, 1.3).unwrap();
    let k = hasse_complex::generate::grid(std::slice::from_ref(&x)).unwrap();
    let tensors = constant(&k, isotropic(3.0));
    let fe = assemble(&k, fe::stiffness_metric(&k, &tensors).unwrap());
    let mut expected = DMatrix::zeros(6, 6);
    for e in 0..5 {
        let w = 3.0 / (x[e + 1] - x[e]);
        expected[(e, e)] += w;
        expected[(e + 1, e + 1)] += w;
        expected[(e, e + 1)] -= w;
        expected[(e + 1, e)] -= w;
    }
    assert_close(&fe, &expected, 1e-14, "P1 1D");
    for kind in [DualKind::Circumcentric, DualKind::Barycentric] {
        let dec = assemble(&k, dec::hodge_metric(&k, kind, &tensors).unwrap());
        assert_close(&dec, &expected, 1e-14, "DEC 1D");
    }
    let b = fe::load(&k, &|p: &[f64]| p[0]).unwrap();
    for (v, bv) in b.iter().enumerate() {
        // ∫ x φ_v over each neighbouring segment [a, c] with φ_v = 1 at a:
        // (c − a)(2a + c)/6.
        let left = (v > 0).then(|| (x[v] - x[v - 1]) * (2.0 * x[v] + x[v - 1]) / 6.0);
        let right = (v < 5).then(|| (x[v + 1] - x[v]) * (2.0 * x[v] + x[v + 1]) / 6.0);
        let expected = left.unwrap_or(0.0) + right.unwrap_or(0.0);
        assert!(
            abs_diff_eq!(*bv, expected, epsilon = 1e-14),
            "{v}: {bv} vs {expected}"
        );
    }
}
