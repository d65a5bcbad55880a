//! The normal gradient of a cell field as a face cochain, g = Ω δ f (the
//! thesis's chapter 6 example on the torus).
//!
//! For a field f on the top cells, δ f = −∂ₙᵀ f restricted to the interior
//! faces is the jump of f across each face along its normal: for a face F
//! between cells c₁ (F oriented outward of c₁) and c₂, (∂ₙᵀ f)_F =
//! f(c₁) − f(c₂), so −(∂ₙᵀ f)_F = f(c₂) − f(c₁). A metric Ω on the faces
//! turns the jumps into a normal gradient: g ≈ ∇f·n_F once Ω carries
//! 1/distance. It is the flux Ω A u of the canonical operator with A the
//! interior rows of ∂ₙ (boundary faces have no jump: their rows are empty)
//! and u = −f.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::physics::gradient::{normal_gradient, FaceMetric};
//! // f = x on a 2×1 grid of unit squares: the shared face has jump 1 along
//! // its normal (±x), boundary faces none.
//! let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
//! let f = [0.5, 1.5];
//! let g = normal_gradient(&k, &f, &FaceMetric::TwoPoint).unwrap();
//! let shared = k.boundary(2).outer_iterator().position(|r| r.nnz() == 2).unwrap();
//! assert_eq!(g.jump[shared].abs(), 1.0);
//! assert_eq!(g.gradient[shared].abs(), 1.0); // jump / centroid distance 1
//! assert!((0..7).filter(|&e| e != shared).all(|e| g.gradient[e] == 0.0));
//! ```

use crate::operator::{BlockMetric, Canonical, CanonicalError};
use hasse_complex::Complex;
use sprs::CsMat;

/// The metric Ω on the (n−1)-cells.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::gradient::{normal_gradient, FaceMetric};
/// // f = 3x + y at the centroids of a 4×4 grid with h = ½: the normal
/// // gradient is ±3 on vertical faces and ±1 on horizontal ones.
/// let k = rectangle(4, 4, [0.0, 2.0], [0.0, 2.0]).unwrap();
/// let f: Vec<f64> = (0..16).map(|c| { let x = k.centroid_of(2, c); 3.0 * x[0] + x[1] }).collect();
/// let two_point = normal_gradient(&k, &f, &FaceMetric::TwoPoint).unwrap();
/// for (face, g) in two_point.gradient.iter().enumerate() {
///     let interior = k.boundary(2).outer_view(face).unwrap().nnz() == 2;
///     let vertical = k.normal()[2 * face].abs() > 0.5;
///     let expected = if !interior { 0.0 } else if vertical { 3.0 } else { 1.0 };
///     assert!((g.abs() - expected).abs() < 1e-12);
/// }
/// // On a uniform grid that is σ = 1/h on every face.
/// let diagonal = normal_gradient(&k, &f, &FaceMetric::Diagonal(2.0)).unwrap();
/// assert!(diagonal.gradient.iter().zip(&two_point.gradient).all(|(a, b)| (a - b).abs() < 1e-12));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum FaceMetric {
    /// Ω = σ I.
    Diagonal(f64),
    /// Ω = diag(1/d_F), d_F the distance between the centroids of the two
    /// cells on F (0 on boundary faces): g is the jump over the distance.
    TwoPoint,
    /// A sparse Ω given by its entries (row face, column face, value);
    /// repeated positions add up.
    Entries(Vec<(usize, usize, f64)>),
}

/// Why a normal gradient could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GradientError {
    /// The complex is a set of points: there are no faces to jump across.
    #[error("a gradient needs a mesh of dimension ≥ 1")]
    NoFaces,
    /// The field has not one value per top cell.
    #[error("{count} field values given for {cells} top cells")]
    FieldCount {
        /// Values given.
        count: usize,
        /// Top cells of the mesh.
        cells: usize,
    },
    /// The field is NaN or ±∞ on a cell.
    #[error("the field is not finite ({value}) at top cell {cell}")]
    NonFinite {
        /// The first such top cell.
        cell: usize,
        /// Its value.
        value: f64,
    },
    /// An entry of [`FaceMetric::Entries`] lies outside the faces.
    #[error("metric entry ({row}, {column}) names a face the mesh does not have (it has {faces}, numbered from 0)")]
    FaceOutOfRange {
        /// The entry's row face.
        row: usize,
        /// The entry's column face.
        column: usize,
        /// Number of (n−1)-cells.
        faces: usize,
    },
    /// A and Ω do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
}

/// The jumps δ f and the normal gradient g = Ω δ f, both on every
/// (n−1)-cell (zero on boundary faces).
#[derive(Clone, Debug, PartialEq)]
pub struct NormalGradient {
    /// −∂ₙᵀ f on interior faces, 0 on boundary faces.
    pub jump: Vec<f64>,
    /// Ω applied to the jumps.
    pub gradient: Vec<f64>,
}

/// ∂ₙ with the rows of boundary faces (on fewer than two top cells)
/// emptied: the faces across which a cell field jumps.
fn interior_incidence(complex: &Complex) -> CsMat<i8> {
    let boundary = complex.boundary(complex.dim());
    let mut indptr = Vec::with_capacity(boundary.rows() + 1);
    let (mut indices, mut data) = (Vec::new(), Vec::new());
    indptr.push(0);
    for row in boundary.outer_iterator() {
        if row.nnz() == 2 {
            indices.extend_from_slice(row.indices());
            data.extend_from_slice(row.data());
        }
        indptr.push(indices.len());
    }
    CsMat::new(boundary.shape(), indptr, indices, data)
}

/// The normal gradient of the cell field `field` (one value per top cell)
/// with the face metric `metric`, through the canonical operator
/// (A = interior ∂ₙ, Ω).
pub fn normal_gradient(
    complex: &Complex,
    field: &[f64],
    metric: &FaceMetric,
) -> Result<NormalGradient, GradientError> {
    let n = complex.dim();
    if n == 0 {
        return Err(GradientError::NoFaces);
    }
    let cells = complex.cell_count(n);
    if field.len() != cells {
        return Err(GradientError::FieldCount {
            count: field.len(),
            cells,
        });
    }
    if let Some(cell) = field.iter().position(|v| !v.is_finite()) {
        return Err(GradientError::NonFinite {
            cell,
            value: field[cell],
        });
    }
    let incidence = interior_incidence(complex);
    let faces = incidence.rows();
    let omega = match metric {
        FaceMetric::Diagonal(sigma) => BlockMetric::from_weights(vec![*sigma; faces]),
        FaceMetric::TwoPoint => {
            let d = complex.embedding_dim();
            let centre = complex.centroid(n);
            let weights = incidence
                .outer_iterator()
                .map(|row| match row.indices() {
                    [a, b] => {
                        let distance = (0..d)
                            .map(|k| (centre[a * d + k] - centre[b * d + k]).powi(2))
                            .sum::<f64>()
                            .sqrt();
                        1.0 / distance
                    }
                    _ => 0.0,
                })
                .collect();
            BlockMetric::from_weights(weights)
        }
        FaceMetric::Entries(entries) => {
            if let Some(&(row, column, _)) =
                entries.iter().find(|&&(r, c, _)| r >= faces || c >= faces)
            {
                return Err(GradientError::FaceOutOfRange { row, column, faces });
            }
            BlockMetric::from_triplets(faces, entries)
        }
    };
    let operator = Canonical::new(incidence, omega)?;
    let minus_f: Vec<f64> = field.iter().map(|v| -v).collect();
    let jump = operator.difference(&minus_f);
    let gradient = operator.metric().apply(&jump);
    Ok(NormalGradient { jump, gradient })
}

#[cfg(test)]
mod tests {
    use super::*;
    use hasse_complex::generate::rectangle;

    #[test]
    fn jumps_and_metrics_on_a_grid_are_the_hand_computed_ones() {
        // 3×1 unit squares with f = (1, 4, 9): interior jumps ±3 and ±5
        // (sign by the face's orientation), boundary faces 0.
        let k = rectangle(3, 1, [0.0, 3.0], [0.0, 1.0]).unwrap();
        let boundary = k.boundary(2);
        let f = [1.0, 4.0, 9.0];
        let g = normal_gradient(&k, &f, &FaceMetric::Diagonal(2.0)).unwrap();
        for (face, row) in boundary.outer_iterator().enumerate() {
            match row.iter().collect::<Vec<_>>()[..] {
                [(a, &sa), (b, &sb)] => {
                    // −Σ ∂(F, c) f_c.
                    let expected = -(f64::from(sa) * f[a] + f64::from(sb) * f[b]);
                    assert_eq!(g.jump[face], expected);
                    assert_eq!(expected.abs(), if a.min(b) == 0 { 3.0 } else { 5.0 });
                    assert_eq!(g.gradient[face], 2.0 * expected);
                }
                _ => assert_eq!((g.jump[face], g.gradient[face]), (0.0, 0.0)),
            }
        }
        // Ω from entries: face e's gradient taken from face e' with scale.
        let interior: Vec<usize> = (0..boundary.rows())
            .filter(|&e| boundary.outer_view(e).unwrap().nnz() == 2)
            .collect();
        let entries = vec![
            (interior[0], interior[1], 0.5),
            (interior[0], interior[1], 0.5),
        ];
        let h = normal_gradient(&k, &f, &FaceMetric::Entries(entries)).unwrap();
        assert_eq!(h.gradient[interior[0]], g.jump[interior[1]]);
        assert_eq!(h.gradient[interior[1]], 0.0);
        assert!(matches!(
            normal_gradient(&k, &f, &FaceMetric::Entries(vec![(0, 99, 1.0)])),
            Err(GradientError::FaceOutOfRange { column: 99, .. })
        ));
        assert!(matches!(
            normal_gradient(&k, &[1.0, f64::NAN, 0.0], &FaceMetric::TwoPoint),
            Err(GradientError::NonFinite { cell: 1, value }) if value.is_nan()
        ));
    }
}
