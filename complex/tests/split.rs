//! Euler make operators, hyperplane SPLIT, chain maps and refinement
//! strategies. Expected matrices are written out by hand (thesis §4.4,
//! Examples 5–10, and §4.5, Figs. 4.8–4.9); everything else is checked
//! against invariants that do not depend on the implementation: ∂∂ = 0,
//! χ and Betti numbers, ∂ζ = ζ∂, measures, the orientation a fresh
//! `Complex::from_lar` computes from geometry alone.

use hasse_complex::euler::{cell_counts, hasse_matrix, make};
use sprs::{CsMat, TriMat};

fn from_rows(rows: &[&[i8]]) -> CsMat<i8> {
    let cols = rows.first().map_or(0, |r| r.len());
    let mut t = TriMat::new((rows.len(), cols));
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), cols);
        for (j, &v) in r.iter().enumerate() {
            if v != 0 {
                t.add_triplet(i, j, v);
            }
        }
    }
    t.to_csr()
}

fn dense(m: &CsMat<i8>) -> Vec<Vec<i8>> {
    let d = m.to_dense();
    d.rows().into_iter().map(|r| r.to_vec()).collect()
}

fn transpose(m: &CsMat<i8>) -> CsMat<i8> {
    m.transpose_view().to_csr()
}

fn is_zero(m: &CsMat<i8>) -> bool {
    m.data().iter().all(|&x| x == 0)
}

fn chi(counts: &[usize]) -> i64 {
    counts
        .iter()
        .enumerate()
        .map(|(p, &k)| if p % 2 == 0 { k as i64 } else { -(k as i64) })
        .sum()
}

/// Thesis Examples 5–10: one triangle, β⁰ splits edge σ¹₁ by v4, then β¹
/// splits the face by e5 = v2 v4. The thesis prints δ (edges × vertices,
/// faces × edges); ∂ is its transpose.
#[test]
fn thesis_triangle_beta0_then_beta1() {
    let delta0: &[&[i8]] = &[&[-1, 0, 1], &[-1, 1, 0], &[0, -1, 1]];
    let delta1: &[&[i8]] = &[&[-1, 1, 1]];
    let d1 = transpose(&from_rows(delta0));
    let d2 = transpose(&from_rows(delta1));
    assert!(is_zero(&(&d1 * &d2)));
    let h = hasse_matrix(&[d1.clone(), d2.clone()]);
    assert_eq!(h.shape(), (3, 4));

    // β⁰: σ¹₁ = v1 → v3 splits at v4; the old index keeps v1 → v4, the
    // appended e4 = v4 → v3.
    let step1 = make(&[d1, d2], 1, 0, &[2]).unwrap();
    let delta0_1: Vec<Vec<i8>> = vec![
        vec![-1, 0, 0, 1],
        vec![-1, 1, 0, 0],
        vec![0, -1, 1, 0],
        vec![0, 0, 1, -1],
    ];
    assert_eq!(dense(&transpose(&step1.boundaries[0])), delta0_1);
    assert_eq!(dense(&transpose(&step1.boundaries[1])), vec![vec![-1, 1, 1, -1]]);
    // C = [I | e1] of the thesis is ζ_1ᵀ.
    assert_eq!(
        dense(&transpose(&step1.zeta[1])),
        vec![vec![1, 0, 0, 1], vec![0, 1, 0, 0], vec![0, 0, 1, 0]]
    );
    assert_eq!(
        dense(&step1.zeta[0]),
        vec![vec![1, 0, 0], vec![0, 1, 0], vec![0, 0, 1], vec![0, 0, 0]]
    );
    assert_eq!(hasse_matrix(&step1.boundaries).shape(), (4, 5));

    // β¹: e3 and e4 move to the new face f2; e5 = ∂(e3 − e4) = v4 − v2.
    let step2 = make(&step1.boundaries, 2, 0, &[2, 3]).unwrap();
    assert_eq!(
        dense(&transpose(&step2.boundaries[0])),
        vec![
            vec![-1, 0, 0, 1],
            vec![-1, 1, 0, 0],
            vec![0, -1, 1, 0],
            vec![0, 0, 1, -1],
            vec![0, -1, 0, 1],
        ]
    );
    assert_eq!(
        dense(&transpose(&step2.boundaries[1])),
        vec![vec![-1, 1, 0, 0, 1], vec![0, 0, 1, -1, -1]]
    );
    assert_eq!(hasse_matrix(&step2.boundaries).shape(), (5, 6));
    for (stage, b) in [&step1.boundaries, &step2.boundaries].iter().enumerate() {
        assert!(is_zero(&(&b[0] * &b[1])), "∂∂ ≠ 0 after step {stage}");
        assert_eq!(chi(&cell_counts(b)), 1);
    }
    // ∂ζ = ζ∂ for both steps.
    for (before, after) in [
        (vec![transpose(&from_rows(delta0)), transpose(&from_rows(delta1))], &step1),
        (step1.boundaries.clone(), &step2),
    ] {
        for p in 1..=2 {
            let left = &after.boundaries[p - 1] * &after.zeta[p];
            let right = &after.zeta[p - 1] * &before[p - 1];
            assert_eq!(dense(&left), dense(&right), "p = {p}");
        }
    }
}

#[test]
fn make_rejects_bad_selections() {
    use hasse_complex::SplitError;
    let d1 = transpose(&from_rows(&[&[-1, 0, 1], &[-1, 1, 0], &[0, -1, 1]]));
    let d2 = transpose(&from_rows(&[&[-1, 1, 1]]));
    let b = [d1, d2];
    assert!(matches!(make(&b, 3, 0, &[0]), Err(SplitError::DimensionOutOfRange { .. })));
    assert!(matches!(make(&b, 2, 1, &[0]), Err(SplitError::CellOutOfRange { .. })));
    // Every facet, no facet, or a vertex that is not on the edge.
    assert!(matches!(make(&b, 2, 0, &[0, 1, 2]), Err(SplitError::BadFacetSelection { .. })));
    assert!(matches!(make(&b, 2, 0, &[]), Err(SplitError::BadFacetSelection { .. })));
    assert!(matches!(make(&b, 1, 0, &[1]), Err(SplitError::BadFacetSelection { .. })));
}
