//! Delaunay triangulation of a planar point set (via `spade`).

use super::{invalid, positive, tag_boundary};
use crate::cells::{TopCells, Vertices};
use crate::error::Result;
use crate::Complex;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use spade::{DelaunayTriangulation, InsertionError, Point2, Triangulation};

/// The Delaunay triangulation of a planar point set, covering its convex
/// hull. Vertex `i` is `points[i]`; the triangles are numbered in `spade`'s
/// face order (deterministic for a given input). The hull edges are tagged
/// `"boundary"`.
///
/// Errors on fewer than 3 points, non-finite coordinates, repeated points
/// (both indices named) and point sets that are all on one line.
///
/// ```
/// let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.4, 0.6]];
/// let k = hasse_complex::generate::delaunay(&pts).unwrap();
/// // 1 interior and 4 hull points: 2·1 + 4 − 2 = 4 triangles.
/// assert_eq!(k.cell_count(2), 4);
/// assert_eq!(k.tag("boundary").unwrap().cells.len(), 4);
/// assert!(hasse_complex::generate::delaunay(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_err());
/// ```
pub fn delaunay(points: &[[f64; 2]]) -> Result<Complex> {
    if points.len() < 3 {
        return invalid(format!(
            "a Delaunay triangulation needs at least 3 points, got {}",
            points.len()
        ));
    }
    if let Some((i, p)) = points
        .iter()
        .enumerate()
        .find(|(_, p)| !(p[0].is_finite() && p[1].is_finite()))
    {
        return invalid(format!(
            "point {i} = {p:?} has a non-finite coordinate; points must be finite"
        ));
    }
    let same = |a: usize, b: usize| points[a][0] == points[b][0] && points[a][1] == points[b][1];
    // Repeated points end up adjacent after sorting by coordinates; −0.0 and
    // +0.0 are equal but sort apart under total_cmp, so normalise them first.
    let key = |p: [f64; 2]| p.map(|x| if x == 0.0 { 0.0 } else { x });
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_unstable_by(|&a, &b| {
        let (p, q) = (key(points[a]), key(points[b]));
        p[0].total_cmp(&q[0])
            .then(p[1].total_cmp(&q[1]))
            .then(a.cmp(&b))
    });
    if let Some(w) = order.windows(2).find(|w| same(w[0], w[1])) {
        return invalid(format!(
            "points {} and {} are both {:?}; Delaunay input points must be distinct",
            w[0], w[1], points[w[0]]
        ));
    }
    let input: Vec<Point2<f64>> = points.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let triangulation =
        DelaunayTriangulation::<Point2<f64>>::bulk_load_stable(input).map_err(|e| {
            crate::ComplexError::Invalid(match e {
                InsertionError::TooSmall => format!(
                    "a point coordinate is nonzero but smaller in magnitude than {:e}, which the Delaunay kernel cannot represent; rescale the points",
                    spade::MIN_ALLOWED_VALUE
                ),
                InsertionError::TooLarge => format!(
                    "a point coordinate exceeds {:e} in magnitude, which the Delaunay kernel cannot represent; rescale the points",
                    spade::MAX_ALLOWED_VALUE
                ),
                InsertionError::NAN => "a point coordinate is NaN".to_string(),
            })
        })?;
    if triangulation.num_vertices() != points.len() {
        return invalid(format!(
            "the Delaunay kernel merged {} coincident points; input points must be distinct",
            points.len() - triangulation.num_vertices()
        ));
    }
    if triangulation.all_vertices_on_line() || triangulation.num_inner_faces() == 0 {
        return invalid(format!(
            "all {} points lie on one line; a triangulation needs points spanning the plane",
            points.len()
        ));
    }
    // bulk_load_stable keeps the input order, so handle index = input index.
    let triangles = triangulation
        .inner_faces()
        .map(|face| face.vertices().map(|v| v.fix().index()));
    let cells = TopCells::simplices(triangles);
    let vertices = Vertices::from_points(points)?;
    let mut complex = Complex::build(vertices, cells)?;
    tag_boundary(&mut complex, &[], |_| None)?;
    Ok(complex)
}

/// The Delaunay triangulation of `n` random points in the rectangle
/// `x × y` together with points spaced evenly along its sides, so that the
/// triangulation covers exactly the rectangle. Boundary edges are tagged
/// `xmin`, `xmax`, `ymin`, `ymax` and `boundary`.
///
/// The interior points are drawn uniformly from the open rectangle by a
/// ChaCha8 stream seeded with `seed` (the same arguments give the same
/// mesh). Each side of length L is cut into `max(1, round(L·√(n/A)))`
/// segments, A the rectangle's area: about the spacing of the interior
/// points. The vertices are the interior points first, then the boundary
/// points (corners included).
///
/// Errors on `n = 0` and on an empty or non-finite extent.
///
/// ```
/// use hasse_complex::generate::delaunay_rectangle;
/// // 100 interior points in the unit square: 10 segments per side, so 40
/// // boundary points. Triangles of a triangulation with i interior and
/// // b hull points: 2i + b − 2 = 238; edges V + F − 1 = 140 + 238 − 1.
/// let k = delaunay_rectangle(100, [0.0, 1.0], [0.0, 1.0], 1).unwrap();
/// assert_eq!(k.cell_counts(), vec![140, 377, 238]);
/// assert_eq!(k.tag("boundary").unwrap().cells.len(), 40);
/// assert_eq!(k.tag("xmin").unwrap().cells.len(), 10);
/// let area: f64 = k.measure(2).iter().sum();
/// assert!((area - 1.0).abs() < 1e-12);
/// ```
pub fn delaunay_rectangle(n: usize, x: [f64; 2], y: [f64; 2], seed: u64) -> Result<Complex> {
    if n == 0 {
        return invalid("a Delaunay mesh needs at least 1 interior point (n ≥ 1), got 0".into());
    }
    for (name, [lo, hi]) in [("x", x), ("y", y)] {
        if !(lo.is_finite() && hi.is_finite()) {
            return invalid(format!("{name} extent [{lo}, {hi}] must be finite numbers"));
        }
        positive(
            &format!("the {name} extent's length ({name}[1] − {name}[0])"),
            hi - lo,
        )?;
    }
    let (width, height) = (x[1] - x[0], y[1] - y[0]);
    let density = (n as f64 / (width * height)).sqrt();
    let segments = |length: f64| ((length * density).round() as usize).max(1);
    let (nx, ny) = (segments(width), segments(height));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut points: Vec<[f64; 2]> = (0..n)
        .map(|_| {
            [
                super::voronoi::open(&mut rng, x),
                super::voronoi::open(&mut rng, y),
            ]
        })
        .collect();
    let along = |[lo, hi]: [f64; 2], k: usize, i: usize| {
        if i == k {
            hi
        } else {
            lo + (hi - lo) * (i as f64 / k as f64)
        }
    };
    // Counter-clockwise from (x0, y0): bottom, right, top, left.
    for i in 0..nx {
        points.push([along(x, nx, i), y[0]]);
    }
    for j in 0..ny {
        points.push([x[1], along(y, ny, j)]);
    }
    for i in (1..=nx).rev() {
        points.push([along(x, nx, i), y[1]]);
    }
    for j in (1..=ny).rev() {
        points.push([x[0], along(y, ny, j)]);
    }
    let mut complex = delaunay(&points)?;
    let on = |vs: &[usize], axis: usize, value: f64| vs.iter().all(|&v| points[v][axis] == value);
    tag_boundary(&mut complex, &["xmin", "xmax", "ymin", "ymax"], |vs| {
        [(0, x[0]), (0, x[1]), (1, y[0]), (1, y[1])]
            .iter()
            .position(|&(axis, value)| on(vs, axis, value))
    })?;
    Ok(complex)
}
