//! Tests of the canonical operator against dense products: Theorem 1,
//! dense, coupling, diagonal and stacked metrics, and the reuse of a
//! pattern across assemblies.

use super::super::*;
use nalgebra::DMatrix;
use sprs::CsMat;
use std::sync::Arc;

/// What a test returns: a failed step is its error.
type TestResult = Result<(), Box<dyn std::error::Error>>;

#[test]
fn theorem_one_reproduces_any_matrix_when_the_kernel_is_trivial() -> TestResult {
    // A = ∂_1 of a path of 6 edges with all 7 vertices kept (7 × 6, full
    // column rank); M = tridiag(−1, 3, −1), the thesis's implicit heat matrix.
    let mut a = DMatrix::zeros(7, 6);
    for e in 0..6 {
        a[(e, e)] = -1.0;
        a[(e + 1, e)] = 1.0;
    }
    let m = DMatrix::from_fn(6, 6, |i, j| match i.abs_diff(j) {
        0 => 3.0,
        1 => -1.0,
        _ => 0.0,
    });
    let omega = metric_from_matrix(&a, &m).ok_or("no metric reproduces the matrix")?;
    let back = a.transpose() * &omega * &a;
    assert!((back - &m).abs().max() < 1e-12);
    // A with a kernel (the closed cycle of 3 edges) has no left inverse.
    let mut cycle = DMatrix::zeros(3, 3);
    for e in 0..3 {
        cycle[(e, e)] = -1.0;
        cycle[((e + 1) % 3, e)] = 1.0;
    }
    assert!(metric_from_matrix(&cycle, &DMatrix::identity(3, 3)).is_none());
    Ok(())
}

#[test]
fn one_dimensional_identity_metric_gives_the_fe_stiffness() -> TestResult {
    // A = ∂_1ᵀ... thesis: A = ∂_1 ((n+1) × n, boundary vertices kept), Ω = I:
    // AᵀA = tridiag(−1, 2, −1).
    let n = 5;
    let mut tri = sprs::TriMat::new((n + 1, n));
    for e in 0..n {
        tri.add_triplet(e, e, -1i8);
        tri.add_triplet(e + 1, e, 1i8);
    }
    let op = Canonical::new(tri.to_csr(), BlockMetric::diagonal(&vec![1.0; n + 1]))?;
    let m = op.assemble().to_dense();
    for i in 0..n {
        for j in 0..n {
            let expected = match i.abs_diff(j) {
                0 => 2.0,
                1 => -1.0,
                _ => 0.0,
            };
            assert_eq!(m[(i, j)], expected);
        }
    }
    Ok(())
}

#[test]
fn dense_blocks_assemble_like_the_dense_triple_product() -> TestResult {
    // A: 4 rows × 3 unknowns; Ω: one 2×2 symmetric block + a diagonal entry
    // + an off-diagonal triplet pair (symmetric).
    let a = CsMat::new(
        (4, 3),
        vec![0, 2, 4, 5, 7],
        vec![0, 1, 1, 2, 0, 0, 2],
        vec![1i8, -1, 1, -1, 1, -1, 1],
    );
    let mut omega = BlockMetric::new(4);
    omega.push_symmetric(&[0, 1], &[2.0, 0.5, 0.5, 3.0]);
    omega.push_block(&[2], &[2], &[1.5]);
    omega.push_block(&[3], &[0], &[0.25]);
    omega.push_block(&[0], &[3], &[0.25]);
    let op = Canonical::new(a.clone(), omega.clone())?;
    let m = op.assemble().to_dense();
    let ad = DMatrix::from_fn(4, 3, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
    let od = DMatrix::from_fn(4, 4, |i, j| omega.to_dense()[i][j]);
    let expected = ad.transpose() * od * ad;
    for i in 0..3 {
        for j in 0..3 {
            assert!((m[(i, j)] - expected[(i, j)]).abs() < 1e-15, "({i},{j})");
        }
    }
    // Matrix-free application agrees with the assembled matrix.
    let u = [0.3, -1.0, 2.0];
    let mu = op.apply(&u);
    for i in 0..3 {
        let row: f64 = (0..3).map(|j| expected[(i, j)] * u[j]).sum();
        assert!((mu[i] - row).abs() < 1e-14);
    }
    assert!(!omega.is_symmetric(0.0));
    Ok(())
}

#[test]
fn coupling_blocks_assemble_like_the_dense_product_with_two_incidences() -> TestResult {
    // A: 4 rows × 3 unknowns, B: the same 4 rows × 2 other unknowns; Ω
    // with a dense 2×2 block, a diagonal entry and an unsymmetric pair,
    // and then diagonal. Expected: the dense Aᵀ Ω B by nalgebra.
    let a = CsMat::new(
        (4, 3),
        vec![0, 2, 4, 5, 7],
        vec![0, 1, 1, 2, 0, 0, 2],
        vec![1i8, -1, 1, -1, 1, -1, 1],
    );
    let b = CsMat::new(
        (4, 2),
        vec![0, 1, 3, 4, 4],
        vec![1, 0, 1, 0],
        vec![-1i8, 1, 1, 1],
    );
    let mut blocks = BlockMetric::new(4);
    blocks.push_symmetric(&[0, 1], &[2.0, 0.5, 0.5, 3.0]);
    blocks.push_block(&[2], &[2], &[1.5]);
    blocks.push_block(&[3], &[0], &[0.25]);
    let diagonal = BlockMetric::diagonal(&[2.0, -1.0, 0.5, 4.0]);
    let dense = |m: &CsMat<i8>, cols| {
        DMatrix::from_fn(4, cols, |i, j| f64::from(*m.get(i, j).unwrap_or(&0)))
    };
    let (ad, bd) = (dense(&a, 3), dense(&b, 2));
    for omega in [blocks, diagonal] {
        let op = Canonical::coupling(a.clone(), omega.clone(), b.clone())?;
        assert_eq!((op.shape(), op.unknowns()), ((3, 2), 2));
        let m = op.assemble().to_dense();
        let od = DMatrix::from_fn(4, 4, |i, j| omega.to_dense()[i][j]);
        let expected = ad.transpose() * od * &bd;
        assert_eq!((m.nrows(), m.ncols()), (3, 2));
        for i in 0..3 {
            for j in 0..2 {
                assert!((m[(i, j)] - expected[(i, j)]).abs() < 1e-15, "({i},{j})");
            }
        }
        let u = [0.7, -2.0];
        let mu = op.apply(&u);
        assert_eq!(mu.len(), 3);
        for i in 0..3 {
            let row: f64 = (0..2).map(|j| expected[(i, j)] * u[j]).sum();
            assert!((mu[i] - row).abs() < 1e-14);
        }
    }
    // B must have Ω's rows.
    let short = CsMat::new((3, 2), vec![0, 1, 2, 3], vec![0, 1, 0], vec![1i8, 1, 1]);
    assert_eq!(
        Canonical::coupling(a, BlockMetric::diagonal(&[1.0; 4]), short).unwrap_err(),
        CanonicalError::SizeMismatch { metric: 4, rows: 3 }
    );
    Ok(())
}

#[test]
fn a_sum_of_operators_is_the_stacked_operator() -> TestResult {
    // 2·(Aᵀ Ω₁ A) + ½·(Iᵀ diag(m) I) against the dense sum, with a block
    // Ω₁ (the general path) and with a diagonal one.
    let a = CsMat::new(
        (4, 3),
        vec![0, 2, 4, 5, 7],
        vec![0, 1, 1, 2, 0, 0, 2],
        vec![1i8, -1, 1, -1, 1, -1, 1],
    );
    let mut blocks = BlockMetric::new(4);
    blocks.push_symmetric(&[0, 1], &[2.0, 0.5, 0.5, 3.0]);
    blocks.push_block(&[2], &[2], &[1.5]);
    blocks.push_block(&[3], &[3], &[0.75]);
    let mass = Canonical::new(CsMat::<i8>::eye(3), BlockMetric::diagonal(&[1.0, 2.0, 4.0]))?;
    let ad = DMatrix::from_fn(4, 3, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
    for omega in [blocks, BlockMetric::diagonal(&[2.0, 3.0, 1.5, 0.75])] {
        let od = DMatrix::from_fn(4, 4, |i, j| omega.to_dense()[i][j]);
        let stiffness = Canonical::new(a.clone(), omega)?;
        let sum = Canonical::sum(&[(2.0, &stiffness), (0.5, &mass)])?;
        let m = sum.assemble().to_dense();
        let expected = ad.transpose() * od * &ad * 2.0
            + DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.5, 1.0, 2.0]));
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[(i, j)] - expected[(i, j)]).abs() < 1e-14, "({i},{j})");
            }
        }
    }
    let other = Canonical::new(CsMat::<i8>::eye(2), BlockMetric::diagonal(&[1.0, 1.0]))?;
    assert_eq!(
        Canonical::sum(&[(1.0, &mass), (1.0, &other)]).unwrap_err(),
        CanonicalError::SumMismatch {
            unknowns: 3,
            found: 2
        }
    );
    Ok(())
}

#[test]
fn the_clique_pattern_couples_the_kept_vertices_of_each_cell() -> TestResult {
    // Two quadrilaterals side by side: bottom vertices 0 1 2, top 3 4
    // 5; cell 0 = {0, 1, 3, 4}, cell 1 = {1, 2, 4, 5}. Vertex 0 is
    // dropped, so vertices 1..5 become 0..4.
    let cells = [vec![0, 1, 3, 4], vec![1, 2, 4, 5]];
    let star = CsMat::new(
        (6, 2),
        vec![0, 1, 3, 4, 5, 7, 8],
        vec![0, 0, 1, 1, 0, 0, 1, 1],
        vec![1u8; 8],
    );
    let keep = [false, true, true, true, true, true];
    let pattern = clique_pattern(&star, |c| &cells[c][..], &keep);
    assert_eq!((pattern.nrows(), pattern.ncols()), (5, 5));
    assert_eq!(pattern.col_ptr(), &[0, 5, 9, 12, 17, 21]);
    assert_eq!(
        pattern.row_idx(),
        &[0, 1, 2, 3, 4, 0, 1, 3, 4, 0, 2, 3, 0, 1, 2, 3, 4, 0, 1, 3, 4]
    );
    Ok(())
}

#[test]
fn blocks_numbered_apart_from_their_unknowns_assemble_like_the_dense_product() -> TestResult {
    // A cycle of 240 unknowns numbered by a stride permutation, one row
    // (edge) per consecutive pair; blocks of three rows picked by
    // another stride, some symmetric, some with different row and
    // column sets, then a 1×1 block per row. A column range's blocks
    // are spread over the whole block range, so each range sorts them
    // (the nodal tests on generated grids take the run path).
    let n = 240;
    let label = |k: usize| (k * 7) % n;
    let (mut indptr, mut indices, mut data) = (vec![0], Vec::new(), Vec::new());
    for r in 0..n {
        let (a, b) = (label(r), label((r + 1) % n));
        let (lo, hi, sign) = if a < b { (a, b, -1i8) } else { (b, a, 1i8) };
        indices.extend([lo, hi]);
        data.extend([sign, -sign]);
        indptr.push(indices.len());
    }
    let a = CsMat::new((n, n), indptr, indices, data);
    let mut omega = BlockMetric::new(n);
    let value = |b: usize, k: usize| 0.1 + ((b * 31 + k * 17) % 23) as f64 / 7.0;
    for b in 0..60 {
        let rows = [(b * 11) % n, (b * 11 + 97) % n, (b * 11 + 181) % n];
        let mut w = [0.0; 9];
        for i in 0..3 {
            for j in 0..=i {
                let v = value(b, i * 3 + j) + if i == j { 5.0 } else { 0.0 };
                w[i * 3 + j] = v;
                w[j * 3 + i] = v;
            }
        }
        if b % 4 == 0 {
            let cols = [(b * 13 + 5) % n, (b * 13 + 50) % n, (b * 13 + 120) % n];
            omega.push_block(&rows, &cols, &w);
        } else {
            omega.push_symmetric(&rows, &w);
        }
    }
    for r in 0..n {
        omega.push_block(&[r], &[r], &[1.0 + r as f64 / n as f64]);
    }
    let m = Canonical::new(a.clone(), omega.clone())?
        .assemble()
        .to_dense();
    let ad = DMatrix::from_fn(n, n, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
    let omega_dense = omega.to_dense();
    let od = DMatrix::from_fn(n, n, |i, j| omega_dense[i][j]);
    let expected = ad.transpose() * od * ad;
    // Entries are sums of a few products of values below 10: the two
    // orders of summation agree to a few ulps of 100.
    for i in 0..n {
        for j in 0..n {
            assert!((m[(i, j)] - expected[(i, j)]).abs() < 1e-12, "({i},{j})");
        }
    }
    Ok(())
}

#[test]
fn a_diagonal_metric_stays_compact_until_a_block_breaks_the_pattern() -> TestResult {
    let mut omega = BlockMetric::new(3);
    omega.push_block(&[0], &[0], &[2.0]);
    omega.push_block(&[1], &[1], &[3.0]);
    assert_eq!(omega.diagonal_weights(), Some(&[2.0, 3.0][..]));
    assert_eq!(omega.block_count(), 2);
    assert_eq!(omega.block(1), (&[1][..], &[1][..], &[3.0][..]));
    // An off-diagonal block: the earlier blocks get records and keep
    // their rows, columns and values.
    omega.push_block(&[2], &[0], &[5.0]);
    assert_eq!(omega.diagonal_weights(), None);
    assert_eq!(omega.block_count(), 3);
    assert_eq!(omega.block(0), (&[0][..], &[0][..], &[2.0][..]));
    assert_eq!(omega.block(2), (&[2][..], &[0][..], &[5.0][..]));
    let dense = omega.to_dense();
    assert_eq!(dense[0], vec![2.0, 0.0, 0.0]);
    assert_eq!(dense[1], vec![0.0, 3.0, 0.0]);
    assert_eq!(dense[2], vec![5.0, 0.0, 0.0]);
    // A block out of row order also ends the compact layout.
    let mut skipped = BlockMetric::new(3);
    skipped.push_block(&[1], &[1], &[1.0]);
    assert_eq!(skipped.diagonal_weights(), None);
    assert_eq!(skipped.apply(&[1.0, 4.0, 9.0]), vec![0.0, 4.0, 0.0]);
    // Out-of-range and non-finite diagonal entries are refused by number.
    let a = CsMat::new((2, 2), vec![0, 1, 3], vec![0, 0, 1], vec![1i8, -1, 1]);
    let mut long = BlockMetric::diagonal(&[1.0, 1.0]);
    long.push_block(&[2], &[2], &[1.0]);
    assert_eq!(
        Canonical::new(a.clone(), long).err(),
        Some(CanonicalError::RowOutOfRange {
            block: 2,
            row: 2,
            size: 2
        })
    );
    let mut beyond = BlockMetric::diagonal(&[1.0]);
    beyond.push_block(&[1], &[1], &[1.0]);
    beyond.push_block(&[2], &[2], &[1.0]);
    assert_eq!(beyond.diagonal_weights().map(<[f64]>::len), Some(3));
    assert_eq!(beyond.size(), 1);
    assert!(matches!(
        beyond.validate(),
        Err(CanonicalError::RowOutOfRange {
            block: 1,
            row: 1,
            size: 1
        })
    ));
    assert_eq!(
        Canonical::new(a, BlockMetric::diagonal(&[1.0, f64::NAN])).err(),
        Some(CanonicalError::NonFinite { block: 1 })
    );
    Ok(())
}

#[test]
fn diagonal_metrics_assemble_like_the_dense_triple_product_and_the_block_path() -> TestResult {
    // A = ∂_2 of a 3×2 grid of squares (17 edges × 6 cells): the
    // two-point flux operator. Dyadic weights make every sum exact, so
    // the column-wise diagonal assembly, the block-wise assembly and
    // the dense product must agree to the last bit.
    let grid = hasse_complex::generate::rectangle(3, 2, [0.0, 3.0], [0.0, 2.0])?;
    let a = grid.boundary(2).clone();
    let rows = a.rows();
    let weights: Vec<f64> = (0..rows).map(|r| 0.25 * (r % 5 + 1) as f64).collect();
    let dense_a = DMatrix::from_fn(rows, 6, |i, j| f64::from(*a.get(i, j).unwrap_or(&0)));
    for blocks in [rows, rows - 4] {
        // Only the first `blocks` rows carry a weight; the rest have no
        // block at all and must not enter the pattern.
        let mut diagonal = BlockMetric::diagonal(&weights[..blocks]);
        diagonal.add_rows(rows - blocks);
        assert!(diagonal.diagonal_weights().is_some());
        let mut by_blocks = BlockMetric::new(rows);
        for r in (0..blocks).rev() {
            by_blocks.push_block(&[r], &[r], &[weights[r]]);
        }
        assert!(by_blocks.diagonal_weights().is_none());
        // With A's CSC form from the complex (used only when every
        // row has its weight) the result is the same.
        let shared = Canonical::with_columns(
            Arc::clone(grid.boundary(2)),
            Arc::clone(grid.boundary_csc(2)),
            diagonal.clone(),
        )?
        .assemble();
        let fast = Canonical::new(a.clone(), diagonal)?.assemble();
        let general = Canonical::new(a.clone(), by_blocks)?.assemble();
        for other in [&general, &shared] {
            assert_eq!(fast.symbolic().col_ptr(), other.symbolic().col_ptr());
            assert_eq!(fast.symbolic().row_idx(), other.symbolic().row_idx());
            assert_eq!(fast.val(), other.val());
        }
        let w = DMatrix::from_fn(rows, rows, |i, j| {
            if i == j && i < blocks {
                weights[i]
            } else {
                0.0
            }
        });
        let expected = dense_a.transpose() * w * &dense_a;
        let m = fast.to_dense();
        for i in 0..6 {
            for j in 0..6 {
                assert_eq!(
                    m[(i, j)],
                    expected[(i, j)],
                    "({i},{j}) with {blocks} blocks"
                );
            }
        }
    }
    // Cells 0 and 5 (opposite corners) share no edge: no stored entry.
    let op = Canonical::new(a, BlockMetric::diagonal(&weights))?;
    let m = op.assemble();
    let column = &m.symbolic().row_idx()[m.symbolic().col_ptr()[0]..m.symbolic().col_ptr()[1]];
    assert!(!column.contains(&5));
    Ok(())
}

#[test]
fn the_last_assembly_takes_the_pattern_and_a_later_one_rebuilds_it() -> TestResult {
    // Q1 blocks on a 3×2 grid (block path) and two-point weights
    // (diagonal path): the owned assembly and the assemblies before and
    // after it, which rebuild the pattern, agree to the last bit.
    let grid = hasse_complex::generate::rectangle(3, 2, [0.0, 3.0], [0.0, 2.0])?;
    let q1 = crate::metric::fe::stiffness_metric(&grid, &[1.0; 6])?;
    let tpfa = crate::metric::fv::two_point(&grid, &[1.0; 6])?;
    for (a, metric) in [
        (Arc::clone(grid.coboundary(0)), q1),
        (Arc::clone(grid.boundary(2)), tpfa),
    ] {
        let mut op = Canonical::new(a, metric)?;
        let before = op.assemble();
        let owned = op.assemble_owned();
        let after = op.assemble();
        for m in [&owned, &after] {
            assert_eq!(m.symbolic().col_ptr(), before.symbolic().col_ptr());
            assert_eq!(m.symbolic().row_idx(), before.symbolic().row_idx());
            assert_eq!(m.val(), before.val());
        }
        assert_eq!(op.nonzeros(), before.val().len());
    }
    Ok(())
}

#[test]
fn metric_values_can_change_without_a_new_pattern() -> TestResult {
    let a = CsMat::new((2, 2), vec![0, 1, 3], vec![0, 0, 1], vec![1i8, -1, 1]);
    let mut op = Canonical::new(a, BlockMetric::diagonal(&[1.0, 1.0]))?;
    op.set_metric(BlockMetric::diagonal(&[2.0, 3.0]))?;
    let m = op.assemble().to_dense();
    assert_eq!((m[(0, 0)], m[(0, 1)], m[(1, 1)]), (5.0, -3.0, 3.0));
    assert_eq!(
        op.set_metric(BlockMetric::from_triplets(2, &[(0, 1, 1.0)])),
        Err(CanonicalError::PatternChanged)
    );
    Ok(())
}

#[test]
fn restricted_columns_give_the_free_block_of_the_canonical_operator() -> TestResult {
    use crate::la::fixed::FixedSplit;
    // A path of 4 vertices (3 edges), Ω = diag(1, 2, 3): the vertex
    // Laplacian; dropping vertices 0 and 3 leaves [[3, −2], [−2, 5]].
    let a = CsMat::new(
        (3, 4),
        vec![0, 2, 4, 6],
        vec![0, 1, 1, 2, 2, 3],
        vec![-1i8, 1, -1, 1, -1, 1],
    );
    let omega = BlockMetric::diagonal(&[1.0, 2.0, 3.0]);
    let split = FixedSplit::from_mask([true, false, false, true]);
    let reduced = Canonical::new(split.restrict_columns(&a), omega.clone())?
        .assemble()
        .to_dense();
    assert_eq!(
        (reduced[(0, 0)], reduced[(0, 1)], reduced[(1, 1)]),
        (3.0, -2.0, 5.0)
    );
    let full = Canonical::new(a, omega)?.assemble();
    assert_eq!(split.free_block(&full).to_dense(), reduced);
    // Eᵀ diag(w) E keeps the free weights.
    let e = split.selection();
    let w = Canonical::new(e, BlockMetric::diagonal(&[1.0, 2.0, 3.0, 4.0]))?
        .assemble()
        .to_dense();
    assert_eq!((w[(0, 0)], w[(1, 1)], w[(0, 1)]), (2.0, 3.0, 0.0));
    Ok(())
}

#[test]
fn a_coupling_block_with_the_identity_and_minus_one_is_minus_the_boundary() -> TestResult {
    use hasse_complex::generate::rectangle;
    // Two squares: ∂₂ is 7 edges × 2 cells. With A = I on the edges and
    // Ω = −I, Aᵀ Ω ∂₂ = −∂₂, the flux–pressure block of mixed Darcy.
    let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0])?;
    let edges = k.cell_count(1);
    let b = Canonical::coupling(
        sprs::CsMat::<i8>::eye(edges),
        BlockMetric::diagonal(&vec![-1.0; edges]),
        Arc::clone(k.boundary(2)),
    )?;
    let m = b.assemble().to_dense();
    assert_eq!((m.nrows(), m.ncols()), (7, 2));
    for (v, (e, c)) in k.boundary(2).iter() {
        assert_eq!(m[(e, c)], -f64::from(*v));
    }
    Ok(())
}

#[test]
fn a_sum_of_operators_is_one_canonical_operator() -> TestResult {
    use hasse_complex::generate::interval;
    let k = interval(2, 0.0, 1.0)?;
    let stiffness = Canonical::new(k.coboundary(0), BlockMetric::diagonal(&[2.0, 2.0]))?;
    let mass = Canonical::new(
        sprs::CsMat::<i8>::eye(3),
        BlockMetric::diagonal(&[0.25, 0.5, 0.25]),
    )?;
    let step = Canonical::sum(&[(4.0, &mass), (0.5, &stiffness)])?;
    let m = step.assemble().to_dense();
    // 4·0.5 + 0.5·(2 + 2) at the middle vertex, 0.5·(−2) beside it.
    assert_eq!((m[(1, 1)], m[(0, 1)]), (4.0, -1.0));
    Ok(())
}

#[test]
fn a_diagonal_metric_stays_diagonal_until_a_block_breaks_the_layout() -> TestResult {
    let mut omega = BlockMetric::from_weights(vec![2.0, 3.0]);
    omega.add_rows(1);
    omega.push_block(&[2], &[2], &[4.0]);
    assert_eq!(omega.diagonal_weights(), Some(&[2.0, 3.0, 4.0][..]));
    // A block off the diagonal (or out of row order) ends the layout.
    omega.push_block(&[0], &[1], &[1.0]);
    assert_eq!(omega.diagonal_weights(), None);
    assert_eq!(omega.block(1), (&[1][..], &[1][..], &[3.0][..]));
    Ok(())
}

#[test]
fn stacked_metrics_sit_along_the_diagonal() -> TestResult {
    let mut dense = BlockMetric::new(2);
    dense.push_symmetric(&[0, 1], &[2.0, -1.0, -1.0, 2.0]);
    let both = BlockMetric::stacked(&[(2.0, &BlockMetric::diagonal(&[1.0])), (0.5, &dense)]);
    assert_eq!(
        both.to_dense(),
        vec![
            vec![2.0, 0.0, 0.0],
            vec![0.0, 1.0, -0.5],
            vec![0.0, -0.5, 1.0]
        ]
    );
    Ok(())
}

#[test]
fn pushed_blocks_apply_as_their_sum() -> TestResult {
    let mut omega = BlockMetric::new(3);
    omega.push_symmetric(&[0, 2], &[2.0, -1.0, -1.0, 2.0]);
    omega.push_block(&[1], &[1], &[5.0]);
    assert_eq!(omega.apply(&[1.0, 1.0, 1.0]), vec![1.0, 5.0, 1.0]);
    Ok(())
}
