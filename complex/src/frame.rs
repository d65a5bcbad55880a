//! Oriented affine frames of cells, and the sign with which a facet
//! appears in the boundary of a cell.
//!
//! The orientation of a p-cell is that of the frame built greedily from its
//! sorted vertex list: v_k − v_0 for the first p vertices that add a new
//! direction. For a simplex this is exactly the orientation of its sorted
//! vertex order. A facet f of a convex cell c carries the induced
//! orientation when (outward direction, frame of f) is positively oriented
//! in the frame of c; the outward direction is taken from the vertex average
//! of c (interior for convex cells) to that of f.

use crate::cells::Vertices;
use nalgebra::Vector3;
use rayon::prelude::*;

/// Points are padded to three coordinates so all dimensions share one code path.
pub(crate) type Point = [f64; 3];

/// Relative size below which a direction is considered already spanned.
const SPAN_TOLERANCE: f64 = 1e-10;

pub(crate) fn point(vertices: &Vertices, i: usize) -> Point {
    let mut x = [0.0; 3];
    for (slot, &c) in x.iter_mut().zip(vertices.point(i)) {
        *slot = c;
    }
    x
}

/// On a flat torus, move every point of a cell to its image nearest the
/// first one, so that the cell is measured with unwrapped coordinates.
pub(crate) fn unwrap_cell(vertices: &Vertices, points: &mut [Point]) {
    if vertices.period().is_none() {
        return;
    }
    if let Some((first, rest)) = points.split_first_mut() {
        for x in rest {
            *x = vertices.nearest(x, first);
        }
    }
}

/// An orthonormal basis of the span of a p-cell, oriented like the cell,
/// and the average of its vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    pub dim: usize,
    pub basis: [Point; 3],
    pub centre: Point,
    /// Largest distance from the first vertex (the cell's length scale).
    pub diameter: f64,
}

impl Frame {
    /// Coordinates of `v` in the basis (first `dim` entries used).
    pub fn local(&self, v: &Point) -> Point {
        let v = Vector3::from(*v);
        let mut out = [0.0; 3];
        for (k, b) in self.basis.iter().take(self.dim).enumerate() {
            out[k] = Vector3::from(*b).dot(&v);
        }
        out
    }
}

/// The frames of many p-cells packed flat: per cell its p basis vectors,
/// its centre and its diameter (3p + 4 numbers, a third less than
/// `Option<Frame>` for p = 2, 3). A cell without a frame (degenerate) has a
/// NaN diameter, which a real frame never has.
pub(crate) struct PackedFrames {
    dim: usize,
    data: Vec<f64>,
}

impl PackedFrames {
    /// `frame_of(j)` for j in 0..count, computed in parallel.
    pub fn new(dim: usize, count: usize, frame_of: impl Fn(usize) -> Option<Frame> + Sync) -> Self {
        let stride = 3 * dim + 4;
        let mut data = vec![0.0; count * stride];
        data.par_chunks_mut(stride)
            .with_min_len(1024)
            .enumerate()
            .for_each(|(j, slot)| match frame_of(j) {
                Some(f) => {
                    for (r, b) in f.basis.iter().take(dim).enumerate() {
                        slot[3 * r..3 * r + 3].copy_from_slice(b);
                    }
                    slot[3 * dim..3 * dim + 3].copy_from_slice(&f.centre);
                    slot[3 * dim + 3] = f.diameter;
                }
                None => slot[3 * dim + 3] = f64::NAN,
            });
        Self { dim, data }
    }

    /// The frame of cell `j`, as `frame_of(j)` returned it.
    #[inline]
    pub fn get(&self, j: usize) -> Option<Frame> {
        let dim = self.dim;
        let slot = &self.data[j * (3 * dim + 4)..(j + 1) * (3 * dim + 4)];
        let diameter = slot[3 * dim + 3];
        if diameter.is_nan() {
            return None;
        }
        let mut basis = [[0.0; 3]; 3];
        for (r, b) in basis.iter_mut().take(dim).enumerate() {
            b.copy_from_slice(&slot[3 * r..3 * r + 3]);
        }
        let mut centre = [0.0; 3];
        centre.copy_from_slice(&slot[3 * dim..3 * dim + 3]);
        Some(Frame {
            dim,
            basis,
            centre,
            diameter,
        })
    }
}

/// The frame of a cell with the given sorted vertices, or `None` when the
/// vertices span fewer than `p` directions (a zero-measure cell).
pub(crate) fn frame(vertices: &Vertices, cell: &[usize], p: usize) -> Option<Frame> {
    // Cells have few vertices; gather their points once (on the stack when
    // they fit) instead of re-reading them in every pass.
    let mut stack = [[0.0; 3]; 8];
    let heap: Vec<Point>;
    let points: &[Point] = if cell.len() <= stack.len() {
        for (slot, &v) in stack.iter_mut().zip(cell) {
            *slot = point(vertices, v);
        }
        unwrap_cell(vertices, &mut stack[..cell.len()]);
        &stack[..cell.len()]
    } else {
        let mut points: Vec<Point> = cell.iter().map(|&v| point(vertices, v)).collect();
        unwrap_cell(vertices, &mut points);
        heap = points;
        &heap
    };
    let origin = Vector3::from(points[0]);
    let mut centre = Vector3::zeros();
    // sqrt is correctly rounded and monotone, so the largest root is the
    // root of the largest square: one sqrt per cell instead of one per vertex.
    let mut diameter_squared: f64 = 0.0;
    for x in points {
        let x = Vector3::from(*x);
        centre += x;
        diameter_squared = diameter_squared.max((x - origin).norm_squared());
    }
    let diameter = diameter_squared.sqrt();
    centre /= points.len() as f64;
    let mut basis = [Vector3::zeros(); 3];
    let mut found = 0;
    if p > 0 {
        for x in &points[1..] {
            let mut w = Vector3::from(*x) - origin;
            // Two Gram–Schmidt passes keep the basis orthonormal to rounding.
            for _ in 0..2 {
                for b in basis.iter().take(found) {
                    let c = w.dot(b);
                    w -= b * c;
                }
            }
            let len = w.norm();
            if len > SPAN_TOLERANCE * diameter {
                basis[found] = w / len;
                found += 1;
                if found == p {
                    break;
                }
            }
        }
    }
    (found == p).then_some(Frame {
        dim: p,
        basis: basis.map(Into::into),
        centre: centre.into(),
        diameter,
    })
}

/// Determinant of the leading `n`×`n` block (n ≤ 3).
pub(crate) fn det(n: usize, m: &[Point; 3]) -> f64 {
    match n {
        0 => 1.0,
        1 => m[0][0],
        2 => m[0][0] * m[1][1] - m[0][1] * m[1][0],
        _ => {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        }
    }
}

/// +1 when `facet` carries the orientation induced by `cell`, −1 when the
/// opposite, `None` when the facet does not separate the cell's interior
/// from outside (degenerate or non-convex geometry).
pub(crate) fn induced_sign(cell: &Frame, facet: &Frame, diameter: f64) -> Option<i8> {
    let outward = (Vector3::from(facet.centre) - Vector3::from(cell.centre)).into();
    let mut m = [[0.0; 3]; 3];
    m[0] = cell.local(&outward);
    for r in 0..facet.dim {
        m[r + 1] = cell.local(&facet.basis[r]);
    }
    let d = det(cell.dim, &m);
    if d.abs() <= SPAN_TOLERANCE * diameter.max(f64::MIN_POSITIVE) {
        return None;
    }
    Some(if d > 0.0 { 1 } else { -1 })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_triangle() -> Vertices {
        Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap()
    }

    #[test]
    fn triangle_boundary_signs_are_alternating() {
        // ∂[v0,v1,v2] = [v1,v2] − [v0,v2] + [v0,v1].
        let v = unit_triangle();
        let tri = frame(&v, &[0, 1, 2], 2).unwrap();
        let sign = |e: [usize; 2]| induced_sign(&tri, &frame(&v, &e, 1).unwrap(), 1.0).unwrap();
        assert_eq!(sign([1, 2]), 1);
        assert_eq!(sign([0, 2]), -1);
        assert_eq!(sign([0, 1]), 1);
    }

    #[test]
    fn edge_boundary_is_head_minus_tail() {
        let v = unit_triangle();
        let edge = frame(&v, &[0, 1], 1).unwrap();
        let at = |i| induced_sign(&edge, &frame(&v, &[i], 0).unwrap(), 1.0).unwrap();
        assert_eq!((at(0), at(1)), (-1, 1));
    }

    #[test]
    fn collinear_points_have_no_2_frame() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).unwrap();
        assert!(frame(&v, &[0, 1, 2], 2).is_none());
        assert!(frame(&v, &[0, 1, 2], 1).is_some());
    }
}
