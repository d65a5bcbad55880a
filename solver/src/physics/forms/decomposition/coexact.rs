//! The coexact part q = M_k⁻¹ d_kᵀ γ of a k-cochain ω (k < n): the part
//! with d_k q = d_k ω that is M_k-orthogonal to every closed k-cochain.
//!
//! The unknown is γ = M_{k+1} β on the (k+1)-cells rather than β itself.
//! The saddle-point system of the issue, [[M_k, −d_kᵀ M_{k+1}],
//! [M_{k+1} d_k, 0]] (q, β) = (0, M_{k+1} d_k ω), becomes with that change
//! of variable and its second row multiplied by −M_{k+1}⁻¹ (both
//! invertible, so the solutions (q, β) ↔ (q, γ) correspond one to one)
//!
//! ```text
//!     [ M_k     −d_kᵀ ] [q]   [    0     ]
//!     [ −d_k     0    ] [γ] = [ −d_k ω   ],
//! ```
//!
//! symmetric, with integer off-diagonal blocks: the coupling is the
//! canonical block d_kᵀ (−I) E (A = d_k, Ω = −I, B = E the free
//! (k+1)-cells). Two reasons for γ: the second row needs no M_{k+1} at
//! all, and the kernel of the system, {γ : d_kᵀ γ = 0} = Z_{k+1} (the
//! (k+1)-cycles), is then a topological space, independent of the star,
//! so the gauge that removes it is a choice of cells made in integers (a
//! kernel β ∈ M_{k+1}⁻¹ Z_{k+1} would depend on the metric, and holding β
//! at zero on a fixed set of cells need not remove it for a non-diagonal
//! M_{k+1}).
//!
//! **Gauge.** γ is held at 0 off a set S of (k+1)-cells whose columns of
//! ∂_{k+1} = d_kᵀ are a basis of im ∂_{k+1}: then d_kᵀ restricted to S is
//! injective (no kernel left) with the same image (q, and so the
//! decomposition, unchanged). S is found by the integer column reduction
//! of ∂_{k+1} (the one `reduction.rs` uses for cohomology; a column is
//! kept when it is independent of the earlier ones), with clearing from
//! the degrees above: a (k+1)-cell that is the low of a reduced column of
//! ∂_{k+2} has a column of ∂_{k+1} that depends on earlier ones (that
//! reduced column is a cycle whose last cell it is), so it is skipped. For
//! k + 1 = n the kernel is one top cycle per closed orientable component
//! and one cell per such component is held (as the 2D code always did).
//! A Lagrange multiplier would keep every cell free but add one unknown
//! per kernel vector, and in 3D for k < 2 the kernel holds every
//! (k+1)-boundary, about as many vectors as there are (k+2)-cells.
//!
//! **Solves.** With a diagonal, positive ⋆_k the first row is eliminated:
//! q = ⋆_k⁻¹ d_kᵀ γ and d_k ⋆_k⁻¹ d_kᵀ γ = d_k ω, the canonical operator
//! A = ∂_{k+1} E, Ω = ⋆_k⁻¹, factored by LLᵀ ([`CoexactSolve::Eliminated`]).
//! Otherwise (the Whitney mass, or on request) the block system above is
//! factored whole by sparse LU with partial pivoting and never inverts
//! M_k ([`CoexactSolve::Mixed`]). Both take one step of iterative
//! refinement on their residual.

use super::super::cohomology::{multiply, multiply_transpose, top_cycles};
use super::super::reduction::reduce;
use super::super::{Forms, FormsError};
use crate::la::direct::{DirectSolver, Factorization};
use crate::la::fixed::FixedSplit;
use crate::operator::block::{Block, BlockSystem, Symmetry};
use crate::operator::{BlockMetric, Canonical};
use hasse_complex::Complex;
use sprs::CsMat;

/// How the coexact part is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoexactSolve {
    /// Eliminated for a diagonal star, mixed for the Whitney mass.
    Auto,
    /// d_k ⋆_k⁻¹ d_kᵀ γ = d_k ω; needs a diagonal star, positive on every
    /// k-cell.
    Eliminated,
    /// The saddle-point block system [[M_k, −d_kᵀ], [−d_k, 0]] by sparse
    /// LU; any star.
    Mixed,
}

/// The (k+1)-cells where γ is held at 0 (module docs, "Gauge").
pub(crate) fn coexact_gauge(complex: &Complex, k: usize) -> Result<Vec<bool>, FormsError> {
    let n = complex.dim();
    let up = k + 1;
    if up == n {
        let mut held = vec![false; complex.cell_count(n)];
        for z in top_cycles(complex) {
            if let Some(first) = z.iter().position(|&s| s != 0) {
                held[first] = true;
            }
        }
        return Ok(held);
    }
    let mut skip: Vec<bool> = Vec::new();
    for p in (up..=n).rev() {
        let reduction = reduce(complex.boundary(p), complex.cell_count(p - 1), &skip, false)?;
        if p == up {
            return Ok(reduction.independent.iter().map(|&i| !i).collect());
        }
        skip = reduction.paired;
    }
    Err(FormsError::Internal(format!(
        "no gauge for the coexact part of degree {k} on a {n}-complex"
    )))
}

fn subtract(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

impl Forms<'_> {
    /// (γ on the (k+1)-cells, q on the k-cells) for k < n.
    pub(super) fn coexact_part(
        &self,
        k: usize,
        omega: &[f64],
        solve: CoexactSolve,
    ) -> Result<(Vec<f64>, Vec<f64>), FormsError> {
        let complex = self.complex;
        let split = FixedSplit::from_mask(coexact_gauge(complex, k)?);
        let d = complex.coboundary(k);
        let curl = multiply(d, omega);
        let cells = complex.cell_count(k);
        if split.free().is_empty() {
            // im d_kᵀ = 0: every k-cochain is closed and q = 0.
            return Ok((vec![0.0; complex.cell_count(k + 1)], vec![0.0; cells]));
        }
        let mixed = match solve {
            CoexactSolve::Auto => !self.star.is_diagonal(),
            CoexactSolve::Eliminated => false,
            CoexactSolve::Mixed => true,
        };
        if !mixed {
            let star = self.positive_diagonal(k, None, "the coexact part ⋆_k⁻¹ d_kᵀ γ")?;
            let inverse: Vec<f64> = star.iter().map(|s| 1.0 / s).collect();
            let boundary = complex.boundary(k + 1);
            let operator = Canonical::new(
                split.restrict_columns(boundary),
                BlockMetric::diagonal(&inverse),
            )?;
            let matrix = operator.assemble();
            let factor = DirectSolver::analyze(matrix.as_ref(), Factorization::Llt)?
                .factorize(matrix.as_ref())?;
            let coexact_of = |gamma: &[f64]| -> Vec<f64> {
                multiply(boundary, gamma)
                    .iter()
                    .zip(&inverse)
                    .map(|(v, w)| v * w)
                    .collect()
            };
            let mut free = factor.solve(&split.restrict(&curl))?;
            // Refinement on d_k (ω − q), whose held rows are combinations
            // of the free ones (as in the exact part).
            let q = coexact_of(&split.lift(&free, &[]));
            let residual = split.restrict(&subtract(&curl, &multiply(d, &q)));
            let correction = factor.solve(&residual)?;
            free.iter_mut().zip(correction).for_each(|(a, c)| *a += c);
            let gamma = split.lift(&free, &[]);
            let q = coexact_of(&gamma);
            return Ok((gamma, q));
        }
        let free = split.free().len();
        let up = complex.cell_count(k + 1);
        let mass = Canonical::new(CsMat::<i8>::eye(cells), self.star(k)?)?;
        // −d_kᵀ E as Aᵀ Ω B: A = d_k, Ω = −I on the (k+1)-cells, B = E.
        let coupling =
            Canonical::coupling(d, BlockMetric::diagonal(&vec![-1.0; up]), split.selection())?;
        let mut system = BlockSystem::new(
            &[cells, free],
            Symmetry::Symmetric,
            vec![
                (0, 0, Block::Canonical(mass.clone())),
                (0, 1, Block::Canonical(coupling)),
            ],
        )?;
        // LU with partial pivoting: faer's LBLᵀ pivots only inside a
        // supernode, and the fill-reducing ordering puts γ unknowns (zero
        // diagonal) where no partner is at hand: it reported a singular
        // pivot on every mesh tried, while the system is not singular.
        let factor = system.factorize(Factorization::Lu)?;
        let rhs: Vec<f64> = std::iter::repeat_n(0.0, cells)
            .chain(split.restrict(&curl).iter().map(|v| -v))
            .collect();
        // K x for x = (q, γ_E): (M q − d_kᵀ γ, −E ᵀ d_k q).
        let apply = |x: &[f64]| -> Vec<f64> {
            let (q, gamma) = x.split_at(cells);
            let top = subtract(
                &mass.apply(q),
                &multiply_transpose(d, &split.lift(gamma, &[])),
            );
            let bottom = split.restrict(&multiply(d, q));
            top.into_iter().chain(bottom.iter().map(|v| -v)).collect()
        };
        let mut x = factor.solve(&rhs)?;
        let correction = factor.solve(&subtract(&rhs, &apply(&x)))?;
        x.iter_mut().zip(correction).for_each(|(a, c)| *a += c);
        let (q, gamma) = x.split_at(cells);
        Ok((split.lift(gamma, &[]), q.to_vec()))
    }
}
