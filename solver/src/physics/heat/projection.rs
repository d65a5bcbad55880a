//! Where conjugate gradients start each step of an iterative run: the
//! L-orthogonal projection of the new level onto the span of the last
//! levels (P. F. Fischer, "Projection techniques for iterative solution
//! of Ax = b with successive right-hand sides", Comput. Methods Appl.
//! Mech. Engrg. 163, 1998).
//!
//! With a basis q₁…q_l of the span that is L-orthonormal (qᵢᵀ L qⱼ = δᵢⱼ),
//! the element of the span closest to the solution x of L x = b in the
//! energy norm ‖·‖_L is x̄ = Σ (qᵢᵀ b) qᵢ, since qᵢᵀ L x = qᵢᵀ b: it needs
//! the new right-hand side and no product with L. Its error is no larger
//! than that of any other start in the span; the span holds uⁿ and uⁿ⁻¹
//! (until a restart), so x̄ is at least as close as uⁿ and as the linear
//! extrapolation 2uⁿ − uⁿ⁻¹, and on a solution smooth in time as close as
//! the extrapolation of the highest order the span holds.
//!
//! After the solve, the new level x is L-orthogonalised against the basis
//! and added: classical Gram–Schmidt twice ("twice is enough", Giraud et
//! al. 2005), the first pass with the coefficients qᵢᵀ L x = qᵢᵀ (b − r)
//! (r the solve's final residual, so no product with L), the second with
//! one product L q, which also gives the norm. Products are formed, not
//! carried along by subtraction: when x lies almost in the span its
//! remainder is tiny and a subtracted product would be all rounding. A
//! full basis restarts from the newest level alone, as Fischer's does.
//! The convergence test of the solve is untouched: the start only decides
//! how many iterations it takes to pass it.

use crate::la::iterative::DOT_CHUNK;
use rayon::prelude::*;

/// The kept basis, for one step size.
pub(super) struct Projection {
    /// At most this many basis vectors.
    capacity: usize,
    /// q₁…q_l on the free unknowns, L-orthonormal.
    basis: Vec<Vec<f64>>,
    /// qᵢᵀ b of the last right-hand side given to [`Projection::guess`],
    /// while the basis is the one that made it.
    coefficients: Vec<f64>,
    /// Vectors no longer in use, kept for the next additions.
    spare: Vec<Vec<f64>>,
    /// L q of the vector being added.
    product: Vec<f64>,
    /// The step size whose L the basis belongs to.
    dt: f64,
}

/// A remainder whose L-norm is below this fraction of the level's own
/// is rounding (the level was already in the span): it is not added.
const NEGLIGIBLE: f64 = 1e-12;

impl Projection {
    /// An empty basis of at most `capacity` vectors (at least one).
    pub(super) fn new(capacity: usize) -> Self {
        Self {
            capacity: capacity.max(1),
            basis: Vec::new(),
            coefficients: Vec::new(),
            spare: Vec::new(),
            product: Vec::new(),
            dt: f64::NAN,
        }
    }

    /// Vectors in the basis.
    #[cfg(test)]
    pub(super) fn len(&self) -> usize {
        self.basis.len()
    }

    /// Make the basis the one of step size `dt` (a new step size has a new
    /// L: its basis starts empty). Whether it holds any vector.
    pub(super) fn for_step(&mut self, dt: f64) -> bool {
        if self.dt != dt {
            self.clear();
            self.dt = dt;
        }
        !self.basis.is_empty()
    }

    fn clear(&mut self) {
        self.spare.append(&mut self.basis);
        self.coefficients.clear();
    }

    /// x̄ = Σ (qᵢᵀ b) qᵢ into `guess`; false (and `guess` untouched) when
    /// the basis is empty.
    pub(super) fn guess(&mut self, b: &[f64], guess: &mut [f64]) -> bool {
        if self.basis.is_empty() {
            return false;
        }
        self.coefficients = dots(&self.basis, b);
        combine(guess, &self.basis, &self.coefficients, None);
        true
    }

    /// Add the level x that solved L x = b with final residual r = b − L x
    /// (after [`guess`](Self::guess) with the same b); `multiply` is
    /// y = L x. The first vector of a basis needs no b and r (pass empty
    /// slices): its norm comes from the product.
    pub(super) fn add(
        &mut self,
        x: &[f64],
        b: &[f64],
        r: &[f64],
        multiply: &dyn Fn(&[f64], &mut [f64]),
    ) {
        if self.basis.len() >= self.capacity {
            self.clear();
        }
        let n = x.len();
        // First pass: qᵢᵀ L x = qᵢᵀ b − qᵢᵀ r.
        let qb = if self.coefficients.len() == self.basis.len() {
            std::mem::take(&mut self.coefficients)
        } else {
            dots(&self.basis, b)
        };
        let qr = dots(&self.basis, r);
        let betas: Vec<f64> = qb.iter().zip(&qr).map(|(b, r)| b - r).collect();
        let mut q = self.spare.pop().unwrap_or_default();
        q.resize(n, 0.0);
        combine(&mut q, &self.basis, &betas, Some(x));
        // Second pass, with the product itself.
        self.product.resize(n, 0.0);
        multiply(&q, &mut self.product);
        let gammas = dots(&self.basis, &self.product);
        let norm2 = crate::la::iterative::dot(&q, &self.product);
        // ‖q − Σγᵢqᵢ‖²_L = qᵀLq − Σγᵢ² for L-orthonormal qᵢ.
        let remainder2 = norm2 - gammas.iter().map(|g| g * g).sum::<f64>();
        // ‖x‖²_L = xᵀ(b − r); with no basis, the remainder is x itself.
        let level2 = if self.basis.is_empty() {
            norm2
        } else {
            crate::la::iterative::dot(x, b) - crate::la::iterative::dot(x, r)
        };
        self.coefficients.clear();
        if !(remainder2.is_finite() && level2.is_finite())
            || remainder2 <= NEGLIGIBLE * NEGLIGIBLE * level2.abs()
        {
            // x was in the span to rounding (or is zero): nothing new.
            self.spare.push(q);
            return;
        }
        let scale = 1.0 / remainder2.sqrt();
        let neg: Vec<f64> = gammas.iter().map(|g| g * scale).collect();
        let basis = &self.basis;
        q.par_chunks_mut(DOT_CHUNK)
            .enumerate()
            .for_each(|(chunk, q)| {
                let base = chunk * DOT_CHUNK;
                for (k, v) in q.iter_mut().enumerate() {
                    let i = base + k;
                    let mut s = *v * scale;
                    for (b, g) in basis.iter().zip(&neg) {
                        s -= g * b[i];
                    }
                    *v = s;
                }
            });
        self.basis.push(q);
    }
}

/// qᵢᵀ y for every vector of `basis`, in one pass over y; each sum is
/// taken in fixed chunks, so the bits do not depend on the threads.
fn dots(basis: &[Vec<f64>], y: &[f64]) -> Vec<f64> {
    let k = basis.len();
    if k == 0 {
        return Vec::new();
    }
    let partial: Vec<Vec<f64>> = y
        .par_chunks(DOT_CHUNK)
        .enumerate()
        .map(|(chunk, ys)| {
            let base = chunk * DOT_CHUNK;
            basis
                .iter()
                .map(|q| {
                    q[base..base + ys.len()]
                        .iter()
                        .zip(ys)
                        .map(|(a, b)| a * b)
                        .sum::<f64>()
                })
                .collect()
        })
        .collect();
    (0..k).map(|i| partial.iter().map(|p| p[i]).sum()).collect()
}

/// out = start − Σ cᵢ qᵢ when `start` is given, else Σ cᵢ qᵢ.
fn combine(out: &mut [f64], basis: &[Vec<f64>], c: &[f64], start: Option<&[f64]>) {
    out.par_chunks_mut(DOT_CHUNK)
        .enumerate()
        .for_each(|(chunk, out)| {
            let base = chunk * DOT_CHUNK;
            for (k, o) in out.iter_mut().enumerate() {
                let i = base + k;
                *o = match start {
                    Some(x) => basis.iter().zip(c).fold(x[i], |s, (q, c)| s - c * q[i]),
                    None => basis.iter().zip(c).map(|(q, c)| c * q[i]).sum(),
                };
            }
        });
}
