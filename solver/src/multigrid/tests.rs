//! Tests of the multigrid hierarchy and cycle.

use super::cycle::spectral_bound;
use super::transfer::{grid_prolongation, grid_prolongations, Transfer};
use super::*;
use crate::la::fixed::FixedSplit;
use crate::la::iterative::RowMatrix;

fn apply(p: &RowMatrix, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; p.nrows()];
    p.multiply(x, &mut y);
    y
}

#[test]
fn grid_prolongation_interpolates_affine_nodal_fields_and_copies_cell_values() {
    // 4×2×2 cells → 2×1×1: u = 1 + x − 2y + 3z at the coarse vertices
    // must come out exact at the fine ones (trilinear interpolation
    // reproduces affine functions), in vertex units (h = 1 per cell).
    let fine = [4, 2, 2];
    let coarse = [2, 1, 1];
    let p = grid_prolongation(&fine, &coarse, Transfer::Nodal).unwrap();
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
    let p = grid_prolongation(&fine, &coarse, Transfer::Cells).unwrap();
    let fine_values = apply(&p, &[10.0, 20.0]);
    let expected: Vec<f64> = (0..16)
        .map(|c| if c % 4 < 2 { 10.0 } else { 20.0 })
        .collect();
    assert_eq!(fine_values, expected);
}

#[test]
fn dirichlet_vertices_remove_their_coarse_twins() {
    // 1D, 4 cells: vertices 0..4, coarse 0..2; both ends fixed.
    let p = grid_prolongations(&[4], Transfer::Nodal).unwrap();
    let fixed = FixedSplit::from_mask([true, false, false, false, true]);
    let free = restrict_to_free(&p, &fixed).unwrap();
    // Fine free 1, 2, 3; coarse free: only the middle vertex (fine 2).
    assert_eq!((free[0].matrix.nrows(), free[0].matrix.ncols()), (3, 1));
    assert_eq!(apply(&free[0].matrix, &[1.0]), vec![0.5, 1.0, 0.5]);
    // Cells: a coarse cell goes only with all its children.
    let p = grid_prolongations(&[4], Transfer::Cells).unwrap();
    let fixed = FixedSplit::from_mask([true, true, false, false]);
    let free = restrict_to_free(&p, &fixed).unwrap();
    assert_eq!((free[0].matrix.nrows(), free[0].matrix.ncols()), (2, 1));
}

#[test]
fn a_prolongation_of_the_wrong_size_and_bad_options_are_errors() {
    let m = RowMatrix::from_rows(2, vec![vec![(0, 2.0)], vec![(1, 2.0)]]).unwrap();
    let p = grid_prolongations(&[8], Transfer::Cells).unwrap();
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
    let negative = RowMatrix::from_rows(2, vec![vec![(0, 2.0)], vec![(1, -1.0)]]).unwrap();
    assert!(matches!(
        Multigrid::new(negative, Vec::new(), &MultigridOptions::default()),
        Err(MultigridError::Coarse { size: 2, .. })
    ));
}

#[test]
fn the_spectral_bound_covers_the_spectrum() {
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
    let m = RowMatrix::from_rows(n, rows).unwrap();
    let lambda = spectral_bound(&m, &vec![0.5; n]);
    let top = 1.0 - (n as f64 * std::f64::consts::PI / (n + 1) as f64).cos();
    assert!(lambda >= top && lambda <= 2.0, "{lambda} vs {top}");
}

#[test]
fn a_grid_hierarchy_solves_the_1d_laplacian_in_few_iterations() {
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
    let m = RowMatrix::from_rows(n, rows).unwrap();
    let options = MultigridOptions {
        coarse_size: 4,
        ..Default::default()
    };
    let p = Hierarchy::Grid { cells: vec![n] }.prolongations(n).unwrap();
    let mg = Multigrid::new(m, p, &options).unwrap();
    assert!(mg.levels().len() > 3);
    let cg = CgOptions {
        tolerance: 1e-10,
        max_iterations: 50,
    };
    let (_, report) = mg.solve(&vec![1.0; n], None, &cg).unwrap();
    assert!(report.iterations < 15);
}

#[test]
fn grid_prolongations_stop_before_an_axis_of_one_cell() {
    let p = grid_prolongations(&[8, 4], Transfer::Nodal).unwrap();
    assert_eq!(p.len(), 1); // 8×4 → 4×2, then stop: 2×1 would have an axis of one cell
    assert_eq!((p[0].matrix.nrows(), p[0].matrix.ncols()), (45, 15));
}
