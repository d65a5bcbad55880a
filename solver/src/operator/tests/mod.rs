//! Tests of the canonical operator and its metric storage.

use super::*;
use faer::sparse::SparseColMat;
use sprs::CsMat;
use std::sync::Arc;

/// What a test returns: a failed step is its error.
type TestResult = Result<(), Box<dyn std::error::Error>>;

#[test]
fn square_blocks_read_like_records_and_turn_into_them_on_a_push() -> TestResult {
    // Two square blocks, over rows {0, 2} and {1, 2, 3}, back to back.
    let first = [2.0, -1.0, -1.0, 2.0];
    let second = [3.0, 0.5, 0.0, 0.5, 4.0, 1.0, 0.0, 1.0, 5.0];
    let values: Vec<f64> = first.iter().chain(&second).copied().collect();
    let square = BlockMetric::from_symmetric_blocks(
        5,
        vec![0, 2, 5],
        vec![0, 4, 13],
        vec![0, 2, 1, 2, 3],
        values,
        false,
    );
    let mut pushed = BlockMetric::new(5);
    pushed.push_symmetric(&[0, 2], &first);
    pushed.push_symmetric(&[1, 2, 3], &second);
    assert_eq!(square.block_count(), 2);
    assert_eq!(square.diagonal_weights(), None);
    for b in 0..2 {
        assert_eq!(square.block(b), pushed.block(b));
    }
    assert_eq!(square.to_dense(), pushed.to_dense());
    assert!(square.is_symmetric(0.0));
    // A push turns the square layout into records of the same blocks.
    let mut more = square.clone();
    more.push_block(&[4], &[4], &[7.0]);
    pushed.push_block(&[4], &[4], &[7.0]);
    assert_eq!(more, pushed);
    assert_eq!(more.apply(&[1.0; 5]), vec![1.0, 3.5, 6.5, 6.0, 7.0]);
    Ok(())
}

/// The error of a five-row Ω whose block 1 lists row 7.
fn assert_row_7_of_block_1(built: Result<Canonical, CanonicalError>) {
    let error = built.unwrap_err();
    assert!(
        matches!(
            error,
            CanonicalError::RowOutOfRange {
                block: 1,
                row: 7,
                size: 5
            }
        ),
        "{error:?}"
    );
}

#[test]
fn square_blocks_skip_the_value_scans_until_their_values_are_changed() -> TestResult {
    let square = |indices: Vec<usize>| {
        let values = [
            2.0, -1.0, -1.0, 2.0, 3.0, 0.5, 0.0, 0.5, 4.0, 1.0, 0.0, 1.0, 5.0,
        ];
        BlockMetric::from_symmetric_blocks(
            5,
            vec![0, 2, 5],
            vec![0, 4, 13],
            indices,
            values.to_vec(),
            false,
        )
    };
    let identity = || CsMat::<i8>::eye(5);
    assert!(Canonical::new(identity(), square(vec![0, 2, 1, 2, 3])).is_ok());
    // A row past Ω's size is still found, in the block that holds it.
    assert_row_7_of_block_1(Canonical::new(identity(), square(vec![0, 2, 1, 2, 7])));
    // Changed values are scanned again.
    let mut changed = square(vec![0, 2, 1, 2, 3]);
    assert!(changed.is_symmetric(0.0));
    changed.block_values_mut(1)[1] = 9.0;
    assert!(!changed.is_symmetric(1e-12));
    changed.block_values_mut(0)[3] = f64::NAN;
    let error = Canonical::new(identity(), changed).unwrap_err();
    assert!(
        matches!(error, CanonicalError::NonFinite { block: 0 }),
        "{error:?}"
    );
    Ok(())
}

#[test]
fn blocks_over_shared_columns_read_like_listed_rows() -> TestResult {
    // The two blocks of the test above, their rows {0, 2} and
    // {1, 2, 3} as the columns of a 5 × 2 CSC matrix.
    let values = vec![
        2.0, -1.0, -1.0, 2.0, 3.0, 0.5, 0.0, 0.5, 4.0, 1.0, 0.0, 1.0, 5.0,
    ];
    let columns = |rows: usize, last: usize| {
        Arc::new(CsMat::new_csc(
            (rows, 2),
            vec![0, 2, 5],
            vec![0, 2, 1, 2, last],
            vec![1i8; 5],
        ))
    };
    let listed = |last: usize| {
        BlockMetric::from_symmetric_blocks(
            5,
            vec![0, 2, 5],
            vec![0, 4, 13],
            vec![0, 2, 1, 2, last],
            values.clone(),
            true,
        )
    };
    let shared = |rows: usize, last: usize| {
        BlockMetric::from_symmetric_column_blocks(
            5,
            columns(rows, last),
            vec![0, 4, 13],
            values.clone(),
            true,
        )
    };
    let metric = shared(5, 3);
    assert_eq!(metric.block_count(), 2);
    for b in 0..2 {
        assert_eq!(metric.block(b), listed(3).block(b));
    }
    assert_eq!(metric.to_dense(), listed(3).to_dense());
    let identity = || CsMat::<i8>::eye(5);
    assert!(Canonical::new(identity(), metric.clone()).is_ok());
    // A row past Ω's size, in a matrix with more rows than Ω: named
    // with its block, as for listed rows.
    assert_row_7_of_block_1(Canonical::new(identity(), shared(8, 7)));
    // A push copies the rows out and continues as records.
    let mut pushed = metric;
    pushed.push_block(&[4], &[4], &[7.0]);
    let mut expected = listed(3);
    expected.push_block(&[4], &[4], &[7.0]);
    assert_eq!(pushed, expected);
    assert_eq!(pushed.apply(&[1.0; 5]), vec![1.0, 3.5, 6.5, 6.0, 7.0]);
    Ok(())
}

/// M of `omega` on the nodal operator of `k`, through the blocks'
/// own pattern and through the complex's cell lists.
fn both_ways(
    k: &hasse_complex::Complex,
    omega: BlockMetric,
) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let gathered =
        Canonical::new(Arc::clone(k.coboundary(0)), omega.clone()).expect("δ⁰ and Ω fit");
    let from_cells =
        Canonical::with_cell_blocks(Arc::clone(k.coboundary(0)), omega, k).expect("δ⁰ and Ω fit");
    (gathered.assemble(), from_cells.assemble())
}

#[test]
fn cell_blocks_give_the_nine_point_stencil_of_the_unit_grid() -> TestResult {
    // Q1 on a 3 × 3 grid of unit squares (h = 1): from the element
    // matrix (4, −1, −2 over 6 on the diagonal, along an edge, across
    // a diagonal), vertex (i, j) gets 4/6 from each of its cells, and
    // a neighbour −1/6 from each shared cell along an edge (two inside,
    // one on the boundary) or −2/6 across a diagonal (one cell).
    let k = hasse_complex::generate::rectangle(3, 3, [0.0, 3.0], [0.0, 3.0])?;
    let omega = crate::metric::fe::stiffness_metric(&k, &[1.0; 9])?;
    let (gathered, from_cells) = both_ways(&k, omega);
    assert_eq!(
        gathered.symbolic().col_ptr(),
        from_cells.symbolic().col_ptr()
    );
    assert_eq!(
        gathered.symbolic().row_idx(),
        from_cells.symbolic().row_idx()
    );
    assert_eq!(gathered.val(), from_cells.val());
    let dense = from_cells.to_dense();
    let at = |v: usize| {
        let p = k.vertices().point(v);
        (p[0].round() as i64, p[1].round() as i64)
    };
    let cells_of = |(x, y): (i64, i64)| {
        let side = |t: i64| if t == 0 || t == 3 { 1 } else { 2 };
        side(x) * side(y)
    };
    for u in 0..16 {
        for v in 0..16 {
            let ((xu, yu), (xv, yv)) = (at(u), at(v));
            let (dx, dy) = ((xu - xv).abs(), (yu - yv).abs());
            let expected = match (dx, dy) {
                (0, 0) => 4.0 / 6.0 * f64::from(cells_of((xu, yu))),
                (1, 0) | (0, 1) => {
                    // Cells on the edge: 2, or 1 when it is on the boundary.
                    let boundary = if dx == 1 {
                        yu == 0 || yu == 3
                    } else {
                        xu == 0 || xu == 3
                    };
                    -1.0 / 6.0 * if boundary { 1.0 } else { 2.0 }
                }
                (1, 1) => -2.0 / 6.0,
                _ => 0.0,
            };
            assert!(
                (dense[(u, v)] - expected).abs() < 1e-14,
                "({u}, {v}): {} against {expected}",
                dense[(u, v)]
            );
        }
    }
    Ok(())
}

#[test]
fn cell_blocks_assemble_like_the_gathered_pattern_on_hexahedra_and_polygons() -> TestResult {
    // Moved vertices: no two blocks are alike.
    let hexes = hasse_complex::generate::box3(3, 2, 2, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0])?;
    let moved: Vec<[f64; 3]> = (0..hexes.cell_count(0))
        .map(|v| {
            let p = hexes.vertices().point(v);
            let t = v as f64;
            [
                p[0] + 0.02 * (1.3 * t).sin(),
                p[1] + 0.02 * (0.7 * t).cos(),
                p[2],
            ]
        })
        .collect();
    let hexes = hexes.with_vertices(hasse_complex::Vertices::from_points(&moved)?)?;
    let tensors = vec![1.5; hexes.cell_count(3)];
    let omega = crate::metric::fe::stiffness_metric(&hexes, &tensors)?;
    let (gathered, from_cells) = both_ways(&hexes, omega);
    assert_eq!(
        gathered.symbolic().row_idx(),
        from_cells.symbolic().row_idx()
    );
    assert_eq!(gathered.val(), from_cells.val());
    // Virtual elements on quadrilaterals.
    let quads = hasse_complex::generate::rectangle(4, 3, [0.0, 1.0], [0.0, 1.0])?;
    let omega = crate::metric::fe::vem_stiffness_metric(&quads, &[1.0; 12])?;
    let (gathered, from_cells) = both_ways(&quads, omega);
    assert_eq!(gathered.val(), from_cells.val());
    // Constants are the kernel: every row of M sums to zero.
    let dense = from_cells.to_dense();
    for i in 0..dense.nrows() {
        let sum: f64 = (0..dense.ncols()).map(|j| dense[(i, j)]).sum();
        assert!(sum.abs() < 1e-13, "row {i} sums to {sum}");
    }
    Ok(())
}

#[test]
fn a_metric_pushed_to_after_it_was_built_per_cell_uses_its_own_pattern() -> TestResult {
    let k = hasse_complex::generate::rectangle(2, 2, [0.0, 1.0], [0.0, 1.0])?;
    let mut omega = crate::metric::fe::stiffness_metric(&k, &[1.0; 4])?;
    assert!(omega.per_cell);
    // One block more than cells: not one block per cell any longer.
    omega.push_symmetric(&[0], &[7.0]);
    assert!(!omega.per_cell);
    let (gathered, from_cells) = both_ways(&k, omega);
    assert_eq!(gathered.val(), from_cells.val());
    // Edge 0's extra weight 7 lands on its two ends a, b: +7 on (a, a),
    // −7 on (a, b).
    let (tail, head) = (k.cell_vertices(1, 0)[0], k.cell_vertices(1, 0)[1]);
    let plain = Canonical::new(
        Arc::clone(k.coboundary(0)),
        crate::metric::fe::stiffness_metric(&k, &[1.0; 4])?,
    )?
    .assemble()
    .to_dense();
    let dense = from_cells.to_dense();
    assert!((dense[(tail, tail)] - plain[(tail, tail)] - 7.0).abs() < 1e-14);
    assert!((dense[(tail, head)] - plain[(tail, head)] + 7.0).abs() < 1e-14);
    Ok(())
}

#[test]
fn the_diagonal_pattern_is_the_cells_coupled_through_faces() -> TestResult {
    // Three cells in a row, four faces: ∂ by faces has rows (1), (−1, 1),
    // (−1, 1), (−1); ∂ᵀ∂ is tridiagonal whatever the face weights.
    let rows = CsMat::new(
        (4, 3),
        vec![0, 1, 3, 5, 6],
        vec![0, 0, 1, 1, 2, 2],
        vec![1i8, -1, 1, -1, 1, -1],
    );
    let by_columns = Arc::new(rows.to_csc());
    let pattern = diagonal_pattern(&rows, &by_columns);
    assert_eq!(pattern.col_ptr(), &[0, 2, 5, 7]);
    assert_eq!(pattern.row_idx(), &[0, 1, 0, 1, 2, 1, 2]);
    // The operator with real weights has that pattern too.
    let metric = BlockMetric::diagonal(&[2.0, 0.5, 3.0, 1.0]);
    let m = Canonical::new(rows, metric)?.assemble();
    assert_eq!(m.symbolic().col_ptr(), pattern.col_ptr());
    assert_eq!(m.symbolic().row_idx(), pattern.row_idx());
    Ok(())
}

mod products;
