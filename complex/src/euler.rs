//! Euler make operators β^p on the signed incidence matrices.
//!
//! β^{p−1} splits one p-cell c into two by inserting a new (p−1)-cell N:
//! it adds one (p−1)-cell and one p-cell, so the Euler characteristic and
//! the Hasse matrix's `columns − rows` do not change (thesis §4.3–4.4).
//! Only three incidence matrices change:
//!
//! - ∂_{p−1} gains the column of N, ∂N = ∂R, where R is the part of ∂c that
//!   moves to the new piece c′ (for p = 1, N is a vertex and has no column);
//! - ∂_p gains the row of N and the column of c′:
//!   ∂c ← (∂c − R) + N, ∂c′ = R − N (for p = 1, R = ±v is one endpoint
//!   and N enters with R's sign, ∂c ← (∂c − R) ± N, so that each edge
//!   still runs from one vertex to another);
//! - ∂_{p+1} gains the row of c′, a copy of the row of c (every coface of c
//!   now has both pieces on its boundary with the sign c had).
//!
//! With this choice N is oriented as a facet of the piece that keeps the old
//! index, both pieces inherit the orientation of c, and ∂∂ = 0 follows from
//! ∂∂c = 0 alone. The subdivision chain map ζ is the identity on old cells
//! except ζ_p(c) = c + c′; new cells have zero rows. ∂̃ζ = ζ∂ holds because
//! ∂̃(c + c′) = ∂c.
//!
//! The same operator as matrices acting on the coboundaries and on the
//! Hasse matrix is in [`crate::hasse_transform`]; its inverse, the kill
//! operator, in [`crate::kill`].

use crate::error::SplitError;
use sprs::{CsMat, TriMat};

/// The incidence matrices after one make operator, and the chain map from
/// the old complex to the new one (`zeta[q]` is |K̃_q| × |K_q|, q = 0..=n).
///
/// ```
/// use hasse_complex::euler::make;
/// use sprs::CsMat;
/// // One edge v0 → v1; β⁰ puts a vertex v2 in its middle.
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// let out = make(&[d1], 1, 0, &[1]).unwrap();
/// // e0 = v2 − v0 keeps the tail, e1 = v1 − v2 is the appended head half.
/// assert_eq!(out.boundaries[0].to_dense().as_slice().unwrap(), &[-1, 0, 0, 1, 1, -1]);
/// assert_eq!(out.zeta[1].to_dense().as_slice().unwrap(), &[1, 1]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Make {
    /// ∂_1 … ∂_n of the new complex.
    pub boundaries: Vec<CsMat<i8>>,
    /// ζ_0 … ζ_n (old cells map to themselves, the split cell to both pieces).
    pub zeta: Vec<CsMat<i8>>,
}

/// Cell counts (|K_0|, …, |K_n|) read off the shapes of ∂_1 … ∂_n.
///
/// ```
/// use hasse_complex::euler::cell_counts;
/// use sprs::CsMat;
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// assert_eq!(cell_counts(&[d1]), vec![2, 1]);
/// ```
pub fn cell_counts(boundaries: &[CsMat<i8>]) -> Vec<usize> {
    let mut counts: Vec<usize> = boundaries.iter().map(|b| b.rows()).collect();
    counts.push(boundaries.last().map_or(0, |b| b.cols()));
    counts
}

/// The Hasse matrix built from ∂_1 … ∂_n alone: rows are the odd cells
/// (K_1, K_3, …), columns the even ones (K_0, K_2, …), the same layout as
/// [`Complex::hasse_matrix`](crate::Complex::hasse_matrix). Its shape r × c
/// gives χ = c − r, which every make operator preserves.
///
/// ```
/// use hasse_complex::euler::{hasse_matrix, make};
/// use sprs::CsMat;
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// let h = hasse_matrix(&[d1.clone()]);
/// let h2 = hasse_matrix(&make(&[d1], 1, 0, &[1]).unwrap().boundaries);
/// assert_eq!((h.shape(), h2.shape()), ((1, 2), (2, 3)));
/// ```
pub fn hasse_matrix(boundaries: &[CsMat<i8>]) -> CsMat<i8> {
    let counts = cell_counts(boundaries);
    let n = boundaries.len();
    let offsets = |parity: usize| {
        let mut off = vec![0; n + 1];
        let mut acc = 0;
        for p in (parity..=n).step_by(2) {
            off[p] = acc;
            acc += counts[p];
        }
        (off, acc)
    };
    let ((row_off, rows), (col_off, cols)) = (offsets(1), offsets(0));
    let mut tri = TriMat::new((rows, cols));
    for (k, b) in boundaries.iter().enumerate() {
        let p = k + 1;
        for (&value, (i, j)) in b.iter() {
            if p % 2 == 1 {
                tri.add_triplet(row_off[p] + j, col_off[p - 1] + i, value);
            } else {
                tri.add_triplet(row_off[p - 1] + i, col_off[p] + j, value);
            }
        }
    }
    tri.to_csr()
}

/// β^{p−1}: split p-cell `cell` into two by a new (p−1)-cell.
///
/// `moved` lists the facets of `cell` (rows of ∂_p) that go to the new
/// piece c′; the rest stay with `cell`. For p = 1 it is the one endpoint
/// that the appended half keeps (the thesis keeps the tail in the old edge:
/// pass the head); both halves keep the edge's direction whichever end
/// moves. For p ≥ 2 the moved facets must have a non-zero
/// boundary, which becomes the boundary of the new (p−1)-cell; the new cell
/// is appended last in K_{p−1} and the new piece last in K_p.
///
/// Errors name the cell when p is out of range, `cell` does not exist, a
/// moved index is not a facet of `cell`, or the selection is empty, all of
/// ∂c, or (p ≥ 2) has zero boundary or one that bounds no cell: the new
/// edge must have two end points, the new polygon one simple closed cycle
/// of edges, so that both pieces are cells.
///
/// ```
/// use hasse_complex::euler::make;
/// use sprs::CsMat;
/// // A square ∂ = e0 + e1 + e2 + e3 around v0 → v1 → v2 → v3 → v0 ...
/// let d1 = CsMat::new_csc((4, 4), vec![0, 2, 4, 6, 8], vec![0, 1, 1, 2, 2, 3, 0, 3],
///                         vec![-1i8, 1, -1, 1, -1, 1, 1, -1]).to_csr();
/// let d2 = CsMat::new_csc((4, 1), vec![0, 4], vec![0, 1, 2, 3], vec![1i8; 4]).to_csr();
/// // ... split along the diagonal: e2, e3 move to the new face, whose
/// // boundary runs v2 → v0, so the new edge is ∂(e2 + e3) = v0 − v2.
/// let out = make(&[d1, d2], 2, 0, &[2, 3]).unwrap();
/// let d1 = &out.boundaries[0];
/// let d2 = &out.boundaries[1];
/// assert_eq!(d2.shape(), (5, 2));
/// assert!((d1 * d2).data().iter().all(|&x| x == 0));
/// let e4: Vec<i8> = (0..4).map(|v| *d1.get(v, 4).unwrap_or(&0)).collect();
/// assert_eq!(e4, vec![1, 0, -1, 0]);
/// ```
pub fn make(
    boundaries: &[CsMat<i8>],
    p: usize,
    cell: usize,
    moved: &[usize],
) -> Result<Make, SplitError> {
    let n = boundaries.len();
    let SplitPlan {
        counts,
        moving,
        nu,
        new_face_boundary,
    } = plan(boundaries, p, cell, moved)?;
    let moved_sorted: Vec<usize> = moving.iter().map(|&(f, _)| f).collect();
    let new_face = counts[p - 1];
    let new_piece = counts[p];

    let mut out = Vec::with_capacity(n);
    for (k, b) in boundaries.iter().enumerate() {
        let q = k + 1;
        let (mut rows, mut cols) = b.shape();
        let mut entries: Vec<(usize, usize, i8)> = b.iter().map(|(&v, (i, j))| (i, j, v)).collect();
        if q + 1 == p {
            // ∂_{p−1}: a new column for N.
            cols += 1;
            for &(g, v) in &new_face_boundary {
                entries.push((g, new_face, v as i8));
            }
        } else if q == p {
            rows += 1;
            cols += 1;
            entries.retain(|&(i, j, _)| j != cell || moved_sorted.binary_search(&i).is_err());
            for &(f, s) in &moving {
                entries.push((f, new_piece, s));
            }
            entries.push((new_face, cell, nu));
            entries.push((new_face, new_piece, -nu));
        } else if q == p + 1 {
            rows += 1;
            let copies: Vec<(usize, usize, i8)> = entries
                .iter()
                .filter(|&&(i, _, _)| i == cell)
                .map(|&(_, j, v)| (new_piece, j, v))
                .collect();
            entries.extend(copies);
        }
        let mut tri = TriMat::with_capacity((rows, cols), entries.len());
        for (i, j, v) in entries {
            tri.add_triplet(i, j, v);
        }
        out.push(tri.to_csr());
    }

    let zeta = (0..=n)
        .map(|q| {
            let old = counts[q];
            let grown = old + usize::from(q == p || q + 1 == p);
            let mut t = TriMat::with_capacity((grown, old), old + 1);
            for i in 0..old {
                t.add_triplet(i, i, 1i8);
            }
            if q == p {
                t.add_triplet(new_piece, cell, 1);
            }
            t.to_csr()
        })
        .collect();
    Ok(Make {
        boundaries: out,
        zeta,
    })
}

/// What a make operator β^{p−1} on `cell` with the facets `moved` does,
/// checked once and shared by [`make`] and the matrix form
/// ([`crate::hasse_transform::MakeMatrices`]).
pub(crate) struct SplitPlan {
    /// (|K_0|, …, |K_n|) before the operator.
    pub counts: Vec<usize>,
    /// ρ: the moved facets, sorted, with the sign they have in ∂c.
    pub moving: Vec<(usize, i8)>,
    /// The coefficient ν of the new (p−1)-cell N in ∂c̃ (and −ν in ∂c′).
    /// For p ≥ 2 it is 1 (N is oriented by ∂N = ∂ρ). For p = 1, N is a
    /// vertex, which has no orientation to choose, so the sign goes into
    /// ∂: ν = the sign of the moved endpoint, which keeps the sum of the
    /// coefficients of each edge's boundary zero (the augmentation
    /// ε∂ = 0). Moving the head gives ν = 1, the thesis's convention.
    pub nu: i8,
    /// ∂N = ∂ρ as a sorted (p−2)-chain (empty for p = 1).
    pub new_face_boundary: Vec<(usize, i32)>,
}

/// Why ∂N = ∂ρ is not the boundary of a (p−1)-cell, if it is not: a new
/// edge (p = 2) has two end points, one +1 and one −1; a new polygon
/// (p = 3) is bounded by one simple closed cycle of edges (each end point
/// on exactly two of them, all connected). ρ lies on the boundary sphere
/// of c, so when ∂ρ is such a sphere both pieces are balls (Jordan–
/// Schoenflies on the 2-sphere for p = 3, a path and its complement on the
/// circle for p = 2): the new pieces are cells.
fn not_a_sphere(boundaries: &[CsMat<i8>], p: usize, chain: &[(usize, i32)]) -> Option<String> {
    match p {
        2 => {
            let signs: Vec<i32> = chain.iter().map(|&(_, v)| v).collect();
            (signs.len() != 2 || signs.iter().sum::<i32>() != 0).then(|| {
                format!(
                    "the moved edges form no path: the new edge would have {} end points (a path between two vertices has 2)",
                    signs.len()
                )
            })
        }
        3 => {
            let edges = boundaries[0].to_csc();
            // Each vertex's cycle edges, and the edges' end points.
            let mut ends: Vec<[usize; 2]> = Vec::with_capacity(chain.len());
            let mut by_vertex: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
            for (k, &(e, _)) in chain.iter().enumerate() {
                let vertices: Vec<usize> = edges
                    .outer_view(e)
                    .map(|col| col.indices().to_vec())
                    .unwrap_or_default();
                let [a, b] = vertices[..] else {
                    return Some(format!("edge {e} of the cut does not have two end points"));
                };
                ends.push([a, b]);
                by_vertex.entry(a).or_default().push(k);
                by_vertex.entry(b).or_default().push(k);
            }
            if let Some((v, on)) = by_vertex.iter().find(|(_, on)| on.len() != 2) {
                return Some(format!(
                    "the moved faces' boundary is not a simple cycle: vertex {v} is on {} of its edges (a polygon's boundary passes each of its vertices once)",
                    on.len()
                ));
            }
            // Walk the cycle from the first edge: it must take every edge.
            let mut seen = vec![false; chain.len()];
            let (mut edge, mut at) = (0, ends[0][1]);
            seen[0] = true;
            let mut walked = 1;
            loop {
                let next = by_vertex[&at].iter().copied().find(|&k| k != edge);
                match next {
                    Some(k) if !seen[k] => {
                        seen[k] = true;
                        walked += 1;
                        at = if ends[k][0] == at {
                            ends[k][1]
                        } else {
                            ends[k][0]
                        };
                        edge = k;
                    }
                    _ => break,
                }
            }
            (walked != chain.len()).then(|| {
                format!(
                    "the moved faces' boundary is {} edges in more than one cycle (the first has {walked}): the new face would not be one polygon",
                    chain.len()
                )
            })
        }
        _ => None,
    }
}

/// Validates a make operator and computes ρ, ν and ∂N (see [`make`] for
/// the errors).
pub(crate) fn plan(
    boundaries: &[CsMat<i8>],
    p: usize,
    cell: usize,
    moved: &[usize],
) -> Result<SplitPlan, SplitError> {
    let n = boundaries.len();
    if p == 0 || p > n {
        return Err(SplitError::DimensionOutOfRange { p, dim: n });
    }
    let counts = cell_counts(boundaries);
    if cell >= counts[p] {
        return Err(SplitError::CellOutOfRange {
            p,
            cell,
            count: counts[p],
        });
    }
    let bad = |reason: String| SplitError::BadFacetSelection { p, cell, reason };
    let dp = boundaries[p - 1].to_csc();
    let column = dp.outer_view(cell).ok_or_else(|| bad("no column".into()))?;
    let facets: Vec<(usize, i8)> = column.iter().map(|(i, &s)| (i, s)).collect();
    let mut moved_sorted = moved.to_vec();
    moved_sorted.sort_unstable();
    moved_sorted.dedup();
    if moved_sorted.is_empty() || moved_sorted.len() >= facets.len() {
        return Err(bad(format!(
            "{} of its {} facets were selected to move; a split needs a proper non-empty part",
            moved_sorted.len(),
            facets.len()
        )));
    }
    // ρ = the moved part of ∂c, with the signs it has in ∂c.
    let mut moving = Vec::with_capacity(moved_sorted.len());
    for &f in &moved_sorted {
        let sign = facets
            .iter()
            .find(|&&(i, _)| i == f)
            .map(|&(_, s)| s)
            .ok_or_else(|| bad(format!("{}-cell {f} is not on its boundary", p - 1)))?;
        moving.push((f, sign));
    }
    if p == 1 && moving.len() != 1 {
        return Err(bad(
            "an edge is split by moving exactly one of its two endpoints".into(),
        ));
    }
    // ∂N = ∂ρ (a (p−2)-chain), needed for p ≥ 2.
    let new_face_boundary: Vec<(usize, i32)> = if p >= 2 {
        let lower = boundaries[p - 2].to_csc();
        let mut acc: Vec<(usize, i32)> = Vec::new();
        for &(f, s) in &moving {
            if let Some(col) = lower.outer_view(f) {
                for (g, &t) in col.iter() {
                    acc.push((g, i32::from(s) * i32::from(t)));
                }
            }
        }
        acc.sort_unstable();
        let mut merged: Vec<(usize, i32)> = Vec::new();
        for (g, v) in acc {
            match merged.last_mut() {
                Some(last) if last.0 == g => last.1 += v,
                _ => merged.push((g, v)),
            }
        }
        merged.retain(|&(_, v)| v != 0);
        if merged.is_empty() {
            return Err(bad(
                "the moved facets form a closed chain, so the new cell would have no boundary"
                    .into(),
            ));
        }
        if merged.iter().any(|&(_, v)| v.abs() != 1) {
            return Err(bad(
                "the moved facets do not bound a cell with unit incidences".into(),
            ));
        }
        if let Some(reason) = not_a_sphere(boundaries, p, &merged) {
            return Err(bad(reason));
        }
        merged
    } else {
        Vec::new()
    };
    let nu = if p == 1 { moving[0].1 } else { 1 };
    Ok(SplitPlan {
        counts,
        moving,
        nu,
        new_face_boundary,
    })
}
