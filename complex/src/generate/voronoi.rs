//! Voronoi polygon meshes of a rectangle from seeded random sites,
//! optionally smoothed by Lloyd's algorithm.
//!
//! The bounded, clipped diagram is read off one Delaunay triangulation
//! (`spade`) of the sites together with their mirror images across the
//! four sides of the rectangle. For a point x inside the rectangle a mirror
//! image is never nearer than its site (x and the site lie on the same side
//! of the mirror line), and for x outside, the mirror of x's nearest site
//! is nearer than any site; so the Voronoi cell of each site in the
//! augmented set is exactly its Voronoi cell clipped to the rectangle, and
//! its corners are the circumcentres of the Delaunay triangles around the
//! site. Clipping needs no polygon intersection and every corner is shared
//! by index between the cells that meet there, so the complex is conforming
//! by construction.

use super::{invalid, positive, tag_boundary};
use crate::cells::{TopCells, Vertices};
use crate::error::Result;
use crate::Complex;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use spade::{DelaunayTriangulation, Point2, Triangulation};
use std::collections::HashMap;

/// The Voronoi diagram of `n` random sites in the rectangle `x × y`,
/// clipped to it: a conforming mesh of `n` convex polygons (cell `i`
/// belongs to site `i`). Boundary edges are tagged `xmin`, `xmax`, `ymin`,
/// `ymax` and `boundary`.
///
/// Sites are drawn uniformly from a ChaCha8 stream seeded with `seed`, so
/// the mesh depends only on the arguments. `lloyd` iterations of Lloyd's
/// algorithm (move every site to the centroid of its cell, rebuild) follow;
/// they make the cells rounder and more uniform in size (towards a
/// centroidal Voronoi tessellation) while the mesh stays a Voronoi diagram.
/// Use [`voronoi_with_sites`] to also get the final sites, which are the
/// points for which the mesh is orthogonal (the segment between two
/// neighbouring sites is perpendicular to their common edge).
///
/// Errors on `n = 0` and on an empty or non-finite extent.
///
/// ```
/// use hasse_complex::generate::voronoi;
/// let k = voronoi(50, [0.0, 2.0], [0.0, 1.0], 7, 3).unwrap();
/// assert_eq!(k.cell_count(2), 50);
/// assert_eq!(k.euler_characteristic(), 1);
/// let area: f64 = k.measure(2).iter().sum();
/// assert!((area - 2.0).abs() < 1e-12);
/// assert_eq!(k, voronoi(50, [0.0, 2.0], [0.0, 1.0], 7, 3).unwrap());
/// ```
pub fn voronoi(n: usize, x: [f64; 2], y: [f64; 2], seed: u64, lloyd: usize) -> Result<Complex> {
    voronoi_with_sites(n, x, y, seed, lloyd).map(|(complex, _)| complex)
}

/// [`voronoi`] together with the sites that generated the final diagram:
/// `sites[i]` lies strictly inside cell `i` and is the point for which the
/// two-point flux between cells is consistent.
///
/// ```
/// use hasse_complex::generate::voronoi_with_sites;
/// let (k, sites) = voronoi_with_sites(20, [0.0, 1.0], [0.0, 1.0], 3, 0).unwrap();
/// assert_eq!(sites.len(), k.cell_count(2));
/// // Every site is nearer to the corners of its own cell than to any other site.
/// for (c, s) in sites.iter().enumerate() {
///     for &v in k.cell_vertices(2, c) {
///         let p = k.vertices().point(v);
///         let d = |q: &[f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
///         assert!(sites.iter().all(|q| d(s) <= d(q) + 1e-12));
///     }
/// }
/// ```
pub fn voronoi_with_sites(
    n: usize,
    x: [f64; 2],
    y: [f64; 2],
    seed: u64,
    lloyd: usize,
) -> Result<(Complex, Vec<[f64; 2]>)> {
    if n == 0 {
        return invalid("a Voronoi mesh needs at least 1 site (n ≥ 1), got 0".into());
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
    let bounds = Bounds { x, y };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sites: Vec<[f64; 2]> = (0..n)
        .map(|_| [open(&mut rng, x), open(&mut rng, y)])
        .collect();
    let mut diagram = clipped_diagram(&sites, &bounds)?;
    for _ in 0..lloyd {
        let moved: Vec<[f64; 2]> = diagram
            .cells
            .iter()
            .map(|cell| polygon_centroid(&diagram.points, cell))
            .collect();
        sites = moved;
        diagram = clipped_diagram(&sites, &bounds)?;
    }
    let vertices = Vertices::from_points(&diagram.points)?;
    let mut complex = Complex::build(vertices, TopCells::polygons(&diagram.cells))?;
    let points = diagram.points;
    let on = |vs: &[usize], axis: usize, value: f64| vs.iter().all(|&v| points[v][axis] == value);
    tag_boundary(&mut complex, &["xmin", "xmax", "ymin", "ymax"], |vs| {
        [(0, x[0]), (0, x[1]), (1, y[0]), (1, y[1])]
            .iter()
            .position(|&(axis, value)| on(vs, axis, value))
    })?;
    Ok((complex, sites))
}

/// A uniform draw from the open interval (lo, hi): a site on the boundary
/// would coincide with its own mirror image.
pub(super) fn open(rng: &mut ChaCha8Rng, [lo, hi]: [f64; 2]) -> f64 {
    loop {
        let t: f64 = rng.gen_range(lo..hi);
        if t > lo {
            return t;
        }
    }
}

struct Bounds {
    x: [f64; 2],
    y: [f64; 2],
}

impl Bounds {
    /// The mirror line of side s (0: xmin, 1: xmax, 2: ymin, 3: ymax):
    /// (axis, value).
    fn side(&self, s: usize) -> (usize, f64) {
        match s {
            0 => (0, self.x[0]),
            1 => (0, self.x[1]),
            2 => (1, self.y[0]),
            _ => (1, self.y[1]),
        }
    }
}

struct Diagram {
    points: Vec<[f64; 2]>,
    /// Counterclockwise corner indices of the cell of each site.
    cells: Vec<Vec<usize>>,
}

fn clipped_diagram(sites: &[[f64; 2]], bounds: &Bounds) -> Result<Diagram> {
    let n = sites.len();
    // Augmented set: sites, then their mirrors across side 0, 1, 2, 3.
    let mut all: Vec<Point2<f64>> = sites.iter().map(|p| Point2::new(p[0], p[1])).collect();
    for s in 0..4 {
        let (axis, value) = bounds.side(s);
        for p in sites {
            let mut q = *p;
            q[axis] = 2.0 * value - q[axis];
            all.push(Point2::new(q[0], q[1]));
        }
    }
    let triangulation = DelaunayTriangulation::<Point2<f64>>::bulk_load_stable(all.clone())
        .map_err(|e| crate::ComplexError::Invalid(format!("Delaunay triangulation of the Voronoi sites failed: {e:?}; use a rectangle of moderate size (coordinates within ±1e10)")))?;
    if triangulation.num_vertices() != all.len() {
        return invalid(format!(
            "{} Voronoi sites coincide; choose another seed",
            all.len() - triangulation.num_vertices()
        ));
    }
    // Triangles touching a site, with their circumcentres.
    let mut triangles: Vec<[usize; 3]> = Vec::new();
    let mut centres: Vec<[f64; 2]> = Vec::new();
    for face in triangulation.inner_faces() {
        let t = face.vertices().map(|v| v.fix().index());
        if t.iter().all(|&v| v >= n) {
            continue;
        }
        let mut c = circumcentre(t.map(|v| [all[v].x, all[v].y]));
        // A triangle holding a site and its own mirror across side s has its
        // circumcentre on the perpendicular bisector of the two: side s. Put
        // it there exactly, so boundary edges lie on the sides bit for bit.
        for &v in &t {
            if v >= n {
                let (s, site) = (v / n - 1, v % n);
                if t.contains(&site) {
                    let (axis, value) = bounds.side(s);
                    c[axis] = value;
                }
            }
        }
        c[0] = c[0].clamp(bounds.x[0], bounds.x[1]);
        c[1] = c[1].clamp(bounds.y[0], bounds.y[1]);
        triangles.push(t);
        centres.push(c);
    }
    // Cocircular sites give neighbouring triangles with one circumcentre:
    // always the case for a site pair and its mirror pair (an isosceles
    // trapezoid). Merge such triangles into one corner, across all cells
    // alike, so no cell gets a zero-length edge.
    let scale = (bounds.x[1] - bounds.x[0]).max(bounds.y[1] - bounds.y[0]);
    let tolerance = 1e-11 * scale;
    let mut parent: Vec<usize> = (0..triangles.len()).collect();
    let mut by_edge: HashMap<(usize, usize), usize> = HashMap::new();
    for (k, t) in triangles.iter().enumerate() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            match by_edge.insert((a.min(b), a.max(b)), k) {
                Some(other) if distance(centres[k], centres[other]) <= tolerance => {
                    let (ra, rb) = (find(&mut parent, k), find(&mut parent, other));
                    parent[ra.max(rb)] = ra.min(rb);
                }
                _ => {}
            }
        }
    }
    let mut corner_of = vec![usize::MAX; triangles.len()];
    let mut points = Vec::new();
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (k, t) in triangles.iter().enumerate() {
        let root = find(&mut parent, k);
        if corner_of[root] == usize::MAX {
            corner_of[root] = points.len();
            points.push(centres[root]);
        }
        for &v in t {
            if v < n {
                around[v].push(corner_of[root]);
            }
        }
    }
    let cells = around
        .into_iter()
        .enumerate()
        .map(|(i, mut corners)| {
            corners.sort_unstable();
            corners.dedup();
            // The cell is convex with its site strictly inside: the angle
            // about the site orders the corners counterclockwise.
            let s = sites[i];
            let angle = |c: usize| (points[c][1] - s[1]).atan2(points[c][0] - s[0]);
            corners.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)));
            corners
        })
        .collect();
    Ok(Diagram { points, cells })
}

fn find(parent: &mut [usize], mut k: usize) -> usize {
    while parent[k] != k {
        parent[k] = parent[parent[k]];
        k = parent[k];
    }
    k
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Circumcentre of a triangle, relative to its first vertex for accuracy.
fn circumcentre([a, b, c]: [[f64; 2]; 3]) -> [f64; 2] {
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    [
        a[0] + (cy * b2 - by * c2) / d,
        a[1] + (bx * c2 - cx * b2) / d,
    ]
}

/// Area centroid of a simple polygon (shoelace), relative to its first
/// corner for accuracy.
fn polygon_centroid(points: &[[f64; 2]], cell: &[usize]) -> [f64; 2] {
    let o = points[cell[0]];
    let (mut area, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for k in 0..cell.len() {
        let p = points[cell[k]];
        let q = points[cell[(k + 1) % cell.len()]];
        let (px, py, qx, qy) = (p[0] - o[0], p[1] - o[1], q[0] - o[0], q[1] - o[1]);
        let cross = px * qy - qx * py;
        area += cross;
        cx += (px + qx) * cross;
        cy += (py + qy) * cross;
    }
    [o[0] + cx / (3.0 * area), o[1] + cy / (3.0 * area)]
}
