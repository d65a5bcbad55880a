//! Exact ranks of sparse integer boundary matrices, Betti numbers and the
//! Euler characteristic of a chain complex.
//!
//! Ranks are computed by sparse column reduction (the "standard algorithm"
//! of persistent homology) over a prime field: `Z/2` for [`Field::Z2`] and
//! `Z/p` with the Mersenne prime `p = 2^31 - 1` for [`Field::Rationals`].
//! See [`rank`] for why the latter gives the rank over `Q` for the boundary
//! matrices of the complexes this crate builds.

use sprs::CsMat;
use std::borrow::Cow;

/// The Mersenne prime `2^31 - 1` used to compute ranks over `Q`.
const MERSENNE_31: u64 = 2_147_483_647;

/// Field in which ranks (and therefore Betti numbers) are computed.
///
/// Over [`Field::Rationals`] the Betti numbers are the ranks of the free
/// parts of the integral homology groups; over [`Field::Z2`] they also count
/// 2-torsion, and do not depend on orientations. The two agree for
/// torsion-free complexes (for instance anything embedded in `R^3`) and
/// differ for non-orientable ones: the real projective plane has
/// `β = (1, 0, 0)` over `Q` and `β = (1, 1, 1)` over `Z/2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// The rational numbers `Q`, computed exactly modulo `2^31 - 1`.
    Rationals,
    /// The two-element field `Z/2`: only the parity of each entry matters.
    Z2,
}

/// Rank of an integer matrix over `field`.
///
/// The matrix may use CSR or CSC storage; explicit zeros are ignored. Empty
/// matrices (`0 × 0`, `0 × k`, `k × 0`) have rank 0. Over [`Field::Z2`] an
/// entry counts as nonzero when it is odd.
///
/// # Exactness over `Q`
///
/// [`Field::Rationals`] is computed exactly in the prime field `Z/p` with
/// `p = 2^31 - 1` (u64 arithmetic, no rounding). The rank modulo a prime
/// never exceeds the rank over `Q`: an `r × r` minor that is nonzero modulo
/// `p` is a nonzero integer. Conversely, the rank over `Q` drops modulo `p`
/// only if `p` divides every nonzero `r × r` minor, `r` the rational rank.
/// For a boundary matrix `∂_k` (entries in `{-1, 0, 1}` or not) of a
/// complex whose homology `H_{k-1}` is torsion-free, e.g. any complex
/// embedded in `R^3`, this cannot happen: the torsion of `H_{k-1}` is that of
/// `coker ∂_k`, i.e. `⊕ Z/d_i` over the invariant factors `d_i` of the
/// Smith normal form of `∂_k`, so all `d_i = 1`, the gcd of the nonzero
/// `r × r` minors (`d_1 ⋯ d_r`) is 1, and some minor survives modulo every
/// prime. In general the result is a lower bound for the rational rank,
/// exact unless `2^31 - 1` divides the order of the torsion. Hadamard's
/// bound (`|det| ≤ n^{n/2}` for entries in `{-1, 0, 1}`) also makes the
/// result exact for every such matrix with at most 15 rows or columns.
///
/// # Algorithm
///
/// Sparse column reduction (the "standard algorithm" of persistent
/// homology). A CSR matrix is first converted to CSC. Each column becomes a
/// sorted sparse vector of `(row, value mod p)`; while its pivot (largest
/// row index) is owned by an earlier reduced column, that column, stored
/// with pivot value 1, is subtracted `value` times. Nonzero reduced columns
/// are kept as eliminators and counted: that count is the rank. Columns
/// are processed in the given order, which for meshes keeps fill-in low.
/// `∂_1` or `∂_2` of a 20³ hexahedral grid (~26 000 × 25 000) takes
/// 10–40 ms in a release build, a few hundred ms unoptimised;
/// [`betti_numbers`] is faster than its separate ranks thanks to clearing.
///
/// # Example
///
/// ```text
/// // ∂_1 of the boundary of a triangle: three vertices, three edges.
/// let d1 = CsMat::new((3, 3), vec![0, 2, 4, 6], vec![0, 1, 0, 2, 1, 2],
///                     vec![-1, 1, -1, 1, -1, 1]);          // CSR storage
/// assert_eq!(rank(&d1, Field::Rationals), 2);
/// assert_eq!(rank(&d1, Field::Z2), 2);
/// ```
pub fn rank(matrix: &CsMat<i8>, field: Field) -> usize {
    match as_columns(matrix) {
        Some(columns) => reduce_over(&columns, field, &[], false).rank,
        // rank A = rank Aᵀ: reduce the rows of a CSR matrix with a huge
        // number of columns rather than materialising its CSC form.
        None => reduce_over(matrix, field, &[], false).rank,
    }
}

/// The matrix in CSC storage: borrowed if it already is, converted from CSR
/// unless its column count is so large compared with its number of entries
/// that the conversion's `cols + 1` column pointers would dominate memory.
fn as_columns(matrix: &CsMat<i8>) -> Option<Cow<'_, CsMat<i8>>> {
    if matrix.is_csc() {
        Some(Cow::Borrowed(matrix))
    } else if matrix.cols() <= sparse_bound(matrix.nnz()) {
        // Column order is the one meshes are built for: cells in storage
        // order, low fill-in. Reducing the rows instead is equally valid but
        // measurably slower on boundary matrices, and prevents clearing.
        Some(Cow::Owned(matrix.to_csc()))
    } else {
        None
    }
}

/// Largest dimension treated densely (pivot table, column pointers) for a
/// matrix with `nnz` entries; beyond it indices are renumbered.
fn sparse_bound(nnz: usize) -> usize {
    nnz.saturating_mul(4).saturating_add(1024)
}

/// [`reduce_mod`] with the prime of `field`.
fn reduce_over(matrix: &CsMat<i8>, field: Field, skip: &[usize], want_pivots: bool) -> Reduction {
    match field {
        Field::Rationals => reduce_mod::<MERSENNE_31>(matrix, skip, want_pivots),
        Field::Z2 => reduce_mod::<2>(matrix, skip, want_pivots),
    }
}

/// Betti numbers `β_0..β_n` of a chain complex over `field`.
///
/// `cell_counts[p] = |K_p|` for `p = 0..=n`, and `boundaries[p - 1] = ∂_p`
/// of shape `|K_{p-1}| × |K_p|` for `p = 1..=n` (CSR or CSC storage). Then
/// `β_p = |K_p| - rank ∂_p - rank ∂_{p+1}`, with `rank ∂_0 = rank ∂_{n+1} = 0`.
///
/// A missing boundary matrix (`boundaries` shorter than `n`) counts as the
/// zero map and surplus matrices are ignored. The result has one entry per
/// cell count (empty for an empty complex). Inputs that are not a chain
/// complex (`∂_p ∂_{p+1} ≠ 0`, or shapes that disagree with the counts) give
/// meaningless but non-panicking results: the subtraction saturates at 0.
///
/// The ranks are computed from the top dimension down with *clearing*
/// (Chen–Kerber "twist"): a `p`-cell that is the pivot of a reduced column
/// of `∂_{p+1}` is the last cell of a `p`-cycle, so its column of `∂_p`
/// would reduce to zero and is skipped. Those are the expensive columns;
/// with clearing the Betti numbers of a 20³ hexahedral grid (~70 000 cells)
/// take 2–20 ms in a release build. This relies on `∂_p ∂_{p+1} = 0`.
///
/// # Example
///
/// ```text
/// // Boundary of a tetrahedron: 4 vertices, 6 edges, 4 triangles (a 2-sphere).
/// betti_numbers(&[4, 6, 4], &[d1, d2], Field::Rationals) == vec![1, 0, 1]
/// ```
pub fn betti_numbers(cell_counts: &[usize], boundaries: &[CsMat<i8>], field: Field) -> Vec<usize> {
    let n = cell_counts.len();
    // ranks[p] = rank ∂_p for p = 0..=n, with ∂_0 = ∂_{n+1} = 0.
    let mut ranks = vec![0usize; n + 1];
    // Clearing: going down in dimension, the p-cells that are pivots of the
    // reduced ∂_{p+1} have columns of ∂_p that reduce to zero, so they are
    // skipped (a pivot j is the last cell of a cycle, hence ∂_p e_j is a
    // combination of ∂_p e_i, i < j). These are exactly the expensive
    // columns of the standard algorithm. `cleared` holds those p-cells,
    // sorted, and `cleared_rows` the row count of the ∂_{p+1} they came
    // from (clearing is only applied when it matches ∂_p's column count).
    let mut cleared: Vec<usize> = Vec::new();
    let mut cleared_rows = None;
    for p in (1..n).rev() {
        let Some(boundary) = boundaries.get(p - 1) else {
            cleared_rows = None;
            continue;
        };
        let Some(columns) = as_columns(boundary) else {
            ranks[p] = rank(boundary, field);
            cleared_rows = None;
            continue;
        };
        let skip = if cleared_rows == Some(columns.cols()) {
            cleared.as_slice()
        } else {
            &[]
        };
        let reduction = reduce_over(&columns, field, skip, p > 1);
        ranks[p] = reduction.rank;
        cleared = reduction.pivots;
        cleared.sort_unstable();
        cleared_rows = Some(columns.rows());
    }
    cell_counts
        .iter()
        .enumerate()
        .map(|(p, &count)| count.saturating_sub(ranks[p]).saturating_sub(ranks[p + 1]))
        .collect()
}

/// Euler characteristic `χ = Σ_p (-1)^p |K_p|` of a complex with
/// `cell_counts[p] = |K_p|`.
///
/// It equals the alternating sum of the Betti numbers over any field.
///
/// # Example
///
/// ```text
/// euler_characteristic(&[4, 6, 4]) == 2      // the 2-sphere
/// euler_characteristic(&[6, 15, 10]) == 1    // the real projective plane
/// euler_characteristic(&[]) == 0
/// ```
pub fn euler_characteristic(cell_counts: &[usize]) -> i64 {
    cell_counts
        .iter()
        .enumerate()
        .map(|(p, &count)| {
            let count = i64::try_from(count).unwrap_or(i64::MAX);
            if p % 2 == 0 {
                count
            } else {
                -count
            }
        })
        .fold(0i64, i64::saturating_add)
}

/// Index type of the pivot slots (renumbered inner indices): `u32` keeps the
/// entries at 8 bytes; `usize` covers matrices with 2^32 or more slots.
trait Slot: Copy + Ord {
    /// Marks a slot not yet owned by a reduced column.
    const NONE: Self;
    fn from_usize(index: usize) -> Self;
    fn index(self) -> usize;
}

impl Slot for u32 {
    const NONE: Self = u32::MAX;
    fn from_usize(index: usize) -> Self {
        index as u32
    }
    fn index(self) -> usize {
        self as usize
    }
}

impl Slot for usize {
    const NONE: Self = usize::MAX;
    fn from_usize(index: usize) -> Self {
        index
    }
    fn index(self) -> usize {
        self
    }
}

/// An entry `(slot, value)` of a sparse vector over `Z/P`, `0 < value < P`.
type Entry<I> = (I, u32);

/// `a^(P-2) mod P`, the inverse of a nonzero `a` in `Z/P` (Fermat).
fn inverse_mod<const P: u64>(a: u64) -> u64 {
    let mut base = a % P;
    let mut exponent = P - 2;
    let mut result = 1u64;
    while exponent > 0 {
        if exponent & 1 == 1 {
            result = result * base % P;
        }
        base = base * base % P;
        exponent >>= 1;
    }
    result
}

/// Outcome of reducing the outer vectors of a matrix.
struct Reduction {
    /// Number of outer vectors that did not reduce to zero.
    rank: usize,
    /// Inner indices of their pivots (original numbering), if requested.
    pivots: Vec<usize>,
}

/// Reduces the outer vectors of `matrix` (its columns if CSC, its rows if
/// CSR) over `Z/P`, `P` prime and `P <= 2^31 - 1`. The outer vectors listed
/// in the sorted `skip` are assumed to reduce to zero and left out
/// (clearing).
fn reduce_mod<const P: u64>(matrix: &CsMat<i8>, skip: &[usize], want_pivots: bool) -> Reduction {
    let inner_dim = matrix.inner_dims();
    let nnz = matrix.nnz();
    if nnz == 0 || matrix.outer_dims() == 0 || inner_dim == 0 {
        return Reduction {
            rank: 0,
            pivots: Vec::new(),
        };
    }
    // Inner indices become pivot slots. When the inner dimension is huge
    // compared with the number of entries, renumber the occurring indices
    // (order-preservingly) so that memory stays O(nnz).
    let renumber = if inner_dim > sparse_bound(nnz) {
        let mut used: Vec<usize> = matrix
            .outer_iterator()
            .flat_map(|outer| outer.indices().to_vec())
            .collect();
        used.sort_unstable();
        used.dedup();
        Some(used)
    } else {
        None
    };
    let slot_count = renumber.as_ref().map_or(inner_dim, Vec::len);
    let mut reduction = if slot_count < u32::MAX as usize {
        reduce::<P, u32>(matrix, renumber.as_deref(), slot_count, skip, want_pivots)
    } else {
        reduce::<P, usize>(matrix, renumber.as_deref(), slot_count, skip, want_pivots)
    };
    if let Some(used) = renumber {
        for pivot in &mut reduction.pivots {
            *pivot = used.get(*pivot).copied().unwrap_or(*pivot);
        }
    }
    reduction
}

/// The column reduction proper; see [`rank`]. Pivots are returned as slots.
fn reduce<const P: u64, I: Slot>(
    matrix: &CsMat<i8>,
    renumber: Option<&[usize]>,
    slot_count: usize,
    skip: &[usize],
    want_pivots: bool,
) -> Reduction {
    let slot_of = |inner: usize| -> I {
        I::from_usize(match renumber {
            Some(used) => used.binary_search(&inner).unwrap_or_default(),
            None => inner,
        })
    };
    // owner[slot] = index (into `starts`) of the reduced column with that
    // pivot. Column indices are < rank <= slot_count, so they never hit NONE.
    let mut owner = vec![I::NONE; slot_count];
    // Reduced, nonzero columns, stored back to back, each scaled so that its
    // pivot (last entry) is 1.
    let mut arena: Vec<Entry<I>> = Vec::with_capacity(matrix.nnz());
    let mut starts: Vec<usize> = vec![0];
    let mut pivots = Vec::new();
    let mut work: Vec<Entry<I>> = Vec::new();
    let mut scratch: Vec<Entry<I>> = Vec::new();

    let mut skip = skip.iter().copied().peekable();
    for (k, outer) in matrix.outer_iterator().enumerate() {
        while skip.next_if(|&s| s < k).is_some() {}
        if skip.next_if_eq(&k).is_some() {
            continue;
        }
        work.clear();
        for (inner, &value) in outer.iter() {
            let value = i64::from(value).rem_euclid(P as i64) as u32;
            if value != 0 {
                work.push((slot_of(inner), value));
            }
        }
        // Valid CsMat vectors are sorted and duplicate-free, and renumbering
        // preserves the order; be defensive about unchecked inputs anyway.
        if !work.windows(2).all(|w| w[0].0 < w[1].0) {
            normalise::<P, I>(&mut work);
        }

        while let Some(&(pivot, value)) = work.last() {
            let column = owner[pivot.index()];
            if column == I::NONE {
                break;
            }
            let column = &arena[starts[column.index()]..starts[column.index() + 1]];
            // work -= value * column cancels the pivot, as column's is 1.
            subtract_scaled::<P, I>(&work, column, u64::from(value), &mut scratch);
            std::mem::swap(&mut work, &mut scratch);
        }

        if let Some(&(pivot, value)) = work.last() {
            owner[pivot.index()] = I::from_usize(starts.len() - 1);
            if value == 1 {
                arena.extend_from_slice(&work);
            } else {
                let inverse = inverse_mod::<P>(u64::from(value));
                arena.extend(
                    work.iter()
                        .map(|&(slot, v)| (slot, (u64::from(v) * inverse % P) as u32)),
                );
            }
            starts.push(arena.len());
            if want_pivots {
                pivots.push(pivot.index());
            }
        }
    }
    Reduction {
        rank: starts.len() - 1,
        pivots,
    }
}

/// Sorts a sparse vector by index, adds up duplicates and drops zeros.
fn normalise<const P: u64, I: Slot>(vector: &mut Vec<Entry<I>>) {
    vector.sort_unstable_by_key(|e| e.0);
    let mut merged: Vec<Entry<I>> = Vec::with_capacity(vector.len());
    for &(index, value) in vector.iter() {
        match merged.last_mut() {
            Some(last) if last.0 == index => {
                last.1 = ((u64::from(last.1) + u64::from(value)) % P) as u32;
            }
            _ => merged.push((index, value)),
        }
    }
    merged.retain(|e| e.1 != 0);
    *vector = merged;
}

/// `out = a - factor * b` over `Z/P` (`0 < factor < P`), for sorted sparse
/// vectors `a`, `b` with values in `1..P`.
fn subtract_scaled<const P: u64, I: Slot>(
    a: &[Entry<I>],
    b: &[Entry<I>],
    factor: u64,
    out: &mut Vec<Entry<I>>,
) {
    out.clear();
    out.reserve(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    if P == 2 {
        // Over Z/2 all values are 1: symmetric difference of the supports.
        while i < a.len() && j < b.len() {
            let (ra, rb) = (a[i].0, b[j].0);
            if ra < rb {
                out.push(a[i]);
                i += 1;
            } else if rb < ra {
                out.push(b[j]);
                j += 1;
            } else {
                i += 1;
                j += 1;
            }
        }
        out.extend_from_slice(&a[i..]);
        out.extend_from_slice(&b[j..]);
        return;
    }
    // a - factor * b = a + (P - factor) * b; one reduction per entry
    // (the sum stays below 2^32 + 2^62).
    let negated = P - factor % P;
    while i < a.len() && j < b.len() {
        let (ra, va) = a[i];
        let (rb, vb) = b[j];
        if ra < rb {
            out.push((ra, va));
            i += 1;
        } else if rb < ra {
            // negated, vb in 1..P and P prime: the product is nonzero.
            out.push((rb, (negated * u64::from(vb) % P) as u32));
            j += 1;
        } else {
            let v = (u64::from(va) + negated * u64::from(vb)) % P;
            if v != 0 {
                out.push((ra, v as u32));
            }
            i += 1;
            j += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend(
        b[j..]
            .iter()
            .map(|&(rb, vb)| (rb, (negated * u64::from(vb) % P) as u32)),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sprs::TriMat;
    use std::collections::{BTreeSet, HashMap};

    /// A CSR matrix from `(row, col, value)` triplets (no duplicates).
    fn matrix(shape: (usize, usize), triplets: &[(usize, usize, i8)]) -> CsMat<i8> {
        let mut tri = TriMat::new(shape);
        for &(r, c, v) in triplets {
            tri.add_triplet(r, c, v);
        }
        tri.to_csr()
    }

    fn dense(m: &CsMat<i8>) -> Vec<Vec<i64>> {
        let mut d = vec![vec![0i64; m.cols()]; m.rows()];
        for (&v, (r, c)) in m.iter() {
            d[r][c] += i64::from(v);
        }
        d
    }

    /// Asserts ∂_p ∂_{p+1} = 0 over the integers.
    fn assert_chain_complex(boundaries: &[CsMat<i8>]) {
        for pair in boundaries.windows(2) {
            let (a, b) = (dense(&pair[0]), dense(&pair[1]));
            assert_eq!(pair[0].cols(), pair[1].rows());
            for row in &a {
                for c in 0..pair[1].cols() {
                    let s: i64 = row.iter().zip(&b).map(|(x, brow)| x * brow[c]).sum();
                    assert_eq!(s, 0, "∂∂ ≠ 0");
                }
            }
        }
    }

    /// Oriented boundary matrix between sorted simplices: the facet obtained
    /// by dropping vertex k appears with sign (-1)^k.
    fn simplicial_boundary(lower: &[Vec<usize>], upper: &[Vec<usize>]) -> CsMat<i8> {
        let index: HashMap<&[usize], usize> = lower
            .iter()
            .enumerate()
            .map(|(i, s)| (s.as_slice(), i))
            .collect();
        let mut triplets = Vec::new();
        for (j, simplex) in upper.iter().enumerate() {
            for k in 0..simplex.len() {
                let mut facet = simplex.clone();
                facet.remove(k);
                let i = index[facet.as_slice()];
                triplets.push((i, j, if k % 2 == 0 { 1 } else { -1 }));
            }
        }
        matrix((lower.len(), upper.len()), &triplets)
    }

    /// Cell counts and boundary matrices of the simplicial complex generated
    /// by `maximal` simplices (all of one dimension).
    fn simplicial_complex(maximal: &[Vec<usize>]) -> (Vec<usize>, Vec<CsMat<i8>>) {
        let top = maximal.first().map_or(0, Vec::len);
        let mut by_dim: Vec<BTreeSet<Vec<usize>>> = vec![BTreeSet::new(); top];
        for simplex in maximal {
            let mut simplex = simplex.clone();
            simplex.sort_unstable();
            let n = simplex.len();
            for mask in 1u32..(1 << n) {
                let face: Vec<usize> = (0..n)
                    .filter(|&i| mask & (1 << i) != 0)
                    .map(|i| simplex[i])
                    .collect();
                by_dim[face.len() - 1].insert(face);
            }
        }
        let cells: Vec<Vec<Vec<usize>>> = by_dim
            .into_iter()
            .map(|s| s.into_iter().collect())
            .collect();
        let counts = cells.iter().map(Vec::len).collect();
        let boundaries: Vec<CsMat<i8>> = cells
            .windows(2)
            .map(|w| simplicial_boundary(&w[0], &w[1]))
            .collect();
        assert_chain_complex(&boundaries);
        (counts, boundaries)
    }

    /// Cubical complex made of the unit cubes `c` of an `n^dim` grid with
    /// `keep(c)`, and all their faces. A cell is (base point, direction
    /// mask); ∂ = Σ_i (-1)^i (face at x + e_{d_i} - face at x), d_0 < d_1 < ...
    fn cubical_complex(
        n: usize,
        dim: usize,
        keep: impl Fn(&[usize]) -> bool,
    ) -> (Vec<usize>, Vec<CsMat<i8>>) {
        type Cell = (Vec<usize>, u32);
        let mut cells: Vec<BTreeSet<Cell>> = vec![BTreeSet::new(); dim + 1];
        let total = n.pow(dim as u32);
        for code in 0..total {
            let base: Vec<usize> = (0..dim).map(|d| code / n.pow(d as u32) % n).collect();
            if !keep(&base) {
                continue;
            }
            // All faces: each direction is either spanned or fixed at 0 or 1.
            for choice in 0..3usize.pow(dim as u32) {
                let mut x = base.clone();
                let mut mask = 0u32;
                for (d, xd) in x.iter_mut().enumerate() {
                    match choice / 3usize.pow(d as u32) % 3 {
                        0 => mask |= 1 << d,
                        1 => {}
                        _ => *xd += 1,
                    }
                }
                cells[mask.count_ones() as usize].insert((x, mask));
            }
        }
        let cells: Vec<Vec<Cell>> = cells.into_iter().map(|s| s.into_iter().collect()).collect();
        let mut boundaries = Vec::new();
        for p in 1..=dim {
            let index: HashMap<&Cell, usize> = cells[p - 1]
                .iter()
                .enumerate()
                .map(|(i, c)| (c, i))
                .collect();
            let mut triplets = Vec::new();
            for (j, (x, mask)) in cells[p].iter().enumerate() {
                let dirs = (0..dim).filter(|&d| mask & (1 << d) != 0);
                for (i, d) in dirs.enumerate() {
                    let sign: i8 = if i % 2 == 0 { 1 } else { -1 };
                    let face_mask = mask & !(1 << d);
                    let mut upper = x.clone();
                    upper[d] += 1;
                    triplets.push((index[&(upper, face_mask)], j, sign));
                    triplets.push((index[&(x.clone(), face_mask)], j, -sign));
                }
            }
            boundaries.push(matrix((cells[p - 1].len(), cells[p].len()), &triplets));
        }
        assert_chain_complex(&boundaries);
        (cells.iter().map(Vec::len).collect(), boundaries)
    }

    /// The standard 6-vertex, 10-triangle real projective plane.
    fn projective_plane() -> Vec<Vec<usize>> {
        [
            [1, 2, 4],
            [2, 3, 5],
            [3, 1, 6],
            [4, 5, 1],
            [5, 6, 2],
            [6, 4, 3],
            [1, 5, 3],
            [2, 6, 1],
            [3, 4, 2],
            [4, 6, 5],
        ]
        .iter()
        .map(|t| t.to_vec())
        .collect()
    }

    /// Rank by dense Gaussian elimination over f64 with partial pivoting.
    fn dense_rank(rows: &[Vec<i8>]) -> usize {
        let mut a: Vec<Vec<f64>> = rows
            .iter()
            .map(|r| r.iter().map(|&v| f64::from(v)).collect())
            .collect();
        let (m, n) = (a.len(), a.first().map_or(0, Vec::len));
        let mut rank = 0;
        for c in 0..n {
            if rank == m {
                break;
            }
            let best = (rank..m)
                .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
                .unwrap();
            if a[best][c].abs() < 1e-9 {
                continue;
            }
            a.swap(rank, best);
            let pivot_row = a[rank].clone();
            for row in a.iter_mut().skip(rank + 1) {
                let f = row[c] / pivot_row[c];
                for (x, p) in row.iter_mut().zip(&pivot_row).skip(c) {
                    *x -= f * p;
                }
            }
            rank += 1;
        }
        rank
    }

    fn both(counts: &[usize], boundaries: &[CsMat<i8>]) -> (Vec<usize>, Vec<usize>) {
        (
            betti_numbers(counts, boundaries, Field::Rationals),
            betti_numbers(counts, boundaries, Field::Z2),
        )
    }

    #[test]
    fn single_triangle() {
        let (counts, boundaries) = simplicial_complex(&[vec![0, 1, 2]]);
        assert_eq!(counts, vec![3, 3, 1]);
        let (q, z2) = both(&counts, &boundaries);
        assert_eq!(q, vec![1, 0, 0]);
        assert_eq!(z2, vec![1, 0, 0]);
        assert_eq!(euler_characteristic(&counts), 1);
    }

    #[test]
    fn triangle_boundary_is_a_circle() {
        // Hand-written ∂_1: edges 01, 02, 12 (columns) over vertices 0, 1, 2.
        let d1 = matrix(
            (3, 3),
            &[
                (0, 0, -1),
                (1, 0, 1),
                (0, 1, -1),
                (2, 1, 1),
                (1, 2, -1),
                (2, 2, 1),
            ],
        );
        assert_eq!(rank(&d1, Field::Rationals), 2);
        assert_eq!(rank(&d1, Field::Z2), 2);
        let (q, z2) = both(&[3, 3], &[d1]);
        assert_eq!(q, vec![1, 1]);
        assert_eq!(z2, vec![1, 1]);
        assert_eq!(euler_characteristic(&[3, 3]), 0);
    }

    #[test]
    fn tetrahedron_boundary_is_a_sphere() {
        let faces: Vec<Vec<usize>> =
            vec![vec![0, 1, 2], vec![0, 1, 3], vec![0, 2, 3], vec![1, 2, 3]];
        let (counts, boundaries) = simplicial_complex(&faces);
        assert_eq!(counts, vec![4, 6, 4]);
        assert_eq!(rank(&boundaries[0], Field::Rationals), 3);
        assert_eq!(rank(&boundaries[1], Field::Rationals), 3);
        let (q, z2) = both(&counts, &boundaries);
        assert_eq!(q, vec![1, 0, 1]);
        assert_eq!(z2, vec![1, 0, 1]);
        assert_eq!(euler_characteristic(&counts), 2);
    }

    #[test]
    fn two_disjoint_edges() {
        let d1 = matrix((4, 2), &[(0, 0, -1), (1, 0, 1), (2, 1, -1), (3, 1, 1)]);
        let (q, z2) = both(&[4, 2], &[d1]);
        assert_eq!(q, vec![2, 0]);
        assert_eq!(z2, vec![2, 0]);
        assert_eq!(euler_characteristic(&[4, 2]), 2);
    }

    #[test]
    fn square_annulus() {
        // 3 × 3 unit squares minus the centre one: 4 × 4 = 16 vertices,
        // 2 · 3 · 4 = 24 edges (none removed with the centre square, whose
        // sides all bound neighbouring squares), 9 - 1 = 8 squares.
        let (counts, boundaries) = cubical_complex(3, 2, |c| c != [1, 1]);
        assert_eq!(counts, vec![16, 24, 8]);
        assert_eq!(rank(&boundaries[0], Field::Rationals), 15);
        assert_eq!(rank(&boundaries[1], Field::Rationals), 8);
        let (q, z2) = both(&counts, &boundaries);
        assert_eq!(q, vec![1, 1, 0]);
        assert_eq!(z2, vec![1, 1, 0]);
        assert_eq!(euler_characteristic(&counts), 0);
    }

    #[test]
    fn projective_plane_depends_on_the_field() {
        let (counts, boundaries) = simplicial_complex(&projective_plane());
        assert_eq!(counts, vec![6, 15, 10]);
        assert_eq!(euler_characteristic(&counts), 1);
        // Over Q no 2-cycle; over Z/2 the sum of all triangles is one.
        assert_eq!(rank(&boundaries[1], Field::Rationals), 10);
        assert_eq!(rank(&boundaries[1], Field::Z2), 9);
        let (q, z2) = both(&counts, &boundaries);
        assert_eq!(q, vec![1, 0, 0]);
        assert_eq!(z2, vec![1, 1, 1]);
        // χ is the alternating sum of the Betti numbers over any field.
        assert_eq!(euler_characteristic(&q), 1);
        assert_eq!(euler_characteristic(&z2), 1);
    }

    #[test]
    fn cube_grids() {
        // Solid 4 × 4 × 4 block: 125 vertices, 3·4·25 = 300 edges,
        // 3·16·5 = 240 squares, 64 cubes; contractible.
        let (counts, boundaries) = cubical_complex(4, 3, |_| true);
        assert_eq!(counts, vec![125, 300, 240, 64]);
        let (q, z2) = both(&counts, &boundaries);
        assert_eq!(q, vec![1, 0, 0, 0]);
        assert_eq!(z2, vec![1, 0, 0, 0]);
        // 3 × 3 × 3 block minus the centre cube: a thickened sphere.
        let (counts, boundaries) = cubical_complex(3, 3, |c| c != [1, 1, 1]);
        assert_eq!(counts, vec![64, 144, 108, 26]);
        let (q, z2) = both(&counts, &boundaries);
        assert_eq!(q, vec![1, 0, 1, 0]);
        assert_eq!(z2, vec![1, 0, 1, 0]);
        assert_eq!(euler_characteristic(&counts), 2);
    }

    /// β_p from separate, unclear ranks: checks the clearing shortcut.
    fn betti_without_clearing(
        counts: &[usize],
        boundaries: &[CsMat<i8>],
        field: Field,
    ) -> Vec<usize> {
        let mut ranks = vec![0; counts.len() + 1];
        for (p, d) in boundaries.iter().enumerate() {
            ranks[p + 1] = rank(d, field);
        }
        counts
            .iter()
            .enumerate()
            .map(|(p, &k)| k - ranks[p] - ranks[p + 1])
            .collect()
    }

    #[test]
    fn clearing_agrees_with_separate_ranks() {
        let complexes = [
            simplicial_complex(&projective_plane()),
            cubical_complex(3, 3, |c| c != [1, 1, 1]),
            cubical_complex(4, 3, |c| (c[0] + c[1] + c[2]) % 3 != 0),
            cubical_complex(5, 2, |c| c[0] % 2 == 0 || c[1] == 2),
        ];
        for (counts, boundaries) in &complexes {
            for field in [Field::Rationals, Field::Z2] {
                let expected = betti_without_clearing(counts, boundaries, field);
                assert_eq!(betti_numbers(counts, boundaries, field), expected);
                let csc: Vec<CsMat<i8>> = boundaries.iter().map(CsMat::to_csc).collect();
                assert_eq!(betti_numbers(counts, &csc, field), expected);
                let chi: i64 = euler_characteristic(counts);
                assert_eq!(euler_characteristic(&expected), chi);
            }
        }
    }

    #[test]
    fn inconsistent_input_does_not_panic() {
        let d1 = matrix((2, 1), &[(0, 0, -1), (1, 0, 1)]);
        let d2 = matrix((5, 4), &[(4, 3, 1), (0, 0, 1)]);
        for field in [Field::Rationals, Field::Z2] {
            assert_eq!(
                betti_numbers(&[1, 7, 0], &[d1.clone(), d2.clone()], field).len(),
                3
            );
            assert_eq!(
                betti_numbers(&[0, 0, 0], &[d2.clone(), d1.clone()], field),
                vec![0, 0, 0]
            );
        }
    }

    #[test]
    fn storage_order_and_transpose_do_not_matter() {
        let (_, boundaries) = simplicial_complex(&projective_plane());
        for d in &boundaries {
            for field in [Field::Rationals, Field::Z2] {
                let r = rank(d, field);
                assert_eq!(rank(&d.to_csc(), field), r);
                assert_eq!(rank(&d.transpose_view().to_owned(), field), r);
                assert_eq!(rank(&d.transpose_view().to_csr(), field), r);
            }
        }
    }

    #[test]
    fn empty_and_zero_matrices() {
        for field in [Field::Rationals, Field::Z2] {
            assert_eq!(rank(&CsMat::zero((0, 0)), field), 0);
            assert_eq!(rank(&CsMat::zero((0, 5)), field), 0);
            assert_eq!(rank(&CsMat::zero((5, 0)), field), 0);
            assert_eq!(rank(&CsMat::<i8>::zero((0, 5)).to_csc(), field), 0);
            assert_eq!(rank(&CsMat::<i8>::zero((5, 0)).to_csc(), field), 0);
            // Explicitly stored zeros.
            let zeros = CsMat::new((2, 2), vec![0, 1, 2], vec![0, 1], vec![0i8, 0]);
            assert_eq!(rank(&zeros, field), 0);
            assert!(betti_numbers(&[], &[], field).is_empty());
            assert_eq!(
                betti_numbers(&[0, 0], &[CsMat::zero((0, 0))], field),
                vec![0, 0]
            );
            // Missing boundaries are zero maps, surplus ones are ignored.
            assert_eq!(betti_numbers(&[3], &[], field), vec![3]);
            assert_eq!(betti_numbers(&[2, 1], &[], field), vec![2, 1]);
            let d1 = matrix((2, 1), &[(0, 0, -1), (1, 0, 1)]);
            assert_eq!(
                betti_numbers(&[2], std::slice::from_ref(&d1), field),
                vec![2]
            );
            assert_eq!(betti_numbers(&[2, 1], &[d1.clone(), d1], field), vec![1, 0]);
        }
        assert_eq!(euler_characteristic(&[]), 0);
    }

    #[test]
    fn z2_sees_only_parity() {
        let two = matrix((1, 1), &[(0, 0, 2)]);
        assert_eq!(rank(&two, Field::Rationals), 1);
        assert_eq!(rank(&two, Field::Z2), 0);
        let hadamard = matrix((2, 2), &[(0, 0, 1), (0, 1, 1), (1, 0, 1), (1, 1, -1)]);
        assert_eq!(rank(&hadamard, Field::Rationals), 2);
        assert_eq!(rank(&hadamard, Field::Z2), 1);
        let extremes = matrix(
            (2, 2),
            &[
                (0, 0, i8::MIN),
                (0, 1, i8::MAX),
                (1, 0, i8::MAX),
                (1, 1, i8::MIN),
            ],
        );
        // det = 128² - 127² = 255.
        assert_eq!(rank(&extremes, Field::Rationals), 2);
        assert_eq!(rank(&extremes, Field::Z2), 2);
    }

    #[test]
    fn huge_inner_dimension_is_renumbered() {
        // 10^12 rows, 3 columns: CSC storage only stores the 3 columns.
        let rows = 1_000_000_000_000usize;
        let csc = CsMat::new_csc(
            (rows, 3),
            vec![0, 2, 4, 6],
            vec![5, rows - 1, 5, 77, 77, rows - 1],
            vec![1i8, -1, 1, -1, 1, -1],
        );
        // Columns e_5 - e_last, e_5 - e_77, e_77 - e_last: rank 2 (first = second + third).
        assert_eq!(rank(&csc, Field::Rationals), 2);
        assert_eq!(rank(&csc, Field::Z2), 2);
        let csr = csc.transpose_view().to_owned();
        assert!(csr.is_csr());
        assert_eq!(rank(&csr, Field::Rationals), 2);
        // A 1-complex with 10^12 vertices and 3 edges, and its "cohomology"
        // counterpart: CSR with 10^12 columns is reduced by rows.
        for field in [Field::Rationals, Field::Z2] {
            assert_eq!(
                betti_numbers(&[rows, 3], std::slice::from_ref(&csc), field),
                vec![rows - 2, 1]
            );
            assert_eq!(
                betti_numbers(&[3, rows], std::slice::from_ref(&csr), field),
                vec![1, rows - 2]
            );
        }
    }

    #[test]
    fn modular_inverse() {
        for a in [1u64, 2, 3, 12345, MERSENNE_31 - 1, 1 << 30] {
            assert_eq!(a * inverse_mod::<MERSENNE_31>(a) % MERSENNE_31, 1);
        }
        assert_eq!(inverse_mod::<2>(1), 1);
    }

    #[test]
    fn euler_characteristics() {
        assert_eq!(euler_characteristic(&[3, 3, 1]), 1);
        assert_eq!(euler_characteristic(&[16, 24, 8]), 0);
        assert_eq!(euler_characteristic(&[64, 144, 108, 26]), 2);
        assert_eq!(euler_characteristic(&[125, 300, 240, 64]), 1);
        assert_eq!(euler_characteristic(&[7]), 7);
    }

    fn small_matrix() -> impl Strategy<Value = Vec<Vec<i8>>> {
        (0usize..=8, 0usize..=8).prop_flat_map(|(m, n)| {
            // Weighted towards zeros so that rank deficiency is common.
            let entry = prop_oneof![3 => Just(0i8), 1 => Just(1i8), 1 => Just(-1i8)];
            proptest::collection::vec(proptest::collection::vec(entry, n), m)
        })
    }

    fn to_sparse(rows: &[Vec<i8>]) -> CsMat<i8> {
        let n = rows.first().map_or(0, Vec::len);
        let mut triplets = Vec::new();
        for (r, row) in rows.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                if v != 0 {
                    triplets.push((r, c, v));
                }
            }
        }
        matrix((rows.len(), n), &triplets)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn rank_matches_dense_elimination(rows in small_matrix()) {
            let sparse = to_sparse(&rows);
            let expected = dense_rank(&rows);
            prop_assert_eq!(rank(&sparse, Field::Rationals), expected);
            prop_assert_eq!(rank(&sparse.to_csc(), Field::Rationals), expected);
            let z2 = rank(&sparse, Field::Z2);
            prop_assert!(z2 <= expected);
            prop_assert_eq!(rank(&sparse.to_csc(), Field::Z2), z2);
            // Over Z/2 a ±1 matrix is its 0/1 pattern.
            let pattern: Vec<Vec<i8>> = rows.iter().map(|r| r.iter().map(|v| v.abs()).collect()).collect();
            prop_assert_eq!(rank(&to_sparse(&pattern), Field::Z2), z2);
        }
    }
}
