//! The elastic operator's two factors: the incidence A = I_d ⊗ δ⁰ (pure
//! topology) and the block metric Ω of the element stiffnesses.

use super::Lame;
use crate::metric::fe::{self, Topology};
use crate::metric::MetricError;
use crate::operator::BlockMetric;
use hasse_complex::Complex;
use nalgebra::DMatrix;
use rayon::prelude::*;
use sprs::{CsMat, TriMat};
use std::sync::Arc;

/// A = I_d ⊗ δ⁰: row a·|K₁| + e holds edge e's differences of component a,
/// column a·|K₀| + v is component a at vertex v.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let a = hasse_solver::physics::elasticity::incidence(&k);
/// assert_eq!(a.shape(), (8, 8)); // 2 × 4 edges, 2 × 4 vertices
/// assert_eq!(a.nnz(), 16);
/// ```
pub fn incidence(complex: &Complex) -> CsMat<i8> {
    let d = complex.embedding_dim();
    let delta = Arc::clone(complex.coboundary(0));
    let (edges, vertices) = delta.shape();
    let mut tri = TriMat::with_capacity((d * edges, d * vertices), d * delta.nnz());
    for a in 0..d {
        for (&s, (e, v)) in delta.iter() {
            tri.add_triplet(a * edges + e, a * vertices + v, s);
        }
    }
    tri.to_csr()
}

/// The elastic metric Ω over the rows of [`incidence`]: one dense block per
/// top cell, Ω_c = (A_c⁺)ᵀ K_c A_c⁺ over the d·|edges of c| rows of its
/// edges (see the [module documentation](self)).
///
/// K_c[(a, i), (b, j)] = Σ_q w_q (λ ∂_a φ_i ∂_b φ_j + μ (δ_ab ∇φ_i·∇φ_j +
/// ∂_b φ_i ∂_a φ_j)) over the quadrature points of the scalar FE metric
/// (one point on simplices, Gauss 2ⁿ on quadrilaterals and hexahedra).
///
/// ```
/// use hasse_complex::{Complex, TopCells, Vertices};
/// use hasse_solver::physics::elasticity::{stiffness_metric, Lame};
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
/// let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
/// let omega = stiffness_metric(&k, &[Lame { lambda: 2.0, mu: 1.0 }]).unwrap();
/// assert_eq!((omega.size(), omega.block_count()), (6, 1));
/// assert!(omega.is_symmetric(1e-14));
/// ```
pub fn stiffness_metric(complex: &Complex, lame: &[Lame]) -> Result<BlockMetric, MetricError> {
    let top = Topology::new(complex, "elasticity")?;
    let (n, d) = (top.n, top.d);
    let cells = complex.cell_count(n);
    if lame.len() != cells {
        return Err(MetricError::CoefficientCount {
            count: lame.len(),
            cells,
        });
    }
    let edges = complex.cell_count(1);
    let blocks = (0..cells)
        .into_par_iter()
        .map(|c| {
            let points = fe::shape_gradients(&top, c)?.ok_or(MetricError::UnsupportedCell {
                method: "elasticity",
                needs: "a triangle, tetrahedron, quadrilateral or hexahedron (P1 or Q1)",
                cell: c,
            })?;
            let m = complex.cell_vertices(n, c).len();
            let Lame { lambda, mu } = lame[c];
            let mut kc = DMatrix::zeros(d * m, d * m);
            for (w, g) in &points {
                for a in 0..d {
                    for b in 0..d {
                        for i in 0..m {
                            for j in 0..m {
                                let mut value = lambda * g[i][a] * g[j][b] + mu * g[i][b] * g[j][a];
                                if a == b {
                                    value += mu * (0..d).map(|k| g[i][k] * g[j][k]).sum::<f64>();
                                }
                                kc[(a * m + i, b * m + j)] += w * value;
                            }
                        }
                    }
                }
            }
            let cell_edges = top.edges_of(c);
            let pinv =
                fe::edge_pseudo_inverse(&top, c, &cell_edges, &mut Vec::new(), "elasticity")?;
            let lift = DMatrix::<f64>::identity(d, d).kronecker(&*pinv);
            let omega = lift.transpose() * kc * &lift;
            let size = omega.nrows();
            let rows: Vec<usize> = (0..d)
                .flat_map(|a| cell_edges.iter().map(move |&e| a * edges + e))
                .collect();
            // Symmetric up to rounding; made exactly so.
            let values: Vec<f64> = (0..size * size)
                .map(|k| {
                    let (i, j) = (k / size, k % size);
                    0.5 * (omega[(i, j)] + omega[(j, i)])
                })
                .collect();
            if values.iter().any(|v| !v.is_finite()) {
                return Err(MetricError::UnsupportedCell {
                    method: "elasticity",
                    needs: "a non-degenerate cell (finite local stiffness)",
                    cell: c,
                });
            }
            Ok((rows, values))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut metric = BlockMetric::new(d * edges);
    for (rows, values) in &blocks {
        metric.push_symmetric(rows, values);
    }
    Ok(metric)
}
