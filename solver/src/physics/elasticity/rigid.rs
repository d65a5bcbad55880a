//! Rigid-body modes, and the check that the prescribed displacement
//! components hold every one of them on every connected part of the mesh.

use super::ElasticityError;
use crate::la::disjoint::DisjointSets;
use hasse_complex::Complex;
use nalgebra::DMatrix;

/// The rigid-body modes of the whole mesh, component-major like the
/// unknowns: d translations, then the rotations about the vertex average
/// (one in 2D; about the x, y and z axes in 3D).
pub fn rigid_modes(complex: &Complex) -> Vec<Vec<f64>> {
    let all: Vec<usize> = (0..complex.cell_count(0)).collect();
    modes_on(complex, &all)
}

/// Rigid modes restricted to the vertices `part` (zero elsewhere).
fn modes_on(complex: &Complex, part: &[usize]) -> Vec<Vec<f64>> {
    let d = complex.embedding_dim();
    let vertices = complex.cell_count(0);
    let mut centre = [0.0; 3];
    for &v in part {
        for (a, x) in complex.vertices().point(v).iter().enumerate() {
            centre[a] += x / part.len() as f64;
        }
    }
    let mut modes = Vec::new();
    for a in 0..d {
        let mut m = vec![0.0; d * vertices];
        for &v in part {
            m[a * vertices + v] = 1.0;
        }
        modes.push(m);
    }
    // Rotation in the (p, q) plane: u_p = −x_q, u_q = x_p.
    let planes: &[(usize, usize)] = if d == 2 {
        &[(0, 1)]
    } else {
        &[(1, 2), (2, 0), (0, 1)]
    };
    for &(p, q) in planes {
        let mut m = vec![0.0; d * vertices];
        for &v in part {
            let x = complex.vertices().point(v);
            m[p * vertices + v] = -(x[q] - centre[q]);
            m[q * vertices + v] = x[p] - centre[p];
        }
        modes.push(m);
    }
    modes
}

/// Connected parts of the edge graph, as vertex lists.
fn parts(complex: &Complex) -> Vec<Vec<usize>> {
    let vertices = complex.cell_count(0);
    let mut sets = DisjointSets::new(vertices);
    for e in 0..complex.cell_count(1) {
        let ends = complex.cell_vertices(1, e);
        sets.join(ends[0], ends[1]);
    }
    let mut index = vec![usize::MAX; vertices];
    let mut out: Vec<Vec<usize>> = Vec::new();
    for v in 0..vertices {
        let r = sets.root(v);
        if index[r] == usize::MAX {
            index[r] = out.len();
            out.push(Vec::new());
        }
        out[index[r]].push(v);
    }
    out
}

/// Below this, a generalised eigenvalue of (modes on fixed unknowns, modes
/// on all unknowns) is a free mode. The eigenvalues lie in [0, 1]; a mode
/// held by a single vertex of a million still has about 1e-6, while one the
/// constraints miss is zero to rounding (≈ 1e-30).
const RIGID_TOLERANCE: f64 = 1e-12;

/// Report the first part of the mesh whose prescribed components leave a
/// rigid-body mode free.
pub(super) fn check_rigid_modes(
    complex: &Complex,
    fixed: &[Option<f64>],
) -> Result<(), ElasticityError> {
    for (part, vertices) in parts(complex).iter().enumerate() {
        let modes = modes_on(complex, vertices);
        let r = modes.len();
        let gram = |held_only: bool| {
            DMatrix::from_fn(r, r, |i, j| {
                modes[i]
                    .iter()
                    .zip(&modes[j])
                    .zip(fixed)
                    .filter(|(_, g)| !held_only || g.is_some())
                    .map(|((x, y), _)| x * y)
                    .sum::<f64>()
            })
        };
        let (held, all) = (gram(true), gram(false));
        // A single vertex has no rotation (its modes are dependent): then
        // the held translations decide alone.
        let free = match all.clone().cholesky() {
            Some(chol) => {
                let l_inv = chol
                    .l()
                    .try_inverse()
                    .unwrap_or_else(|| DMatrix::zeros(r, r));
                let scaled = &l_inv * held * l_inv.transpose();
                scaled
                    .symmetric_eigenvalues()
                    .iter()
                    .filter(|&&e| e < RIGID_TOLERANCE)
                    .count()
            }
            None => (0..complex.embedding_dim())
                .filter(|&a| held[(a, a)] == 0.0)
                .count(),
        };
        if free > 0 {
            return Err(ElasticityError::RigidModes {
                part,
                free,
                modes: r,
            });
        }
    }
    Ok(())
}
