//! Unknowns held at known values: the one place where a system is split
//! into free and fixed unknowns, reduced to the free ones and lifted back.
//!
//! For M x = b with x_d = g known (Dirichlet values, prescribed fluxes,
//! walls), the free unknowns solve
//!
//! ```text
//! M_ff x_f = b_f − M_fd g
//! ```
//!
//! which keeps a symmetric M symmetric (and positive definite when M is):
//! the fixed rows are dropped and the fixed columns move to the right-hand
//! side. A canonical operator Aᵀ Ω A reduces the same way by dropping the
//! fixed columns of A ([`FixedSplit::restrict_columns`]): (A E)ᵀ Ω (A E) =
//! M_ff with E the selection of the free unknowns.

use crate::la::parallel::{ranges, split_at_ranges};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;
use sprs::CsMat;

/// Which unknowns of a system are free, in increasing order, and the
/// position of each among them. The values of the fixed unknowns are
/// given where they are needed (they may change while the split stays,
/// as Dirichlet data in time do).
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use hasse_solver::la::fixed::FixedSplit;
/// // tridiag(−1, 2, −1) on 4 unknowns with x₀ = 1 and x₃ = 4 held: the
/// // free block [[2, −1], [−1, 2]] and b_f = (0, 0) + (1, 4).
/// let mut t = Vec::new();
/// for i in 0..4 {
///     t.push(Triplet::new(i, i, 2.0));
///     if i + 1 < 4 {
///         t.push(Triplet::new(i, i + 1, -1.0));
///         t.push(Triplet::new(i + 1, i, -1.0));
///     }
/// }
/// let m = SparseColMat::<usize, f64>::try_new_from_triplets(4, 4, &t).unwrap();
/// let fixed = [Some(1.0), None, None, Some(4.0)];
/// let split = FixedSplit::new(&fixed);
/// assert_eq!(split.free(), &[1, 2]);
/// assert_eq!(split.free_block(&m).to_dense()[(0, 1)], -1.0);
/// assert_eq!(split.reduced_rhs(&m, &[0.0; 4], &fixed), vec![1.0, 4.0]);
/// // The free solution of [[2, −1], [−1, 2]] x = (1, 4) is (2, 3).
/// assert_eq!(split.lift(&[2.0, 3.0], &fixed), vec![1.0, 2.0, 3.0, 4.0]);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FixedSplit {
    free: Vec<usize>,
    /// Position among the free unknowns, `usize::MAX` for a fixed one.
    index: Vec<usize>,
}

impl FixedSplit {
    /// The split of `fixed` (one entry per unknown: `Some(value)` held,
    /// `None` free).
    pub fn new(fixed: &[Option<f64>]) -> Self {
        Self::from_mask(fixed.iter().map(Option::is_some))
    }

    /// The split from one flag per unknown, `true` for a fixed one.
    pub fn from_mask(fixed: impl IntoIterator<Item = bool>) -> Self {
        let mut free = Vec::new();
        let index = fixed
            .into_iter()
            .enumerate()
            .map(|(i, is_fixed)| {
                if is_fixed {
                    usize::MAX
                } else {
                    free.push(i);
                    free.len() - 1
                }
            })
            .collect();
        Self { free, index }
    }

    /// Number of unknowns, free and fixed.
    pub fn unknowns(&self) -> usize {
        self.index.len()
    }

    /// The free unknowns, in increasing order.
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// The position of unknown `i` among the free ones, `None` if it is
    /// fixed.
    pub fn free_index(&self, i: usize) -> Option<usize> {
        self.index.get(i).copied().filter(|&k| k != usize::MAX)
    }

    /// Whether unknown `i` is fixed.
    pub fn is_fixed(&self, i: usize) -> bool {
        self.free_index(i).is_none()
    }

    /// Whether no unknown is fixed.
    pub fn all_free(&self) -> bool {
        self.free.len() == self.index.len()
    }

    /// M_ff: the block of `matrix` on the free unknowns. Renumbering keeps
    /// the order of the rows, so the CSC invariants of `matrix` carry over
    /// and nothing is sorted; the columns are copied in parallel ranges,
    /// each counted and then written in place.
    pub fn free_block(&self, matrix: &SparseColMat<usize, f64>) -> SparseColMat<usize, f64> {
        let free_index = &self.index;
        let kept_rows = |j: usize| {
            let range = matrix.col_range(j);
            matrix.row_idx()[range.clone()]
                .iter()
                .zip(&matrix.val()[range])
                .filter(|(&i, _)| free_index[i] != usize::MAX)
                .map(|(&i, &v)| (free_index[i], v))
        };
        let free = &self.free;
        let size = free.len();
        let parts = ranges(size);
        let mut col_ptr = vec![0usize; size + 1];
        let counts = split_at_ranges(&mut col_ptr[1..], &parts, |k| k);
        parts.par_iter().zip(counts).for_each(|(range, counts)| {
            for (k, count) in range.clone().zip(counts) {
                *count = kept_rows(free[k]).count();
            }
        });
        for k in 0..size {
            col_ptr[k + 1] += col_ptr[k];
        }
        let mut row_idx = vec![0usize; col_ptr[size]];
        let mut val = vec![0.0; col_ptr[size]];
        let row_pieces = split_at_ranges(&mut row_idx, &parts, |k| col_ptr[k]);
        let val_pieces = split_at_ranges(&mut val, &parts, |k| col_ptr[k]);
        parts
            .par_iter()
            .zip(row_pieces.into_par_iter().zip(val_pieces))
            .for_each(|(range, (rows_out, vals_out))| {
                let slots = rows_out.iter_mut().zip(vals_out.iter_mut());
                let entries = range.clone().flat_map(|k| kept_rows(free[k]));
                for ((row, value), (i, v)) in slots.zip(entries) {
                    *row = i;
                    *value = v;
                }
            });
        let symbolic = SymbolicSparseColMat::new_checked(size, size, col_ptr, None, row_idx);
        SparseColMat::new(symbolic, val)
    }

    /// b_f − M_fd g: the free rows of `rhs` with the fixed columns of
    /// `matrix` times their values `fixed` moved over, column after column
    /// of the fixed unknowns.
    pub fn reduced_rhs(
        &self,
        matrix: &SparseColMat<usize, f64>,
        rhs: &[f64],
        fixed: &[Option<f64>],
    ) -> Vec<f64> {
        let mut reduced = self.restrict(rhs);
        for (j, g) in fixed.iter().enumerate() {
            if let Some(g) = *g {
                let range = matrix.col_range(j);
                for (&i, &v) in matrix.row_idx()[range.clone()]
                    .iter()
                    .zip(&matrix.val()[range])
                {
                    if let Some(k) = self.free_index(i) {
                        reduced[k] -= v * g;
                    }
                }
            }
        }
        reduced
    }

    /// M_fd: the entries (free position, fixed unknown, value) of `matrix`
    /// in free rows and fixed columns, column after column, to move new
    /// fixed values to the right-hand side without the matrix
    /// ([`FixedSplit::lift_into`]).
    pub fn coupling(&self, matrix: &SparseColMat<usize, f64>) -> Vec<(usize, usize, f64)> {
        let mut entries = Vec::new();
        for j in (0..matrix.ncols()).filter(|&j| self.is_fixed(j)) {
            let range = matrix.col_range(j);
            for (&i, &v) in matrix.row_idx()[range.clone()]
                .iter()
                .zip(&matrix.val()[range])
            {
                if let Some(k) = self.free_index(i) {
                    entries.push((k, j, v));
                }
            }
        }
        entries
    }

    /// rhs_f −= M_fd g for the entries of [`FixedSplit::coupling`] and the
    /// values `fixed` (a fixed unknown without a value counts as 0).
    pub fn lift_into(coupling: &[(usize, usize, f64)], fixed: &[Option<f64>], rhs: &mut [f64]) {
        for &(k, j, v) in coupling {
            rhs[k] -= v * fixed[j].unwrap_or(0.0);
        }
    }

    /// v_f: the free entries of `v`.
    pub fn restrict(&self, v: &[f64]) -> Vec<f64> {
        self.free.iter().map(|&i| v[i]).collect()
    }

    /// The whole vector: free unknowns from `x_free`, fixed ones at their
    /// values in `fixed` (0 where a fixed unknown has none).
    pub fn lift(&self, x_free: &[f64], fixed: &[Option<f64>]) -> Vec<f64> {
        let mut x: Vec<f64> = (0..self.unknowns())
            .map(|i| fixed.get(i).copied().flatten().unwrap_or(0.0))
            .collect();
        for (&i, &v) in self.free.iter().zip(x_free) {
            x[i] = v;
        }
        x
    }

    /// A E: the columns of an incidence matrix (rows × unknowns) on the
    /// free unknowns, renumbered; the canonical operator (A E)ᵀ Ω (A E) is
    /// M_ff.
    pub fn restrict_columns(&self, a: &CsMat<i8>) -> CsMat<i8> {
        let a = if a.is_csr() { a } else { &a.to_csr() };
        let mut indptr = Vec::with_capacity(a.rows() + 1);
        let mut indices = Vec::with_capacity(a.nnz());
        let mut data = Vec::with_capacity(a.nnz());
        indptr.push(0);
        for row in a.outer_iterator() {
            for (j, &v) in row.iter() {
                if let Some(k) = self.free_index(j) {
                    indices.push(k);
                    data.push(v);
                }
            }
            indptr.push(indices.len());
        }
        CsMat::new((a.rows(), self.free.len()), indptr, indices, data)
    }

    /// Eᵀ A: the rows of a matrix (unknowns × anything) at the free
    /// unknowns, renumbered.
    pub fn restrict_rows(&self, a: &CsMat<i8>) -> CsMat<i8> {
        let a = if a.is_csr() { a } else { &a.to_csr() };
        let mut indptr = Vec::with_capacity(self.free.len() + 1);
        let mut indices = Vec::new();
        let mut data = Vec::new();
        indptr.push(0);
        for &i in &self.free {
            if let Some(row) = a.outer_view(i) {
                indices.extend_from_slice(row.indices());
                data.extend_from_slice(row.data());
            }
            indptr.push(indices.len());
        }
        CsMat::new((self.free.len(), a.cols()), indptr, indices, data)
    }

    /// E as an incidence matrix (unknowns × free): column k is the k-th
    /// free unknown. Eᵀ W E is W on the free unknowns; E₁ᵀ W E₂ couples
    /// the free unknowns of two splits through the same rows.
    pub fn selection(&self) -> CsMat<i8> {
        let mut indptr = Vec::with_capacity(self.unknowns() + 1);
        let mut indices = Vec::with_capacity(self.free.len());
        indptr.push(0);
        for i in 0..self.unknowns() {
            if let Some(k) = self.free_index(i) {
                indices.push(k);
            }
            indptr.push(indices.len());
        }
        let data = vec![1i8; indices.len()];
        CsMat::new((self.unknowns(), self.free.len()), indptr, indices, data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    /// A 4×4 unsymmetric matrix with known blocks, by hand.
    fn matrix() -> SparseColMat<usize, f64> {
        let entries = [
            (0, 0, 4.0),
            (1, 0, 1.0),
            (3, 0, 2.0),
            (1, 1, 5.0),
            (2, 1, -1.0),
            (0, 2, 3.0),
            (2, 2, 6.0),
            (3, 3, 7.0),
            (2, 3, 0.5),
        ];
        let t: Vec<_> = entries
            .iter()
            .map(|&(i, j, v)| Triplet::new(i, j, v))
            .collect();
        SparseColMat::try_new_from_triplets(4, 4, &t).unwrap()
    }

    #[test]
    fn the_free_block_and_the_moved_columns_are_the_hand_computed_ones() {
        let m = matrix();
        // Unknowns 0 and 3 fixed at 10 and 100.
        let fixed = [Some(10.0), None, None, Some(100.0)];
        let split = FixedSplit::new(&fixed);
        assert_eq!(split.free(), &[1, 2]);
        assert_eq!((split.free_index(2), split.free_index(3)), (Some(1), None));
        // M_ff = [[5, 0], [−1, 6]] (rows and columns 1, 2).
        let block = split.free_block(&m).to_dense();
        assert_eq!(
            (block[(0, 0)], block[(0, 1)], block[(1, 0)], block[(1, 1)]),
            (5.0, 0.0, -1.0, 6.0)
        );
        // b_f − M_fd g: row 1 loses M_10·10 = 10, row 2 loses M_23·100 = 50.
        let b = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(split.reduced_rhs(&m, &b, &fixed), vec![-9.0, -48.0]);
        // The same through the stored coupling, for new values 20 and 200.
        let coupling = split.coupling(&m);
        assert_eq!(coupling, vec![(0, 0, 1.0), (1, 3, 0.5)]);
        let mut rhs = split.restrict(&b);
        FixedSplit::lift_into(&coupling, &[Some(20.0), None, None, Some(200.0)], &mut rhs);
        assert_eq!(rhs, vec![-19.0, -98.0]);
        assert_eq!(split.lift(&[7.0, 8.0], &fixed), vec![10.0, 7.0, 8.0, 100.0]);
    }

    #[test]
    fn the_free_block_drops_fixed_rows_and_columns_in_order() {
        // A 4×4 matrix with entry (i, j) = 10 i + j + 1 on its pattern
        // (every entry but (0, 3) and (3, 0)); unknowns 1 and 2 fixed.
        // The free block on {0, 3}, renumbered 0 and 1, keeps (0, 0) = 1
        // and (3, 3) = 34, and nothing between them.
        let mut entries = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                if (i, j) != (0, 3) && (i, j) != (3, 0) {
                    entries.push(Triplet::new(i, j, (10 * i + j + 1) as f64));
                }
            }
        }
        let m = SparseColMat::try_new_from_triplets(4, 4, &entries).unwrap();
        let block = FixedSplit::from_mask([false, true, true, false]).free_block(&m);
        assert_eq!(block.col_ptr(), [0, 1, 2]);
        assert_eq!(block.row_idx(), [0, 1]);
        assert_eq!(block.val(), [1.0, 34.0]);
        // Only unknown 1 fixed: column 0 keeps rows 0 and 2 (renumbered 0
        // and 1; (3, 0) is not stored), column 2 rows 0, 2, 3, column 3
        // rows 2 and 3.
        let block = FixedSplit::from_mask([false, true, false, false]).free_block(&m);
        assert_eq!(block.col_ptr(), [0, 2, 5, 7]);
        assert_eq!(block.row_idx(), [0, 1, 0, 1, 2, 1, 2]);
        assert_eq!(block.val(), [1.0, 21.0, 3.0, 23.0, 33.0, 24.0, 34.0]);
    }
}
