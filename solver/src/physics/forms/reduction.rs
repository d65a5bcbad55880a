//! Cohomology generators of every degree by integer column reduction of
//! the coboundary matrices (the "standard algorithm" of persistence, in
//! its cohomology form with clearing), and the gauge that makes the
//! exact-part solve of degree k ≥ 2 definite.
//!
//! # The reduction
//!
//! δᵏ (rows: (k+1)-cells, columns: k-cells) is reduced column by column in
//! index order: while column j's lowest nonzero row (its *low*) is the low
//! of an earlier reduced column i, column j becomes a·R_j − b·R_i with
//! a = R_i[low]/g, b = R_j[low]/g, g = gcd (fraction free, so exact over Z
//! without a prime or rational numbers). The same operations on the
//! identity give V with R = δᵏ V exactly in integers; V is upper
//! triangular with a nonzero diagonal (±1 while every pivot is ±1, which is
//! what the meshes here give). Each column of R and V together is divided
//! by the gcd of its entries, which keeps the entries small.
//!
//! Then, as for any persistence reduction:
//!
//! - a column j with R_j = 0 gives an integer cocycle V_j (δᵏ V_j = R_j = 0
//!   exactly), whose lowest entry is at row j;
//! - the nonzero columns of the reduced δ^{k−1} have distinct lows, k-cells
//!   ("paired" cells), and span im δ^{k−1};
//! - the cocycles V_j of the *unpaired* zero columns (the essential k-cells)
//!   are independent modulo im δ^{k−1}: together with the nonzero R columns
//!   of δ^{k−1} they have pairwise distinct lows, so they are independent
//!   and, by their count dim ker δᵏ, a basis of ker δᵏ. Hence they give a
//!   basis of Hᵏ(K; Q), β_k of them.
//!
//! Clearing (Chen–Kerber "twist"): a k-cell that is the low of a reduced
//! column of δ^{k−1} has a column of δᵏ that would reduce to zero (it is a
//! combination of earlier columns, since δᵏ δ^{k−1} = 0), so it is skipped;
//! those are exactly the paired cells, and the expensive columns.
//!
//! Every cocycle is checked closed in integer arithmetic before it is
//! returned, and an integer overflow in the reduction is an error rather
//! than a wrong result. Over Z the cocycles generate Hᵏ(K; Q); on a complex
//! with torsion in its cohomology (never one embedded in R³) a class may be
//! a multiple of a primitive integer class.

use super::FormsError;
use hasse_complex::Complex;
use sprs::CsMat;
use std::sync::Arc;

/// A sparse integer column: (row, value), rows increasing, values nonzero.
type Column = Vec<(usize, i64)>;

/// The outcome of reducing one coboundary matrix.
pub(super) struct Reduction {
    /// Per row: whether it is the low of a nonzero reduced column (a
    /// paired cell of the next degree).
    pub paired: Vec<bool>,
    /// Per column: whether its reduced column is nonzero (its original
    /// column is then independent of the earlier ones: together these
    /// columns are a basis of the image).
    pub independent: Vec<bool>,
    /// (column, V_column) of the columns that reduced to zero and were not
    /// skipped, when V was kept.
    pub cycles: Vec<(usize, Column)>,
}

fn gcd(mut a: i64, mut b: i64) -> i64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.abs()
}

fn overflow() -> FormsError {
    FormsError::Cohomology(
        "the integer reduction of the coboundary overflowed 64-bit integers (coefficient growth); cohomology generators could not be computed exactly".into(),
    )
}

/// a·x − b·y for sorted sparse columns, dropping zeros; checked.
fn combine(a: i64, x: &[(usize, i64)], b: i64, y: &[(usize, i64)]) -> Result<Column, FormsError> {
    let mut out = Vec::with_capacity(x.len() + y.len());
    let (mut i, mut j) = (0, 0);
    while i < x.len() || j < y.len() {
        let (rx, ry) = (x.get(i).map(|e| e.0), y.get(j).map(|e| e.0));
        // The next row in either column; each column whose next entry sits
        // there contributes to it.
        let row = match (rx, ry) {
            (Some(r), Some(q)) => r.min(q),
            (Some(r), None) | (None, Some(r)) => r,
            (None, None) => break,
        };
        let mut value = 0i64;
        if rx == Some(row) {
            value = a.checked_mul(x[i].1).ok_or_else(overflow)?;
            i += 1;
        }
        if ry == Some(row) {
            let by = b.checked_mul(y[j].1).ok_or_else(overflow)?;
            value = value.checked_sub(by).ok_or_else(overflow)?;
            j += 1;
        }
        if value != 0 {
            out.push((row, value));
        }
    }
    Ok(out)
}

/// Divide both columns by the gcd of all their entries.
fn normalise(r: &mut Column, v: &mut Column) {
    let g = r.iter().chain(v.iter()).fold(0, |g, &(_, x)| gcd(g, x));
    if g > 1 {
        r.iter_mut().chain(v.iter_mut()).for_each(|(_, x)| *x /= g);
    }
}

/// The columns of an integer matrix as sorted sparse columns.
fn columns(matrix: &CsMat<i8>) -> Vec<Column> {
    let mut cols = vec![Vec::new(); matrix.cols()];
    // sprs yields (row, column) whatever the storage.
    for (&value, (i, j)) in matrix.iter() {
        if value != 0 {
            cols[j].push((i, i64::from(value)));
        }
    }
    cols.iter_mut()
        .for_each(|c| c.sort_unstable_by_key(|e| e.0));
    cols
}

/// Reduce the columns of `matrix` (`rows` rows) not marked in `skip`; with
/// `keep_cycles` track V and return the columns that reduce to zero.
pub(super) fn reduce(
    matrix: &CsMat<i8>,
    rows: usize,
    skip: &[bool],
    keep_cycles: bool,
) -> Result<Reduction, FormsError> {
    let cols = columns(matrix);
    let mut owner = vec![usize::MAX; rows];
    let mut reduced: Vec<Column> = vec![Vec::new(); cols.len()];
    let mut transforms: Vec<Column> = vec![Vec::new(); cols.len()];
    let mut independent = vec![false; cols.len()];
    let mut cycles = Vec::new();
    for (j, column) in cols.into_iter().enumerate() {
        if skip.get(j).copied().unwrap_or(false) {
            continue;
        }
        let mut r = column;
        let mut v: Column = if keep_cycles {
            vec![(j, 1)]
        } else {
            Vec::new()
        };
        while let Some(&(low, value)) = r.last() {
            let i = owner[low];
            if i == usize::MAX {
                owner[low] = j;
                independent[j] = true;
                break;
            }
            let pivot = reduced[i].last().map_or(1, |e| e.1);
            let g = gcd(pivot, value);
            let (a, b) = (pivot / g, value / g);
            r = combine(a, &r, b, &reduced[i])?;
            if keep_cycles {
                v = combine(a, &v, b, &transforms[i])?;
            }
            normalise(&mut r, &mut v);
        }
        if independent[j] {
            reduced[j] = r;
            transforms[j] = v;
        } else if keep_cycles {
            cycles.push((j, v));
        }
    }
    Ok(Reduction {
        paired: owner.iter().map(|&o| o != usize::MAX).collect(),
        independent,
        cycles,
    })
}

/// The coboundaries δ⁰ … δⁿ of a cochain complex as integer matrices
/// (δᵖ: (p+1)-cells × p-cells; δⁿ the empty 0 × |K_n|): the complex's own
/// (absolute cochains) or restricted to the cells off the boundary
/// subcomplex (relative cochains, `relative.rs`). The reduction reads
/// only these, so both cohomologies come from the same code.
pub(super) struct Coboundaries(Vec<Arc<CsMat<i8>>>);

impl Coboundaries {
    /// δ⁰ … δⁿ of the complex itself (shared, no copy).
    pub(super) fn absolute(complex: &Complex) -> Self {
        let n = complex.dim();
        Self(
            (0..=n)
                .map(|p| {
                    if p == n {
                        Arc::new(CsMat::zero((0, complex.cell_count(n))))
                    } else {
                        Arc::clone(complex.coboundary(p))
                    }
                })
                .collect(),
        )
    }

    /// Given matrices, δ⁰ … δⁿ in order; δᵖ must have as many columns as
    /// δ^{p−1} has rows (checked by the caller that builds them).
    pub(super) fn new(matrices: Vec<CsMat<i8>>) -> Self {
        Self(matrices.into_iter().map(Arc::new).collect())
    }

    /// δᵖ (p ≤ n).
    fn delta(&self, p: usize) -> &CsMat<i8> {
        // Every caller has p ≤ n (degrees are checked before); clamping
        // keeps a wrong degree from panicking (δⁿ has no rows, so nothing
        // above n is ever reduced).
        let last = self.0.len().saturating_sub(1);
        &self.0[p.min(last)]
    }

    /// How many p-cells the cochain complex has.
    fn cells(&self, p: usize) -> usize {
        self.delta(p).cols()
    }
}

/// The reduction of δ^{k−1} with clearing from the degrees below: which
/// k-cells are paired, and which (k−1)-cells have independent columns.
/// None for k = 0.
fn reduce_below(deltas: &Coboundaries, k: usize) -> Result<Option<Reduction>, FormsError> {
    let mut last: Option<Reduction> = None;
    for p in 0..k {
        let skip = last.as_ref().map(|r| r.paired.clone()).unwrap_or_default();
        last = Some(reduce(deltas.delta(p), deltas.cells(p + 1), &skip, false)?);
    }
    Ok(last)
}

/// Integer cocycles of a basis of Hᵏ(K; Q), any degree, any complex (see
/// the module docs); each is verified closed in integers.
pub(super) fn cocycles(complex: &Complex, k: usize) -> Result<Vec<Vec<f64>>, FormsError> {
    cocycles_of(&Coboundaries::absolute(complex), k)
}

/// Integer cocycles of a basis of Hᵏ of the cochain complex `deltas`, as
/// cochains on its k-cells; each is verified closed in integers.
pub(super) fn cocycles_of(deltas: &Coboundaries, k: usize) -> Result<Vec<Vec<f64>>, FormsError> {
    let cells = deltas.cells(k);
    let paired = reduce_below(deltas, k)?
        .map(|r| r.paired)
        .unwrap_or_else(|| vec![false; cells]);
    let delta = deltas.delta(k);
    let rows = delta.rows();
    let reduction = reduce(delta, rows, &paired, true)?;
    let full = columns(delta);
    reduction
        .cycles
        .into_iter()
        .map(|(_, v)| {
            // δ z = 0 in integers, row by row (the reduction guarantees it;
            // this is the check the result is returned on).
            let mut image = vec![0i64; rows];
            for &(cell, value) in &v {
                for &(row, s) in &full[cell] {
                    let term = s.checked_mul(value).ok_or_else(overflow)?;
                    image[row] = image[row].checked_add(term).ok_or_else(overflow)?;
                }
            }
            if image.iter().any(|&x| x != 0) {
                return Err(FormsError::Cohomology(format!(
                    "a lifted {k}-cochain is not closed in integer arithmetic (torsion, or a non-orientable complex); no integer cocycle generators"
                )));
            }
            let mut z = vec![0.0; cells];
            for (cell, value) in v {
                // Entries are small (|value| < 2^53 is checked to be exact).
                if value.unsigned_abs() > 1 << 53 {
                    return Err(overflow());
                }
                z[cell] = value as f64;
            }
            Ok(z)
        })
        .collect()
}

/// The (k−1)-cells whose columns of δ^{k−1} are a basis of im δ^{k−1}
/// (k ≥ 1): holding α = 0 on the others makes d_{k−1}ᵀ ⋆ d_{k−1} definite
/// without changing the exact part d α it can reach.
pub(super) fn exact_gauge(complex: &Complex, k: usize) -> Result<Vec<bool>, FormsError> {
    exact_gauge_of(&Coboundaries::absolute(complex), k)
}

/// [`exact_gauge`] of the cochain complex `deltas`, on its (k−1)-cells.
pub(super) fn exact_gauge_of(deltas: &Coboundaries, k: usize) -> Result<Vec<bool>, FormsError> {
    Ok(reduce_below(deltas, k)?
        .map(|r| r.independent)
        .unwrap_or_default())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boundary of a triangle as a 1-complex: δ⁰ of the 3-cycle
    /// (edges 01, 02, 12: −1 at the tail, +1 at the head) by hand. H¹ = Z,
    /// one generator; its cocycle evaluates to ±1 on the cycle 01 − 02 + 12.
    #[test]
    fn cycle_graph_has_one_generator() {
        // Rows edges, columns vertices (CSR).
        let d0 = CsMat::new(
            (3, 3),
            vec![0, 2, 4, 6],
            vec![0, 1, 0, 2, 1, 2],
            vec![-1i8, 1, -1, 1, -1, 1],
        );
        let below = reduce(&d0, 3, &[], false).unwrap();
        // Two independent vertex columns (rank δ⁰ = 2), two paired edges.
        assert_eq!(below.independent.iter().filter(|b| **b).count(), 2);
        assert_eq!(below.paired.iter().filter(|b| **b).count(), 2);
        let empty = CsMat::<i8>::zero((0, 3));
        let top = reduce(&empty, 0, &below.paired, true).unwrap();
        assert_eq!(top.cycles.len(), 1);
        let (_, z) = &top.cycles[0];
        let mut dense = [0i64; 3];
        z.iter().for_each(|&(e, v)| dense[e] = v);
        let period = dense[0] - dense[1] + dense[2];
        assert_eq!(period.abs(), 1);
    }
}
