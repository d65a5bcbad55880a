//! The Poisson problem for k-forms, Δ_k u = f with Δ_k = d δ + δ d, on
//! an n-complex with absolute (natural) or relative (essential) boundary
//! conditions.
//!
//! **Weak form.** With the pencil (K, M) of [`super::HodgeLaplacian`]
//! (K = d_kᵀ ⋆_{k+1} d_k + ⋆_k d_{k−1} ⋆_{k−1}⁻¹ d_{k−1}ᵀ ⋆_k for a
//! diagonal star; the symmetric mixed block matrix with σ = δu on the
//! (k−1)-cells for any star), the problem is K u = M f on the free
//! k-cells: both parts of the Laplacian, the curl–curl part d δ of the
//! upper degree and the grad–div part δ d of the lower one. M f is the
//! star of the whole cochain f read on the free rows: for essential
//! conditions the test cochains vanish on the boundary, the data need not.
//!
//! **Harmonic forms.** K is singular exactly on the harmonic k-forms ℌ,
//! β_k of them (absolute) or β_k(K, ∂K) (relative), and Δ_k u = f is
//! solvable only for f ⊥ ℌ. As in the mixed formulation of Arnold, Falk
//! and Winther (Acta Numerica 2006, §3.2, where a multiplier p ∈ ℌ takes
//! the harmonic part of f), the problem solved is
//!
//! ```text
//!     Δ_k u = f − P_ℌ f,     u ⊥ ℌ,     P_ℌ f = Σ_j ⟨f, h_j⟩ h_j,
//! ```
//!
//! h_j the basis of [`Forms::harmonic_basis_with`] made M-orthonormal.
//! P_ℌ f is returned ([`FormPoisson::source_harmonic`]) so a caller can say
//! how much of f was not in the range of Δ_k. The kernel is removed by a
//! gauge rather than by the multiplier's bordered system, whose dense
//! columns M h_j made the sparse LU fill in (33 s against 0.1 s on an
//! annulus of 16 000 edges): u is held at 0 on β k-cells where the
//! harmonic forms restricted are independent (complete pivoting), which
//! leaves a nonsingular system whose held equations hold by
//! compatibility; the harmonic part of that solution is then subtracted
//! (K h = 0, so it still solves the problem).
//!
//! **Solves.** The diagonal form is symmetric positive definite once the
//! kernel is held (LLᵀ); the mixed form is symmetric indefinite but has
//! no zero on its diagonal for k < n (−M_{k−1} on σ, d_kᵀM_{k+1}d_k on
//! u), so it is factored by LDLᵀ without pivoting, checked by its
//! residual, with sparse LU with partial pivoting as the fallback (and for
//! k = n, where the u block is zero). One step of iterative
//! refinement keeps the residual at rounding.

use super::cohomology::multiply_transpose;
use super::laplacian::HodgeLaplacian;
use super::{Boundary, Forms, FormsError};
use crate::la::direct::{DirectSolver, Factorization};
use crate::la::eigen::multiply;
use crate::la::fixed::FixedSplit;
use crate::operator::Canonical;
use sprs::CsMat;

/// Above this relative residual an LDLᵀ solve of the mixed form is not
/// trusted (rounding gives 1e-15 to 1e-14) and LU is used instead.
const LDLT_RESIDUAL: f64 = 1e-10;

/// The solution of Δ_k u = f.
#[derive(Clone, Debug, PartialEq)]
pub struct FormPoisson {
    /// The degree k.
    pub degree: usize,
    /// The boundary condition.
    pub boundary: Boundary,
    /// u on every k-cell (0 on the boundary's k-cells for essential
    /// conditions), ⋆-orthogonal to every harmonic k-form.
    pub solution: Vec<f64>,
    /// σ = δ_k u on every (k−1)-cell (the mixed form's unknown; ⋆_{k−1}⁻¹
    /// d_{k−1}ᵀ ⋆_k u for a diagonal star), 0 on the boundary's
    /// (k−1)-cells for essential conditions; empty for k = 0.
    pub codifferential: Vec<f64>,
    /// The harmonic part projected out of the source, Σ_j ⟨f, h_j⟩ h_j
    /// (zero when f ⊥ ℌ, e.g. when there are no harmonic forms).
    pub source_harmonic: Vec<f64>,
    /// The harmonic forms used as constraints, M-orthonormal.
    pub harmonic: Vec<Vec<f64>>,
    /// ‖b − A x‖₂ / ‖M f‖₂ of the solved system, b = M(f − P_ℌ f) on the
    /// free rows (0 for f = 0).
    pub residual: f64,
    /// The factorisation used.
    pub factorization: Factorization,
    /// Size of the solved system (σ and u, less the gauge's held cells).
    pub unknowns: usize,
}

impl Forms<'_> {
    /// Solve Δ_k u = f for the k-cochain `source` = f (e.g. the de Rham
    /// cochain of a field, [`super::whitney_map::de_rham`]) with the
    /// boundary condition `boundary` (module docs).
    ///
    /// ```
    /// use hasse_complex::{dual::DualKind, generate::rectangle};
    /// use hasse_solver::physics::forms::whitney_map::{de_rham, Field};
    /// use hasse_solver::physics::forms::{Boundary, Forms, Star};
    /// use std::f64::consts::PI;
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// // u = ∇(cos πx cos πy) on the unit square: u·n = 0 and curl u = 0
    /// // on the boundary (absolute conditions) and Δ₁u = 2π² u.
    /// let k = rectangle(16, 16, [0.0, 1.0], [0.0, 1.0])?;
    /// let u = |p: &[f64]| [-PI * (PI * p[0]).sin() * (PI * p[1]).cos(),
    ///                      -PI * (PI * p[0]).cos() * (PI * p[1]).sin(), 0.0];
    /// let f = de_rham(&k, 1, Field::Vector(&|p| u(p).map(|c| 2.0 * PI * PI * c)))?;
    /// let forms = Forms::new(&k, Star::Diagonal(DualKind::Barycentric));
    /// let solved = forms.poisson(1, Boundary::Natural, &f)?;
    /// let exact = de_rham(&k, 1, Field::Vector(&u))?;
    /// let error: Vec<f64> = solved.solution.iter().zip(&exact).map(|(a, b)| a - b).collect();
    /// let relative = (forms.inner(1, &error, &error)? / forms.inner(1, &exact, &exact)?).sqrt();
    /// assert!(relative < 1e-2);
    /// # Ok(())
    /// # }
    /// ```
    pub fn poisson(
        &self,
        k: usize,
        boundary: Boundary,
        source: &[f64],
    ) -> Result<FormPoisson, FormsError> {
        self.check(k)?;
        let complex = self.complex;
        let cells = complex.cell_count(k);
        if source.len() != cells {
            return Err(FormsError::Field(format!(
                "a {k}-cochain needs {cells} values (one per {k}-cell), got {}",
                source.len()
            )));
        }
        let laplacian = self.hodge_laplacian(k, boundary)?;
        let free = laplacian.free_cells().to_vec();
        let sigma = laplacian.stiffness().nrows() - free.len();
        let size = sigma + free.len();
        let mass = Canonical::new(CsMat::<i8>::eye(cells), self.star(k)?)?;
        let harmonic = self.constraint_forms(k, boundary, &laplacian)?;
        // f = (f − Σ ⟨f, h_j⟩ h_j) + Σ ⟨f, h_j⟩ h_j: only the first part is
        // in the range of Δ_k.
        let mut source_harmonic = vec![0.0; cells];
        for h in &harmonic {
            let p = self.inner(k, source, h)?;
            source_harmonic
                .iter_mut()
                .zip(h)
                .for_each(|(s, v)| *s += p * v);
        }
        let compatible: Vec<f64> = source
            .iter()
            .zip(&source_harmonic)
            .map(|(f, h)| f - h)
            .collect();
        let mf = mass.apply(&compatible);
        let rhs: Vec<f64> = std::iter::repeat_n(0.0, sigma)
            .chain(free.iter().map(|&c| mf[c]))
            .collect();
        // The gauge: u held at 0 on β cells where the harmonic forms are
        // independent, which removes the kernel.
        let held = gauge_cells(&harmonic, &free);
        let split =
            FixedSplit::from_mask((0..size).map(|i| i >= sigma && held.contains(&(i - sigma))));
        let matrix = laplacian.stiffness_matrix();
        let reduced = split.free_block(matrix);
        let residual_of = |x: &[f64]| -> Vec<f64> {
            let ax = multiply(matrix.as_ref(), x);
            rhs.iter().zip(ax).map(|(b, a)| b - a).collect()
        };
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        // Relative to the whole source's load M f: the compatible part can
        // be 0 (a harmonic source), and the residual is then rounding of f.
        let load = mass.apply(source);
        let scale = norm(&free.iter().map(|&c| load[c]).collect::<Vec<_>>());
        let relative = |x: &[f64]| {
            if scale > 0.0 {
                norm(&residual_of(x)) / scale
            } else {
                0.0
            }
        };
        let solve = |kind: Factorization| -> Result<Vec<f64>, FormsError> {
            let factor =
                DirectSolver::analyze(reduced.as_ref(), kind)?.factorize(reduced.as_ref())?;
            let mut x = split.lift(&factor.solve(&split.restrict(&rhs))?, &[]);
            let correction = split.lift(&factor.solve(&split.restrict(&residual_of(&x)))?, &[]);
            x.iter_mut().zip(correction).for_each(|(a, c)| *a += c);
            Ok(x)
        };
        let (mut x, factorization) = if sigma == 0 {
            (solve(Factorization::Llt)?, Factorization::Llt)
        } else if k == complex.dim() {
            // No (k+1)-cells: the u block is zero and LDLᵀ would meet zero
            // pivots.
            (solve(Factorization::Lu)?, Factorization::Lu)
        } else {
            // LDLᵀ without pivoting first: every diagonal entry of the
            // mixed matrix is nonzero for k < n (−M_{k−1} < 0 on σ,
            // d_kᵀM_{k+1}d_k > 0 on a k-cell with a coface), and it was 3.7× faster than LU
            // on a 16³ Kuhn box (3.9 s against 14.5 s, 36 000 unknowns) with
            // the same residual; a zero or tiny pivot shows as a failed
            // factorisation or a large residual, and LU takes over.
            match solve(Factorization::Ldlt) {
                Ok(x) if relative(&x) < LDLT_RESIDUAL => (x, Factorization::Ldlt),
                _ => (solve(Factorization::Lu)?, Factorization::Lu),
            }
        };
        let mut solution = vec![0.0; cells];
        for (r, &cell) in free.iter().enumerate() {
            solution[cell] = x[sigma + r];
        }
        // The gauge's solution differs from the one ⊥ ℌ by a harmonic form.
        for h in &harmonic {
            let c = self.inner(k, &solution, h)?;
            solution.iter_mut().zip(h).for_each(|(u, v)| *u -= c * v);
        }
        for (r, &cell) in free.iter().enumerate() {
            x[sigma + r] = solution[cell];
        }
        let residual = relative(&x);
        let codifferential = self.codifferential_of(k, boundary, &solution, &x[..sigma])?;
        Ok(FormPoisson {
            degree: k,
            boundary,
            solution,
            codifferential,
            source_harmonic,
            harmonic,
            residual,
            factorization,
            unknowns: split.free().len(),
        })
    }

    /// The harmonic k-forms of the boundary condition, M-orthonormal
    /// (modified Gram–Schmidt in the star inner product); refused when
    /// their count is not the Betti number, as the system would then be
    /// singular.
    fn constraint_forms(
        &self,
        k: usize,
        boundary: Boundary,
        laplacian: &HodgeLaplacian,
    ) -> Result<Vec<Vec<f64>>, FormsError> {
        if laplacian.betti() == 0 {
            return Ok(Vec::new());
        }
        let basis = self.harmonic_basis_with(k, boundary)?;
        if basis.forms.len() != laplacian.betti() {
            return Err(FormsError::Cohomology(format!(
                "{} harmonic {k}-forms were found but the Betti number is {}: Δ_{k} u = f cannot be made well posed (a non-manifold or non-orientable complex?)",
                basis.forms.len(),
                laplacian.betti()
            )));
        }
        let mut orthonormal: Vec<Vec<f64>> = Vec::with_capacity(basis.forms.len());
        for mut h in basis.forms {
            for q in &orthonormal {
                let c = self.inner(k, &h, q)?;
                h.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
            }
            let norm = self.inner(k, &h, &h)?.sqrt();
            if !(norm > 0.0 && norm.is_finite()) {
                return Err(FormsError::Cohomology(format!(
                    "the harmonic {k}-forms are linearly dependent in the star inner product"
                )));
            }
            h.iter_mut().for_each(|a| *a /= norm);
            orthonormal.push(h);
        }
        Ok(orthonormal)
    }

    /// σ = δ_k u on every (k−1)-cell: the mixed solve's σ lifted from the
    /// free (k−1)-cells, or ⋆_{k−1}⁻¹ d_{k−1}ᵀ ⋆_k u on the free ones for a
    /// diagonal star.
    fn codifferential_of(
        &self,
        k: usize,
        boundary: Boundary,
        u: &[f64],
        mixed_sigma: &[f64],
    ) -> Result<Vec<f64>, FormsError> {
        if k == 0 {
            return Ok(Vec::new());
        }
        let lower = HodgeLaplacian::splits(self, k, boundary)?
            .1
            .ok_or_else(|| FormsError::Internal("no (k−1)-cells for k ≥ 1".into()))?;
        if !mixed_sigma.is_empty() {
            return Ok(lower.lift(mixed_sigma, &[]));
        }
        let star_lower = self.positive_diagonal(k - 1, Some(lower.free()), "δ_k u = ⋆⁻¹ dᵀ ⋆ u")?;
        let star_u = self.star(k)?.apply(u);
        let t = multiply_transpose(self.complex.coboundary(k - 1), &star_u);
        let mut sigma = vec![0.0; t.len()];
        for &c in lower.free() {
            sigma[c] = t[c] / star_lower[c];
        }
        Ok(sigma)
    }
}

/// β cells, one per harmonic form, on which the forms restricted are
/// independent: Gaussian elimination with complete pivoting over the free
/// cells (the largest remaining entry of each form, after the earlier
/// pivots are eliminated from it). Holding u = 0 there removes the kernel
/// of Δ_k: a harmonic form vanishing on them is zero.
fn gauge_cells(harmonic: &[Vec<f64>], free: &[usize]) -> Vec<usize> {
    let mut rows: Vec<Vec<f64>> = harmonic
        .iter()
        .map(|h| free.iter().map(|&c| h[c]).collect())
        .collect();
    let mut held = Vec::with_capacity(rows.len());
    for j in 0..rows.len() {
        let (pivot, _) = rows[j]
            .iter()
            .enumerate()
            .fold(
                (0, 0.0f64),
                |(b, m), (i, v)| if v.abs() > m { (i, v.abs()) } else { (b, m) },
            );
        let (done, rest) = rows.split_at_mut(j + 1);
        let row = &done[j];
        for other in rest {
            let factor = other[pivot] / row[pivot];
            other
                .iter_mut()
                .zip(row)
                .for_each(|(a, b)| *a -= factor * b);
        }
        held.push(pivot);
    }
    held.sort_unstable();
    held
}
