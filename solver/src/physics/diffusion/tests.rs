//! Tests of the diffusion problem's internals.

use super::solve::free_block;
use super::*;
use faer::sparse::Triplet;

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
    let free = [0, 3];
    let free_index = [0, usize::MAX, usize::MAX, 1];
    let block = free_block(&m, &free, &free_index);
    assert_eq!(block.col_ptr(), [0, 1, 2]);
    assert_eq!(block.row_idx(), [0, 1]);
    assert_eq!(block.val(), [1.0, 34.0]);
    // Only unknown 1 fixed: column 0 keeps rows 0 and 2 (renumbered 0
    // and 1; (3, 0) is not stored), column 2 rows 0, 2, 3, column 3
    // rows 2 and 3.
    let free = [0, 2, 3];
    let free_index = [0, usize::MAX, 1, 2];
    let block = free_block(&m, &free, &free_index);
    assert_eq!(block.col_ptr(), [0, 2, 5, 7]);
    assert_eq!(block.row_idx(), [0, 1, 0, 1, 2, 1, 2]);
    assert_eq!(block.val(), [1.0, 21.0, 3.0, 23.0, 33.0, 24.0, 34.0]);
}
