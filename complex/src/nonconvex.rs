//! Simple non-convex polygons as 2-cells (the LAR paper's Fig. 2d: two
//! non-convex hexagons forming an annulus).
//!
//! The orientation of a facet of a convex cell is read from geometry: the
//! direction from the cell's vertex average to the facet's points outward.
//! In a non-convex polygon that direction points inward for the edges
//! behind a reflex corner, and the signs so found do not close up
//! (∂₁∂₂ ≠ 0). Those polygons are oriented here by their boundary cycle
//! instead: the edges of the cell (from the filtered LAR product) must
//! form one simple closed cycle; walking it, an edge traversed from its
//! lower to its higher vertex takes the sign of the cycle's signed area in
//! the cell's frame, an edge traversed the other way the opposite sign.
//! Convex cells keep their geometric signs (and so do meshes without
//! non-convex cells, bit for bit). A cycle that crosses itself is refused
//! as a twisted or self-intersecting cell, as before.

use crate::complex::Complex;
use crate::error::{ComplexError, Result};
use crate::frame::{self, Frame};
use crate::lar::Lar;
use nalgebra::Vector3;
use sprs::CsMat;

fn twisted(lar: &Lar, cell: usize, why: &str) -> ComplexError {
    ComplexError::Invalid(format!(
        "2-cell {cell} (vertices {:?}) is twisted or self-intersecting: {why}; check the order of its vertices",
        lar.cell_vertices(2, cell)
    ))
}

/// The boundary cycle of 2-cell `cell` from its edges: (edge, traversed
/// from its lower to its higher vertex) in walking order.
fn cycle(lar: &Lar, cell: usize, edges: &[usize]) -> Result<Vec<(usize, bool)>> {
    let vertices = lar.cell_vertices(2, cell);
    let mut around: Vec<Vec<usize>> = vec![Vec::new(); vertices.len()];
    let local = |v: usize| vertices.binary_search(&v).ok();
    for &e in edges {
        for &v in lar.cell_vertices(1, e) {
            let k = local(v).ok_or_else(|| twisted(lar, cell, "an edge leaves the cell"))?;
            around[k].push(e);
        }
    }
    if let Some(k) = around.iter().position(|a| a.len() != 2) {
        return Err(twisted(
            lar,
            cell,
            &format!(
                "its vertex {} ends {} of its edges, not 2 (its edges are not one cycle; an edge of a neighbour may run through it)",
                vertices[k],
                around[k].len()
            ),
        ));
    }
    let mut walk = Vec::with_capacity(edges.len());
    let (mut at, mut edge) = (vertices[0], around[0][0]);
    loop {
        let ends = lar.cell_vertices(1, edge);
        let forward = ends[0] == at;
        walk.push((edge, forward));
        at = if forward { ends[1] } else { ends[0] };
        let k = local(at).ok_or_else(|| twisted(lar, cell, "an edge leaves the cell"))?;
        edge = if around[k][0] == edge {
            around[k][1]
        } else {
            around[k][0]
        };
        if at == vertices[0] {
            break;
        }
    }
    if walk.len() != edges.len() {
        return Err(twisted(lar, cell, "its edges form more than one cycle"));
    }
    Ok(walk)
}

/// Local 2D coordinates of the walk's vertices in the cell's frame.
fn outline(lar: &Lar, frame: &Frame, walk: &[(usize, bool)]) -> Vec<(f64, f64)> {
    walk.iter()
        .map(|&(e, forward)| {
            let ends = lar.cell_vertices(1, e);
            let start = if forward { ends[0] } else { ends[1] };
            let p = frame::point(lar.vertices(), start);
            let r = (Vector3::from(p) - Vector3::from(frame.centre)).into();
            let x = frame.local(&r);
            (x[0], x[1])
        })
        .collect()
}

/// Signed volume enclosed by a closed oriented surface component:
/// (1/6) Σ_cells Σ_{oriented boundary edges a→b} det[x_c, x_a, x_b].
pub(crate) fn enclosed_volume(
    lar: &Lar,
    by_cell: &CsMat<i8>,
    flags: &[i8],
    component: &[usize],
) -> f64 {
    let vertices = lar.vertices();
    let mut volume = 0.0;
    for &c in component {
        let centre =
            frame::frame(vertices, lar.cell_vertices(2, c), 0).map_or([0.0; 3], |f| f.centre);
        let Some(col) = by_cell.outer_view(c) else {
            continue;
        };
        for (edge, &s) in col.iter() {
            let ends = lar.cell_vertices(1, edge);
            let (a, b) = (
                frame::point(vertices, ends[0]),
                frame::point(vertices, ends[1]),
            );
            let m = [centre, a, b];
            volume += f64::from(flags[c] * s) * frame::det(3, &m) / 6.0;
        }
    }
    volume
}

fn cross(o: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
}

/// Whether two non-adjacent sides of a closed outline cross or touch;
/// `scale` is the outline's size.
fn self_intersecting(points: &[(f64, f64)], scale: f64) -> bool {
    let tolerance = 1e-12 * scale * scale;
    let slack = 1e-12 * scale;
    let within = |a: (f64, f64), b: (f64, f64), p: (f64, f64)| {
        p.0 >= a.0.min(b.0) - slack
            && p.0 <= a.0.max(b.0) + slack
            && p.1 >= a.1.min(b.1) - slack
            && p.1 <= a.1.max(b.1) + slack
    };
    let opposite =
        |x: f64, y: f64| (x > tolerance && y < -tolerance) || (x < -tolerance && y > tolerance);
    let n = points.len();
    let side = |k: usize| (points[k], points[(k + 1) % n]);
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let ((a, b), (c, d)) = (side(i), side(j));
            let (d1, d2) = (cross(a, b, c), cross(a, b, d));
            let (d3, d4) = (cross(c, d, a), cross(c, d, b));
            let crossing = opposite(d1, d2) && opposite(d3, d4);
            // A vertex of one side on the other (collinear sides that
            // overlap, or a touching corner).
            let touching = (d1.abs() <= tolerance && within(a, b, c))
                || (d2.abs() <= tolerance && within(a, b, d))
                || (d3.abs() <= tolerance && within(c, d, a))
                || (d4.abs() <= tolerance && within(c, d, b));
            if crossing || touching {
                return true;
            }
        }
    }
    false
}

/// Orient every 2-cell of ∂₂ whose geometric signs failed (a zero entry)
/// or do not close up, by its boundary cycle. `boundaries` are ∂₁ … ∂_n
/// before the top cells are oriented.
pub(crate) fn orient_by_cycles(lar: &Lar, boundaries: &mut [CsMat<i8>]) -> Result<()> {
    if boundaries.len() < 2 {
        return Ok(());
    }
    let d2 = boundaries[1].to_csc();
    let mut repairs: Vec<(usize, Vec<(usize, i8)>)> = Vec::new();
    let mut sums: Vec<i32> = vec![0; lar.cell_count(0)];
    for (cell, column) in d2.outer_iterator().enumerate() {
        if lar.cell_vertices(2, cell).len() == 3 {
            continue;
        }
        let mut open = column.data().contains(&0);
        if !open {
            for (e, &s) in column.iter() {
                let ends = lar.cell_vertices(1, e);
                sums[ends[0]] -= i32::from(s);
                sums[ends[1]] += i32::from(s);
            }
            open = lar.cell_vertices(2, cell).iter().any(|&v| sums[v] != 0);
            for &v in lar.cell_vertices(2, cell) {
                sums[v] = 0;
            }
        }
        if open {
            repairs.push((cell, cycle_signs(lar, cell, column.indices())?));
        }
    }
    for (cell, signs) in repairs {
        for (edge, sign) in signs {
            if let Some(entry) = boundaries[1].get_mut(edge, cell) {
                *entry = sign;
            }
        }
    }
    Ok(())
}

/// The signs of the edges of 2-cell `cell` in the orientation of its frame.
fn cycle_signs(lar: &Lar, cell: usize, edges: &[usize]) -> Result<Vec<(usize, i8)>> {
    let walk = cycle(lar, cell, edges)?;
    let frame = frame::frame(lar.vertices(), lar.cell_vertices(2, cell), 2).ok_or_else(|| {
        ComplexError::DegenerateCell {
            dim: 2,
            cell,
            vertices: lar.cell_vertices(2, cell).to_vec(),
        }
    })?;
    let points = outline(lar, &frame, &walk);
    let scale = frame.diameter.max(f64::MIN_POSITIVE);
    if self_intersecting(&points, scale) {
        return Err(twisted(lar, cell, "its boundary crosses itself"));
    }
    let n = points.len();
    let area: f64 = (0..n)
        .map(|k| cross((0.0, 0.0), points[k], points[(k + 1) % n]))
        .sum::<f64>()
        / 2.0;
    if area.abs() <= 1e-12 * scale * scale {
        return Err(ComplexError::DegenerateCell {
            dim: 2,
            cell,
            vertices: lar.cell_vertices(2, cell).to_vec(),
        });
    }
    let orientation: i8 = if area > 0.0 { 1 } else { -1 };
    Ok(walk
        .into_iter()
        .map(|(e, forward)| (e, if forward { orientation } else { -orientation }))
        .collect())
}

impl Complex {
    /// The 2-cells that are not convex: some vertex lies to the right of
    /// an edge of the cell's oriented boundary (in the plane of its vector
    /// area). Simple non-convex polygons are valid 2-cells; methods whose
    /// formulas need convex cells refuse these by id. Empty for
    /// complexes of dimension below 2. In parallel, with no allocation per
    /// cell: every method that needs convex cells asks.
    ///
    /// ```
    /// use hasse_complex::{Complex, TopCells, Vertices};
    /// // An L-shaped hexagon, given by its boundary cycle, and a square.
    /// let v = Vertices::from_points(&[
    ///     [0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0],
    ///     [3.0, 0.0], [3.0, 1.0],
    /// ]).unwrap();
    /// let k = Complex::build(v, TopCells::polygons([vec![0, 1, 2, 3, 4, 5], vec![1, 6, 7, 2]])).unwrap();
    /// assert_eq!(k.non_convex_cells(), vec![0]);
    /// ```
    pub fn non_convex_cells(&self) -> Vec<usize> {
        use rayon::prelude::*;
        if self.dim() < 2 {
            return Vec::new();
        }
        let lar = self.lar();
        let d2 = self.boundary_csc(2);
        let point = |v: usize| Vector3::from(frame::point(lar.vertices(), v));
        (0..self.cell_count(2))
            .into_par_iter()
            .with_min_len(1024)
            .filter(|&cell| {
                let vertices = lar.cell_vertices(2, cell);
                let Some(column) = d2.outer_view(cell) else {
                    return false;
                };
                if vertices.len() <= 3 {
                    return false;
                }
                let origin = point(vertices[0]);
                let oriented = |(e, &r): (usize, &i8)| {
                    let ends = lar.cell_vertices(1, e);
                    let (a, b) = (point(ends[0]) - origin, point(ends[1]) - origin);
                    if r > 0 {
                        (a, b)
                    } else {
                        (b, a)
                    }
                };
                let area: Vector3<f64> = column
                    .iter()
                    .map(|entry| {
                        let (a, b) = oriented(entry);
                        a.cross(&b) * 0.5
                    })
                    .sum();
                let scale = area.norm();
                column.iter().any(|entry| {
                    let (a, b) = oriented(entry);
                    vertices.iter().any(|&v| {
                        (b - a).cross(&(point(v) - origin - a)).dot(&area) < -1e-10 * scale * scale
                    })
                })
            })
            .collect()
    }
}
