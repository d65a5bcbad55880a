//! Geometry and dual measures of hand-built complexes, every expected value
//! derived independently (by hand or in closed form from the coordinates).
//!
//! Tolerances: single cells are checked to a few ulps (1e-14 relative);
//! sums over whole grids to 1e-12 relative, since each of the N ≤ 10³
//! cell values carries a relative rounding error of a few ε ≈ 2.2e-16 and
//! their sum at most N times that (≈ 2e-13).

use approx::{abs_diff_eq, assert_abs_diff_eq, relative_eq};
use hasse_complex::{Complex, DualKind, TopCells, Vertices};

// ---------------------------------------------------------------- helpers

/// Deterministic pseudo-random number in [−1, 1] from an integer triple.
fn hash(i: usize, j: usize, k: usize) -> f64 {
    let mut x = (i as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add((k as u64).wrapping_mul(0x1656_67B1_9E37_79F9));
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Grid points of [0, lx] × [0, ly] with nx × ny squares; interior points
/// moved by up to `jitter` times the spacing in each direction.
fn grid_points_2d(nx: usize, ny: usize, lx: f64, ly: f64, jitter: f64) -> Vec<[f64; 2]> {
    let (hx, hy) = (lx / nx as f64, ly / ny as f64);
    let mut points = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let interior = i > 0 && i < nx && j > 0 && j < ny;
            let (dx, dy) = if interior {
                (jitter * hx * hash(i, j, 1), jitter * hy * hash(i, j, 2))
            } else {
                (0.0, 0.0)
            };
            points.push([i as f64 * hx + dx, j as f64 * hy + dy]);
        }
    }
    points
}

fn quad_grid(nx: usize, ny: usize, lx: f64, ly: f64, jitter: f64) -> Complex {
    let id = |i: usize, j: usize| i + (nx + 1) * j;
    let mut cells = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            cells.push([id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)]);
        }
    }
    let v = Vertices::from_points(&grid_points_2d(nx, ny, lx, ly, jitter)).unwrap();
    Complex::build(v, TopCells::cuboids(cells)).unwrap()
}

/// Kuhn triangulation: each square split along its (0,0)–(1,1) diagonal.
fn kuhn_2d(nx: usize, ny: usize, lx: f64, ly: f64, jitter: f64) -> Complex {
    let id = |i: usize, j: usize| i + (nx + 1) * j;
    let mut cells = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            cells.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            cells.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
        }
    }
    let v = Vertices::from_points(&grid_points_2d(nx, ny, lx, ly, jitter)).unwrap();
    Complex::build(v, TopCells::simplices(cells)).unwrap()
}

fn grid_points_3d(n: [usize; 3], l: [f64; 3], jitter: f64) -> Vec<[f64; 3]> {
    let h = [0, 1, 2].map(|a| l[a] / n[a] as f64);
    let mut points = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let idx = [i, j, k];
                let interior = (0..3).all(|a| idx[a] > 0 && idx[a] < n[a]);
                let mut x = [0.0; 3];
                for a in 0..3 {
                    let shift = if interior {
                        jitter * h[a] * hash(i + 7 * a, j, k + 1)
                    } else {
                        0.0
                    };
                    x[a] = idx[a] as f64 * h[a] + shift;
                }
                points.push(x);
            }
        }
    }
    points
}

fn id3(n: [usize; 3]) -> impl Fn(usize, usize, usize) -> usize {
    move |i, j, k| i + (n[0] + 1) * (j + (n[1] + 1) * k)
}

fn hex_grid(n: [usize; 3], l: [f64; 3], jitter: f64) -> Complex {
    let id = id3(n);
    let mut cells = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                cells.push(std::array::from_fn::<usize, 8, _>(|local| {
                    id(
                        i + (local & 1),
                        j + ((local >> 1) & 1),
                        k + ((local >> 2) & 1),
                    )
                }));
            }
        }
    }
    let v = Vertices::from_points(&grid_points_3d(n, l, jitter)).unwrap();
    Complex::build(v, TopCells::cuboids(cells)).unwrap()
}

/// Six Kuhn tetrahedra per cube: the monotone paths from (0,0,0) to (1,1,1).
fn tet_grid(n: [usize; 3], l: [f64; 3], jitter: f64) -> Complex {
    let id = id3(n);
    let orders = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut cells = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for order in orders {
                    let mut at = [i, j, k];
                    let mut tet = vec![id(at[0], at[1], at[2])];
                    for axis in order {
                        at[axis] += 1;
                        tet.push(id(at[0], at[1], at[2]));
                    }
                    cells.push(tet);
                }
            }
        }
    }
    let v = Vertices::from_points(&grid_points_3d(n, l, jitter)).unwrap();
    Complex::build(v, TopCells::simplices(cells)).unwrap()
}

/// The cube [0, s]³ as a single polyhedron.
fn cube_polyhedron(s: f64) -> Complex {
    let mut points = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..2 {
                points.push([i as f64 * s, j as f64 * s, k as f64 * s]);
            }
        }
    }
    let faces = vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![2, 6, 7, 3],
        vec![0, 4, 6, 2],
        vec![1, 3, 7, 5],
    ];
    let v = Vertices::from_points(&points).unwrap();
    Complex::build(v, TopCells::polyhedra([faces])).unwrap()
}

/// Regular hexagon of side `s` centred at `centre`.
fn hexagon(s: f64, centre: [f64; 2]) -> Complex {
    let points: Vec<[f64; 2]> = (0..6)
        .map(|k| {
            let t = std::f64::consts::PI / 3.0 * k as f64;
            [centre[0] + s * t.cos(), centre[1] + s * t.sin()]
        })
        .collect();
    let v = Vertices::from_points(&points).unwrap();
    Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4, 5]])).unwrap()
}

fn sub(a: &[f64], b: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for k in 0..a.len() {
        out[k] = a[k] - b[k];
    }
    out
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: &[f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// |a − b| ≤ rel · max(|a|, |b|, f64::MIN_POSITIVE).
fn close(a: f64, b: f64, rel: f64) -> bool {
    relative_eq!(a, b, epsilon = rel * f64::MIN_POSITIVE, max_relative = rel)
}

fn assert_close(a: f64, b: f64, rel: f64) {
    assert!(close(a, b, rel), "{a} vs {b} (rel {rel})");
}

fn assert_point(got: &[f64], want: &[f64], tol: f64) {
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        assert!(abs_diff_eq!(g, w, epsilon = tol), "{got:?} vs {want:?}");
    }
}

/// Cotangent of the angle at `o` in the triangle (o, a, b).
fn cot(o: &[f64], a: &[f64], b: &[f64]) -> f64 {
    let (u, v) = (sub(a, o), sub(b, o));
    dot(&u, &v) / norm(&cross(&u, &v))
}

/// (facets, signs) of cell `c` of dimension p.
fn facets(k: &Complex, p: usize, c: usize) -> Vec<(usize, i8)> {
    let csc = k.boundary_csc(p);
    let col = csc.outer_view(c).unwrap();
    col.iter().map(|(f, &s)| (f, s)).collect()
}

// ---------------------------------------------------------------- measures

#[test]
fn measures_of_single_cells() {
    // 3-4-5 right triangle: area 6, perimeter 12.
    let v = Vertices::from_points(&[[0.0, 0.0], [3.0, 0.0], [0.0, 4.0]]).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    assert_close(k.measure(2)[0], 6.0, 1e-15);
    assert_close(k.measure(1).iter().sum::<f64>(), 12.0, 1e-15);
    assert_eq!(k.measure(0), &[1.0, 1.0, 1.0]);

    // Parallelogram (0,0),(3,0),(1,2),(4,2): base 3 × height 2.
    let v = Vertices::from_points(&[[0.0, 0.0], [3.0, 0.0], [1.0, 2.0], [4.0, 2.0]]).unwrap();
    let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    assert_close(k.measure(2)[0], 6.0, 1e-15);

    // Box 1 × 2 × 3 as a hexahedron: volume 6, faces 2, 3, 6 (twice each).
    let k = hex_grid([1, 1, 1], [1.0, 2.0, 3.0], 0.0);
    assert_close(k.measure(3)[0], 6.0, 1e-15);
    let mut faces = k.measure(2).to_vec();
    faces.sort_by(f64::total_cmp);
    for (got, want) in faces.iter().zip([2.0, 2.0, 3.0, 3.0, 6.0, 6.0]) {
        assert_close(*got, want, 1e-15);
    }

    // Parallelepiped spanned by a, b, c: |det[a b c]| = 1·(2·3 − 0) − 0.5·(0 − 0) + 0.2·(0·0 − 2·0.3) = 5.88.
    let (a, b, c) = ([1.0, 0.5, 0.2], [0.0, 2.0, 0.0], [0.3, 0.0, 3.0]);
    let det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0]);
    assert_close(det, 5.88, 1e-15);
    let points: Vec<[f64; 3]> = (0..8)
        .map(|l| {
            let (i, j, m) = ((l & 1) as f64, ((l >> 1) & 1) as f64, ((l >> 2) & 1) as f64);
            [0, 1, 2].map(|x| i * a[x] + j * b[x] + m * c[x])
        })
        .collect();
    let k = Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::cuboids([[0, 1, 2, 3, 4, 5, 6, 7]]),
    )
    .unwrap();
    assert_close(k.measure(3)[0], 5.88, 1e-14);
    // Its centroid is the centre (a + b + c) / 2.
    assert_point(
        k.centroid_of(3, 0),
        &[0, 1, 2].map(|x| (a[x] + b[x] + c[x]) / 2.0),
        1e-14,
    );

    // Tetrahedron with vertices 0, (2,0,0), (0,3,0), (0,0,4): volume 2·3·4/6 = 4.
    let v = Vertices::from_points(&[
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 3.0, 0.0],
        [0.0, 0.0, 4.0],
    ])
    .unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
    assert_close(k.measure(3)[0], 4.0, 1e-15);
    // The slanted face: |(−2,3,0) × (−2,0,4)| / 2 = |(12, 8, 6)| / 2 = √244 / 2.
    let slanted = k.find_cell(2, &[1, 2, 3]).unwrap();
    assert_close(k.measure(2)[slanted], 244f64.sqrt() / 2.0, 1e-15);

    // Regular hexagon of side 2: 3√3/2 · 4 = 6√3.
    let k = hexagon(2.0, [1.0, -1.0]);
    assert_close(k.measure(2)[0], 6.0 * 3f64.sqrt(), 1e-14);
    assert_point(k.centroid_of(2, 0), &[1.0, -1.0], 1e-14);
    for e in k.measure(1) {
        assert_close(*e, 2.0, 1e-15);
    }

    // Cube of side 2 as a polyhedron: volume 8, six faces of area 4, twelve edges of length 2.
    let k = cube_polyhedron(2.0);
    assert_eq!(k.cell_counts(), vec![8, 12, 6, 1]);
    assert_close(k.measure(3)[0], 8.0, 1e-15);
    assert!(k.measure(2).iter().all(|&f| close(f, 4.0, 1e-15)));
    assert!(k.measure(1).iter().all(|&e| close(e, 2.0, 1e-15)));
    assert_point(k.centroid_of(3, 0), &[1.0, 1.0, 1.0], 1e-15);

    // A segment in R³: length 3 (2² + 1² + 2² = 9).
    let v = Vertices::from_points(&[[1.0, 1.0, 1.0], [3.0, 2.0, 3.0]]).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1]])).unwrap();
    assert_eq!(k.measure(1), &[3.0]);
    assert_eq!(k.centroid(1), &[2.0, 1.5, 2.0]);
    // Nothing above the top dimension.
    assert!(k.measure(2).is_empty() && k.centroid(2).is_empty());
}

#[test]
fn embedded_quads_planar_and_twisted() {
    // Unit square rotated into the plane x + z = const: area 1, centroid its centre.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let v = Vertices::from_points(&[[0.0, 0.0, 0.0], [s, 0.0, -s], [0.0, 1.0, 0.0], [s, 1.0, -s]])
        .unwrap();
    let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    assert_close(k.measure(2)[0], 1.0, 1e-15);
    assert_point(k.centroid_of(2, 0), &[s / 2.0, 0.5, -s / 2.0], 1e-15);

    // Twisted quad (0,0,0), (1,0,h), (0,1,h), (1,1,0). Its fan from the vertex
    // average a = (½, ½, h/2) has four congruent triangles; for the edge
    // (0,0,0)–(1,0,h): (v₀ − a) × (v₁ − a) = (−h/2, 0, ½), so each has area
    // ¼ √(1 + h²) and the quad √(1 + h²). By symmetry the centroid is a.
    let h = 0.6;
    let v = Vertices::from_points(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, h],
        [0.0, 1.0, h],
        [1.0, 1.0, 0.0],
    ])
    .unwrap();
    let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    assert_close(k.measure(2)[0], (1.0 + h * h).sqrt(), 1e-15);
    assert_point(k.centroid_of(2, 0), &[0.5, 0.5, h / 2.0], 1e-15);
}

#[test]
fn top_measures_sum_to_the_domain_on_distorted_grids() {
    // [0,2] × [0,1], convex jittered quads.
    let k = quad_grid(8, 6, 2.0, 1.0, 0.25);
    assert_close(k.measure(2).iter().sum(), 2.0, 1e-12);
    let k = kuhn_2d(7, 5, 2.0, 1.0, 0.2);
    assert_close(k.measure(2).iter().sum(), 2.0, 1e-12);
    // [0,1] × [0,2] × [0,3]: 6. The jittered hexahedra have non-planar faces;
    // shared faces are triangulated alike from both sides, and boundary faces
    // stay planar, so the volumes still add up to the box.
    let k = hex_grid([5, 4, 3], [1.0, 2.0, 3.0], 0.2);
    assert_close(k.measure(3).iter().sum(), 6.0, 1e-12);
    let k = tet_grid([4, 3, 3], [1.0, 2.0, 3.0], 0.15);
    assert_close(k.measure(3).iter().sum(), 6.0, 1e-12);
    // The boundary of each box: faces on the boundary sum to the surface area 22.
    let surface: f64 = (0..k.cell_count(2))
        .filter(|&f| k.boundary(3).outer_view(f).is_some_and(|r| r.nnz() == 1))
        .map(|f| k.measure(2)[f])
        .sum();
    assert_close(surface, 22.0, 1e-12);
}

#[test]
fn weighted_centroids_give_the_domain_centroid() {
    // Σ |c| centroid_c = |Ω| centroid_Ω: the cells tile the domain exactly.
    let check = |k: &Complex, volume: f64, centre: &[f64]| {
        let n = k.dim();
        let d = k.embedding_dim();
        let mut moment = vec![0.0; d];
        for (c, m) in k.measure(n).iter().enumerate() {
            for (x, y) in moment.iter_mut().zip(k.centroid_of(n, c)) {
                *x += m * y;
            }
        }
        for (x, y) in moment.iter().zip(centre) {
            assert_close(*x / volume, *y, 1e-12);
        }
    };
    check(&quad_grid(8, 6, 2.0, 1.0, 0.25), 2.0, &[1.0, 0.5]);
    check(&kuhn_2d(5, 5, 2.0, 1.0, 0.2), 2.0, &[1.0, 0.5]);
    check(
        &hex_grid([4, 3, 3], [1.0, 2.0, 3.0], 0.2),
        6.0,
        &[0.5, 1.0, 1.5],
    );
    check(
        &tet_grid([3, 3, 2], [1.0, 2.0, 3.0], 0.15),
        6.0,
        &[0.5, 1.0, 1.5],
    );
}

#[test]
fn centroids_in_closed_form() {
    // L-shape [0,1.5]×[0,1] ∪ [0,1]×[0,1.5]: its vertex average (5/6, 5/6)
    // sees every edge, so it is a valid (star-shaped) polygon here.
    // Area 1.5 + 0.5 = 2; centroid (1.5·(0.75, 0.5) + 0.5·(0.5, 1.25)) / 2 = (0.6875, 0.6875).
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [1.5, 0.0],
        [1.5, 1.0],
        [1.0, 1.0],
        [1.0, 1.5],
        [0.0, 1.5],
    ])
    .unwrap();
    let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4, 5]])).unwrap();
    assert_close(k.measure(2)[0], 2.0, 1e-15);
    assert_point(k.centroid_of(2, 0), &[0.6875, 0.6875], 1e-15);

    // A tetrahedron's centroid is its vertex average.
    let pts = [
        [0.1, 0.2, 0.3],
        [2.0, -0.5, 0.4],
        [0.3, 1.7, -0.2],
        [-0.4, 0.6, 2.2],
    ];
    let v = Vertices::from_points(&pts).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
    let average = [0, 1, 2].map(|x| pts.iter().map(|p| p[x]).sum::<f64>() / 4.0);
    assert_point(k.centroid_of(3, 0), &average, 1e-15);

    // Trapezoid (0,0),(4,0),(3,2),(0,2) = rectangle [0,3]×[0,2] (area 6,
    // centroid (1.5, 1)) + triangle (3,0),(4,0),(3,2) (area 1, centroid (10/3, 2/3)):
    // area 7, centroid (37/21, 20/21).
    let v = Vertices::from_points(&[[0.0, 0.0], [4.0, 0.0], [3.0, 2.0], [0.0, 2.0]]).unwrap();
    let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3]])).unwrap();
    assert_close(k.measure(2)[0], 7.0, 1e-15);
    assert_point(k.centroid_of(2, 0), &[37.0 / 21.0, 20.0 / 21.0], 1e-15);
    // The same trapezoid in tensor (cuboid) vertex order.
    let v = Vertices::from_points(&[[0.0, 0.0], [4.0, 0.0], [0.0, 2.0], [3.0, 2.0]]).unwrap();
    let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    assert_point(k.centroid_of(2, 0), &[37.0 / 21.0, 20.0 / 21.0], 1e-15);
}

#[test]
fn mesh_size_is_the_largest_cell_diameter() {
    let k = quad_grid(4, 2, 2.0, 1.0, 0.0);
    // Cells 0.5 × 0.5: diagonal √0.5.
    assert_close(k.mesh_size(), 0.5f64.sqrt(), 1e-15);
    let k = hex_grid([1, 2, 3], [1.0, 2.0, 3.0], 0.0);
    // Unit cubes: space diagonal √3.
    assert_close(k.mesh_size(), 3f64.sqrt(), 1e-15);
}

// ---------------------------------------------------------------- normals

/// Σ_{f ∈ ∂c} ∂(f, c) |f| n_f = 0 for every top cell of a flat complex.
fn assert_closed(k: &Complex) {
    let n = k.dim();
    let d = k.embedding_dim();
    let normal = k.normal();
    let measure = k.measure(n - 1);
    let scale = measure.iter().copied().fold(0.0, f64::max);
    for c in 0..k.cell_count(n) {
        let mut sum = [0.0; 3];
        for (f, s) in facets(k, n, c) {
            for x in 0..d {
                sum[x] += f64::from(s) * measure[f] * normal[f * d + x];
            }
        }
        assert!(norm(&sum) <= 1e-12 * scale, "cell {c}: {sum:?}");
    }
}

#[test]
fn oriented_boundaries_of_cells_close() {
    assert_closed(&quad_grid(5, 4, 2.0, 1.0, 0.25));
    assert_closed(&kuhn_2d(5, 4, 2.0, 1.0, 0.2));
    assert_closed(&hexagon(1.5, [0.3, 0.2]));
    assert_closed(&tet_grid([3, 2, 2], [1.0, 2.0, 3.0], 0.15));
    assert_closed(&hex_grid([3, 2, 2], [1.0, 2.0, 3.0], 0.0));
    assert_closed(&cube_polyhedron(2.0));
}

#[test]
fn boundaries_of_faces_in_3d_close() {
    // For every 2-cell F of a 3-complex: Σ_{e ∈ ∂F} |e| ν_{e,F} = 0 with
    // ν_{e,F} the in-plane unit normal of e pointing away from F.
    for k in [
        tet_grid([2, 2, 2], [1.0, 2.0, 3.0], 0.15),
        hex_grid([2, 2, 2], [1.0, 2.0, 3.0], 0.0),
        cube_polyhedron(2.0),
    ] {
        let lengths = k.measure(1);
        for face in 0..k.cell_count(2) {
            let mut sum = [0.0; 3];
            for (e, _) in facets(&k, 2, face) {
                let ends = k.cell_vertices(1, e);
                let t = sub(k.vertices().point(ends[1]), k.vertices().point(ends[0]));
                let t = t.map(|x| x / norm(&t));
                let w = sub(k.centroid_of(1, e), k.centroid_of(2, face));
                let along = dot(&w, &t);
                let nu = [0, 1, 2].map(|x| w[x] - along * t[x]);
                for x in 0..3 {
                    sum[x] += lengths[e] * nu[x] / norm(&nu);
                }
            }
            let scale = lengths.iter().copied().fold(0.0, f64::max);
            assert!(norm(&sum) <= 1e-12 * scale, "face {face}: {sum:?}");
        }
    }
}

/// s · n_f · (centroid_f − centroid_c) > 0 for every face f of every top cell
/// c with ∂(f, c) = s, and |n_f| = 1.
fn assert_normals_follow_boundary_signs(k: &Complex) {
    let n = k.dim();
    let d = k.embedding_dim();
    let normal = k.normal();
    for (value, (f, c)) in k.boundary(n).iter() {
        let nf = sub(&normal[f * d..(f + 1) * d], &[0.0; 3][..d]);
        assert_close(norm(&nf), 1.0, 1e-14);
        let away = sub(k.centroid_of(n - 1, f), k.centroid_of(n, c));
        assert!(
            f64::from(*value) * dot(&nf, &away) > 0.0,
            "face {f}, cell {c}"
        );
    }
}

#[test]
fn normals_point_out_of_positively_incident_cells() {
    // Unit square, 4 × 3 cells: boundary normals are ± the outward axis.
    let k = quad_grid(4, 3, 1.0, 1.0, 0.0);
    let normal = k.normal();
    let top = k.boundary(2);
    let mut checked = 0;
    for f in 0..k.cell_count(1) {
        let row = top.outer_view(f).unwrap();
        if row.nnz() != 1 {
            continue;
        }
        let s = f64::from(row.data()[0]);
        let m = k.centroid_of(1, f);
        let outward = if m[0] == 0.0 {
            [-1.0, 0.0]
        } else if m[0] == 1.0 {
            [1.0, 0.0]
        } else if m[1] == 0.0 {
            [0.0, -1.0]
        } else {
            assert_eq!(m[1], 1.0);
            [0.0, 1.0]
        };
        assert_point(
            &normal[2 * f..2 * f + 2],
            &[s * outward[0], s * outward[1]],
            1e-15,
        );
        checked += 1;
    }
    assert_eq!(checked, 14);

    assert_normals_follow_boundary_signs(&k);
    assert_normals_follow_boundary_signs(&quad_grid(5, 4, 2.0, 1.0, 0.25));
    assert_normals_follow_boundary_signs(&kuhn_2d(5, 4, 2.0, 1.0, 0.2));
    assert_normals_follow_boundary_signs(&hex_grid([3, 2, 2], [1.0, 2.0, 3.0], 0.2));
    assert_normals_follow_boundary_signs(&tet_grid([2, 2, 2], [1.0, 2.0, 3.0], 0.15));
    assert_normals_follow_boundary_signs(&cube_polyhedron(1.0));
    assert_normals_follow_boundary_signs(&hexagon(1.0, [0.0, 0.0]));
}

#[test]
fn normals_of_curves_and_surfaces_are_tangent() {
    // A polyline in R²: the normal of a vertex is ± its edge direction.
    let v = Vertices::from_points(&[[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]]).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1], [1, 2]])).unwrap();
    let normal = k.normal();
    // Vertex 0 only bounds edge {0,1}, as its tail (∂ = −1): ν = −(0.6, 0.8)
    // points away from the edge, and n = −ν points into it.
    assert_point(&normal[0..2], &[0.6, 0.8], 1e-15);
    // Vertex 2 is the head of {1,2}: n = (0, 1).
    assert_point(&normal[4..6], &[0.0, 1.0], 1e-15);
    // Vertex 1: head of {0,1}, tail of {1,2}: the average tangent.
    let t = [0.6, 1.8];
    let len: f64 = t[0] * t[0] + t[1] * t[1];
    assert_point(
        &normal[2..4],
        &[t[0] / len.sqrt(), t[1] / len.sqrt()],
        1e-15,
    );
    assert_normals_follow_boundary_signs(&k);

    // A flat quad grid tilted into R³: edge normals lie in the plane.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let flat = quad_grid(3, 2, 1.0, 1.0, 0.2);
    let points: Vec<[f64; 3]> = (0..flat.cell_count(0))
        .map(|i| {
            let x = flat.vertices().point(i);
            [s * x[0], x[1], -s * x[0]]
        })
        .collect();
    let cells: Vec<Vec<usize>> = (0..flat.cell_count(2))
        .map(|c| flat.cell_vertices(2, c).to_vec())
        .collect();
    let k = Complex::build(
        Vertices::from_points(&points).unwrap(),
        TopCells::cuboids(cells),
    )
    .unwrap();
    assert_close(k.measure(2).iter().sum(), 1.0, 1e-12);
    let plane_normal = [s, 0.0, s];
    for f in 0..k.cell_count(1) {
        let nf = sub(&k.normal()[3 * f..3 * f + 3], &[0.0; 3]);
        assert_abs_diff_eq!(dot(&nf, &plane_normal), 0.0, epsilon = 1e-15);
    }
    assert_normals_follow_boundary_signs(&k);
    assert_closed(&k);
}

// ---------------------------------------------------------------- circumcentres

#[test]
fn circumcentres_in_closed_form() {
    // Right angle at vertex 0: the circumcentre is the midpoint of the hypotenuse.
    let v = Vertices::from_points(&[[1.0, 1.0], [4.0, 1.0], [1.0, 5.0]]).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    assert_point(k.circumcentre(2).unwrap(), &[2.5, 3.0], 1e-15);
    // Edge circumcentres are midpoints, vertex circumcentres the vertices.
    assert_point(k.circumcentre(1).unwrap(), k.centroid(1), 1e-15);
    assert_eq!(k.circumcentre(0).unwrap(), k.vertices().as_slice());

    // Regular tetrahedron: circumcentre = centroid.
    let pts = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let v = Vertices::from_points(&pts).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
    assert_point(k.circumcentre(3).unwrap(), &[0.0, 0.0, 0.0], 1e-15);
    // Its faces are equilateral: circumcentre = face centroid.
    assert_point(k.circumcentre(2).unwrap(), k.centroid(2), 1e-15);

    // Equilateral triangle in R³ on the plane x + y + z = 1.
    let v = Vertices::from_points(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    assert_point(k.circumcentre(2).unwrap(), &[1.0 / 3.0; 3], 1e-15);

    // Obtuse triangle (0,0), (4,0), (1,1): centre on x = 2, and
    // 4 + y² = 1 + (1 − y)² gives y = −1: outside, below the long edge.
    let v = Vertices::from_points(&[[0.0, 0.0], [4.0, 0.0], [1.0, 1.0]]).unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    assert_point(k.circumcentre(2).unwrap(), &[2.0, -1.0], 1e-14);

    // A right tetrahedron 0, 2e₁, 2e₂, 2e₃: centre (1, 1, 1).
    let v = Vertices::from_points(&[
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 2.0, 0.0],
        [0.0, 0.0, 2.0],
    ])
    .unwrap();
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
    assert_point(k.circumcentre(3).unwrap(), &[1.0, 1.0, 1.0], 1e-15);
}

#[test]
fn circumcentres_need_simplices() {
    let k = quad_grid(2, 1, 1.0, 1.0, 0.0);
    let err = k.circumcentre(2).unwrap_err().to_string();
    assert!(err.contains("2-cell 0"), "{err}");
    assert!(k.circumcentre(1).is_ok());
    assert!(k.circumcentre(3).unwrap().is_empty());
    let err = k.hodge_star(DualKind::Circumcentric, 1).unwrap_err();
    assert!(err.to_string().contains("simplicial"), "{err}");
    assert!(k.dual_measure(DualKind::Barycentric, 3).is_err());
}

// ---------------------------------------------------------------- dual

/// (cot α + cot β) / 2 for every edge, from the angles opposite it.
fn cotangent_weights(k: &Complex) -> Vec<f64> {
    let mut weights = vec![0.0; k.cell_count(1)];
    let point = |i: usize| k.vertices().point(i);
    for t in 0..k.cell_count(2) {
        let tri = k.cell_vertices(2, t);
        for skip in 0..3 {
            let others: Vec<usize> = (0..3).filter(|&x| x != skip).map(|x| tri[x]).collect();
            let e = k.find_cell(1, &others).unwrap();
            weights[e] += 0.5 * cot(point(tri[skip]), point(others[0]), point(others[1]));
        }
    }
    weights
}

/// Two triangles sharing edge {0,1}; the upper one is obtuse at vertex 2
/// (its circumcentre lies below the shared edge), plus one obtuse boundary
/// triangle and one acute one.
fn obtuse_mesh() -> Complex {
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [2.0, 0.0],
        [1.0, 0.4],
        [1.0, -1.5],
        [3.0, 1.0],
        [3.5, -0.5],
    ])
    .unwrap();
    Complex::build(
        v,
        TopCells::simplices([[0, 1, 2], [0, 3, 1], [1, 4, 2], [1, 3, 5], [1, 5, 4]]),
    )
    .unwrap()
}

#[test]
fn circumcentric_star1_is_the_cotangent_formula() {
    for k in [
        obtuse_mesh(),
        kuhn_2d(4, 4, 1.0, 1.0, 0.3),
        kuhn_2d(3, 2, 2.0, 1.0, 0.0),
    ] {
        let star = k.hodge_star(DualKind::Circumcentric, 1).unwrap();
        let expected = cotangent_weights(&k);
        for (e, (s, w)) in star.iter().zip(&expected).enumerate() {
            assert!(abs_diff_eq!(s, w, epsilon = 1e-13), "edge {e}: {s} vs {w}");
        }
    }
    // The obtuse mesh has negative weights (and dual edges).
    let k = obtuse_mesh();
    let shared = k.find_cell(1, &[0, 1]).unwrap();
    let star = k.hodge_star(DualKind::Circumcentric, 1).unwrap();
    let dual = k.dual_measure(DualKind::Circumcentric, 1).unwrap();
    assert!(star[shared] < 0.0 && dual[shared] < 0.0, "{}", star[shared]);
    // Triangle [1,4,2] is obtuse at vertex 1 ((1,1)·(−1,0.4) < 0), and the
    // opposite edge {2,4} is on the boundary: one negative cotangent term.
    let boundary = k.find_cell(1, &[2, 4]).unwrap();
    let point = |i: usize| k.vertices().point(i);
    let expected = 0.5 * cot(point(1), point(2), point(4));
    assert!(expected < 0.0 && dual[boundary] < 0.0);
    assert_close(star[boundary], expected, 1e-13);
}

#[test]
fn circumcentric_vertex_duals_tile_the_domain() {
    for (k, area) in [
        (obtuse_mesh(), {
            // Shoelace area of the outline 0,3,5,4,2 (counter-clockwise).
            let p = [[0.0, 0.0], [1.0, -1.5], [3.5, -0.5], [3.0, 1.0], [1.0, 0.4]];
            (0..5)
                .map(|i| {
                    let (a, b) = (p[i], p[(i + 1) % 5]);
                    a[0] * b[1] - a[1] * b[0]
                })
                .sum::<f64>()
                / 2.0
        }),
        (kuhn_2d(5, 4, 2.0, 1.0, 0.3), 2.0),
    ] {
        let star0 = k.dual_measure(DualKind::Circumcentric, 0).unwrap();
        assert_close(star0.iter().sum(), area, 1e-12);
        // Barycentric duals tile it too, with positive cells.
        let bary = k.dual_measure(DualKind::Barycentric, 0).unwrap();
        assert!(bary.iter().all(|&x| x > 0.0));
        assert_close(bary.iter().sum(), area, 1e-12);
    }
    // 3D: Kuhn tetrahedra (circumcentres on the cube diagonals), plain and jittered.
    for jitter in [0.0, 0.15] {
        let k = tet_grid([3, 2, 2], [1.0, 2.0, 3.0], jitter);
        let star0 = k.dual_measure(DualKind::Circumcentric, 0).unwrap();
        assert_close(star0.iter().sum(), 6.0, 1e-12);
    }
    // Hexahedra, barycentric.
    let k = hex_grid([3, 2, 2], [1.0, 2.0, 3.0], 0.0);
    let star0 = k.dual_measure(DualKind::Barycentric, 0).unwrap();
    assert_close(star0.iter().sum(), 6.0, 1e-12);
}

#[test]
fn primal_dual_pyramids_tile_the_domain() {
    // |σ| |⋆σ| is C(n, p) times the volume of the pyramid joining σ to its
    // dual (they are orthogonal), and these pyramids tile every simplex:
    // Σ_σ |σ| |⋆σ| = C(n, p) |Ω|.
    let binomial = [
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0],
        [1.0, 2.0, 1.0, 0.0],
        [1.0, 3.0, 3.0, 1.0],
    ];
    for (k, volume) in [
        (kuhn_2d(4, 3, 2.0, 1.0, 0.3), 2.0),
        (obtuse_mesh(), 4.975),
        (tet_grid([3, 2, 2], [1.0, 2.0, 3.0], 0.0), 6.0),
        (tet_grid([3, 2, 2], [1.0, 2.0, 3.0], 0.15), 6.0),
    ] {
        let n = k.dim();
        for (p, choose) in binomial[n].iter().enumerate().take(n + 1) {
            let dual = k.dual_measure(DualKind::Circumcentric, p).unwrap();
            let sum: f64 = dual.iter().zip(k.measure(p)).map(|(a, b)| a * b).sum();
            assert_close(sum, choose * volume, 1e-12);
        }
    }
}

#[test]
fn hodge_stars_of_extreme_degrees() {
    for (k, kind) in [
        (kuhn_2d(3, 3, 1.0, 1.0, 0.2), DualKind::Circumcentric),
        (
            tet_grid([2, 2, 1], [1.0, 1.0, 1.0], 0.0),
            DualKind::Circumcentric,
        ),
        (quad_grid(3, 2, 1.0, 1.0, 0.2), DualKind::Barycentric),
        (
            hex_grid([2, 2, 2], [1.0, 1.0, 1.0], 0.1),
            DualKind::Barycentric,
        ),
    ] {
        let n = k.dim();
        let top = k.hodge_star(kind, n).unwrap();
        for (s, m) in top.iter().zip(k.measure(n)) {
            assert_close(*s, 1.0 / m, 1e-15);
        }
        assert_eq!(k.dual_measure(kind, n).unwrap(), vec![1.0; k.cell_count(n)]);
        assert_eq!(
            k.hodge_star(kind, 0).unwrap(),
            k.dual_measure(kind, 0).unwrap()
        );
        assert_eq!(
            k.dual_vertices(kind).unwrap().len(),
            k.cell_count(n) * k.embedding_dim()
        );
        assert!(k.dual_measure(kind, n + 1).is_err());
    }
}

#[test]
fn barycentric_duals_of_a_uniform_quad_grid() {
    let h = 0.25;
    let k = quad_grid(4, 4, 1.0, 1.0, 0.0);
    let edges = k.dual_measure(DualKind::Barycentric, 1).unwrap();
    let vertices = k.dual_measure(DualKind::Barycentric, 0).unwrap();
    let on_boundary = |x: &[f64]| x.iter().any(|&c| c == 0.0 || c == 1.0);
    for (e, dual) in edges.iter().enumerate() {
        // Boundary edges get half a dual edge (truncated at the boundary).
        let want = if on_boundary(k.centroid_of(1, e)) {
            h / 2.0
        } else {
            h
        };
        assert_close(*dual, want, 1e-15);
    }
    for (v, dual) in vertices.iter().enumerate() {
        let x = k.vertices().point(v);
        let sides = x.iter().filter(|&&c| c == 0.0 || c == 1.0).count();
        // Interior h², edge h²/2, corner h²/4.
        let want = h * h / f64::from(1 << sides);
        assert_close(*dual, want, 1e-15);
    }
    // On a uniform grid the circumcentric and barycentric points agree, so
    // ⋆₁ is the five-point-stencil weight 1 (dual h over primal h).
    let star = k.hodge_star(DualKind::Barycentric, 1).unwrap();
    assert!(star
        .iter()
        .all(|&s| close(s, 1.0, 1e-15) || close(s, 0.5, 1e-15)));
}

#[test]
fn barycentric_duals_of_a_uniform_hex_grid() {
    let h = 0.5;
    let k = hex_grid([2, 2, 2], [1.0, 1.0, 1.0], 0.0);
    // The single interior vertex (1/2, 1/2, 1/2) has a dual cube h³.
    let centre = (0..k.cell_count(0))
        .find(|&v| k.vertices().point(v) == [0.5, 0.5, 0.5])
        .unwrap();
    assert_close(
        k.dual_measure(DualKind::Barycentric, 0).unwrap()[centre],
        h * h * h,
        1e-15,
    );
    // Edges and faces whose centre lies strictly inside (those through the
    // interior vertex) have an untruncated dual: a square h² and a segment h.
    let interior = |x: &[f64]| x.iter().all(|&c| c > 0.0 && c < 1.0);
    let edges = k.dual_measure(DualKind::Barycentric, 1).unwrap();
    let faces = k.dual_measure(DualKind::Barycentric, 2).unwrap();
    let mut seen = (0, 0);
    for (e, dual) in edges.iter().enumerate() {
        if interior(k.centroid_of(1, e)) {
            assert_close(*dual, h * h, 1e-15);
            seen.0 += 1;
        }
    }
    for (f, dual) in faces.iter().enumerate() {
        if interior(k.centroid_of(2, f)) {
            assert_close(*dual, h, 1e-15);
            seen.1 += 1;
        }
    }
    assert_eq!(seen, (6, 12));
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let compute = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let k = hex_grid([4, 3, 3], [1.0, 2.0, 3.0], 0.2);
            let t = tet_grid([3, 3, 2], [1.0, 2.0, 3.0], 0.15);
            let mut all = Vec::new();
            for p in 0..=3 {
                all.extend_from_slice(k.measure(p));
                all.extend_from_slice(k.centroid(p));
                all.extend_from_slice(k.dual_measure(DualKind::Barycentric, p).unwrap());
                all.extend_from_slice(t.dual_measure(DualKind::Circumcentric, p).unwrap());
                all.extend_from_slice(t.circumcentre(p).unwrap());
            }
            all.extend_from_slice(k.normal());
            all.extend_from_slice(t.normal());
            all.iter().map(|x| x.to_bits()).collect::<Vec<u64>>()
        })
    };
    assert_eq!(compute(1), compute(3));
}

#[test]
#[ignore = "timing, run by hand: cargo test --release -p hasse-complex --test complex geometry:: -- --ignored --nocapture"]
fn timing_of_a_million_hexahedra() {
    let start = std::time::Instant::now();
    let k = hex_grid([100, 100, 100], [1.0, 1.0, 1.0], 0.0);
    let built = start.elapsed();
    let start = std::time::Instant::now();
    for p in 0..=3 {
        let _ = k.measure(p);
        let _ = k.centroid(p);
    }
    let _ = k.normal();
    let geometry = start.elapsed();
    let volume: f64 = k.measure(3).iter().sum();
    println!(
        "100³ hexahedra, {} threads: counts {:?}, build {built:?}, measures + centroids + normals {geometry:?}, volume {volume}",
        rayon::current_num_threads(),
        k.cell_counts()
    );
    assert_abs_diff_eq!(volume, 1.0, epsilon = 1e-9);
}
