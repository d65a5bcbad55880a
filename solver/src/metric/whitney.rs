//! The Whitney (Galerkin) Hodge star of every degree: the mass matrix
//! (M_k)_{στ} = ∫ W_σ · W_τ of the Whitney k-forms on a simplicial complex.
//!
//! On a simplex T with barycentric coordinates λ₀ … λ_n, the Whitney form
//! of the face σ = [s₀, …, s_k] (vertices in increasing order: the
//! orientation of simplices in the complex) is
//!
//! ```text
//!     W_σ = k! Σ_i (−1)^i λ_{s_i} dλ_{s_0} ∧ … ∧ (dλ_{s_i} omitted) ∧ … ∧ dλ_{s_k},
//! ```
//!
//! the form whose integral over σ is 1 and over every other k-face 0. The
//! inner product of two k-covectors dλ_{a₁}∧…∧dλ_{a_k} and
//! dλ_{b₁}∧…∧dλ_{b_k} is det[∇λ_{a_i} · ∇λ_{b_j}], and
//! ∫_T λ_a λ_b = |T| (1 + δ_ab) / ((n+1)(n+2)), so
//!
//! ```text
//!     ∫_T W_σ · W_ρ = (k!)² Σ_{i,j} (−1)^{i+j} ∫_T λ_{s_i} λ_{r_j} · det[g]_{(σ∖s_i) × (ρ∖r_j)},
//! ```
//!
//! g the Gram matrix of the barycentric gradients, computed in the
//! simplex's own tangent space (so surfaces in R³ work): for the edge
//! vectors E = [x₁ − x₀, …, x_n − x₀], g_ab = (EᵀE)⁻¹_ab for a, b ≥ 1, and
//! ∇λ₀ = −Σ ∇λ_a. For k = 0 this is the P1 consistent mass, for k = 1
//! the Nédélec edge mass (the metric [`super::dec::whitney_metric`] builds
//! with a coefficient), for k = n the diagonal 1/|T|. One dense block per
//! top simplex over its k-faces; the blocks overlap on shared faces and
//! add up in the canonical assembly Iᵀ Ω I.

use super::MetricError;
use crate::operator::BlockMetric;
use hasse_complex::Complex;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// M_k, the Whitney star of degree `k` (0 ≤ k ≤ n): a [`BlockMetric`] over
/// the k-cells, one dense block per top simplex. Cells that are not
/// simplices are [`MetricError::UnsupportedCell`]; a degenerate simplex is
/// [`MetricError::UnsupportedMesh`].
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_solver::metric::whitney::whitney_mass;
/// use hasse_solver::operator::Canonical;
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// // The P1 mass integrates 1 · 1 to the area; the top star is 1/|T|.
/// let m0 = Canonical::new(sprs::CsMat::<i8>::eye(9), whitney_mass(&k, 0).unwrap()).unwrap();
/// let ones = vec![1.0; 9];
/// let total: f64 = m0.apply(&ones).iter().sum();
/// assert!((total - 1.0).abs() < 1e-14);
/// let m2 = whitney_mass(&k, 2).unwrap();
/// assert!(m2.to_dense().iter().enumerate().all(|(i, row)| (row[i] - 8.0).abs() < 1e-12));
/// ```
pub fn whitney_mass(complex: &Complex, k: usize) -> Result<BlockMetric, MetricError> {
    let n = complex.dim();
    if k > n {
        return Err(MetricError::Geometry(
            hasse_complex::ComplexError::DimensionOutOfRange { p: k, dim: n },
        ));
    }
    let faces = local_faces(n + 1, k + 1);
    let blocks: Vec<(Vec<usize>, Vec<f64>)> = (0..complex.cell_count(n))
        .into_par_iter()
        .map(|c| cell_block(complex, c, k, &faces))
        .collect::<Result<_, _>>()?;
    let mut metric = BlockMetric::new(complex.cell_count(k));
    for (rows, values) in &blocks {
        metric.push_symmetric(rows, values);
    }
    Ok(metric)
}

/// Every increasing list of `size` indices out of `0..count`.
fn local_faces(count: usize, size: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut current = Vec::with_capacity(size);
    fn extend(
        start: usize,
        count: usize,
        size: usize,
        current: &mut Vec<usize>,
        out: &mut Vec<Vec<usize>>,
    ) {
        if current.len() == size {
            out.push(current.clone());
            return;
        }
        for i in start..count {
            current.push(i);
            extend(i + 1, count, size, current, out);
            current.pop();
        }
    }
    extend(0, count, size, &mut current, &mut out);
    out
}

/// The k-face rows and the row-major block ∫_T W_σ · W_ρ of top cell `c`.
fn cell_block(
    complex: &Complex,
    c: usize,
    k: usize,
    faces: &[Vec<usize>],
) -> Result<(Vec<usize>, Vec<f64>), MetricError> {
    let n = complex.dim();
    let vertices = complex.cell_vertices(n, c);
    if vertices.len() != n + 1 {
        return Err(MetricError::UnsupportedCell {
            method: "the Whitney star",
            needs: "a simplex",
            cell: c,
        });
    }
    // Unwrapped on a flat torus: the geometry of this one cell.
    let points = complex.cell_points(n, c);
    let edges: Vec<nalgebra::Vector3<f64>> = points[1..]
        .iter()
        .map(|x| nalgebra::Vector3::from(*x) - nalgebra::Vector3::from(points[0]))
        .collect();
    let gram = DMatrix::from_fn(n, n, |a, b| edges[a].dot(&edges[b]));
    let volume = gram.determinant().max(0.0).sqrt() / factorial(n);
    let degenerate = || MetricError::UnsupportedMesh {
        method: "the Whitney star",
        needs: "non-degenerate simplices",
        detail: format!("top cell {c} has zero volume"),
    };
    let inverse = gram.try_inverse().ok_or_else(degenerate)?;
    if volume.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(degenerate());
    }
    // g_ab = ∇λ_a · ∇λ_b for a, b in 0..=n.
    let g = DMatrix::from_fn(n + 1, n + 1, |a, b| match (a, b) {
        (0, 0) => inverse.sum(),
        (0, b) => -inverse.column(b - 1).sum(),
        (a, 0) => -inverse.row(a - 1).sum(),
        (a, b) => inverse[(a - 1, b - 1)],
    });
    let lambda =
        |a: usize, b: usize| volume * if a == b { 2.0 } else { 1.0 } / ((n + 1) * (n + 2)) as f64;
    let scale = factorial(k).powi(2);
    let size = faces.len();
    let mut values = vec![0.0; size * size];
    for (r, sigma) in faces.iter().enumerate() {
        for (s, rho) in faces.iter().enumerate().skip(r) {
            let mut sum = 0.0;
            for (i, &si) in sigma.iter().enumerate() {
                for (j, &rj) in rho.iter().enumerate() {
                    let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
                    let minor = DMatrix::from_fn(k, k, |a, b| {
                        let a = sigma[if a < i { a } else { a + 1 }];
                        let b = rho[if b < j { b } else { b + 1 }];
                        g[(a, b)]
                    });
                    sum += sign * lambda(si, rj) * minor.determinant();
                }
            }
            values[r * size + s] = scale * sum;
            values[s * size + r] = scale * sum;
        }
    }
    let rows = faces
        .iter()
        .map(|face| {
            let global: Vec<usize> = face.iter().map(|&a| vertices[a]).collect();
            complex
                .find_cell(k, &global)
                .ok_or_else(|| MetricError::UnsupportedMesh {
                    method: "the Whitney star",
                    needs: "every face of a top simplex in the complex",
                    detail: format!("face {global:?} of top cell {c} is missing"),
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((rows, values))
}

fn factorial(k: usize) -> f64 {
    (1..=k).map(|i| i as f64).product()
}
