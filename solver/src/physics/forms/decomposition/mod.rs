//! The discrete Hodge decomposition of a k-cochain ω on an n-complex
//! (0 ≤ k ≤ n), absolute (natural) conditions:
//!
//! ```text
//!     ω = d α + q + h,     q = M_k⁻¹ d_kᵀ γ  (= δβ with γ = M_{k+1} β),
//! ```
//!
//! exact, coexact and harmonic parts, mutually orthogonal in the star (mass)
//! inner product ⟨a, b⟩ = aᵀ M_k b, where M = ⋆ is the diagonal DEC star or
//! the Whitney (Galerkin) mass, one dense block per top simplex.
//!
//! - **exact**: d_{k−1}ᵀ M_k d_{k−1} α = d_{k−1}ᵀ M_k ω on the (k−1)-cells,
//!   the canonical operator A = d_{k−1}, Ω = M_k ([`Forms::exact_part`],
//!   with its gauge: one vertex per component for k = 1, a basis of
//!   im d_{k−1} for k ≥ 2). It needs no inverse of M, so it is the same
//!   code for both stars.
//! - **coexact**: the part q of ω with d_k q = d_k ω that is orthogonal to
//!   every closed k-cochain, i.e. q = M_k⁻¹ d_kᵀ γ. Its unknown is
//!   γ = M_{k+1} β on the (k+1)-cells (see [`coexact`] for the two ways
//!   it is solved: eliminated with ⋆_k⁻¹ for a diagonal star, a mixed
//!   saddle-point block system for any star).
//! - **harmonic**: what remains, h = ω − dα − q: closed (d_k h = d_k ω −
//!   d_k q = 0) and co-closed (d_{k−1}ᵀ M_k h = 0 by the exact solve).
//!
//! **The ends.** For k = 0 there is no (−1)-cochain, so the exact part is
//! zero and ω = q + h, h the locally constant 0-cochain whose value on a
//! component is the ⋆₀-mean of ω there (the harmonic 0-forms are the
//! constants per component) and q the rest, of ⋆₀-mean zero. For k = n
//! there is no (n+1)-cochain, so the coexact part is zero and ω = dα + h,
//! h nonzero only on closed orientable components (a multiple of the
//! volume form M_n⁻¹ z per component, z its top cycle); on a component
//! with boundary every n-cochain is exact.
//!
//! **Boundary conditions** (absolute, what the discrete spaces impose
//! weakly): α is free on the boundary (the exact part is the Neumann
//! projection ∇α with ∂α/∂n = ω·n for k = 1); γ is free on every
//! (k+1)-cell, which makes the coexact part's weak form ⟨q, v⟩ = ⟨β, d v⟩
//! hold for all v, i.e. β has zero tangential trace: for k = 1 in 2D,
//! q = curl ψ with ψ = 0 on the boundary (q·n = 0), in 3D q = curl A with
//! A × n = 0; and the harmonic part has zero normal component (h·n = 0)
//! and represents the absolute cohomology Hᵏ(K).
//!
//! **Orthogonality** is an identity of the construction up to the solves'
//! residuals: ⟨dα, q⟩ = αᵀ d_{k−1}ᵀ d_kᵀ γ = αᵀ (d_k d_{k−1})ᵀ γ = 0 in
//! integers (given M q = dᵀγ, exact in the eliminated form, a residual of
//! the mixed one); ⟨dα, h⟩ is the exact solve's residual; ⟨q, h⟩ =
//! γᵀ (d_k ω − d_k q) is the coexact solve's residual (d d α = 0 exactly).
//! So ‖ω‖² = ‖dα‖² + ‖q‖² + ‖h‖² (Pythagoras) to rounding; each solve takes
//! one step of iterative refinement to keep those residuals at rounding.
//!
//! ```
//! use hasse_complex::{dual::DualKind, generate::sphere};
//! use hasse_solver::physics::forms::whitney_map::{de_rham, Field};
//! use hasse_solver::physics::forms::{Forms, Star};
//! let k = sphere(1.0, 2).unwrap();
//! let forms = Forms::new(&k, Star::Diagonal(DualKind::Circumcentric));
//! let omega = de_rham(&k, 1, Field::Vector(&|p| [1.0 - p[1], p[0] + p[2], 0.5])).unwrap();
//! let parts = forms.hodge_decomposition(&omega).unwrap();
//! // The sphere has no harmonic 1-forms, and the parts add up to ω.
//! assert!(parts.harmonic.iter().all(|h| h.abs() < 1e-12));
//! let sum: f64 = [&parts.exact, &parts.coexact].iter().map(|p| forms.inner(1, p, p).unwrap()).sum();
//! assert!((sum - forms.inner(1, &omega, &omega).unwrap()).abs() < 1e-12 * sum);
//! ```

pub mod coexact;

pub use coexact::CoexactSolve;

use super::{Forms, FormsError};

/// The three parts of a k-cochain and their potentials.
#[derive(Clone, Debug, PartialEq)]
pub struct Decomposition {
    /// The degree k.
    pub degree: usize,
    /// d α (zero for k = 0).
    pub exact: Vec<f64>,
    /// q = M_k⁻¹ d_kᵀ γ (zero for k = n).
    pub coexact: Vec<f64>,
    /// ω minus the other two.
    pub harmonic: Vec<f64>,
    /// α on the (k−1)-cells (0 on the gauge's held cells; empty for k = 0).
    pub potential: Vec<f64>,
    /// γ = M_{k+1} β on the (k+1)-cells (0 on the gauge's held cells;
    /// empty for k = n).
    pub copotential: Vec<f64>,
}

impl Decomposition {
    /// The parts in the order exact, coexact, harmonic.
    pub fn parts(&self) -> [&[f64]; 3] {
        [&self.exact, &self.coexact, &self.harmonic]
    }
}

impl Forms<'_> {
    /// The Hodge decomposition of the 1-cochain `omega`:
    /// [`Forms::decompose`] with k = 1.
    pub fn hodge_decomposition(&self, omega: &[f64]) -> Result<Decomposition, FormsError> {
        self.decompose(1, omega)
    }

    /// The Hodge decomposition of the k-cochain `omega` (module
    /// [`super::decomposition`]), the coexact part solved by
    /// [`CoexactSolve::Auto`]: eliminated for a diagonal star, mixed for
    /// the Whitney mass.
    ///
    /// ```
    /// use hasse_complex::generate::{kuhn, uniform_axis};
    /// use hasse_solver::physics::forms::whitney_map::{de_rham, Field};
    /// use hasse_solver::physics::forms::{Forms, Star};
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let x = uniform_axis(3, 0.0, 1.0)?;
    /// let k = kuhn(&[x.clone(), x.clone(), x])?;
    /// let forms = Forms::new(&k, Star::Whitney);
    /// // The flux of a gradient through the faces: a 2-form with d ω = 0
    /// // wherever div F = 0; here F = ∇(x² − y²), harmonic, so ω is closed.
    /// let omega = de_rham(&k, 2, Field::Vector(&|p| [2.0 * p[0], -2.0 * p[1], 0.0]))?;
    /// let parts = forms.decompose(2, &omega)?;
    /// // Closed: the coexact part (the one d sees) vanishes.
    /// let scale = omega.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    /// assert!(parts.coexact.iter().all(|q| q.abs() < 1e-12 * scale));
    /// # Ok(())
    /// # }
    /// ```
    pub fn decompose(&self, k: usize, omega: &[f64]) -> Result<Decomposition, FormsError> {
        self.decompose_with(k, omega, CoexactSolve::Auto)
    }

    /// [`Forms::decompose`] with a choice of coexact solve (the mixed one
    /// also works with a diagonal star, where it must agree with the
    /// eliminated one).
    pub fn decompose_with(
        &self,
        k: usize,
        omega: &[f64],
        solve: CoexactSolve,
    ) -> Result<Decomposition, FormsError> {
        self.check(k)?;
        let complex = self.complex;
        let n = complex.dim();
        let cells = complex.cell_count(k);
        if omega.len() != cells {
            return Err(FormsError::Field(format!(
                "a {k}-cochain needs {cells} values (one per {k}-cell), got {}",
                omega.len()
            )));
        }
        let (potential, exact) = if k == 0 {
            (Vec::new(), vec![0.0; cells])
        } else {
            let super::ExactPart { potential, exact } = self
                .exact_part(k, &[omega.to_vec()])?
                .pop()
                .ok_or_else(|| FormsError::Internal("no exact part".into()))?;
            (potential, exact)
        };
        let (copotential, coexact) = if k == n {
            (Vec::new(), vec![0.0; cells])
        } else {
            self.coexact_part(k, omega, solve)?
        };
        let harmonic = omega
            .iter()
            .zip(&exact)
            .zip(&coexact)
            .map(|((w, e), c)| w - e - c)
            .collect();
        Ok(Decomposition {
            degree: k,
            exact,
            coexact,
            harmonic,
            potential,
            copotential,
        })
    }
}
