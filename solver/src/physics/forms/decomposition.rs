//! The discrete Hodge decomposition of a 1-cochain on a 2-complex,
//!
//! ```text
//!     ω = d α + ⋆₁⁻¹ d₁ᵀ γ + h,
//! ```
//!
//! exact, coexact and harmonic parts, ⋆-orthogonal to one another, by two
//! Poisson-type solves with canonical operators:
//!
//! - exact: d₀ᵀ ⋆₁ d₀ α = d₀ᵀ ⋆₁ ω on the vertices (A = d₀, Ω = ⋆₁; one
//!   vertex per component held at 0, the kernel being the constants);
//! - coexact: d₁ ⋆₁⁻¹ d₁ᵀ γ = d₁ ω on the faces (A = d₁ᵀ = ∂₂,
//!   Ω = ⋆₁⁻¹; one face per closed orientable component held at 0, the
//!   kernel being the 2-cycles), so that d₁ of the coexact part is d₁ ω;
//!   γ = ⋆₂ β for the 2-form β of δβ = ⋆₁⁻¹ d₁ᵀ ⋆₂ β;
//! - harmonic: what remains, h = ω − dα − ⋆₁⁻¹ d₁ᵀ γ, closed (d₁ h = 0)
//!   and co-closed (d₀ᵀ ⋆₁ h = 0) up to the solves' rounding.
//!
//! Orthogonality is an identity of the construction: ⟨dα, ⋆₁⁻¹d₁ᵀγ⟩_⋆ =
//! αᵀ (d₁ d₀)ᵀ γ = 0 in integers, and the other two pairs are the solves'
//! residuals. So ‖ω‖² = ‖dα‖² + ‖δβ‖² + ‖h‖² (Pythagoras) to rounding.
//! The coexact part divides by ⋆₁, so the star must be diagonal and
//! positive (the circumcentric one on a well-centred mesh, or the
//! barycentric one).
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

use super::cohomology::{multiply, top_cycles};
use super::{Forms, FormsError};
use crate::la::direct::{DirectSolver, Factorization};
use crate::la::fixed::FixedSplit;
use crate::operator::{BlockMetric, Canonical};

/// The three parts of a 1-cochain and their potentials.
#[derive(Clone, Debug, PartialEq)]
pub struct Decomposition {
    /// d α.
    pub exact: Vec<f64>,
    /// ⋆₁⁻¹ d₁ᵀ γ.
    pub coexact: Vec<f64>,
    /// ω minus the other two.
    pub harmonic: Vec<f64>,
    /// α on the vertices (0 at one vertex per component).
    pub potential: Vec<f64>,
    /// γ = ⋆₂ β on the faces (0 at one face per closed component).
    pub copotential: Vec<f64>,
}

impl Decomposition {
    /// The parts in the order exact, coexact, harmonic.
    pub fn parts(&self) -> [&[f64]; 3] {
        [&self.exact, &self.coexact, &self.harmonic]
    }
}

impl Forms<'_> {
    /// The Hodge decomposition of the 1-cochain `omega` on a 2-complex
    /// (module [`super::decomposition`]).
    pub fn hodge_decomposition(&self, omega: &[f64]) -> Result<Decomposition, FormsError> {
        let complex = self.complex;
        if complex.dim() != 2 {
            return Err(FormsError::Cohomology(format!(
                "the Hodge decomposition of 1-cochains is computed on 2-complexes (surfaces and planar domains); this complex has dimension {}",
                complex.dim()
            )));
        }
        let star = self.positive_diagonal(1, None, "the coexact part ⋆₁⁻¹ d₁ᵀ γ")?;
        let super::cohomology::ExactPart { potential, exact } = self
            .exact_part(1, &[omega.to_vec()])?
            .pop()
            .ok_or_else(|| FormsError::Internal("no exact part".into()))?;
        let faces = complex.cell_count(2);
        let mut pinned = vec![false; faces];
        for z in top_cycles(complex) {
            if let Some(first) = z.iter().position(|&s| s != 0) {
                pinned[first] = true;
            }
        }
        let split = FixedSplit::from_mask(pinned);
        let boundary = complex.boundary(2);
        let inverse: Vec<f64> = star.iter().map(|s| 1.0 / s).collect();
        let operator = Canonical::new(
            split.restrict_columns(boundary),
            BlockMetric::diagonal(&inverse),
        )?;
        let matrix = operator.assemble();
        let curl = multiply(complex.coboundary(1), omega);
        let rhs = split.restrict(&curl);
        let free = if split.free().is_empty() {
            Vec::new()
        } else {
            DirectSolver::analyze(matrix.as_ref(), Factorization::Llt)?
                .factorize(matrix.as_ref())?
                .solve(&rhs)?
        };
        let copotential = split.lift(&free, &[]);
        let coexact: Vec<f64> = multiply(boundary, &copotential)
            .iter()
            .zip(&inverse)
            .map(|(v, w)| v * w)
            .collect();
        let harmonic = omega
            .iter()
            .zip(&exact)
            .zip(&coexact)
            .map(|((w, e), c)| w - e - c)
            .collect();
        Ok(Decomposition {
            exact,
            coexact,
            harmonic,
            potential,
            copotential,
        })
    }
}
