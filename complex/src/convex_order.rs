//! Cells given as unordered vertex sets (as in LAR files) turned into the
//! ordered descriptions [`TopCells`] needs: a convex polygon as its cycle,
//! a convex polyhedron as its cyclic faces (the supporting planes of its
//! vertex set, the paper's "qhull on each cell" done by brute force, which
//! is cheap for the handful of vertices a cell has).
//!
//! Only convex cells can be ordered from their vertices alone: a vertex
//! strictly inside the convex hull of the others is refused, because the
//! cell it belongs to cannot be recovered without its edges.

use crate::cells::{TopCells, Vertices};
use crate::frame::{point, Point};
use nalgebra::Vector3;

/// Relative tolerance (times the cell's diameter) for coplanarity and turns.
const TOLERANCE: f64 = 1e-9;

/// Why a vertex set could not be ordered as a convex cell.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum OrderError {
    /// The vertices span fewer dimensions than the cell has.
    Degenerate,
    /// The vertices of a 2-cell in R³ do not lie in one plane.
    NotPlanar { vertex: usize },
    /// The vertex lies inside the convex hull of the others.
    NotConvex { vertex: usize },
}

fn sub(a: &Point, b: &Point) -> Vector3<f64> {
    Vector3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2])
}

fn diameter(points: &[Point]) -> f64 {
    let mut largest: f64 = 0.0;
    for a in points {
        for b in points {
            largest = largest.max(sub(a, b).norm());
        }
    }
    largest
}

/// The cyclic order of a convex polygon's vertices (in R² or on a plane in
/// R³): sorted by angle around their average, then every turn checked.
pub(crate) fn polygon_cycle(vertices: &Vertices, cell: &[usize]) -> Result<Vec<usize>, OrderError> {
    let points: Vec<Point> = cell.iter().map(|&v| point(vertices, v)).collect();
    let scale = diameter(&points);
    let tol = TOLERANCE * scale;
    if points.len() < 3 || scale == 0.0 {
        return Err(OrderError::Degenerate);
    }
    // An orthonormal basis (u, w) of the polygon's plane from its first
    // vertex and the two directions that span the most.
    let origin = points[0];
    let u = points
        .iter()
        .map(|p| sub(p, &origin))
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .ok_or(OrderError::Degenerate)?
        .normalize();
    let w_raw = points
        .iter()
        .map(|p| {
            let r = sub(p, &origin);
            r - u * u.dot(&r)
        })
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .ok_or(OrderError::Degenerate)?;
    if w_raw.norm() <= tol {
        return Err(OrderError::Degenerate);
    }
    let w = w_raw.normalize();
    let normal = u.cross(&w);
    if let Some(k) = points
        .iter()
        .position(|p| normal.dot(&sub(p, &origin)).abs() > tol)
    {
        return Err(OrderError::NotPlanar { vertex: cell[k] });
    }
    let local: Vec<(f64, f64)> = points
        .iter()
        .map(|p| {
            let r = sub(p, &origin);
            (u.dot(&r), w.dot(&r))
        })
        .collect();
    let count = local.len() as f64;
    let centre = (
        local.iter().map(|p| p.0).sum::<f64>() / count,
        local.iter().map(|p| p.1).sum::<f64>() / count,
    );
    let mut order: Vec<usize> = (0..cell.len()).collect();
    let angle = |k: usize| (local[k].1 - centre.1).atan2(local[k].0 - centre.0);
    order.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)));
    // Every turn must be left (or straight, for a vertex on a side): a
    // right turn marks a vertex inside the hull of the others.
    for k in 0..order.len() {
        let (a, b, c) = (
            local[order[k]],
            local[order[(k + 1) % order.len()]],
            local[order[(k + 2) % order.len()]],
        );
        let turn = (b.0 - a.0) * (c.1 - b.1) - (b.1 - a.1) * (c.0 - b.0);
        if turn < -tol * scale {
            return Err(OrderError::NotConvex {
                vertex: cell[order[(k + 1) % order.len()]],
            });
        }
    }
    Ok(order.into_iter().map(|k| cell[k]).collect())
}

/// The faces of a convex polyhedron, each in cyclic order: the planes
/// through three of its vertices with every other vertex on one side.
pub(crate) fn polyhedron_faces(
    vertices: &Vertices,
    cell: &[usize],
) -> Result<Vec<Vec<usize>>, OrderError> {
    let points: Vec<Point> = cell.iter().map(|&v| point(vertices, v)).collect();
    let scale = diameter(&points);
    let tol = TOLERANCE * scale;
    let mut faces: Vec<Vec<usize>> = Vec::new();
    let n = points.len();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let normal = sub(&points[j], &points[i]).cross(&sub(&points[k], &points[i]));
                let length = normal.norm();
                if length <= tol * scale {
                    continue;
                }
                let normal = normal / length;
                let distance: Vec<f64> = points
                    .iter()
                    .map(|p| normal.dot(&sub(p, &points[i])))
                    .collect();
                let above = distance.iter().any(|&d| d > tol);
                let below = distance.iter().any(|&d| d < -tol);
                if above && below {
                    continue;
                }
                let face: Vec<usize> = (0..n).filter(|&m| distance[m].abs() <= tol).collect();
                if !faces.contains(&face) {
                    faces.push(face);
                }
            }
        }
    }
    if faces.len() < 4 {
        return Err(OrderError::Degenerate);
    }
    if let Some(m) = (0..n).find(|m| !faces.iter().any(|f| f.contains(m))) {
        return Err(OrderError::NotConvex { vertex: cell[m] });
    }
    faces
        .iter()
        .map(|face| {
            let ids: Vec<usize> = face.iter().map(|&m| cell[m]).collect();
            polygon_cycle(vertices, &ids)
        })
        .collect()
}

/// The cycle through all of `cell`'s vertices made by the given edges that
/// join two of them, if they make exactly one.
fn edge_cycle(cell: &[usize], edges: &[Vec<usize>]) -> Option<Vec<usize>> {
    let mut around: std::collections::HashMap<usize, Vec<usize>> =
        cell.iter().map(|&v| (v, Vec::new())).collect();
    for e in edges {
        if let [a, b] = e[..] {
            if around.contains_key(&a) && around.contains_key(&b) {
                around.get_mut(&a)?.push(b);
                around.get_mut(&b)?.push(a);
            }
        }
    }
    if around.values().any(|n| n.len() != 2) {
        return None;
    }
    let mut order = vec![cell[0]];
    let mut previous = cell[0];
    let mut at = around[&cell[0]][0];
    while at != cell[0] {
        order.push(at);
        let next = around[&at].iter().copied().find(|&n| n != previous)?;
        (previous, at) = (at, next);
        if order.len() > cell.len() {
            return None;
        }
    }
    (order.len() == cell.len()).then_some(order)
}

/// The cells of one dimension `p` (1, 2 or 3), each an unordered vertex
/// set, as [`TopCells`]: simplices when they have p + 1 vertices, convex
/// polygons and polyhedra otherwise. A 2-cell that is not convex is
/// ordered by the cycle of the given `edges` through its vertices, when
/// they make one (the complex then orients it by that cycle). The error
/// names the cell.
pub(crate) fn top_cells(
    vertices: &Vertices,
    p: usize,
    cells: &[Vec<usize>],
    edges: Option<&[Vec<usize>]>,
) -> Result<TopCells, (usize, OrderError)> {
    let mut out = TopCells::default();
    for (i, cell) in cells.iter().enumerate() {
        if cell.len() == p + 1 {
            out.push_simplex(cell);
        } else if p == 2 {
            let cycle = match polygon_cycle(vertices, cell) {
                Err(OrderError::NotConvex { vertex }) => edges
                    .and_then(|edges| edge_cycle(cell, edges))
                    .ok_or((i, OrderError::NotConvex { vertex }))?,
                other => other.map_err(|e| (i, e))?,
            };
            out.push_polygon(&cycle);
        } else {
            out.push_polyhedron(&polyhedron_faces(vertices, cell).map_err(|e| (i, e))?);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shuffled_square_is_ordered_cyclically() -> Result<(), Box<dyn std::error::Error>> {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])?;
        let cycle = polygon_cycle(&v, &[0, 1, 2, 3]).map_err(|e| format!("{e:?}"))?;
        // Neighbours in the cycle are sides of the square, never diagonals.
        for k in 0..4 {
            let (a, b) = (cycle[k], cycle[(k + 1) % 4]);
            assert!(
                ![(0, 1), (1, 0), (2, 3), (3, 2)].contains(&(a, b)),
                "{cycle:?}"
            );
        }
        Ok(())
    }

    #[test]
    fn a_vertex_inside_the_hull_is_refused() -> Result<(), Box<dyn std::error::Error>> {
        let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 0.5]])?;
        assert_eq!(
            polygon_cycle(&v, &[0, 1, 2, 3]),
            Err(OrderError::NotConvex { vertex: 3 })
        );
        Ok(())
    }

    #[test]
    fn a_cube_has_six_square_faces() -> Result<(), Box<dyn std::error::Error>> {
        let points: Vec<[f64; 3]> = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let v = Vertices::from_points(&points)?;
        let faces =
            polyhedron_faces(&v, &[0, 1, 2, 3, 4, 5, 6, 7]).map_err(|e| format!("{e:?}"))?;
        assert_eq!(faces.len(), 6);
        assert!(faces.iter().all(|f| f.len() == 4));
        Ok(())
    }
}
