//! Relative cohomology Hᵏ(K, ∂K) of every degree: cochains that vanish on
//! the boundary subcomplex ∂K (the (n−1)-cells with one coface and all
//! their faces, [`Complex::boundary_subcomplex`]), with the coboundary δᵏ
//! restricted to the cells off it.
//!
//! The relative cochain complex is C^p(K, ∂K) = cochains on the interior
//! p-cells, δᵖ_rel = δᵖ with its columns and rows restricted to interior
//! cells. Dropping the rows of boundary (p+1)-cells loses nothing: an
//! interior p-cell is not a face of a boundary (p+1)-cell (∂K is closed
//! under faces), so those rows are zero in the interior columns. A
//! relative cocycle extended by 0 on ∂K is then an ordinary cocycle that
//! vanishes on ∂K exactly.
//!
//! The generators are the integer column reduction of these matrices (the
//! same code as the absolute generators, `reduction.rs`): closed exactly
//! in integers, independent modulo relative exact forms δ^{k−1}_rel α, and
//! β_k(K, ∂K) of them. On an orientable n-manifold with boundary Lefschetz
//! duality gives β_k(K, ∂K) = β_{n−k}(K) (the annulus: (0, 1, 1); a box:
//! zero but 1 in degree n; a box with a cavity: (0, 1, 0, 1)).
//!
//! ```
//! use hasse_complex::generate::hollow_box;
//! use hasse_solver::physics::forms::relative_cocycle_generators;
//! // A box with a cavity (β = 1, 0, 1, 0): β₁(K, ∂K) = β₂(K) = 1, the
//! // class of a path from the cavity to the outer surface.
//! let k = hollow_box(3, [1, 2])?;
//! let generators = relative_cocycle_generators(&k, 1)?;
//! assert_eq!(generators.len(), 1);
//! // It vanishes on the boundary's edges.
//! let wall = k.boundary_subcomplex();
//! assert!((0..k.cell_count(1)).all(|e| !wall.contains(1, e) || generators[0][e] == 0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use super::reduction::{self, Coboundaries};
use super::FormsError;
use crate::la::fixed::FixedSplit;
use hasse_complex::Complex;
use sprs::CsMat;

/// Per p-cell, whether it lies on the boundary subcomplex ∂K.
pub(super) fn wall_mask(complex: &Complex, p: usize) -> Vec<bool> {
    let wall = complex.boundary_subcomplex();
    (0..complex.cell_count(p))
        .map(|i| wall.contains(p, i))
        .collect()
}

/// The relative cochain complex: the interior cells of every degree (free
/// in a [`FixedSplit`], boundary cells fixed) and δ⁰_rel … δⁿ_rel.
struct RelativeComplex {
    cells: Vec<FixedSplit>,
    deltas: Coboundaries,
}

impl RelativeComplex {
    fn new(complex: &Complex) -> Self {
        let n = complex.dim();
        let wall = complex.boundary_subcomplex();
        let cells: Vec<FixedSplit> = (0..=n)
            .map(|p| FixedSplit::from_mask((0..complex.cell_count(p)).map(|i| wall.contains(p, i))))
            .collect();
        let matrices = (0..=n)
            .map(|p| {
                if p == n {
                    CsMat::zero((0, cells[n].free().len()))
                } else {
                    cells[p + 1].restrict_rows(&cells[p].restrict_columns(complex.coboundary(p)))
                }
            })
            .collect();
        Self {
            cells,
            deltas: Coboundaries::new(matrices),
        }
    }
}

/// The integer cocycles of a basis of Hᵏ(K, ∂K; Q), every degree k ≤ n and
/// any complex, as k-cochains on all k-cells (exactly 0 on ∂K): the
/// integer reduction of the relative coboundaries (see the module docs),
/// each checked closed in integers. On a complex without boundary these
/// are the absolute generators of the reduction.
///
/// A lift that is not closed in integers (torsion, a non-orientable
/// complex) is the typed error [`FormsError::Cohomology`], never a wrong
/// generator.
pub fn relative_cocycle_generators(
    complex: &Complex,
    k: usize,
) -> Result<Vec<Vec<f64>>, FormsError> {
    let n = complex.dim();
    if k > n {
        return Err(FormsError::Degree { degree: k, dim: n });
    }
    let relative = RelativeComplex::new(complex);
    let cells = &relative.cells[k];
    Ok(reduction::cocycles_of(&relative.deltas, k)?
        .iter()
        .map(|z| cells.lift(z, &[]))
        .collect())
}

/// The (k−1)-cells (k ≥ 1) where the potential α of a relative exact part
/// is held at 0: the boundary's, and the interior ones whose columns of
/// δ^{k−1}_rel depend on earlier columns. The rest are a basis of
/// im δ^{k−1}_rel, so d_{k−1}ᵀ ⋆ d_{k−1} on them is definite and reaches
/// every relative exact form.
pub(super) fn relative_gauge(complex: &Complex, k: usize) -> Result<Vec<bool>, FormsError> {
    let n = complex.dim();
    if k == 0 || k > n {
        return Err(FormsError::Degree { degree: k, dim: n });
    }
    let relative = RelativeComplex::new(complex);
    let lower = &relative.cells[k - 1];
    let independent = reduction::exact_gauge_of(&relative.deltas, k)?;
    let mut pinned = vec![true; complex.cell_count(k - 1)];
    for (&cell, basis) in lower.free().iter().zip(independent) {
        pinned[cell] = !basis;
    }
    Ok(pinned)
}
