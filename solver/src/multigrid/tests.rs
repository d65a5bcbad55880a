//! Tests of the multigrid hierarchy and cycle.

use super::cycle::spectral_bound;
use super::transfer::{grid_prolongation, grid_prolongations, Transfer};
use super::*;
use crate::la::fixed::FixedSplit;
use crate::la::iterative::RowMatrix;

/// What a test returns: a failed step is its error.
type TestResult = Result<(), Box<dyn std::error::Error>>;

fn apply(p: &RowMatrix, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; p.nrows()];
    p.multiply(x, &mut y);
    y
}

#[test]
fn grid_prolongation_interpolates_affine_nodal_fields_and_copies_cell_values() -> TestResult {
    // 4×2×2 cells → 2×1×1: u = 1 + x − 2y + 3z at the coarse vertices
    // must come out exact at the fine ones (trilinear interpolation
    // reproduces affine functions), in vertex units (h = 1 per cell).
    let fine = [4, 2, 2];
    let coarse = [2, 1, 1];
    let p = grid_prolongation(&fine, &coarse, Transfer::Nodal)?;
    let u = |x: f64, y: f64, z: f64| 1.0 + x - 2.0 * y + 3.0 * z;
    let mut uc = Vec::new();
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..3 {
                uc.push(u(2.0 * i as f64, 2.0 * j as f64, 2.0 * k as f64));
            }
        }
    }
    let uf = apply(&p, &uc);
    let mut v = 0;
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..5 {
                assert_eq!(uf[v], u(i as f64, j as f64, k as f64));
                v += 1;
            }
        }
    }
    // Cells: child (i, j, k) takes parent (i/2, j/2, k/2).
    let p = grid_prolongation(&fine, &coarse, Transfer::Cells)?;
    let fine_values = apply(&p, &[10.0, 20.0]);
    let expected: Vec<f64> = (0..16)
        .map(|c| if c % 4 < 2 { 10.0 } else { 20.0 })
        .collect();
    assert_eq!(fine_values, expected);
    Ok(())
}

#[test]
fn dirichlet_vertices_remove_their_coarse_twins() -> TestResult {
    // 1D, 4 cells: vertices 0..4, coarse 0..2; both ends fixed.
    let p = grid_prolongations(&[4], Transfer::Nodal)?;
    let fixed = FixedSplit::from_mask([true, false, false, false, true]);
    let free = restrict_to_free(&p, &fixed)?;
    // Fine free 1, 2, 3; coarse free: only the middle vertex (fine 2).
    assert_eq!((free[0].matrix.nrows(), free[0].matrix.ncols()), (3, 1));
    assert_eq!(apply(&free[0].matrix, &[1.0]), vec![0.5, 1.0, 0.5]);
    // Cells: a coarse cell goes only with all its children.
    let p = grid_prolongations(&[4], Transfer::Cells)?;
    let fixed = FixedSplit::from_mask([true, true, false, false]);
    let free = restrict_to_free(&p, &fixed)?;
    assert_eq!((free[0].matrix.nrows(), free[0].matrix.ncols()), (2, 1));
    Ok(())
}

#[test]
fn a_prolongation_of_the_wrong_size_and_bad_options_are_errors() -> TestResult {
    let m = RowMatrix::from_rows(2, vec![vec![(0, 2.0)], vec![(1, 2.0)]])?;
    let p = grid_prolongations(&[8], Transfer::Cells)?;
    let options = MultigridOptions {
        coarse_size: 1,
        ..Default::default()
    };
    assert!(matches!(
        Multigrid::new(m.clone(), p, &options),
        Err(MultigridError::Size {
            level: 0,
            expected: 2,
            found: 8
        })
    ));
    let bad = MultigridOptions {
        smoother: Smoother::Jacobi {
            omega: 2.5,
            sweeps: 1,
        },
        ..Default::default()
    };
    assert!(matches!(
        Multigrid::new(m.clone(), Vec::new(), &bad),
        Err(MultigridError::Option { .. })
    ));
    let negative = RowMatrix::from_rows(2, vec![vec![(0, 2.0)], vec![(1, -1.0)]])?;
    assert!(matches!(
        Multigrid::new(negative, Vec::new(), &MultigridOptions::default()),
        Err(MultigridError::Coarse { size: 2, .. })
    ));
    Ok(())
}

#[test]
fn the_spectral_bound_covers_the_spectrum() -> TestResult {
    // D⁻¹M of tridiag(−1, 2, −1) has eigenvalues 1 − cos(kπ/(n+1)) ∈ (0, 2).
    let n = 500;
    let rows = (0..n)
        .map(|i| {
            let mut row = Vec::new();
            if i > 0 {
                row.push((i - 1, -1.0));
            }
            row.push((i, 2.0));
            if i + 1 < n {
                row.push((i + 1, -1.0));
            }
            row
        })
        .collect();
    let m = RowMatrix::from_rows(n, rows)?;
    let lambda = spectral_bound(&m, &vec![0.5; n]);
    let top = 1.0 - (n as f64 * std::f64::consts::PI / (n + 1) as f64).cos();
    assert!(lambda >= top && lambda <= 2.0, "{lambda} vs {top}");
    Ok(())
}

#[test]
fn a_grid_hierarchy_solves_the_1d_laplacian_in_few_iterations() -> TestResult {
    use crate::la::iterative::CgOptions;
    // The 1D Dirichlet Laplacian on 64 cells (cell-centred, ghost at both ends).
    let n = 64;
    let rows = (0..n)
        .map(|i| {
            let mut row = vec![(i, if i == 0 || i == n - 1 { 3.0 } else { 2.0 })];
            if i > 0 {
                row.push((i - 1, -1.0));
            }
            if i + 1 < n {
                row.push((i + 1, -1.0));
            }
            row.sort_by_key(|e| e.0);
            row
        })
        .collect();
    let m = RowMatrix::from_rows(n, rows)?;
    let options = MultigridOptions {
        coarse_size: 4,
        ..Default::default()
    };
    let p = Hierarchy::Grid { cells: vec![n] }.prolongations(n)?;
    let mg = Multigrid::new(m, p, &options)?;
    assert!(mg.levels().len() > 3);
    let cg = CgOptions {
        tolerance: 1e-10,
        max_iterations: 50,
    };
    let (_, report) = mg.solve(&vec![1.0; n], None, &cg)?;
    assert!(report.iterations < 15);
    Ok(())
}

#[test]
fn grid_prolongations_stop_before_an_axis_of_one_cell() -> TestResult {
    let p = grid_prolongations(&[8, 4], Transfer::Nodal)?;
    assert_eq!(p.len(), 1); // 8×4 → 4×2, then stop: 2×1 would have an axis of one cell
    assert_eq!((p[0].matrix.nrows(), p[0].matrix.ncols()), (45, 15));
    Ok(())
}

/// The cell-centred two-point-flux Laplacian of an n×n×n grid of unit
/// cubes (7 points, x fastest): −1 to each face neighbour; a boundary face
/// adds `boundary` to the diagonal (2 for u = 0 half a cell away, 0 for a
/// pure Neumann problem, whose kernel is then the constant).
fn seven_point(n: usize, boundary: f64) -> RowMatrix {
    let index = |i: usize, j: usize, k: usize| i + n * (j + n * k);
    let mut rows = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let mut row = Vec::with_capacity(7);
                let mut diagonal = 0.0;
                let c = [i, j, k];
                for axis in 0..3 {
                    for up in [false, true] {
                        let mut d = c;
                        let inside = if up { c[axis] + 1 < n } else { c[axis] > 0 };
                        if inside {
                            d[axis] = if up { c[axis] + 1 } else { c[axis] - 1 };
                            row.push((index(d[0], d[1], d[2]), -1.0));
                            diagonal += 1.0;
                        } else {
                            diagonal += boundary;
                        }
                    }
                }
                row.push((index(i, j, k), diagonal));
                row.sort_by_key(|e| e.0);
                rows.push(row);
            }
        }
    }
    RowMatrix::from_rows(n * n * n, rows).expect("rows of the 7-point stencil")
}

fn dense(m: &RowMatrix) -> nalgebra::DMatrix<f64> {
    let mut d = nalgebra::DMatrix::zeros(m.nrows(), m.ncols());
    for i in 0..m.nrows() {
        let (c, v) = m.row(i);
        for (&j, &a) in c.iter().zip(v) {
            d[(i, j as usize)] += a;
        }
    }
    d
}

#[test]
fn the_galerkin_product_is_the_dense_triple_product() -> TestResult {
    // A 5×5 symmetric matrix with a full row and an empty-coupling row, and
    // a 5×3 P with overlapping columns, a zero row and an entry of each
    // sign: Pᵀ(AP) from the sparse products against nalgebra's dense
    // product, entry by entry. Every entry here is a sum of a few products
    // of small integers and halves, so both are exact.
    let a = RowMatrix::from_rows(
        5,
        vec![
            vec![(0, 4.0), (1, -1.0), (2, -1.0), (3, -1.0), (4, -1.0)],
            vec![(0, -1.0), (1, 3.0), (2, -0.5)],
            vec![(0, -1.0), (1, -0.5), (2, 2.5)],
            vec![(0, -1.0), (3, 2.0)],
            vec![(0, -1.0), (4, 1.5)],
        ],
    )?;
    let p = RowMatrix::new(
        5,
        3,
        vec![0, 2, 3, 5, 5, 6],
        vec![0, 2, 0, 1, 2, 1],
        vec![1.0, 0.5, 1.0, -0.5, 2.0, 1.0],
    )?;
    let coarse = p.transpose().product(&a.product(&p));
    let expected = dense(&p).transpose() * dense(&a) * dense(&p);
    assert_eq!((coarse.nrows(), coarse.ncols()), (3, 3));
    assert_eq!(dense(&coarse), expected);
    // Rows keep increasing column order (the smoother and the coarse
    // factorisation rely on it).
    for i in 0..3 {
        assert!(coarse.row(i).0.windows(2).all(|w| w[0] < w[1]));
    }
    Ok(())
}

#[test]
fn aggregation_coarsens_every_level_of_a_3d_seven_point_stencil() -> TestResult {
    // With one θ for all levels the coarsening stalled on level 1 (its
    // Galerkin operator spreads each row over ~30 neighbours, every
    // scaled coupling below θ = 0.08): the hierarchy stopped at 4096
    // unknowns instead of going down to `coarse_size`, and in a 100³ run
    // the sparse LLᵀ of that level took the whole setup.
    let m = seven_point(32, 2.0);
    let options = MultigridOptions {
        coarse_size: 50,
        ..Default::default()
    };
    let mg = Multigrid::algebraic(m, &options)?;
    let levels = mg.levels();
    let sizes: Vec<usize> = levels.iter().map(|l| l.unknowns).collect();
    assert!(levels.len() >= 3, "{sizes:?}");
    assert!(
        levels.last().ok_or("no levels")?.unknowns <= 50,
        "{sizes:?}"
    );
    // Aggregates of a 3D stencil hold a node and its strong neighbours
    // (7 on the fine level), so each level is at least 4× smaller.
    for pair in sizes.windows(2) {
        assert!(pair[1] * 4 <= pair[0], "{sizes:?}");
    }
    // Operator complexity: level 1 has n/8 unknowns (a node and its six
    // neighbours, plus joiners) with ~30 entries per row against 7 on
    // level 0 (30/(8·7) ≈ 0.54), level 2 ~n/100 with ~100 (≈ 0.15), the
    // rest much less; 1.8 bounds the sum (measured 1.70–1.72 from 40³ to
    // 100³).
    let complexity = mg.operator_complexity();
    assert!(complexity <= 1.8, "{complexity} for levels {sizes:?}");
    Ok(())
}

#[test]
fn strength_is_absolute_on_the_finest_level_and_row_relative_below() -> TestResult {
    use super::aggregation::{strong_neighbours, Strength};
    use super::cycle::{level_strength, COARSE_STRENGTH};
    // Row 0 has diagonal 4 and couplings −2, −0.6, −0.4 to unknowns of
    // diagonal 4: scaled couplings |a_0j|/√(4·4) = 0.5, 0.15, 0.1 (by hand).
    // Absolute θ = 0.08: all three are strong. Row-relative 0.25: the
    // threshold is 0.25 · 0.5 = 0.125, so 0.5 and 0.15 are strong and 0.1
    // is not. Row 3 (diagonal 4, one coupling −0.4 to row 0): its only
    // coupling is its strongest, so it is strong under the relative test
    // although 0.1 is weak for row 0: the relation is not symmetric.
    let m = RowMatrix::from_rows(
        4,
        vec![
            vec![(0, 4.0), (1, -2.0), (2, -0.6), (3, -0.4)],
            vec![(0, -2.0), (1, 4.0)],
            vec![(0, -0.6), (2, 4.0)],
            vec![(0, -0.4), (3, 4.0)],
        ],
    )?;
    assert_eq!(level_strength(0.08, 0), Strength::Absolute(0.08));
    assert_eq!(level_strength(0.08, 3), Strength::Relative(0.25));
    let absolute = strong_neighbours(&m, Strength::Absolute(0.08));
    assert_eq!(absolute[0], vec![1, 2, 3]);
    // θ = 0.12: 0.1 falls below it, 0.15 stays above.
    assert_eq!(
        strong_neighbours(&m, Strength::Absolute(0.12))[0],
        vec![1, 2]
    );
    let relative = strong_neighbours(&m, Strength::Relative(COARSE_STRENGTH));
    assert_eq!(relative, vec![vec![1, 2], vec![0], vec![0], vec![0]]);
    Ok(())
}

#[test]
fn the_coarse_operators_of_a_neumann_laplacian_keep_its_kernel() -> TestResult {
    use super::aggregation::{aggregate, smooth_prolongation};
    use super::cycle::level_strength;
    // Pure Neumann: A·1 = 0. P₀ b_c = 1 for the coarse near-null vector
    // b_c (aggregate norms), and the smoothing step keeps it, since
    // (I − ωD⁻¹A)·1 = 1; so A_c b_c = Pᵀ A P b_c = Pᵀ A·1 = 0 on every
    // level, to rounding. A singular Neumann matrix cannot go through
    // Multigrid::new (its coarsest level is factorised), so the levels are
    // built here from the same pieces.
    let mut a = seven_point(16, 0.0);
    let mut candidate = vec![1.0; a.nrows()];
    for level in 0..3 {
        let (tentative, coarse_candidate) = aggregate(&a, level_strength(0.08, level), &candidate)?
            .ok_or("no two unknowns aggregate")?;
        let inverse_diagonal: Vec<f64> = a.diagonal().iter().map(|d| 1.0 / d).collect();
        let lambda = spectral_bound(&a, &inverse_diagonal);
        let p = smooth_prolongation(&a, &inverse_diagonal, lambda, &tentative)?;
        // P b_c reproduces the fine near-null vector.
        let fine = apply(&p, &coarse_candidate);
        let scale = candidate.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (f, c) in fine.iter().zip(&candidate) {
            assert!((f - c).abs() <= 1e-12 * scale, "level {level}: {f} vs {c}");
        }
        let r = p.transpose();
        let coarse = r.product(&a.product(&p));
        let kernel = apply(&coarse, &coarse_candidate);
        // The rounding scale of row i: the same sums with every term's
        // absolute value, |R| |A| |P| b_c (b_c > 0). The diagonal is no
        // scale: an operator of few aggregates is itself zero to rounding.
        let magnitude = |m: &RowMatrix, x: &[f64]| -> Vec<f64> {
            (0..m.nrows())
                .map(|i| {
                    let (c, v) = m.row(i);
                    c.iter().zip(v).map(|(&j, a)| a.abs() * x[j as usize]).sum()
                })
                .collect()
        };
        let terms = magnitude(&r, &magnitude(&a, &magnitude(&p, &coarse_candidate)));
        for (i, r) in kernel.iter().enumerate() {
            let size = terms[i];
            assert!(
                r.abs() <= 1e-12 * size,
                "level {level}, row {i}: {r} vs {size}"
            );
        }
        assert!(
            coarse.nrows() * 4 <= a.nrows(),
            "level {level}: {}",
            coarse.nrows()
        );
        a = coarse;
        candidate = coarse_candidate;
    }
    Ok(())
}
