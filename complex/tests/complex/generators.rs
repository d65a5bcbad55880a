//! Mesh generators checked against independently derived numbers: closed-form
//! cell counts, Euler characteristics and Betti numbers of the shapes,
//! ∂∂ = 0, tag sizes, areas by the shoelace formula, sphere radii, torus
//! orientation, perturbation invariants, and for Voronoi meshes convexity,
//! exact tiling of the rectangle and the nearest-site property.

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_relative_eq, relative_eq};
use hasse_complex::generate::{
    annulus, box3, delaunay, graded_axis, grid, hollow_box, interval, kuhn, perturb, rectangle,
    sphere, torus, uniform_axis, voronoi, voronoi_with_sites,
};
use hasse_complex::{Complex, ComplexError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

// ---------------------------------------------------------------- helpers

type P3 = [f64; 3];

fn point3(k: &Complex, v: usize) -> P3 {
    let mut x = [0.0; 3];
    let p = k.vertices().point(v);
    x[..p.len()].copy_from_slice(p);
    x
}

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: P3) -> f64 {
    dot(a, a).sqrt()
}

/// Every entry of ∂_{p−1} ∂_p is exactly zero, for all p (products in i32).
fn assert_dd_zero(k: &Complex) {
    for p in 2..=k.dim() {
        let a = k.boundary(p - 1).map(|&x| i32::from(x));
        let b = k.boundary(p).map(|&x| i32::from(x));
        let product = &a * &b;
        assert!(
            product.data().iter().all(|&x| x == 0),
            "∂_{}∂_{p} has a nonzero entry",
            p - 1
        );
    }
}

fn assert_topology(k: &Complex, chi: i64, betti: &[usize]) {
    assert_eq!(k.euler_characteristic(), chi, "Euler characteristic");
    assert_eq!(k.betti_numbers(), betti, "Betti numbers");
    let alternating: i64 = betti
        .iter()
        .enumerate()
        .map(|(p, &b)| if p % 2 == 0 { b as i64 } else { -(b as i64) })
        .sum();
    assert_eq!(alternating, chi, "Euler–Poincaré on the expected values");
    assert_dd_zero(k);
}

fn tag_len(k: &Complex, name: &str) -> usize {
    k.tag(name)
        .unwrap_or_else(|| panic!("tag {name} missing"))
        .cells
        .len()
}

fn message(err: ComplexError) -> String {
    err.to_string()
}

/// Oriented edge ends (tail, head), read off ∂_1 (−1 at the tail).
fn edge_ends(k: &Complex, e: usize) -> (usize, usize) {
    let d1 = k.boundary_csc(1);
    let col = d1.outer_view(e).unwrap();
    let mut tail = usize::MAX;
    let mut head = usize::MAX;
    for (v, &s) in col.iter() {
        if s < 0 {
            tail = v;
        } else {
            head = v;
        }
    }
    (tail, head)
}

/// Twice the vector area of each oriented 2-cell: Σ_e s_e (x_tail × x_head).
fn vector_areas(k: &Complex) -> Vec<P3> {
    let d1 = k.boundary_csc(1);
    let d2 = k.boundary_csc(2);
    (0..k.cell_count(2))
        .map(|c| {
            let mut n = [0.0; 3];
            for (e, &s) in d2.outer_view(c).unwrap().iter() {
                let col = d1.outer_view(e).unwrap();
                let (mut tail, mut head) = (0, 0);
                for (v, &t) in col.iter() {
                    if t < 0 {
                        tail = v;
                    } else {
                        head = v;
                    }
                }
                let w = cross(point3(k, tail), point3(k, head));
                for a in 0..3 {
                    n[a] += f64::from(s) * w[a];
                }
            }
            n
        })
        .collect()
}

fn vertex_average(k: &Complex, p: usize, c: usize) -> P3 {
    let vs = k.cell_vertices(p, c);
    let mut m = [0.0; 3];
    for &v in vs {
        let x = point3(k, v);
        for a in 0..3 {
            m[a] += x[a] / vs.len() as f64;
        }
    }
    m
}

/// Andrew's monotone chain: number of strict convex hull vertices.
fn hull_size(points: &[[f64; 2]]) -> usize {
    let mut pts = points.to_vec();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull.len()
}

fn jittered_grid(n: usize, jitter: f64, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let h = 1.0 / n as f64;
    let mut pts = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            pts.push([
                i as f64 * h + jitter * h * rng.gen_range(-1.0..1.0),
                j as f64 * h + jitter * h * rng.gen_range(-1.0..1.0),
            ]);
        }
    }
    pts
}

fn random_points(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| [rng.gen(), rng.gen()]).collect()
}

// ---------------------------------------------------------------- axes

#[test]
fn uniform_and_graded_axes() {
    let x = uniform_axis(5, -1.0, 1.5).unwrap();
    assert_eq!(x.len(), 6);
    assert_eq!((x[0], x[5]), (-1.0, 1.5));
    for w in x.windows(2) {
        assert_abs_diff_eq!(w[1] - w[0], 0.5, epsilon = 1e-15);
    }
    let g = graded_axis(6, 0.0, 2.0, 1.3).unwrap();
    assert_eq!((g[0], g[6]), (0.0, 2.0));
    // Closed form of the first spacing: (b − a)(r − 1)/(r^n − 1).
    let h0 = 2.0 * 0.3 / (1.3f64.powi(6) - 1.0);
    assert_abs_diff_eq!(g[1], h0, epsilon = 1e-14);
    for k in 1..6 {
        let ratio = (g[k + 1] - g[k]) / (g[k] - g[k - 1]);
        assert!(
            abs_diff_eq!(ratio, 1.3, epsilon = 1e-12),
            "spacing ratio {ratio}"
        );
    }
    assert_eq!(
        graded_axis(4, 0.0, 1.0, 1.0).unwrap(),
        uniform_axis(4, 0.0, 1.0).unwrap()
    );
}

#[test]
fn axis_errors_name_the_parameter() {
    assert!(message(uniform_axis(0, 0.0, 1.0).unwrap_err()).contains("n must be at least 1"));
    assert!(message(uniform_axis(3, 1.0, 1.0).unwrap_err()).contains("a < b"));
    assert!(message(uniform_axis(3, 0.0, f64::NAN).unwrap_err()).contains("finite"));
    assert!(message(graded_axis(3, 0.0, 1.0, 0.0).unwrap_err()).contains("ratio"));
    assert!(message(graded_axis(3, 0.0, 1.0, f64::INFINITY).unwrap_err()).contains("ratio"));
    assert!(message(graded_axis(2000, 0.0, 1.0, 1e10).unwrap_err()).contains("ratio"));
}

// ---------------------------------------------------------------- grids

#[test]
fn grid_cell_counts_in_closed_form() {
    for n in [1, 2, 9] {
        let k = interval(n, 0.0, 1.0).unwrap();
        assert_eq!(k.cell_counts(), vec![n + 1, n]);
    }
    for (nx, ny) in [(1, 1), (3, 2), (7, 5)] {
        let k = rectangle(nx, ny, [0.0, 1.0], [0.0, 2.0]).unwrap();
        assert_eq!(
            k.cell_counts(),
            vec![(nx + 1) * (ny + 1), nx * (ny + 1) + ny * (nx + 1), nx * ny]
        );
    }
    for (nx, ny, nz) in [(1, 1, 1), (2, 3, 4), (5, 4, 3)] {
        let k = box3(nx, ny, nz, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
        let v = (nx + 1) * (ny + 1) * (nz + 1);
        let e = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
        let f = nx * ny * (nz + 1) + nx * (ny + 1) * nz + (nx + 1) * ny * nz;
        assert_eq!(k.cell_counts(), vec![v, e, f, nx * ny * nz]);
    }
}

#[test]
fn grid_numbering_is_x_fastest_with_tensor_order_cells() {
    let x = vec![0.0, 1.0, 3.0];
    let y = vec![-1.0, 0.5];
    let z = vec![2.0, 2.5, 4.0];
    let k = grid(&[x.clone(), y.clone(), z.clone()]).unwrap();
    for (kk, &zk) in z.iter().enumerate() {
        for (j, &yj) in y.iter().enumerate() {
            for (i, &xi) in x.iter().enumerate() {
                assert_eq!(k.vertices().point(i + 3 * (j + 2 * kk)), &[xi, yj, zk]);
            }
        }
    }
    // 2 × 1 × 2 cells: hex (i, j, k) = (1, 0, 1) is cell 1 + 2 (0 + 1·1) = 3,
    // its lowest corner vertex (1, 0, 1) = 1 + 3 (0 + 2·1) = 7.
    let o = 7;
    let mut expected: Vec<usize> = (0..8)
        .map(|l| o + (l & 1) + 3 * ((l >> 1) & 1) + 6 * ((l >> 2) & 1))
        .collect();
    expected.sort_unstable();
    assert_eq!(k.cell_vertices(3, 3), expected.as_slice());

    let k = rectangle(3, 2, [0.0, 3.0], [0.0, 2.0]).unwrap();
    // Quad (2, 1) is cell 2 + 3·1 = 5 with corners 6, 7, 10, 11.
    assert_eq!(k.cell_vertices(2, 5), &[6, 7, 10, 11]);
    assert_eq!(k.vertices().point(7), &[3.0, 1.0]);
}

#[test]
fn kuhn_cell_counts_in_closed_form() {
    for (nx, ny) in [(1, 1), (4, 3)] {
        let ax = uniform_axis(nx, 0.0, 1.0).unwrap();
        let ay = uniform_axis(ny, 0.0, 1.0).unwrap();
        let k = kuhn(&[ax, ay]).unwrap();
        let grid_edges = nx * (ny + 1) + ny * (nx + 1);
        assert_eq!(
            k.cell_counts(),
            vec![(nx + 1) * (ny + 1), grid_edges + nx * ny, 2 * nx * ny]
        );
    }
    for n in [1, 2, 4] {
        let a = uniform_axis(n, 0.0, 1.0).unwrap();
        let k = kuhn(&[a.clone(), a.clone(), a]).unwrap();
        let v = (n + 1).pow(3);
        let e = 3 * n * (n + 1) * (n + 1);
        let f = 3 * n * n * (n + 1);
        let c = n.pow(3);
        // Every grid face gets one diagonal, every cube one main diagonal;
        // each face splits in 2 triangles and each cube adds 6 inner ones.
        assert_eq!(k.cell_counts(), vec![v, e + f + c, 2 * f + 6 * c, 6 * c]);
    }
    let k = kuhn(&[uniform_axis(3, 0.0, 1.0).unwrap()]).unwrap();
    assert_eq!(k.cell_counts(), vec![4, 3]);
}

#[test]
fn kuhn_tetrahedra_fill_the_cube() {
    // Six tetrahedra of volume 1/6 each on the unit cube, all sharing 0–7.
    let a = vec![0.0, 1.0];
    let k = kuhn(&[a.clone(), a.clone(), a]).unwrap();
    let mut total = 0.0;
    for t in 0..6 {
        let vs = k.cell_vertices(3, t);
        assert!(vs.contains(&0) && vs.contains(&7));
        let x: Vec<P3> = vs.iter().map(|&v| point3(&k, v)).collect();
        let vol = dot(sub(x[1], x[0]), cross(sub(x[2], x[0]), sub(x[3], x[0]))).abs() / 6.0;
        total += vol;
        assert_abs_diff_eq!(vol, 1.0 / 6.0, epsilon = 1e-15);
    }
    assert_abs_diff_eq!(total, 1.0, epsilon = 1e-14);
}

#[test]
fn grid_boundary_tags() {
    let (nx, ny) = (5, 3);
    let k = rectangle(nx, ny, [1.0, 2.0], [0.0, 3.0]).unwrap();
    assert_eq!(tag_len(&k, "xmin"), ny);
    assert_eq!(tag_len(&k, "xmax"), ny);
    assert_eq!(tag_len(&k, "ymin"), nx);
    assert_eq!(tag_len(&k, "ymax"), nx);
    assert_eq!(tag_len(&k, "boundary"), 2 * (nx + ny));
    for (name, axis, value) in [
        ("xmin", 0, 1.0),
        ("xmax", 0, 2.0),
        ("ymin", 1, 0.0),
        ("ymax", 1, 3.0),
    ] {
        let tag = k.tag(name).unwrap();
        assert_eq!(tag.dim, 1);
        for &e in &tag.cells {
            for &v in k.cell_vertices(1, e) {
                assert_eq!(k.vertices().point(v)[axis], value, "{name}");
            }
        }
    }

    let (nx, ny, nz) = (2, 3, 4);
    let k = box3(nx, ny, nz, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    for (name, count) in [
        ("xmin", ny * nz),
        ("xmax", ny * nz),
        ("ymin", nx * nz),
        ("ymax", nx * nz),
        ("zmin", nx * ny),
        ("zmax", nx * ny),
        ("boundary", 2 * (nx * ny + ny * nz + nx * nz)),
    ] {
        assert_eq!(tag_len(&k, name), count, "{name}");
        assert_eq!(k.tag(name).unwrap().dim, 2);
    }
    for &f in &k.tag("zmax").unwrap().cells {
        assert!(k
            .cell_vertices(2, f)
            .iter()
            .all(|&v| k.vertices().point(v)[2] == 1.0));
    }

    let a = uniform_axis(3, 0.0, 1.0).unwrap();
    let k = kuhn(&[a.clone(), a.clone(), a.clone()]).unwrap();
    for name in ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"] {
        assert_eq!(tag_len(&k, name), 2 * 9, "{name}");
    }
    assert_eq!(tag_len(&k, "boundary"), 6 * 2 * 9);
    let k = kuhn(&[a.clone(), a]).unwrap();
    assert_eq!(tag_len(&k, "xmin"), 3);
    assert_eq!(tag_len(&k, "boundary"), 12);

    let k = interval(4, 0.0, 2.0).unwrap();
    assert_eq!(k.tag("xmin").unwrap().cells, vec![0]);
    assert_eq!(k.tag("xmax").unwrap().cells, vec![4]);
    assert_eq!(k.tag("boundary").unwrap().cells, vec![0, 4]);
    assert_eq!(k.tag("xmax").unwrap().dim, 0);
}

#[test]
fn grid_errors_name_the_parameter() {
    assert!(
        message(rectangle(0, 2, [0.0, 1.0], [0.0, 1.0]).unwrap_err())
            .contains("nx must be at least 1, got 0")
    );
    assert!(
        message(box3(1, 1, 0, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap_err())
            .contains("nz must be at least 1, got 0")
    );
    assert!(message(rectangle(2, 2, [0.0, 1.0], [1.0, 0.0]).unwrap_err()).contains("y"));
    assert!(message(grid(&[]).unwrap_err()).contains("1 to 3"));
    assert!(message(grid(&[vec![0.0]]).unwrap_err()).contains("axis 0"));
    assert!(
        message(grid(&[vec![0.0, 1.0], vec![0.0, 2.0, 2.0]]).unwrap_err())
            .contains("axis 1 must be strictly increasing")
    );
    assert!(message(kuhn(&[vec![0.0, f64::NAN]]).unwrap_err()).contains("finite"));
    let four = vec![vec![0.0, 1.0]; 4];
    assert!(grid(&four).is_err());
    assert!(message(hollow_box(2, [1, 1]).unwrap_err()).contains("n must be at least 3"));
    assert!(message(hollow_box(4, [0, 2]).unwrap_err()).contains("cavity"));
    assert!(message(hollow_box(4, [1, 4]).unwrap_err()).contains("cavity"));
    assert!(message(hollow_box(4, [2, 2]).unwrap_err()).contains("cavity"));
}

// ---------------------------------------------------------------- topology

#[test]
fn topology_of_flat_domains() {
    for (nx, ny) in [(1, 1), (4, 3), (9, 7)] {
        assert_topology(
            &rectangle(nx, ny, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            1,
            &[1, 0, 0],
        );
        let ax = graded_axis(nx, 0.0, 1.0, 1.2).unwrap();
        let ay = uniform_axis(ny, -1.0, 1.0).unwrap();
        assert_topology(&kuhn(&[ax, ay]).unwrap(), 1, &[1, 0, 0]);
    }
    for n in [1, 6] {
        assert_topology(&interval(n, 0.0, 1.0).unwrap(), 1, &[1, 0]);
        assert_topology(
            &kuhn(&[uniform_axis(n, 0.0, 1.0).unwrap()]).unwrap(),
            1,
            &[1, 0],
        );
    }
    for (n, seed) in [(20, 1), (200, 2)] {
        let k = delaunay(&random_points(n, seed)).unwrap();
        assert_topology(&k, 1, &[1, 0, 0]);
    }
    for (nr, na) in [(1, 3), (3, 16)] {
        assert_topology(&annulus(0.5, 1.5, nr, na).unwrap(), 0, &[1, 1, 0]);
    }
}

#[test]
fn topology_of_solids() {
    for (nx, ny, nz) in [(1, 1, 1), (3, 2, 4)] {
        let k = box3(nx, ny, nz, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert_topology(&k, 1, &[1, 0, 0, 0]);
        let axes = [
            uniform_axis(nx, 0.0, 1.0).unwrap(),
            graded_axis(ny, 0.0, 1.0, 0.7).unwrap(),
            uniform_axis(nz, 0.0, 2.0).unwrap(),
        ];
        assert_topology(&kuhn(&axes).unwrap(), 1, &[1, 0, 0, 0]);
    }
    for (n, cavity) in [(3, [1, 2]), (5, [1, 3]), (6, [2, 5])] {
        assert_topology(&hollow_box(n, cavity).unwrap(), 2, &[1, 0, 1, 0]);
    }
}

#[test]
fn topology_of_closed_surfaces() {
    for (nm, nn) in [(3, 3), (10, 6)] {
        assert_topology(&torus(2.0, 0.7, nm, nn).unwrap(), 0, &[1, 2, 1]);
    }
    for level in [0, 1, 2] {
        assert_topology(&sphere(1.5, level).unwrap(), 2, &[1, 0, 1]);
    }
}

// ---------------------------------------------------------------- curved shapes

#[test]
fn annulus_tags_and_area() {
    let (ri, ro, nr, na) = (0.5, 2.0, 3, 24);
    let k = annulus(ri, ro, nr, na).unwrap();
    assert_eq!(
        k.cell_counts(),
        vec![na * (nr + 1), na * (2 * nr + 1), na * nr]
    );
    assert_eq!(tag_len(&k, "inner"), na);
    assert_eq!(tag_len(&k, "outer"), na);
    assert_eq!(tag_len(&k, "boundary"), 2 * na);
    for (name, r) in [("inner", ri), ("outer", ro)] {
        for &e in &k.tag(name).unwrap().cells {
            for &v in k.cell_vertices(1, e) {
                let p = k.vertices().point(v);
                assert!(abs_diff_eq!(p[0].hypot(p[1]), r, epsilon = 1e-14), "{name}");
            }
        }
    }
    // Shoelace area of each quad, its corners taken counter-clockwise from
    // the documented layout: vertex (k, i) = angle index k, ring i.
    let mut area = 0.0;
    for i in 0..nr {
        for kk in 0..na {
            let v = |k_: usize, i_: usize| (k_ % na) + na * i_;
            let ring = [v(kk, i), v(kk, i + 1), v(kk + 1, i + 1), v(kk + 1, i)];
            let mut twice = 0.0;
            for m in 0..4 {
                let p = k.vertices().point(ring[m]);
                let q = k.vertices().point(ring[(m + 1) % 4]);
                twice += p[0] * q[1] - p[1] * q[0];
            }
            assert!(twice > 0.0);
            area += twice / 2.0;
        }
    }
    let exact = 0.5 * na as f64 * (2.0 * PI / na as f64).sin() * (ro * ro - ri * ri);
    assert_relative_eq!(area, exact, epsilon = 0.0, max_relative = 1e-12);
    // and it approaches π(ro² − ri²) as n_angular grows
    assert_relative_eq!(
        area,
        PI * (ro * ro - ri * ri),
        epsilon = 0.0,
        max_relative = 0.02
    );
}

#[test]
fn sphere_counts_and_radius() {
    for level in 0..=3u32 {
        let radius = 2.5;
        let k = sphere(radius, level).unwrap();
        let f = 4usize.pow(level);
        assert_eq!(k.cell_counts(), vec![10 * f + 2, 30 * f, 20 * f]);
        for v in 0..k.cell_count(0) {
            let r = norm(point3(&k, v));
            assert!(
                relative_eq!(r, radius, epsilon = 0.0, max_relative = 1e-14),
                "vertex {v} at {r}"
            );
        }
        // Outward orientation and acute (well-centred) triangles.
        for (c, n) in vector_areas(&k).into_iter().enumerate() {
            assert!(
                dot(n, vertex_average(&k, 2, c)) > 0.0,
                "triangle {c} points inward"
            );
            let vs = k.cell_vertices(2, c);
            for m in 0..3 {
                let o = point3(&k, vs[m]);
                let a = sub(point3(&k, vs[(m + 1) % 3]), o);
                let b = sub(point3(&k, vs[(m + 2) % 3]), o);
                assert!(dot(a, b) > 0.0, "triangle {c} is not acute");
            }
        }
    }
    assert_eq!(sphere(1.0, 2).unwrap(), sphere(1.0, 2).unwrap());
    assert!(message(sphere(0.0, 1).unwrap_err()).contains("radius"));
    assert!(message(sphere(1.0, 11).unwrap_err()).contains("subdivisions"));
}

#[test]
fn torus_is_coherently_and_outwardly_oriented() {
    let (big_r, r, nm, nn) = (3.0, 1.0, 16, 8);
    let k = torus(big_r, r, nm, nn).unwrap();
    assert_eq!(k.cell_counts(), vec![nm * nn, 2 * nm * nn, nm * nn]);
    // Vertex layout: (i, j) ↦ i + n_major j at angles 2πi/nm, 2πj/nn.
    for j in 0..nn {
        for i in 0..nm {
            let (t, f) = (
                2.0 * PI * i as f64 / nm as f64,
                2.0 * PI * j as f64 / nn as f64,
            );
            let expected = [
                (big_r + r * f.cos()) * t.cos(),
                (big_r + r * f.cos()) * t.sin(),
                r * f.sin(),
            ];
            let p = point3(&k, i + nm * j);
            assert!(norm(sub(p, expected)) < 1e-14);
        }
    }
    // Every edge lies on exactly two quads, with opposite signs.
    for (e, row) in k.boundary(2).outer_iterator().enumerate() {
        assert_eq!(row.nnz(), 2, "edge {e}");
        assert_eq!(row.data()[0], -row.data()[1], "edge {e}");
    }
    // Edges are oriented from the tail to the head of ∂_1.
    for e in 0..k.cell_count(1) {
        let (t, h) = edge_ends(&k, e);
        assert_ne!(t, h);
    }
    for (c, n) in vector_areas(&k).into_iter().enumerate() {
        let m = vertex_average(&k, 2, c);
        let rho = m[0].hypot(m[1]);
        let centre = [big_r * m[0] / rho, big_r * m[1] / rho, 0.0];
        assert!(
            dot(n, sub(m, centre)) > 0.0,
            "quad {c} points into the tube"
        );
    }
    assert!(message(torus(1.0, 1.0, 8, 8).unwrap_err()).contains("major_radius"));
    assert!(message(torus(2.0, 1.0, 2, 8).unwrap_err()).contains("n_major"));
    assert!(message(torus(2.0, -1.0, 8, 8).unwrap_err()).contains("minor_radius"));
}

#[test]
fn annulus_errors_name_the_parameter() {
    assert!(message(annulus(0.0, 1.0, 2, 8).unwrap_err()).contains("r_inner"));
    assert!(message(annulus(1.0, 1.0, 2, 8).unwrap_err()).contains("r_outer"));
    assert!(message(annulus(1.0, 2.0, 0, 8).unwrap_err()).contains("n_radial"));
    assert!(message(annulus(1.0, 2.0, 2, 2).unwrap_err()).contains("n_angular must be at least 3"));
}

#[test]
fn hollow_box_tags() {
    for (n, cavity) in [(3, [1, 2]), (5, [1, 4]), (7, [2, 5])] {
        let k = hollow_box(n, cavity).unwrap();
        let c = cavity[1] - cavity[0];
        assert_eq!(k.cell_count(3), n * n * n - c * c * c);
        // Vertices strictly inside the cavity are gone.
        assert_eq!(k.cell_count(0), (n + 1).pow(3) - (c - 1).pow(3));
        assert_eq!(tag_len(&k, "cavity"), 6 * c * c);
        assert_eq!(tag_len(&k, "outer"), 6 * n * n);
        assert_eq!(tag_len(&k, "boundary"), 6 * c * c + 6 * n * n);
        let lo = cavity[0] as f64 / n as f64 - 1e-12;
        let hi = cavity[1] as f64 / n as f64 + 1e-12;
        for &f in &k.tag("cavity").unwrap().cells {
            for &v in k.cell_vertices(2, f) {
                assert!(k.vertices().point(v).iter().all(|&x| lo <= x && x <= hi));
            }
        }
    }
}

// ---------------------------------------------------------------- Delaunay

#[test]
fn delaunay_triangle_count_matches_euler_formula() {
    for (n, jitter, seed) in [(4, 0.2, 3), (10, 0.3, 4), (15, 0.1, 5)] {
        let pts = jittered_grid(n, jitter, seed);
        let k = delaunay(&pts).unwrap();
        let hull = hull_size(&pts);
        let interior = pts.len() - hull;
        assert_eq!(k.cell_count(2), 2 * interior + hull - 2);
        assert_eq!(k.cell_count(0), pts.len());
        assert_eq!(tag_len(&k, "boundary"), hull);
        for (v, p) in pts.iter().enumerate() {
            assert_eq!(k.vertices().point(v), p);
        }
    }
}

#[test]
fn delaunay_rejects_bad_point_sets() {
    let e = message(delaunay(&[[0.0, 0.0], [1.0, 0.0]]).unwrap_err());
    assert!(e.contains("at least 3 points, got 2"), "{e}");
    let e = message(delaunay(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 0.0]]).unwrap_err());
    assert!(e.contains("points 1 and 3"), "{e}");
    let e = message(delaunay(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]).unwrap_err());
    assert!(e.contains("one line"), "{e}");
    let e = message(delaunay(&[[0.0, 0.0], [1.0, f64::NAN], [2.0, 1.0]]).unwrap_err());
    assert!(e.contains("point 1"), "{e}");
    let e = message(delaunay(&[[0.0, 0.0], [-0.0, 1.0], [0.0, -0.0], [1.0, 1.0]]).unwrap_err());
    assert!(e.contains("points 0 and 2"), "{e}");
}

// ---------------------------------------------------------------- Voronoi

/// Corners of polygon `c` in boundary order, walked along its oriented
/// edges (each edge taken with its sign in ∂₂), and the signed shoelace
/// area of that walk.
fn polygon_walk(k: &Complex, c: usize) -> (Vec<usize>, f64) {
    let d2 = k.boundary_csc(2);
    let mut next = std::collections::HashMap::new();
    for (e, &s) in d2.outer_view(c).unwrap().iter() {
        let (t, h) = edge_ends(k, e);
        let (t, h) = if s > 0 { (t, h) } else { (h, t) };
        assert!(next.insert(t, h).is_none(), "cell {c}: two edges leave {t}");
    }
    let start = *next.keys().min().unwrap();
    let mut walk = vec![start];
    let mut v = next[&start];
    while v != start {
        walk.push(v);
        v = next[&v];
        assert!(
            walk.len() <= next.len(),
            "cell {c}: its edges are not one cycle"
        );
    }
    assert_eq!(
        walk.len(),
        next.len(),
        "cell {c}: its edges are not one cycle"
    );
    let area = (0..walk.len())
        .map(|i| {
            let (p, q) = (point3(k, walk[i]), point3(k, walk[(i + 1) % walk.len()]));
            p[0] * q[1] - q[0] * p[1]
        })
        .sum::<f64>()
        / 2.0;
    (walk, area)
}

#[test]
fn voronoi_cells_are_convex_and_tile_the_rectangle() {
    let (x, y) = ([-1.0, 2.0], [0.5, 1.5]);
    let rect = (x[1] - x[0]) * (y[1] - y[0]);
    for (n, seed, lloyd) in [(1, 0, 0), (2, 1, 0), (37, 5, 0), (200, 6, 3), (500, 7, 10)] {
        let k = voronoi(n, x, y, seed, lloyd).unwrap();
        assert_eq!(k.cell_count(2), n);
        assert_topology(&k, 1, &[1, 0, 0]);
        let mut total = 0.0;
        for c in 0..n {
            let (walk, area) = polygon_walk(&k, c);
            // Strictly convex: every corner turns the same way as the walk.
            let m = walk.len();
            for i in 0..m {
                let (a, b, d) = (
                    point3(&k, walk[i]),
                    point3(&k, walk[(i + 1) % m]),
                    point3(&k, walk[(i + 2) % m]),
                );
                let turn = cross(sub(b, a), sub(d, b))[2];
                assert!(
                    turn * area > 0.0,
                    "n = {n}: cell {c} is not strictly convex at corner {i}"
                );
            }
            assert!(
                abs_diff_eq!(area.abs(), k.measure(2)[c], epsilon = 1e-12 * rect),
                "n = {n}: cell {c} measure {} vs shoelace {area}",
                k.measure(2)[c]
            );
            total += area.abs();
        }
        assert!(
            relative_eq!(total, rect, epsilon = 0.0, max_relative = 1e-12),
            "n = {n}: areas sum to {total}"
        );
        // Boundary edges lie exactly on the sides, and the side tags cover them.
        let side_length = |name: &str| -> f64 {
            k.tag(name)
                .unwrap()
                .cells
                .iter()
                .map(|&e| k.measure(1)[e])
                .sum()
        };
        for (name, length) in [("xmin", 1.0), ("xmax", 1.0), ("ymin", 3.0), ("ymax", 3.0)] {
            assert!(
                abs_diff_eq!(side_length(name), length, epsilon = 1e-12),
                "n = {n}: {name}"
            );
        }
        assert_eq!(
            tag_len(&k, "boundary"),
            ["xmin", "xmax", "ymin", "ymax"]
                .iter()
                .map(|t| tag_len(&k, t))
                .sum::<usize>()
        );
    }
}

#[test]
fn voronoi_cells_are_the_nearest_site_regions() {
    let (k, sites) = voronoi_with_sites(150, [0.0, 1.0], [0.0, 1.0], 11, 2).unwrap();
    let d = |p: P3, q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    for (c, &s) in sites.iter().enumerate() {
        // Every corner of cell c is at least as near to site c as to any other.
        for &v in k.cell_vertices(2, c) {
            let p = point3(&k, v);
            let own = d(p, s);
            assert!(
                sites.iter().all(|&q| own <= d(p, q) + 1e-12),
                "cell {c}, corner {v}"
            );
        }
        // The site lies inside its cell: on the inner side of every edge.
        let (walk, area) = polygon_walk(&k, c);
        for i in 0..walk.len() {
            let (a, b) = (point3(&k, walk[i]), point3(&k, walk[(i + 1) % walk.len()]));
            let side = cross(sub(b, a), sub([s[0], s[1], 0.0], a))[2];
            assert!(side * area > 0.0, "site {c} outside its cell");
        }
    }
}

#[test]
fn voronoi_is_seeded_and_lloyd_moves_sites_towards_centroids() {
    let k = voronoi(80, [0.0, 1.0], [0.0, 1.0], 3, 2).unwrap();
    assert_eq!(k, voronoi(80, [0.0, 1.0], [0.0, 1.0], 3, 2).unwrap());
    assert_ne!(k, voronoi(80, [0.0, 1.0], [0.0, 1.0], 4, 2).unwrap());
    // Lloyd's fixed points are centroidal tessellations: the largest
    // site–centroid distance shrinks with the iterations.
    let offset = |lloyd: usize| {
        let (k, sites) = voronoi_with_sites(80, [0.0, 1.0], [0.0, 1.0], 3, lloyd).unwrap();
        (0..80)
            .map(|c| {
                let g = k.centroid_of(2, c);
                (g[0] - sites[c][0]).hypot(g[1] - sites[c][1])
            })
            .fold(0.0, f64::max)
    };
    let (none, some, many) = (offset(0), offset(5), offset(40));
    assert!(some < none && many < some, "{none} {some} {many}");
}

#[test]
fn voronoi_rejects_bad_parameters() {
    let e = message(voronoi(0, [0.0, 1.0], [0.0, 1.0], 0, 0).unwrap_err());
    assert!(e.contains("at least 1 site"), "{e}");
    let e = message(voronoi(5, [1.0, 1.0], [0.0, 1.0], 0, 0).unwrap_err());
    assert!(e.contains("x extent"), "{e}");
    let e = message(voronoi(5, [0.0, 1.0], [0.0, f64::NAN], 0, 0).unwrap_err());
    assert!(e.contains("y extent"), "{e}");
}

// ---------------------------------------------------------------- perturbation

fn on_box_boundary(p: &[f64]) -> bool {
    p.iter().any(|&x| x == 0.0 || x == 1.0)
}

#[test]
fn perturb_moves_interior_vertices_only() {
    let a = uniform_axis(5, 0.0, 1.0).unwrap();
    // (complex, shortest edge at every vertex of these uniform grids)
    let cases = [
        (interval(8, 0.0, 1.0).unwrap(), 1.0 / 8.0),
        (rectangle(6, 5, [0.0, 1.0], [0.0, 1.0]).unwrap(), 1.0 / 6.0),
        (kuhn(&[a.clone(), a.clone()]).unwrap(), 1.0 / 5.0),
        (
            box3(4, 3, 4, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
            1.0 / 4.0,
        ),
        (kuhn(&[a.clone(), a.clone(), a]).unwrap(), 1.0 / 5.0),
    ];
    for (k, h) in &cases {
        let amplitude = 0.2;
        let p = perturb(k, amplitude, 42).unwrap();
        assert_eq!(
            p,
            perturb(k, amplitude, 42).unwrap(),
            "same seed, same mesh"
        );
        assert_ne!(
            p,
            perturb(k, amplitude, 43).unwrap(),
            "another seed moves differently"
        );
        assert_eq!(p.cell_counts(), k.cell_counts());
        assert_eq!(p.euler_characteristic(), k.euler_characteristic());
        assert_eq!(p.tags(), k.tags());
        assert_dd_zero(&p);
        for v in 0..k.cell_count(0) {
            let (x, y) = (k.vertices().point(v), p.vertices().point(v));
            if on_box_boundary(x) {
                assert_eq!(x, y, "boundary vertex {v} moved");
            } else {
                assert_ne!(x, y, "interior vertex {v} did not move");
                for (a, b) in x.iter().zip(y) {
                    assert_abs_diff_eq!(a, b, epsilon = amplitude * h * (1.0 + 1e-12));
                }
            }
        }
    }
    let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    assert_eq!(perturb(&k, 0.0, 1).unwrap(), k);
}

#[test]
fn perturb_rejects_bad_input() {
    let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    for bad in [-0.1, 0.5, 1.0, f64::NAN] {
        let e = message(perturb(&k, bad, 0).unwrap_err());
        assert!(e.contains("amplitude must be in [0, 0.5)"), "{e}");
    }
    let e = message(perturb(&torus(2.0, 1.0, 6, 6).unwrap(), 0.1, 0).unwrap_err());
    assert!(e.contains("2-dimensional in R^3"), "{e}");
}

// ---------------------------------------------------------------- ∂∂ = 0

#[test]
fn boundary_of_boundary_vanishes_on_every_generator() {
    let a = uniform_axis(3, 0.0, 1.0).unwrap();
    let complexes = [
        interval(3, 0.0, 1.0).unwrap(),
        kuhn(std::slice::from_ref(&a)).unwrap(),
        rectangle(3, 2, [0.0, 1.0], [0.0, 1.0]).unwrap(),
        kuhn(&[a.clone(), a.clone()]).unwrap(),
        box3(2, 3, 2, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap(),
        kuhn(&[a.clone(), a.clone(), a]).unwrap(),
        delaunay(&random_points(50, 9)).unwrap(),
        annulus(1.0, 2.0, 2, 10).unwrap(),
        torus(3.0, 1.0, 8, 5).unwrap(),
        sphere(1.0, 2).unwrap(),
        hollow_box(4, [1, 3]).unwrap(),
        voronoi(40, [0.0, 1.0], [0.0, 1.0], 2, 1).unwrap(),
    ];
    for k in &complexes {
        assert_dd_zero(k);
    }
}
