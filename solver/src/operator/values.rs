//! The numeric pass of [`Canonical`]: M's values, column by column in
//! parallel, in the order of its pattern.

use super::pattern::{Assembly, Columns, LocalPattern};
use super::Canonical;
use crate::la::parallel::{ranges, split_at_ranges};
use rayon::prelude::*;

impl Canonical {
    /// M's values in the order of its pattern.
    pub(super) fn values(&self) -> Vec<f64> {
        match (&*self.assembly, self.metric.diagonal_weights()) {
            (Assembly::Diagonal(columns), Some(weights)) => self.diagonal_values(columns, weights),
            (Assembly::Blocks(local), _) => self.block_values(local),
            // `set_metric` keeps the block layout, and with it the variant.
            (Assembly::Diagonal(_), None) => unreachable!("a diagonal pattern with a block metric"),
        }
    }

    /// Row r of A: its unknowns and signs.
    fn row(&self, r: usize) -> (&[usize], &[i8]) {
        row_of(&self.incidence, r)
    }

    /// M's values for Ω = diag(w), column after column in parallel; entry
    /// (i, j) sums w_r a_ri a_rj over r in increasing order, whatever the
    /// thread count.
    fn diagonal_values(&self, columns: &Columns, weights: &[f64]) -> Vec<f64> {
        let mut values = vec![0.0; self.nonzeros()];
        let pattern = self.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let parts = ranges(self.unknowns());
        let slices = split_at_ranges(&mut values, &parts, |j| col_ptr[j]);
        parts.into_par_iter().zip(slices).for_each(|(range, out)| {
            // Written before the sums read it (see `zeroed`): one page
            // fault per fresh page instead of two and a TLB flush.
            out.fill(0.0);
            let base = col_ptr[range.start];
            for j in range {
                let (first, last) = (col_ptr[j], col_ptr[j + 1]);
                let column = &row_idx[first..last];
                let column_values = &mut out[first - base..last - base];
                let (rows, signs) = columns.column(j);
                for (&r, &sign) in rows.iter().zip(signs) {
                    let weight = weights[r] * f64::from(sign);
                    let (unknowns, row_signs) = self.row(r);
                    for (&i, &x) in unknowns.iter().zip(row_signs) {
                        column_values[position(column, i)] += weight * f64::from(x);
                    }
                }
            }
        });
        values
    }

    /// M's values in parallel over ranges of columns: entry (i, j) adds the
    /// blocks' (A_Rᵀ W A_S)_ij in block order, each formed as
    /// Σ_r a_ri (Σ_s W_rs a_sj) with r and s in the block's order, whatever
    /// the thread count. Each range's thread walks the blocks that touch
    /// its columns in block order and reads each block's local incidence
    /// (A_R and A_S in the block's own unknown lists) once, for all of
    /// the block's columns in the range.
    fn block_values(&self, local: &LocalPattern) -> Vec<f64> {
        let mut values = vec![0.0; self.nonzeros()];
        let pattern = self.pattern();
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let parts = ranges(self.unknowns());
        let slices = split_at_ranges(&mut values, &parts, |j| col_ptr[j]);
        parts.into_par_iter().zip(slices).for_each_init(
            BlockScratch::default,
            |scratch, (range, out)| {
                // Written before the sums read it (see `zeroed`).
                out.fill(0.0);
                let base = col_ptr[range.start];
                let touching = || {
                    range
                        .clone()
                        .flat_map(|j| local.blocks_of(j).iter().copied())
                };
                let (first, last, count) = touching().fold((usize::MAX, 0, 0), |(lo, hi, k), b| {
                    (lo.min(b), hi.max(b + 1), k + 1)
                });
                // Blocks numbered like their unknowns (cells and vertices of
                // a generated grid) touch a range in a short run of block
                // numbers: walk the run. Otherwise sort the touching blocks.
                let scattered;
                let blocks: &mut dyn Iterator<Item = usize> =
                    if last.saturating_sub(first) <= 2 * count {
                        &mut (first..last.max(first))
                    } else {
                        let mut list: Vec<usize> = touching().collect();
                        list.sort_unstable();
                        list.dedup();
                        scattered = list;
                        &mut scattered.iter().copied()
                    };
                for b in blocks {
                    let (_, right) = local.sides(b);
                    let in_range = right.partition_point(|&j| j < range.start)
                        ..right.partition_point(|&j| j < range.end);
                    if in_range.is_empty() {
                        continue;
                    }
                    self.add_block_columns(
                        local,
                        b,
                        in_range,
                        scratch,
                        |j, rows, column_values| {
                            // Both row lists are sorted and the block's are in
                            // M's column: one walk finds them all.
                            let column = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                            let target = &mut out[col_ptr[j] - base..col_ptr[j + 1] - base];
                            let mut k = 0;
                            for (&i, &v) in rows.iter().zip(column_values) {
                                while column[k] < i {
                                    k += 1;
                                }
                                target[k] += v;
                            }
                        },
                    );
                }
            },
        );
        values
    }

    /// Columns `columns` (positions in the block's column-side unknowns)
    /// of block b's A_Rᵀ W A_S, handed to `add(j, rows, values)` column
    /// by column, `rows` the block's row-side unknowns (sorted).
    fn add_block_columns(
        &self,
        local: &LocalPattern,
        b: usize,
        columns: std::ops::Range<usize>,
        scratch: &mut BlockScratch,
        mut add: impl FnMut(usize, &[usize], &[f64]),
    ) {
        let (rows, cols, w) = self.metric.block(b);
        let (left, right) = local.sides(b);
        // The Q1 cells' shapes (4 edges over 4 vertices, 12 over 8) in
        // fixed-size arrays.
        if local.is_shared(b) {
            match (rows.len(), left.len()) {
                (4, 4) => return self.square_block_columns::<4, 4>(rows, w, left, columns, add),
                (12, 8) => return self.square_block_columns::<12, 8>(rows, w, left, columns, add),
                _ => {}
            }
        }
        // A_S and A_R over the block's own unknowns: (local row, local
        // unknown, sign), in row order and each row's order; one list when
        // the block's rows are its columns.
        let BlockScratch {
            column_side,
            row_side,
            half,
            dense,
        } = scratch;
        let local_incidence =
            |a: &sprs::CsMat<i8>, a_rows: &[usize], unknowns: &[usize], out: &mut Vec<_>| {
                out.clear();
                for (k, &r) in a_rows.iter().enumerate() {
                    let (row_unknowns, signs) = row_of(a, r);
                    for (&u, &sign) in row_unknowns.iter().zip(signs) {
                        out.push((k, position(unknowns, u), f64::from(sign)));
                    }
                }
            };
        local_incidence(self.right(), cols, right, column_side);
        let row_side: &[(usize, usize, f64)] = if local.is_shared(b) {
            column_side
        } else {
            local_incidence(&self.incidence, rows, left, row_side);
            row_side
        };
        // A_Rᵀ (W A_S)_{·j} on the stack when the block is small (every
        // FE cell), else in the scratch.
        let mut stack = [0.0; 16];
        let dense: &mut [f64] = if left.len() <= stack.len() {
            &mut stack[..left.len()]
        } else {
            dense.resize(left.len(), 0.0);
            dense
        };
        for jl in columns {
            // (W A_S)_{·j}, then A_Rᵀ (W A_S)_{·j}.
            half.clear();
            half.resize(rows.len(), 0.0);
            for &(si, _, sign) in column_side.iter().filter(|e| e.1 == jl) {
                for (ri, h) in half.iter_mut().enumerate() {
                    *h += w[ri * cols.len() + si] * sign;
                }
            }
            dense.fill(0.0);
            for &(ri, il, sign) in row_side {
                dense[il] += sign * half[ri];
            }
            add(right[jl], left, dense);
        }
    }

    /// [`Canonical::add_block_columns`] for a block over the same K rows
    /// on both sides, touching M unknowns (`unknowns`, sorted), in arrays
    /// of those sizes: A_c as a dense K × M matrix of signs, then
    /// (W A_c)_{·j} and A_cᵀ (W A_c)_{·j}. Every sum adds its nonzero
    /// terms in the order of the general path (rows in block order), and
    /// the zero terms in between leave a sum as it is, so the values are
    /// the general path's.
    fn square_block_columns<const K: usize, const M: usize>(
        &self,
        rows: &[usize],
        w: &[f64],
        unknowns: &[usize],
        columns: std::ops::Range<usize>,
        mut add: impl FnMut(usize, &[usize], &[f64]),
    ) {
        let mut signs = [[0.0; M]; K];
        for (signs_row, &r) in signs.iter_mut().zip(rows) {
            let (row_unknowns, row_signs) = self.row(r);
            for (&u, &sign) in row_unknowns.iter().zip(row_signs) {
                signs_row[position(unknowns, u)] = f64::from(sign);
            }
        }
        for jl in columns {
            let mut half = [0.0; K];
            for (h, w_row) in half.iter_mut().zip(w.chunks_exact(K)) {
                for (&weight, signs_row) in w_row.iter().zip(&signs) {
                    *h += weight * signs_row[jl];
                }
            }
            let mut column = [0.0; M];
            for (signs_row, &h) in signs.iter().zip(&half) {
                for (c, &sign) in column.iter_mut().zip(signs_row) {
                    *c += sign * h;
                }
            }
            add(unknowns[jl], unknowns, &column);
        }
    }
}

/// Scratch of [`Canonical::add_block_columns`], reused from block to block.
#[derive(Default)]
struct BlockScratch {
    column_side: Vec<(usize, usize, f64)>,
    row_side: Vec<(usize, usize, f64)>,
    half: Vec<f64>,
    dense: Vec<f64>,
}

/// Row r of `a` (CSR): its unknowns and signs.
fn row_of(a: &sprs::CsMat<i8>, r: usize) -> (&[usize], &[i8]) {
    let range = a.indptr().outer_inds_sz(r);
    (&a.indices()[range.clone()], &a.data()[range])
}

/// Index of `x` in the short list `list` (it is there).
fn position(list: &[usize], x: usize) -> usize {
    list.iter().position(|&y| y == x).unwrap_or(0)
}
