//! P1 elements on simplices: barycentric gradients and the diagonal
//! (cotangent) edge weights.

use super::*;

/// Measure of a simplex and the gradients of its barycentric coordinates,
/// tangent to the simplex (so embedded simplices work); `None` when the
/// simplex is degenerate.
pub(crate) fn simplex_gradients(x: &[Point], d: usize) -> Option<(f64, Vec<Point>)> {
    let n = x.len().checked_sub(1)?;
    if n == 0 {
        return None;
    }
    let factorial: f64 = (1..=n).map(|k| k as f64).product();
    let edges = DMatrix::from_fn(d, n, |i, j| x[j + 1][i] - x[0][i]);
    // Rows: ∇λ_1 … ∇λ_n, the pseudo-inverse of the edge matrix. A
    // full-dimensional simplex inverts it directly; an embedded one goes
    // through E = QR (E⁺ = R⁻¹Qᵀ), whose conditioning is that of E and not
    // of the Gram matrix EᵀE.
    let (measure, rows) = if n == d {
        let det = edges.determinant();
        (det.abs() / factorial, edges.try_inverse()?)
    } else {
        let qr = edges.qr();
        let r = qr.r();
        let det = r.determinant();
        (det.abs() / factorial, r.try_inverse()? * qr.q().transpose())
    };
    if measure.is_nan() || measure <= 0.0 {
        return None;
    }
    let mut gradients = vec![[0.0; 3]; n + 1];
    for k in 0..n {
        for i in 0..d {
            gradients[k + 1][i] = rows[(k, i)];
            gradients[0][i] -= rows[(k, i)];
        }
    }
    Some((measure, gradients))
}

/// gᵀ K h over the leading d coordinates.
pub(crate) fn k_dot(g: &Point, k: &Tensor, h: &Point, d: usize) -> f64 {
    (0..d)
        .map(|i| g[i] * (0..d).map(|j| k[i][j] * h[j]).sum::<f64>())
        .sum()
}

pub(super) fn p1_weights(top: &Topology, c: usize, k: &Tensor) -> Result<Local, MetricError> {
    let vertices = top.complex.cell_vertices(top.n, c);
    let (measure, gradients) =
        simplex_gradients(&top.points(c), top.d).ok_or(MetricError::UnsupportedCell {
            method: "P1",
            needs: "a simplex of positive measure",
            cell: c,
        })?;
    top.edges_of(c)
        .into_iter()
        .map(|e| {
            let (a, b) = top.local_ends(e, vertices, c)?;
            Ok((e, -measure * k_dot(&gradients[a], k, &gradients[b], top.d)))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Local::Diagonal)
}
