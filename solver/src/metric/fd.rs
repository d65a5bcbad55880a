//! Finite-difference metrics for cell-centred unknowns on A = ∂ₙ.
//!
//! - [`five_point`]: the three/five/seven-point stencil on a (possibly
//!   graded) grid of axis-aligned boxes, built from grid spacings only.
//! - [`from_face_values`], [`from_face_matrix`]: an Ω given by the user,
//!   diagonal (the thesis's σ_F = λ/h of §5.4) or face-to-face (the wider,
//!   possibly non-symmetric banded Ω of the thesis's chapter 6).
//!
//! In the thesis's canonical form the unknowns T_K sit on top cells, ∂ₙ
//! takes differences across faces, Ω turns them into fluxes and δ = ∂ₙᵀ
//! sums the fluxes of each cell.

use super::{CellTensors, MetricError};
use crate::operator::BlockMetric;
use hasse_complex::Complex;

const METHOD: &str = "finite differences";

/// Bounding box of a top cell that has been checked to be an axis-aligned
/// box: lower corner and widths h_a.
#[derive(Clone, Copy, Debug)]
struct Box3 {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Box3 {
    fn width(&self, axis: usize) -> f64 {
        self.hi[axis] - self.lo[axis]
    }
}

/// The axis-aligned box of top cell `cell`, or why it is not one: 2ⁿ
/// vertices, each a distinct corner of the cell's bounding box, and
/// positive width along every axis.
fn axis_box(complex: &Complex, cell: usize) -> Result<Box3, MetricError> {
    let n = complex.dim();
    let vertices = complex.cell_vertices(n, cell);
    let not_a_box = |why: String| MetricError::UnsupportedMesh {
        method: METHOD,
        needs: "a grid of axis-aligned boxes",
        detail: format!("top cell {cell} (vertices {vertices:?}) {why}"),
    };
    if vertices.len() != 1 << n {
        return Err(not_a_box(format!(
            "has {} vertices, a box has {}",
            vertices.len(),
            1 << n
        )));
    }
    let mut b = Box3 {
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
    };
    for &v in vertices {
        for (a, &x) in complex.vertices().point(v).iter().enumerate() {
            b.lo[a] = b.lo[a].min(x);
            b.hi[a] = b.hi[a].max(x);
        }
    }
    let largest = (0..n).map(|a| b.width(a)).fold(0.0f64, f64::max);
    if let Some(a) = (0..n).find(|&a| !(b.width(a) > 0.0 && b.width(a).is_finite())) {
        return Err(not_a_box(format!("has zero width along axis {a}")));
    }
    // Coordinates are compared with a tolerance relative to the cell, so a
    // grid read back from a text file with rounded digits still passes.
    let tolerance = 1e-10 * largest;
    let mut seen = vec![false; 1 << n];
    for &v in vertices {
        let x = complex.vertices().point(v);
        let mut corner = 0;
        for (a, &xa) in x.iter().enumerate().take(n) {
            if (xa - b.hi[a]).abs() <= tolerance {
                corner |= 1 << a;
            } else if (xa - b.lo[a]).abs() > tolerance {
                return Err(not_a_box(format!(
                    "has vertex {v} inside its bounding box along axis {a}"
                )));
            }
        }
        if std::mem::replace(&mut seen[corner], true) {
            return Err(not_a_box("has two vertices at the same corner".into()));
        }
    }
    Ok(b)
}

/// The axis normal to (n−1)-cell `face` of box `b`: the one axis along
/// which all the face's vertices sit on the same side of the box.
fn face_axis(complex: &Complex, face: usize, b: &Box3) -> Option<usize> {
    let n = complex.dim();
    let vertices = complex.cell_vertices(n - 1, face);
    let tolerance = 1e-10 * (0..n).map(|a| b.width(a)).fold(0.0f64, f64::max);
    let on = |a: usize, side: f64| {
        vertices
            .iter()
            .all(|&v| (complex.vertices().point(v)[a] - side).abs() <= tolerance)
    };
    let mut axes = (0..n).filter(|&a| on(a, b.lo[a]) || on(a, b.hi[a]));
    match (axes.next(), axes.next()) {
        (Some(a), None) => Some(a),
        _ => None,
    }
}

/// The five-point (2D), seven-point (3D) or three-point (1D) stencil for
/// −∇·(λ∇u) with cell-centred unknowns on a grid of axis-aligned boxes,
/// as a diagonal Ω on A = ∂ₙ.
///
/// Every top cell must be an axis-aligned box (else
/// [`MetricError::UnsupportedMesh`] names the first that is not) and every
/// tensor diagonal; only the grid spacings are used, read from the cells'
/// vertex coordinates (no areas or normals from the geometry module). For a
/// face normal to axis a between cells K and L, with widths h_{K,a},
/// h_{L,a} along a and w the product of the face's widths along the other
/// axes,
///
/// σ_F = λ_F w / ((h_{K,a} + h_{L,a}) / 2),
/// λ_F = (h_{K,a} + h_{L,a}) / (h_{K,a}/λ_K + h_{L,a}/λ_L),
///
/// λ the diagonal entry K_aa and λ_F its harmonic average weighted by the
/// half widths; a boundary face of K has σ_F = λ_K w / (h_{K,a}/2) (the
/// Dirichlet value sits on the face). Row K of Aᵀ Ω A is the flux balance
/// of K: on a uniform grid it is the classical 5/7-point difference
/// quotient multiplied by the cell volume, and it equals the two-point
/// finite-volume metric [`two_point`](super::fv::two_point) on any such
/// grid.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::operator::Canonical;
/// use hasse_solver::metric::{fd, isotropic};
/// // 3×3 cells of 0.5 × 0.25: the centre row is |K|·(2/hx² + 2/hy²) on
/// // the diagonal and −|K|/hx², −|K|/hy² to the neighbours.
/// let k = rectangle(3, 3, [0.0, 1.5], [0.0, 0.75]).unwrap();
/// let omega = fd::five_point(&k, &[isotropic(1.0); 9]).unwrap();
/// let m = Canonical::new(k.boundary(2), omega).unwrap().assemble().to_dense();
/// let volume = 0.5 * 0.25;
/// assert!((m[(4, 4)] - volume * (2.0 / 0.25 + 2.0 / 0.0625)).abs() < 1e-12);
/// assert!((m[(4, 5)] + volume / 0.25).abs() < 1e-12);
/// assert!((m[(4, 7)] + volume / 0.0625).abs() < 1e-12);
/// ```
pub fn five_point<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<BlockMetric, MetricError> {
    let tensors = tensors.into();
    let (n, d) = (complex.dim(), complex.embedding_dim());
    if n == 0 || n != d {
        return Err(MetricError::UnsupportedMesh {
            method: METHOD,
            needs: "a grid that fills its space (n = d ≥ 1)",
            detail: format!("the complex is {n}-dimensional in R^{d}"),
        });
    }
    let cells = complex.cell_count(n);
    let tensors = tensors.checked(cells, d)?;
    if let Some(cell) =
        (0..cells).find(|&c| (0..d).any(|i| (0..d).any(|j| i != j && tensors.get(c)[i][j] != 0.0)))
    {
        return Err(MetricError::UnsupportedMesh {
            method: METHOD,
            needs: "diagonal (axis-aligned) tensors",
            detail: format!("the coefficient of top cell {cell} has off-diagonal entries; use the mimetic method for full tensors"),
        });
    }
    let boxes = (0..cells)
        .map(|c| axis_box(complex, c))
        .collect::<Result<Vec<_>, _>>()?;
    let boundary = complex.try_boundary(n)?;
    let mut sigma = Vec::with_capacity(boundary.rows());
    for (face, row) in boundary.outer_iterator().enumerate() {
        let adjacent: Vec<usize> = row.indices().to_vec();
        let Some(&k) = adjacent.first() else {
            // A face on no top cell carries no flux.
            sigma.push(0.0);
            continue;
        };
        let axis =
            face_axis(complex, face, &boxes[k]).ok_or_else(|| MetricError::UnsupportedMesh {
                method: METHOD,
                needs: "a grid of axis-aligned boxes",
                detail: format!("(n−1)-cell {face} is not a side of top cell {k}"),
            })?;
        let w: f64 = (0..n)
            .filter(|&b| b != axis)
            .map(|b| boxes[k].width(b))
            .product();
        let (hk, lk) = (boxes[k].width(axis), tensors.get(k)[axis][axis]);
        sigma.push(match adjacent.as_slice() {
            [_] => lk * w / (hk / 2.0),
            [_, l] => {
                let (hl, ll) = (boxes[*l].width(axis), tensors.get(*l)[axis][axis]);
                let lambda = (hk + hl) / (hk / lk + hl / ll);
                lambda * w / ((hk + hl) / 2.0)
            }
            _ => {
                return Err(MetricError::UnsupportedMesh {
                    method: METHOD,
                    needs: "every (n−1)-cell shared by at most two top cells",
                    detail: format!("(n−1)-cell {face} lies on {} top cells", adjacent.len()),
                })
            }
        });
    }
    Ok(BlockMetric::diagonal(&sigma))
}

/// A user-given diagonal Ω: σ_F on (n−1)-cell F, e.g. the thesis's
/// σ = λ/h of eq. (5.17). The length must be the number of rows of A (an
/// error when the operator is built otherwise).
///
/// ```
/// use hasse_solver::metric::fd;
/// let omega = fd::from_face_values(&[1.0, 2.0]);
/// assert_eq!(omega.to_dense(), vec![vec![1.0, 0.0], vec![0.0, 2.0]]);
/// ```
pub fn from_face_values(sigma: &[f64]) -> BlockMetric {
    BlockMetric::diagonal(sigma)
}

/// A user-given face-to-face Ω of `size` rows from (row, column, value)
/// entries (repeated positions add up), such as the thesis's banded
/// chapter-6 Ω that couples a face with its neighbours. It need not be
/// symmetric; then Aᵀ Ω A is not either and needs an LU solve. Entries out
/// of range are reported when the operator is built.
///
/// ```
/// use hasse_solver::metric::fd;
/// let omega = fd::from_face_matrix(2, &[(0, 0, 2.0), (0, 1, -1.0), (1, 1, 2.0)]);
/// assert_eq!(omega.to_dense(), vec![vec![2.0, -1.0], vec![0.0, 2.0]]);
/// ```
pub fn from_face_matrix(size: usize, entries: &[(usize, usize, f64)]) -> BlockMetric {
    BlockMetric::from_triplets(size, entries)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::isotropic;
    use hasse_complex::generate::{grid, perturb, rectangle};
    use hasse_complex::{TopCells, Vertices};

    #[test]
    fn one_dimensional_three_point_stencil_on_a_graded_axis() {
        // Cells [0,1], [1,3]: interior σ = λ_F/((1+2)/2) with
        // λ_F = 3/(1/2 + 2/4) = 3, so σ = 2; boundary σ = λ/(h/2).
        let k = grid(&[vec![0.0, 1.0, 3.0]]).unwrap();
        let omega = five_point(&k, &[isotropic(2.0), isotropic(4.0)]).unwrap();
        let dense = omega.to_dense();
        let mut sigma: Vec<(f64, f64)> = (0..3)
            .map(|v| (k.vertices().point(v)[0], dense[v][v]))
            .collect();
        sigma.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(sigma, vec![(0.0, 4.0), (1.0, 2.0), (3.0, 4.0)]);
    }

    #[test]
    fn non_boxes_and_full_tensors_are_rejected() {
        let k = perturb(&rectangle(3, 3, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.2, 1).unwrap();
        let err = five_point(&k, &[isotropic(1.0); 9]).unwrap_err();
        assert!(
            matches!(err, MetricError::UnsupportedMesh { ref detail, .. } if detail.starts_with("top cell 0 ")),
            "{err}"
        );
        let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let full = [[1.0, 0.1, 0.0], [0.1, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let err = five_point(&k, &[full]).unwrap_err();
        assert!(
            err.to_string().contains("diagonal (axis-aligned) tensors"),
            "{err}"
        );
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
        let t = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        assert!(five_point(&t, &[isotropic(1.0)]).is_err());
    }
}
