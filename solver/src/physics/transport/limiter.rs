//! The limited second-order face values: a least-squares cell gradient,
//! limited by Barth–Jespersen, evaluated at the face centroid of the
//! upwind cell.
//!
//! For cell c with neighbours N (across its interior faces) the gradient
//! G_c minimises Σ_N (u_c + G·(x_N − x_c) − u_N)²; it is exact for linear
//! u (the pseudo-inverse of the normal matrix handles cells whose
//! neighbours span fewer than d directions, e.g. a one-cell-thick strip).
//! The limiter is the largest φ_c ∈ [0, 1] such that every face value
//! u_c + φ_c G_c·(x_f − x_c) of the cell lies between the smallest and the
//! largest of u_c and its neighbours' values: the multidimensional minmod
//! of Barth and Jespersen (1989).
//!
//! Why this gives a maximum principle: on cells whose centroid is the
//! mean of their face centroids (boxes, simplices), the linear
//! reconstruction averages back to the cell value, u_c = (1/N_c) Σ_f u_f^c,
//! so a forward Euler step writes u_c + Δt/|c| (Σ_in |F| u_f^up − Σ_out F
//! u_f^c) as a combination of face values with weights 1/N_c − Δt F_f/|c|
//! on the outflow faces and Δt|F|/|c| on the inflow ones, which is convex
//! when the velocity is discretely divergence free and N_c Δt F_f / |c| ≤ 1
//! on every outflow face. Each face value lies in some cell's neighbour
//! range, so no new extremum appears; SSP-RK2 is a convex combination of
//! two such steps.

use super::flux::Inflow;
use hasse_complex::Complex;
use nalgebra::DMatrix;
use sprs::CsMat;

/// The geometry of the reconstruction, computed once per mesh.
pub(super) struct Reconstruction {
    d: usize,
    /// Interior neighbours of every cell.
    neighbours: Vec<Vec<usize>>,
    /// (x_N − x_c) of each neighbour, stride d, in `neighbours` order.
    offsets: Vec<Vec<f64>>,
    /// The pseudo-inverse of Σ (x_N − x_c)(x_N − x_c)ᵀ, d×d row-major.
    inverse: Vec<Vec<f64>>,
    /// (face, x_f − x_c) of every face of every cell.
    faces: Vec<Vec<(usize, Vec<f64>)>>,
}

impl Reconstruction {
    pub(super) fn new(complex: &Complex) -> Self {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let top = complex.boundary(n);
        let by_cell = complex.boundary_csc(n);
        let centre = complex.centroid(n);
        let face_centre = complex.centroid(n - 1);
        let cells = complex.cell_count(n);
        let (mut neighbours, mut offsets, mut inverse, mut faces) = (
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
            Vec::with_capacity(cells),
        );
        for (c, column) in by_cell.outer_iterator().enumerate() {
            let xc = &centre[c * d..(c + 1) * d];
            let mut near = Vec::new();
            let mut offset = Vec::new();
            let mut own = Vec::new();
            for (f, _) in column.iter() {
                let xf = &face_centre[f * d..(f + 1) * d];
                own.push((f, (0..d).map(|i| xf[i] - xc[i]).collect()));
                if let Some(row) = top.outer_view(f) {
                    for (other, _) in row.iter() {
                        if other != c {
                            near.push(other);
                            let xo = &centre[other * d..(other + 1) * d];
                            offset.extend((0..d).map(|i| xo[i] - xc[i]));
                        }
                    }
                }
            }
            let mut normal = DMatrix::<f64>::zeros(d, d);
            for k in 0..near.len() {
                let r = &offset[k * d..(k + 1) * d];
                for i in 0..d {
                    for j in 0..d {
                        normal[(i, j)] += r[i] * r[j];
                    }
                }
            }
            let scale = normal.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let pinv = normal
                .pseudo_inverse(1e-10 * scale.max(f64::MIN_POSITIVE))
                .unwrap_or_else(|_| DMatrix::zeros(d, d));
            inverse.push(pinv.transpose().iter().copied().collect());
            neighbours.push(near);
            offsets.push(offset);
            faces.push(own);
        }
        Self {
            d,
            neighbours,
            offsets,
            inverse,
            faces,
        }
    }

    /// The limited increment u_f − u_c of every (cell, face) pair, in the
    /// order of `faces`.
    fn increments(&self, u: &[f64]) -> Vec<Vec<f64>> {
        let d = self.d;
        (0..u.len())
            .map(|c| {
                let mut moment = vec![0.0; d];
                let (mut lo, mut hi) = (u[c], u[c]);
                for (k, &nb) in self.neighbours[c].iter().enumerate() {
                    let du = u[nb] - u[c];
                    lo = lo.min(u[nb]);
                    hi = hi.max(u[nb]);
                    let offset = &self.offsets[c][k * d..(k + 1) * d];
                    for (m, r) in moment.iter_mut().zip(offset) {
                        *m += r * du;
                    }
                }
                let p = &self.inverse[c];
                let gradient: Vec<f64> = (0..d)
                    .map(|i| (0..d).map(|j| p[i * d + j] * moment[j]).sum())
                    .collect();
                let raw: Vec<f64> = self.faces[c]
                    .iter()
                    .map(|(_, r)| r.iter().zip(&gradient).map(|(a, b)| a * b).sum())
                    .collect();
                let mut phi = 1.0f64;
                for &delta in &raw {
                    if delta > 0.0 {
                        phi = phi.min((hi - u[c]) / delta);
                    } else if delta < 0.0 {
                        phi = phi.min((lo - u[c]) / delta);
                    }
                }
                let phi = phi.max(0.0);
                raw.into_iter().map(|r| phi * r).collect()
            })
            .collect()
    }

    /// Σ_f ∂ₙ(f, c) F_f u_f on every cell with the limited upwind face
    /// values, minus the inflow Σ |F| g: the advective part of M u − b.
    pub(super) fn advection(
        &self,
        top: &CsMat<i8>,
        flux: &[f64],
        inflow: &[Inflow],
        u: &[f64],
    ) -> Vec<f64> {
        let increments = self.increments(u);
        let mut face_value = vec![f64::NAN; flux.len()];
        for (c, own) in self.faces.iter().enumerate() {
            for (k, (f, _)) in own.iter().enumerate() {
                let Some(row) = top.outer_view(*f) else {
                    continue;
                };
                // c is upwind of f when the flow leaves it there.
                let leaving = row
                    .iter()
                    .any(|(cell, &s)| cell == c && f64::from(s) * flux[*f] > 0.0);
                if leaving {
                    face_value[*f] = u[c] + increments[c][k];
                }
            }
        }
        let mut balance = vec![0.0; u.len()];
        for (f, row) in top.outer_iterator().enumerate() {
            if flux[f] == 0.0 || face_value[f].is_nan() {
                continue;
            }
            for (c, &s) in row.iter() {
                balance[c] += f64::from(s) * flux[f] * face_value[f];
            }
        }
        for i in inflow {
            balance[i.cell] -= i.weight * i.value;
        }
        balance
    }

    /// Faces of every cell (N_c).
    pub(super) fn face_counts(&self) -> Vec<usize> {
        self.faces.iter().map(Vec::len).collect()
    }
}
