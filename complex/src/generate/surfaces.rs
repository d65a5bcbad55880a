//! Curved domains: a polar annulus, a torus and an icosphere.

use super::{invalid, positive, tag_boundary};
use crate::cells::{TopCells, Vertices};
use crate::error::Result;
use crate::Complex;
use std::collections::HashMap;
use std::f64::consts::PI;

fn at_least(name: &str, value: usize, min: usize) -> Result<()> {
    if value < min {
        return invalid(format!("{name} must be at least {min}, got {value}"));
    }
    Ok(())
}

/// The quad with corners `(i, j)`, `(i+1, j)`, `(i, j+1)`, `(i+1, j+1)` of a
/// grid whose vertex `(i, j)` is `i + n_i j`, in tensor order, for the first
/// `cells_i × cells_j` cells; corner indices wrap modulo `n_i` and `n_j`, so
/// `cells_i = n_i` makes the grid periodic in `i`.
fn periodic_quads(
    n_i: usize,
    n_j: usize,
    cells_i: usize,
    cells_j: usize,
) -> impl Iterator<Item = [usize; 4]> {
    (0..cells_j).flat_map(move |j| {
        (0..cells_i).map(move |i| {
            let (i1, j1) = ((i + 1) % n_i, (j + 1) % n_j);
            [i + n_i * j, i1 + n_i * j, i + n_i * j1, i1 + n_i * j1]
        })
    })
}

/// A polar quad grid of the annulus `r_inner ≤ |x| ≤ r_outer` in R^2:
/// `n_radial` uniform rings of `n_angular` cells each.
///
/// Vertex `(k, i)` sits at radius `r_inner + (r_outer − r_inner) i / n_radial`
/// and angle `2πk / n_angular`, with index `k + n_angular i` (angle fastest);
/// the angle is periodic, so the seam has no duplicate vertices. Quad
/// `(k, i)` has index `k + n_angular i` and corners in tensor order
/// `[(k, i), (k+1, i), (k, i+1), (k+1, i+1)]`. The cells are the straight-sided
/// trapezoids between those vertices, so the meshed area is
/// `½ n_angular sin(2π / n_angular) (r_outer² − r_inner²)`. Tags: `"inner"`
/// and `"outer"` (`n_angular` edges each) and `"boundary"`.
///
/// ```
/// let k = hasse_complex::generate::annulus(1.0, 2.0, 2, 8).unwrap();
/// assert_eq!(k.cell_counts(), vec![24, 40, 16]);
/// assert_eq!(k.euler_characteristic(), 0);
/// assert_eq!(k.tag("inner").unwrap().cells.len(), 8);
/// ```
pub fn annulus(r_inner: f64, r_outer: f64, n_radial: usize, n_angular: usize) -> Result<Complex> {
    positive("r_inner", r_inner)?;
    if !(r_outer.is_finite() && r_outer > r_inner) {
        return invalid(format!(
            "r_outer must be finite and greater than r_inner = {r_inner}, got {r_outer}"
        ));
    }
    at_least("n_radial", n_radial, 1)?;
    at_least("n_angular", n_angular, 3)?;
    let mut coords = Vec::with_capacity(2 * n_angular * (n_radial + 1));
    for i in 0..=n_radial {
        let r = if i == n_radial {
            r_outer
        } else {
            r_inner + (r_outer - r_inner) * (i as f64 / n_radial as f64)
        };
        for k in 0..n_angular {
            let (s, c) = (2.0 * PI * k as f64 / n_angular as f64).sin_cos();
            coords.extend_from_slice(&[r * c, r * s]);
        }
    }
    let cells = TopCells::cuboids(periodic_quads(n_angular, n_radial + 1, n_angular, n_radial));
    let mut complex = Complex::build(Vertices::new(2, coords)?, cells)?;
    let ring = |v: usize| v / n_angular;
    tag_boundary(&mut complex, &["inner", "outer"], |edge| {
        Some(usize::from(ring(edge[0]) != 0))
    })?;
    Ok(complex)
}

/// A closed quad surface of the torus in R^3, periodic in both angles:
///
/// `x = (R + r cos φ) cos θ`, `y = (R + r cos φ) sin θ`, `z = r sin φ`,
///
/// with `R = major_radius > r = minor_radius > 0`, `θ = 2πi / n_major` and
/// `φ = 2πj / n_minor`. Vertex `(i, j)` has index `i + n_major j` (θ fastest),
/// quad `(i, j)` the same index and corners `[(i, j), (i+1, j), (i, j+1),
/// (i+1, j+1)]` (indices modulo the counts; no seam duplicates). Each quad is
/// a planar isosceles trapezoid. The complex orients the surface
/// coherently with outward normals. No tags (the surface has no boundary).
///
/// **Unfolded coordinates.** The thesis's flat torus of length `l` and
/// width `m` uses `ξ = l θ / (2π)`, `η = m φ / (2π)`. For vertex `(i, j)`
/// that is `ξ = l i / n_major`, `η = m j / n_minor`; from a point,
/// `θ = atan2(y, x)`, `φ = atan2(z, √(x² + y²) − R)` (taken in `[0, 2π)`).
///
/// ```
/// let k = hasse_complex::generate::torus(2.0, 0.5, 12, 6).unwrap();
/// assert_eq!(k.cell_counts(), vec![72, 144, 72]);
/// assert_eq!(k.euler_characteristic(), 0);
/// // Unfolded coordinates of vertex (i, j) = (3, 2) on a 2π × 2π square:
/// let (l, m) = (2.0 * std::f64::consts::PI, 2.0 * std::f64::consts::PI);
/// let (i, j) = (3, 2);
/// let (xi, eta) = (l * i as f64 / 12.0, m * j as f64 / 6.0);
/// let p = k.vertices().point(i + 12 * j);
/// let theta = p[1].atan2(p[0]);
/// let phi = p[2].atan2(p[0].hypot(p[1]) - 2.0);
/// assert!((xi - l * theta / (2.0 * std::f64::consts::PI)).abs() < 1e-12);
/// assert!((eta - m * phi / (2.0 * std::f64::consts::PI)).abs() < 1e-12);
/// ```
pub fn torus(
    major_radius: f64,
    minor_radius: f64,
    n_major: usize,
    n_minor: usize,
) -> Result<Complex> {
    positive("minor_radius", minor_radius)?;
    if !(major_radius.is_finite() && major_radius > minor_radius) {
        return invalid(format!(
            "major_radius must be finite and greater than minor_radius = {minor_radius} (otherwise the torus intersects itself), got {major_radius}"
        ));
    }
    at_least("n_major", n_major, 3)?;
    at_least("n_minor", n_minor, 3)?;
    let mut coords = Vec::with_capacity(3 * n_major * n_minor);
    for j in 0..n_minor {
        let (sp, cp) = (2.0 * PI * j as f64 / n_minor as f64).sin_cos();
        let rho = major_radius + minor_radius * cp;
        for i in 0..n_major {
            let (st, ct) = (2.0 * PI * i as f64 / n_major as f64).sin_cos();
            coords.extend_from_slice(&[rho * ct, rho * st, minor_radius * sp]);
        }
    }
    let cells = TopCells::cuboids(periodic_quads(n_major, n_minor, n_major, n_minor));
    Complex::build(Vertices::new(3, coords)?, cells)
}

/// Largest accepted icosphere subdivision level (10·4^10 + 2 ≈ 10^7 vertices).
const MAX_SUBDIVISIONS: u32 = 10;

/// An icosphere: the regular icosahedron inscribed in the sphere of the
/// given radius, each triangle split into 4 (at its edge midpoints)
/// `subdivisions` times, every new vertex projected radially onto the
/// sphere. A closed, outward-oriented triangle surface in R^3 with
/// `10·4^k + 2` vertices, `30·4^k` edges and `20·4^k` triangles for
/// `k = subdivisions`; its triangles are nearly equilateral (acute, so the
/// mesh is well-centred). Deterministic; no tags.
///
/// ```
/// let k = hasse_complex::generate::sphere(1.0, 1).unwrap();
/// assert_eq!(k.cell_counts(), vec![42, 120, 80]);
/// assert_eq!(k.euler_characteristic(), 2);
/// ```
pub fn sphere(radius: f64, subdivisions: u32) -> Result<Complex> {
    positive("radius", radius)?;
    if subdivisions > MAX_SUBDIVISIONS {
        return invalid(format!(
            "subdivisions must be in 0..={MAX_SUBDIVISIONS}, got {subdivisions}"
        ));
    }
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut points: Vec<[f64; 3]> = vec![
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ];
    let mut triangles: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let project = |p: [f64; 3]| {
        let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        p.map(|x| x / len)
    };
    for p in &mut points {
        *p = project(*p);
    }
    for _ in 0..subdivisions {
        let mut midpoint: HashMap<(usize, usize), usize> =
            HashMap::with_capacity(triangles.len() * 3 / 2);
        let mut split = Vec::with_capacity(4 * triangles.len());
        for &[a, b, c] in &triangles {
            let mut mid = |u: usize, v: usize| {
                *midpoint.entry((u.min(v), u.max(v))).or_insert_with(|| {
                    let (p, q) = (points[u], points[v]);
                    points.push(project([p[0] + q[0], p[1] + q[1], p[2] + q[2]]));
                    points.len() - 1
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            split.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = split;
    }
    let coords: Vec<f64> = points.iter().flat_map(|p| p.map(|x| x * radius)).collect();
    Complex::build(Vertices::new(3, coords)?, TopCells::simplices(triangles))
}
