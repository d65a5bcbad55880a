//! Smoothed aggregation: strength of connection, greedy aggregates, and the
//! damped-Jacobi smoothing of a tentative prolongation.

use super::cycle::ROW_CHUNK;
use super::MultigridError;
use crate::la::iterative::RowMatrix;
use rayon::prelude::*;

/// P − ω D⁻¹ M P with ω = 4/(3λ), λ bounding the spectrum of D⁻¹M: one
/// damped Jacobi step applied to the columns of P, as in smoothed
/// aggregation ([`RowMatrix::smoothed`]: one parallel pass over the rows).
pub(super) fn smooth_prolongation(
    matrix: &RowMatrix,
    inverse_diagonal: &[f64],
    lambda: f64,
    p: &RowMatrix,
) -> Result<RowMatrix, MultigridError> {
    let omega = 4.0 / (3.0 * lambda);
    let scale: Vec<f64> = inverse_diagonal
        .par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|d| omega * d)
        .collect();
    Ok(matrix.smoothed(p, &scale))
}

/// Which off-diagonal entries of a row are strong couplings, in terms of
/// the scaled coupling s_ij = |a_ij| / √|a_ii a_jj|.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Strength {
    /// s_ij ≥ θ: Vaněk, Mandel and Brezina's measure, for the finest
    /// level, whose rows are the discretisation's own stencils.
    Absolute(f64),
    /// s_ij ≥ θ · max_k s_ik (k ≠ i): each row against its own strongest
    /// coupling, as classical AMG measures strength (hypre's default
    /// threshold is 0.25), for Galerkin levels whose rows spread over many
    /// neighbours; see [`level_strength`](super::cycle::level_strength).
    Relative(f64),
}

/// The strong neighbours of every row (without the row itself and without
/// zero entries). Under [`Strength::Relative`] the relation need not be
/// symmetric; the aggregation passes read it row by row and do not need it
/// to be.
pub(super) fn strong_neighbours(matrix: &RowMatrix, strength: Strength) -> Vec<Vec<u32>> {
    let diagonal = matrix.diagonal();
    // Squared scaled couplings: s_ij² = a_ij² / |a_ii a_jj|, no square root.
    let scaled = |i: usize, j: u32, a: f64| a * a / (diagonal[i] * diagonal[j as usize]).abs();
    (0..matrix.nrows())
        .into_par_iter()
        .with_min_len(ROW_CHUNK)
        .map(|i| {
            let (c, v) = matrix.row(i);
            let threshold2 = match strength {
                Strength::Absolute(theta) => theta * theta,
                Strength::Relative(theta) => {
                    let largest = c
                        .iter()
                        .zip(v)
                        .filter(|(&j, _)| j as usize != i)
                        .fold(0.0f64, |m, (&j, &a)| m.max(scaled(i, j, a)));
                    theta * theta * largest
                }
            };
            c.iter()
                .zip(v)
                .filter(|(&j, &a)| j as usize != i && a != 0.0 && scaled(i, j, a) >= threshold2)
                .map(|(&j, _)| j)
                .collect()
        })
        .collect()
}

/// The tentative prolongation of smoothed aggregation and the coarse
/// near-null vector: aggregates of strongly connected unknowns (standard
/// greedy aggregation in three passes), one column per aggregate J holding
/// the near-null vector `candidate` restricted to J and normalised,
/// b_J / ‖b_J‖, and the coarse near-null vector b_c with (b_c)_J = ‖b_J‖,
/// so that P₀ b_c = b exactly on the aggregated unknowns (the QR step of
/// Vaněk, Mandel and Brezina with one candidate).
///
/// The coarse vector is not the constant even when b is: with normalised
/// columns the fine constant is P₀ b_c with (b_c)_J = √|J|, and on an
/// unstructured mesh |J| varies from 2 to 11 or more. Taking the constant
/// as every level's near-null vector (as this function once did) puts the
/// fine constant outside the coarse spaces from the second algebraic
/// level on: V-cycle counts then grew with the number of levels (Delaunay
/// P1, θ = 0.08: 11/12/14/20 for 2·10⁴ … 10⁶ triangles, 11/12/12/13 with
/// the restricted vector).
///
/// Unknowns without strong neighbours but coupled to others are
/// aggregates of their own (pass 4 says why); decoupled unknowns stay out.
/// `None` when no two unknowns aggregate.
pub(super) fn aggregate(
    matrix: &RowMatrix,
    strength: Strength,
    candidate: &[f64],
) -> Result<Option<(RowMatrix, Vec<f64>)>, MultigridError> {
    let n = matrix.nrows();
    let strong = strong_neighbours(matrix, strength);
    const NONE: usize = usize::MAX;
    let mut agg = vec![NONE; n];
    let mut count = 0usize;
    // Pass 1: an unknown whose strong neighbours are all free seeds an
    // aggregate with them.
    for i in 0..n {
        if agg[i] != NONE || strong[i].is_empty() {
            continue;
        }
        if strong[i].iter().all(|&j| agg[j as usize] == NONE) {
            agg[i] = count;
            for &j in &strong[i] {
                agg[j as usize] = count;
            }
            count += 1;
        }
    }
    let after_first = agg.clone();
    // Pass 2: the rest join a neighbouring aggregate of pass 1.
    for i in 0..n {
        if agg[i] == NONE {
            if let Some(&j) = strong[i].iter().find(|&&j| after_first[j as usize] != NONE) {
                agg[i] = after_first[j as usize];
            }
        }
    }
    // Pass 3: leftovers aggregate with their still free neighbours.
    for i in 0..n {
        if agg[i] == NONE && !strong[i].is_empty() {
            agg[i] = count;
            for &j in &strong[i] {
                if agg[j as usize] == NONE {
                    agg[j as usize] = count;
                }
            }
            count += 1;
        }
    }
    if count == 0 {
        return Ok(None);
    }
    // Pass 4: an unknown without strong neighbours but with off-diagonal
    // entries becomes an aggregate of its own. Leaving it out (as standard
    // aggregation does) is safe only for a row the smoother solves alone,
    // one whose diagonal dominates its couplings; but with row sums near
    // zero (a Laplacian) a node with k comparable neighbours has
    // |a_ij| ≈ a_ii/k < θ √(a_ii a_jj) once k > 1/θ, so no strong neighbour
    // while its error is as smooth as its neighbours'. Out of every
    // aggregate, the near-null vector is lost there and each such node
    // leaves a slow mode to CG: jittered Delaunay P1 with θ = 0.25 left 9 %
    // of the nodes out and needed 104 iterations at 3.2·10⁵ triangles
    // (180 at 10⁶), 9 with the singletons. Rows without off-diagonal
    // entries (decoupled unknowns) stay out: the smoother solves them.
    for (i, a) in agg.iter_mut().enumerate() {
        if *a == NONE {
            let (c, v) = matrix.row(i);
            if c.iter().zip(v).any(|(&j, &m)| j as usize != i && m != 0.0) {
                *a = count;
                count += 1;
            }
        }
    }
    let mut norm = vec![0.0f64; count];
    for (&a, &b) in agg.iter().zip(candidate) {
        if a != NONE {
            norm[a] += b * b;
        }
    }
    norm.iter_mut().for_each(|v| *v = v.sqrt());
    let mut ptr = vec![0];
    let mut idx = Vec::with_capacity(n);
    let mut val = Vec::with_capacity(n);
    for (&a, &b) in agg.iter().zip(candidate) {
        if a != NONE {
            idx.push(a as u32);
            // The candidates of the levels are positive (the constant,
            // then norms of its pieces), so no aggregate has norm zero.
            val.push(b / norm[a]);
        }
        ptr.push(idx.len());
    }
    Ok(Some((RowMatrix::new(n, count, ptr, idx, val)?, norm)))
}
