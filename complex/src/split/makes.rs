//! The SPLIT of one top cell as a composition of Euler make operators β
//! ([`crate::euler::make`]), so that its chain map ζ is the product of the
//! makes' ζ: the Euler algebra's own account of a hyperplane cut.
//!
//! Bottom-up, as the thesis's classification chains go (§4.5): the vertex
//! classes c₀ = sgn(h·x − b) (with the snap rule of
//! [`vertex_classes`](super::vertex_classes)); every edge of the cell's
//! closure with vertices on both sides is split by β⁰ (the new vertex has
//! class 0, the appended half is the positive one); then every polygon of
//! the closure that straddles the plane by β¹, its facets on the positive
//! side moving to the appended piece; in 3D then the cell itself by β²
//! the same way. Within a dimension cells are taken in index order, which
//! is the order in which SPLIT appends their pieces and cut cells: the
//! result has SPLIT's numbering. Orientations differ where SPLIT re-orients
//! a new cell by the complex's conventions (an edge from its lower to its
//! higher vertex), while a make orients every piece like its parent.
//!
//! [`split`](super::split) itself does not go through this path; the tests
//! compare both.

use super::{vertex_classes, Hyperplane};
use crate::complex::Complex;
use crate::error::SplitError;
use crate::euler::make;
use sprs::CsMat;
use std::collections::BTreeSet;

/// The boundaries after the makes of a one-cell SPLIT, the composed chain
/// map and the makes applied.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::split::{split_by_makes, Hyperplane};
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let made = split_by_makes(&k, 0, &Hyperplane::axis(2, 0, 0.5).unwrap(), 1e-6).unwrap();
/// // β⁰ on the bottom and top sides, then β¹ on the square.
/// assert_eq!(made.makes, vec![(1, 0), (1, 3), (2, 0)]);
/// assert_eq!(made.zeta[2].to_dense().as_slice().unwrap(), &[1, 1]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MadeSplit {
    /// ∂_1 … ∂_n after the makes.
    pub boundaries: Vec<CsMat<i8>>,
    /// ζ_0 … ζ_n: the product of the makes' ζ (refined × original cells).
    pub zeta: Vec<CsMat<i8>>,
    /// The makes in the order applied: (p, cell) for β^{p−1} on p-cell
    /// `cell` (numbered at the time it was applied).
    pub makes: Vec<(usize, usize)>,
}

/// Split top cell `cell` of `complex` by `plane` with make operators
/// only (see the module documentation). `snap` is SPLIT's tolerance.
///
/// Errors: the checks of [`vertex_classes`] and of [`make`] (a cell whose
/// positive facets do not form a valid selection, e.g. a non-convex cell).
pub fn split_by_makes(
    complex: &Complex,
    cell: usize,
    plane: &Hyperplane,
    snap: f64,
) -> Result<MadeSplit, SplitError> {
    let n = complex.dim();
    if cell >= complex.cell_count(n) {
        return Err(SplitError::CellOutOfRange {
            p: n,
            cell,
            count: complex.cell_count(n),
        });
    }
    let mut classes = vertex_classes(complex, plane, snap)?;
    let mut boundaries: Vec<CsMat<i8>> = (1..=n).map(|p| (**complex.boundary(p)).clone()).collect();
    let mut zeta: Vec<CsMat<i8>> = complex.cell_counts().into_iter().map(CsMat::eye).collect();
    let mut makes = Vec::new();
    // The closure of the cell, per dimension (original indices: pieces are
    // appended, so these stay valid).
    let mut closure: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n + 1];
    closure[n].insert(cell);
    for p in (1..=n).rev() {
        let csc = complex.boundary_csc(p);
        let below: BTreeSet<usize> = closure[p]
            .iter()
            .flat_map(|&c| {
                csc.outer_view(c)
                    .map(|v| v.indices().to_vec())
                    .unwrap_or_default()
            })
            .collect();
        closure[p - 1] = below;
    }
    for p in 1..=n {
        for &c in &closure[p] {
            // Vertex classes of the cell's vertices, from the current ∂.
            let vertices = cell_vertices(&boundaries, p, c);
            let has = |s: i8| vertices.iter().any(|&v| classes[v] == s);
            if !(has(-1) && has(1)) {
                continue;
            }
            let facets: Vec<usize> = boundaries[p - 1]
                .to_csc()
                .outer_view(c)
                .map(|v| v.indices().to_vec())
                .unwrap_or_default();
            let moved: Vec<usize> = facets
                .into_iter()
                .filter(|&f| {
                    let vs = if p == 1 {
                        vec![f]
                    } else {
                        cell_vertices(&boundaries, p - 1, f)
                    };
                    vs.iter().all(|&v| classes[v] >= 0) && vs.iter().any(|&v| classes[v] > 0)
                })
                .collect();
            let done = make(&boundaries, p, c, &moved)?;
            if p == 1 {
                classes.push(0);
            }
            for (z, step) in zeta.iter_mut().zip(&done.zeta) {
                *z = step * &*z;
            }
            boundaries = done.boundaries;
            makes.push((p, c));
        }
    }
    Ok(MadeSplit {
        boundaries,
        zeta: zeta.into_iter().map(|z| z.to_csr()).collect(),
        makes,
    })
}

/// The vertices of p-cell `c` from ∂_1 … ∂_p.
fn cell_vertices(boundaries: &[CsMat<i8>], p: usize, c: usize) -> Vec<usize> {
    let mut cells = vec![c];
    for q in (1..=p).rev() {
        cells = facets_of_all(&cells, &boundaries[q - 1].to_csc());
    }
    cells
}

/// The facets of `cells` (sorted, once each) through ∂ stored by columns.
pub(crate) fn facets_of_all(cells: &[usize], csc: &CsMat<i8>) -> Vec<usize> {
    let mut next: Vec<usize> = cells
        .iter()
        .flat_map(|&j| {
            csc.outer_view(j)
                .map(|v| v.indices().to_vec())
                .unwrap_or_default()
        })
        .collect();
    next.sort_unstable();
    next.dedup();
    next
}
