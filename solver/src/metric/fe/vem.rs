//! Lowest-order virtual elements on polygons and polyhedra: moments of
//! the cell and the projected stiffness.

use super::*;
use nalgebra::Vector3;

/// ∫_∂c φ_i n for every vertex of a polygon (exact: φ_i is linear on each
/// edge) and the polygon's area, both from the outward edge normals.
pub(super) fn polygon_moments(
    top: &Topology,
    c: usize,
    x: &[Vector3<f64>],
    centre: &Vector3<f64>,
) -> Result<(Vec<Vector3<f64>>, f64), MetricError> {
    let vertices = top.complex.cell_vertices(2, c);
    let mut moments = vec![Vector3::zeros(); x.len()];
    let mut area = 0.0;
    // Outward normals from the cell's oriented boundary (∂₂'s signs and
    // the sense of the walk), not from the vertex average, which lies
    // behind some edges of a non-convex polygon.
    let (edges, signs) = top.facets_of(2, c);
    let mut walk = 0.0;
    for (&e, &r) in edges.iter().zip(signs) {
        let (a, b) = top.local_ends(e, vertices, c)?;
        let (p, q) = (x[a] - centre, x[b] - centre);
        walk += f64::from(r) * (p[0] * q[1] - p[1] * q[0]);
    }
    let sense = if walk < 0.0 { -1.0 } else { 1.0 };
    for (&e, &r) in edges.iter().zip(signs) {
        let (a, b) = top.local_ends(e, vertices, c)?;
        let t = x[b] - x[a];
        let mid = Vector3::new(0.5 * (x[a][0] + x[b][0]), 0.5 * (x[a][1] + x[b][1]), 0.0);
        let normal = Vector3::new(t[1], -t[0], 0.0) * (f64::from(r) * sense);
        for i in [a, b] {
            moments[i] += normal * 0.5;
        }
        area += 0.5 * (mid - centre).dot(&normal);
    }
    Ok((moments, area))
}

/// ∫_∂c φ_i n for every vertex of a polyhedron and its volume, over the
/// faces split into fans of triangles about their vertex averages, with the
/// vertex rule on each triangle (exact for functions linear on it).
pub(super) fn polyhedron_moments(
    top: &Topology,
    c: usize,
    x: &[Vector3<f64>],
    centre: &Vector3<f64>,
) -> Result<(Vec<Vector3<f64>>, f64), MetricError> {
    let vertices = top.complex.cell_vertices(3, c);
    let mut moments = vec![Vector3::zeros(); x.len()];
    let mut volume = 0.0;
    for &f in top.facets_of(3, c).0 {
        let face: Vec<usize> = top
            .complex
            .cell_vertices(2, f)
            .iter()
            .map(|v| {
                vertices
                    .binary_search(v)
                    .map_err(|_| MetricError::UnsupportedMesh {
                        method: "VEM",
                        needs: "cells whose faces use their own vertices",
                        detail: format!("face {f} of top cell {c} has a vertex outside the cell"),
                    })
            })
            .collect::<Result<_, _>>()?;
        let apex = face.iter().map(|&i| x[i]).sum::<Vector3<f64>>() / face.len() as f64;
        // Fan triangles (apex, tail, head), all turning the face's way.
        let (edges, signs) = top.facets_of(2, f);
        let mut fan = Vec::with_capacity(edges.len());
        let mut total = Vector3::zeros();
        for (&e, &s) in edges.iter().zip(signs) {
            let (a, b) = top.local_ends(e, vertices, c)?;
            let (t, h) = if s > 0 { (a, b) } else { (b, a) };
            let area = (x[t] - apex).cross(&(x[h] - apex)) * 0.5;
            total += area;
            fan.push((t, h, area));
        }
        let outward = match total.dot(&(apex - centre)) {
            s if s > 0.0 => 1.0,
            s if s < 0.0 => -1.0,
            _ => {
                return Err(MetricError::UnsupportedCell {
                    method: "VEM",
                    needs: "a convex polyhedron (a face is edge-on to the cell centre)",
                    cell: c,
                })
            }
        };
        let share = 1.0 / (3 * face.len()) as f64;
        for (t, h, area) in fan {
            let area = area * outward;
            moments[t] += area / 3.0;
            moments[h] += area / 3.0;
            for &j in &face {
                moments[j] += area * share;
            }
            let centroid = [apex, x[t], x[h]].iter().sum::<Vector3<f64>>() / 3.0;
            volume += (centroid - centre).dot(&area) / 3.0;
        }
    }
    Ok((moments, volume))
}

pub(super) fn vem_stiffness(
    top: &Topology,
    c: usize,
    k: &Tensor,
) -> Result<DMatrix<f64>, MetricError> {
    let n = top.n;
    let x: Vec<Vector3<f64>> = top.points(c).into_iter().map(Vector3::from).collect();
    let m = x.len();
    let centre = x.iter().sum::<Vector3<f64>>() / m as f64;
    let (moments, measure) = if n == 2 {
        polygon_moments(top, c, &x, &centre)?
    } else {
        polyhedron_moments(top, c, &x, &centre)?
    };
    if measure.is_nan() || measure <= 0.0 {
        return Err(MetricError::UnsupportedCell {
            method: "VEM",
            needs: "a convex cell of positive measure",
            cell: c,
        });
    }
    // Π̃ (n × m): gradient of the projection, column i = ∫_∂c φ_i n / |c|.
    let pit = DMatrix::from_fn(n, m, |a, i| moments[i][a] / measure);
    let kn = DMatrix::from_fn(n, n, |a, b| k[a][b]);
    let consistency = pit.transpose() * &kn * &pit * measure;
    let offsets = DMatrix::from_fn(m, n, |i, a| x[i][a] - centre[a]);
    let projection = DMatrix::from_element(m, m, 1.0 / m as f64) + &offsets * &pit;
    let residual = DMatrix::identity(m, m) - projection;
    let diameter = x
        .iter()
        .flat_map(|a| x.iter().map(move |b| (a - b).norm_squared()))
        .fold(0.0f64, f64::max)
        .sqrt();
    let alpha = kn.trace() / n as f64 * diameter.powi(n as i32 - 2);
    Ok(consistency + residual.transpose() * residual * alpha)
}
