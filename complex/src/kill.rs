//! Euler kill operators κ: merge two p-cells across the one (p−1)-cell
//! they share, the inverse of the make operators of [`crate::euler`].
//!
//! The paper (seed 000 §4.2) names κ ("klastos") but gives no formula. Here
//! κ on p-cells a (kept) and b (removed) sharing the facet N, with α and β
//! the coefficients of N in ∂a and ∂b, orients b inside the merged cell m
//! by σ = −αβ (so that N cancels) and gives m the orientation of a:
//!
//! - ∂m = ∂a + σ ∂b, the N terms cancelling (∂_p loses row N and column b);
//! - ∂_{p−1} loses the column of N;
//! - ∂_{p+1} loses the row of b: every coface τ of the pair has
//!   ∂τ ∋ t a + σ t b (∂∂τ = 0 at N forces it), and it becomes t m.
//!
//! Numbering: m keeps a's index; N and b are deleted and the later cells
//! of their dimensions move down by one, in order. [`make`] appends its two
//! new cells last, so `kill(make(K, p, c, ρ), p, c, k_p)` returns the
//! boundaries of K exactly (κ ∘ β = id).
//!
//! Two chain maps come back. ζ : C(K̃) → C(K), m ↦ a + σb, is the
//! subdivision map of the make that would undo the merge (it is the `zeta`
//! of that [`make`]). ψ : C(K) → C(K̃) is its left inverse, ψζ = id, and is
//! a chain map, ∂̃ψ = ψ∂: ψ(a) = m, ψ(b) = 0 and ψ(N) = −β (∂b − βN), the
//! rest of b's boundary (for p = 1, the far end of b). It is the chain map
//! of the cellular map that squeezes b onto the rest of its boundary; the
//! naive projection a, b ↦ m is not a chain map (it maps ∂τ to 2tm).
//!
//! [`make`]: crate::euler::make

use crate::error::SplitError;
use crate::euler::cell_counts;
use sprs::{CsMat, TriMat};
use std::collections::BTreeSet;

/// The boundary matrices after one kill operator and its chain maps.
///
/// ```
/// use hasse_complex::kill::kill;
/// use sprs::CsMat;
/// // Two edges v0 → v1 → v2; merging them across v1 leaves v0 → v2, renumbered v0 → v1.
/// let d1 = CsMat::new_csc((3, 2), vec![0, 2, 4], vec![0, 1, 1, 2], vec![-1i8, 1, -1, 1]).to_csr();
/// let out = kill(&[d1], 1, 0, 1).unwrap();
/// assert_eq!(out.boundaries[0].to_dense().as_slice().unwrap(), &[-1, 1]);
/// assert_eq!(out.facet, 1);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Kill {
    /// ∂_1 … ∂_n of the merged complex K̃.
    pub boundaries: Vec<CsMat<i8>>,
    /// ψ_0 … ψ_n, `psi[q]` is |K̃_q| × |K_q|: the chain map C(K) → C(K̃).
    pub psi: Vec<CsMat<i8>>,
    /// ζ_0 … ζ_n, `zeta[q]` is |K_q| × |K̃_q|: the subdivision chain map
    /// C(K̃) → C(K), m ↦ a + σ b.
    pub zeta: Vec<CsMat<i8>>,
    /// The removed (p−1)-cell N, numbered in K.
    pub facet: usize,
    /// σ = ±1: the orientation of b relative to the merged cell.
    pub sigma: i8,
}

/// Columns of ∂ as sorted (row, value) lists.
fn columns(b: &CsMat<i8>) -> Vec<Vec<(usize, i8)>> {
    let csc = b.to_csc();
    csc.outer_iterator()
        .map(|col| col.iter().map(|(i, &v)| (i, v)).collect())
        .collect()
}

/// The faces of every dimension q < p of the p-cell `cell`, from the
/// columns of ∂_1 … ∂_p (`cols[q]` = columns of ∂_{q+1}).
fn closure(cols: &[Vec<Vec<(usize, i8)>>], p: usize, cell: usize) -> Vec<BTreeSet<usize>> {
    let mut faces = vec![BTreeSet::new(); p + 1];
    faces[p].insert(cell);
    for q in (1..=p).rev() {
        let below: BTreeSet<usize> = faces[q]
            .iter()
            .flat_map(|&c| cols[q - 1][c].iter().map(|&(i, _)| i))
            .collect();
        faces[q - 1] = below;
    }
    faces
}

/// κ: merge p-cells `keep` and `remove` across the one (p−1)-cell they
/// share. For p = 1 that is a vertex of degree 2 between two edges; for
/// p ≥ 2 a facet that bounds only these two cells.
///
/// Errors: [`SplitError::DimensionOutOfRange`] and
/// [`SplitError::CellOutOfRange`] for indices, [`SplitError::SameCell`],
/// [`SplitError::NotAdjacent`] when the cells do not share exactly one
/// facet, [`SplitError::FacetHasOtherCofaces`] when that facet bounds a
/// third p-cell, and [`SplitError::NotACell`] when the closures of the two
/// cells meet outside the closure of the facet (the union would be pinched,
/// not a ball) or a (p+1)-cell has them on its boundary with incompatible
/// signs (∂∂ ≠ 0 in the input).
///
/// ```
/// use hasse_complex::{euler::make, kill::kill};
/// use sprs::CsMat;
/// // A triangle (edges v0→v1, v1→v2, v0→v2; ∂f = e0 + e1 − e2), split by
/// // a make and merged back: the original boundaries come out.
/// let d1 = CsMat::new_csc((3, 3), vec![0, 2, 4, 6], vec![0, 1, 1, 2, 0, 2],
///                         vec![-1i8, 1, -1, 1, -1, 1]).to_csr();
/// let d2 = CsMat::new((3, 1), vec![0, 1, 2, 3], vec![0, 0, 0], vec![1i8, 1, -1]);
/// let made = make(&[d1.clone(), d2.clone()], 1, 2, &[2]).unwrap();
/// let back = kill(&made.boundaries, 1, 2, 3).unwrap();
/// assert_eq!(back.boundaries, vec![d1, d2]);
/// assert_eq!(back.zeta, made.zeta);
/// ```
pub fn kill(
    boundaries: &[CsMat<i8>],
    p: usize,
    keep: usize,
    remove: usize,
) -> Result<Kill, SplitError> {
    let n = boundaries.len();
    if p == 0 || p > n {
        return Err(SplitError::DimensionOutOfRange { p, dim: n });
    }
    let counts = cell_counts(boundaries);
    for cell in [keep, remove] {
        if cell >= counts[p] {
            return Err(SplitError::CellOutOfRange {
                p,
                cell,
                count: counts[p],
            });
        }
    }
    if keep == remove {
        return Err(SplitError::SameCell { p, cell: keep });
    }
    let (a, b) = (keep, remove);
    let cols: Vec<Vec<Vec<(usize, i8)>>> = boundaries[..p].iter().map(columns).collect();
    let (da, db) = (&cols[p - 1][a], &cols[p - 1][b]);
    let shared: Vec<usize> = da
        .iter()
        .filter(|(i, _)| db.iter().any(|(j, _)| j == i))
        .map(|&(i, _)| i)
        .collect();
    let &[facet] = shared.as_slice() else {
        return Err(SplitError::NotAdjacent { p, a, b, shared });
    };
    // N must bound a and b only: its row of ∂_p.
    if let Some(other) = boundaries[p - 1]
        .to_csr()
        .outer_view(facet)
        .and_then(|row| row.iter().map(|(j, _)| j).find(|&j| j != a && j != b))
    {
        return Err(SplitError::FacetHasOtherCofaces {
            p,
            facet,
            a,
            b,
            other,
        });
    }
    let not_a_cell = |reason: String| SplitError::NotACell { p, a, b, reason };
    // The closures of a and b must meet in the closure of N exactly.
    let (ca, cb) = (closure(&cols, p, a), closure(&cols, p, b));
    let cn = closure(&cols, p - 1, facet);
    for q in (0..p.saturating_sub(1)).rev() {
        if let Some(&x) = ca[q].intersection(&cb[q]).find(|x| !cn[q].contains(x)) {
            return Err(not_a_cell(format!(
                "their closures also meet in {q}-cell {x}, which is not a face of the shared {}-cell {facet}",
                p - 1
            )));
        }
    }
    let coefficient = |d: &[(usize, i8)]| d.iter().find(|&&(i, _)| i == facet).map(|&(_, v)| v);
    let (alpha, beta) = coefficient(da)
        .zip(coefficient(db))
        .ok_or_else(|| not_a_cell("internal: the shared facet lost its coefficient".into()))?;
    let sigma = -alpha * beta;
    // Every coface must see b as σ times a, or merging breaks its boundary.
    if p < n {
        for (tau, col) in columns(&boundaries[p]).iter().enumerate() {
            let t = |x: usize| col.iter().find(|&&(i, _)| i == x).map_or(0, |&(_, v)| v);
            if t(b) != sigma * t(a) {
                return Err(not_a_cell(format!(
                    "({})-cell {tau} has them on its boundary with signs {} and {}, not related by σ = {sigma}",
                    p + 1,
                    t(a),
                    t(b)
                )));
            }
        }
    }

    // Renumbering: old index → new index, None for the deleted cells.
    let renumber = |q: usize, i: usize| -> Option<usize> {
        let gone = if q == p {
            Some(b)
        } else if q + 1 == p {
            Some(facet)
        } else {
            None
        };
        match gone {
            Some(g) if i == g => None,
            Some(g) if i > g => Some(i - 1),
            _ => Some(i),
        }
    };
    let new_counts: Vec<usize> = counts
        .iter()
        .enumerate()
        .map(|(q, &k)| k - usize::from(q == p || q + 1 == p))
        .collect();
    let m = renumber(p, a).ok_or_else(|| not_a_cell("internal: kept cell renumbered".into()))?;

    let mut out = Vec::with_capacity(n);
    for (k, bd) in boundaries.iter().enumerate() {
        let q = k + 1;
        let mut tri = TriMat::new((new_counts[q - 1], new_counts[q]));
        for (&v, (i, j)) in bd.iter() {
            // Column b of ∂_p joins column a with the factor σ; row N goes.
            let (j, v) = if q == p && j == b {
                (a, sigma * v)
            } else {
                (j, v)
            };
            if let (Some(i), Some(j)) = (renumber(q - 1, i), renumber(q, j)) {
                tri.add_triplet(i, j, v);
            }
        }
        out.push(tri.to_csr());
    }

    let identity_part =
        |q: usize| (0..counts[q]).filter_map(move |i| renumber(q, i).map(|r| (r, i)));
    let psi: Vec<CsMat<i8>> = (0..=n)
        .map(|q| {
            let mut t = TriMat::new((new_counts[q], counts[q]));
            for (r, i) in identity_part(q) {
                t.add_triplet(r, i, 1i8);
            }
            if q + 1 == p {
                // ψ(N) = −β (∂b − βN).
                for &(g, v) in db.iter().filter(|&&(g, _)| g != facet) {
                    if let Some(r) = renumber(q, g) {
                        t.add_triplet(r, facet, -beta * v);
                    }
                }
            }
            t.to_csr()
        })
        .collect();
    let zeta: Vec<CsMat<i8>> = (0..=n)
        .map(|q| {
            let mut t = TriMat::new((counts[q], new_counts[q]));
            for (r, i) in identity_part(q) {
                t.add_triplet(i, r, 1i8);
            }
            if q == p {
                t.add_triplet(b, m, sigma);
            }
            t.to_csr()
        })
        .collect();
    Ok(Kill {
        boundaries: out,
        psi,
        zeta,
        facet,
        sigma,
    })
}
