//! The Euler algebra on the incidence matrices: the matrix form of the make
//! operators (C, R, S_i, T_i), the Hasse transformation η and the kill
//! operators κ. The seed numbers are those of seed 000 (the Hasse-matrix
//! paper), Examples 5–10 (Figs. 4–6, §4.3), listed as H4 and H8 in
//! `shared/notes/seed-000-hasse-matrix-digest.md`; the same numbers are the
//! thesis's (seed 003) Examples 5–10, digest V2. Everything else is
//! checked against hand-computed matrices or invariants that do not depend
//! on the code: ∂∂ = 0, χ and the Betti numbers of known shapes, chain-map
//! identities, and κ ∘ β = id.

use crate::split::from_rows;
use hasse_complex::euler::{cell_counts, hasse_matrix, make};
use hasse_complex::generate::{annulus, box3, interval, kuhn, rectangle, uniform_axis};
use hasse_complex::hasse_transform::{eta, hasse_blocks, MakeMatrices};
use hasse_complex::homology::{betti_numbers, euler_characteristic};
use hasse_complex::kill::kill;
use hasse_complex::{Complex, Field, SplitError};
use sprs::CsMat;

type TestResult = Result<(), Box<dyn std::error::Error>>;

fn dense(m: &CsMat<i8>) -> Vec<Vec<i8>> {
    let mut out = vec![vec![0; m.cols()]; m.rows()];
    for (&v, (i, j)) in m.iter() {
        out[i][j] += v;
    }
    out
}

fn rows(r: &[&[i8]]) -> Vec<Vec<i8>> {
    r.iter().map(|x| x.to_vec()).collect()
}

fn transpose(m: &CsMat<i8>) -> CsMat<i8> {
    m.transpose_view().to_csr()
}

fn is_zero(m: &CsMat<i8>) -> bool {
    m.data().iter().all(|&x| x == 0)
}

/// ∂_1 … ∂_n of a generated complex (the one place that reads them).
fn boundaries_of(k: &Complex) -> Vec<CsMat<i8>> {
    (1..=k.dim()).map(|p| (**k.boundary(p)).clone()).collect()
}

fn betti(b: &[CsMat<i8>]) -> Vec<usize> {
    betti_numbers(&cell_counts(b), b, Field::Rationals)
}

fn identity(n: usize) -> Vec<Vec<i8>> {
    (0..n)
        .map(|i| (0..n).map(|j| i8::from(i == j)).collect())
        .collect()
}

// ------------------------------------- seed 000, Examples 5–10 (digest H4)

/// Seed 000 Example 5 ([δ0]) and Example 6 ([δ1]) of the triangle of
/// Fig. 4: vertices σ0^1..3, edges σ1^1..3, one face (here 0-based).
fn triangle() -> (CsMat<i8>, CsMat<i8>) {
    let delta0 = from_rows(&[&[-1, 0, 1], &[-1, 1, 0], &[0, -1, 1]]);
    let delta1 = from_rows(&[&[-1, 1, 1]]);
    (delta0, delta1)
}

/// Seed 000 Example 7 (§4.3, Fig. 5; digest H4): β0 splits σ1^1 (row 1 of
/// [δ0], σ0^1 → σ0^3) by the new vertex σ0^4; the old edge keeps its tail,
/// so the head σ0^3 moves to the appended edge σ1^4. Every printed matrix:
/// S1, S2, S3, S_i[δ0], S_i[δ0]T_i and their sum [δ̃0].
#[test]
fn example_7_beta0_s_and_t_matrices_as_printed() -> TestResult {
    let (delta0, delta1) = triangle();
    let b = [transpose(&delta0), transpose(&delta1)];
    let m = MakeMatrices::new(&b, 1, 0, &[2])?;
    let (s1, s2, s3) = (
        m.s(1).ok_or("S1")?,
        m.s(2).ok_or("S2")?,
        m.s(3).ok_or("S3")?,
    );
    let (t1, t2, t3) = (
        m.t(1).ok_or("T1")?,
        m.t(2).ok_or("T2")?,
        m.t(3).ok_or("T3")?,
    );
    assert_eq!(
        dense(s1),
        rows(&[&[1, 0, 0], &[0, 0, 0], &[0, 0, 0], &[0, 0, 0]])
    );
    assert_eq!(
        dense(s2),
        rows(&[&[0, 0, 0], &[0, 0, 0], &[0, 0, 0], &[1, 0, 0]])
    );
    assert_eq!(
        dense(s3),
        rows(&[&[0, 0, 0], &[0, 1, 0], &[0, 0, 1], &[0, 0, 0]])
    );
    assert_eq!(
        dense(&(s1 * &delta0)),
        rows(&[&[-1, 0, 1], &[0, 0, 0], &[0, 0, 0], &[0, 0, 0]])
    );
    assert_eq!(
        dense(&(s2 * &delta0)),
        rows(&[&[0, 0, 0], &[0, 0, 0], &[0, 0, 0], &[-1, 0, 1]])
    );
    assert_eq!(
        dense(&(s3 * &delta0)),
        rows(&[&[0, 0, 0], &[-1, 1, 0], &[0, -1, 1], &[0, 0, 0]])
    );
    assert_eq!(
        dense(&(&(s1 * &delta0) * t1)),
        rows(&[&[-1, 0, 0, 1], &[0, 0, 0, 0], &[0, 0, 0, 0], &[0, 0, 0, 0]])
    );
    assert_eq!(
        dense(&(&(s2 * &delta0) * t2)),
        rows(&[&[0, 0, 0, 0], &[0, 0, 0, 0], &[0, 0, 0, 0], &[0, 0, 1, -1]])
    );
    assert_eq!(
        dense(&(&(s3 * &delta0) * t3)),
        rows(&[&[0, 0, 0, 0], &[-1, 1, 0, 0], &[0, -1, 1, 0], &[0, 0, 0, 0]])
    );
    let refined = m.coboundaries(&[delta0, delta1])?;
    assert_eq!(
        dense(&refined[0]),
        rows(&[
            &[-1, 0, 0, 1],
            &[-1, 1, 0, 0],
            &[0, -1, 1, 0],
            &[0, 0, 1, -1]
        ])
    );
    // Example 8: [δ̃1] = [δ1] C with the printed C = [I | e1].
    assert_eq!(
        dense(m.c()),
        rows(&[&[1, 0, 0, 1], &[0, 1, 0, 0], &[0, 0, 1, 0]])
    );
    assert_eq!(dense(&refined[1]), rows(&[&[-1, 1, 1, -1]]));
    // β0 has no δ_{−1} to give a row to.
    assert!(m.r().is_none());
    Ok(())
}

/// Seed 000 Examples 9 and 10 (Fig. 6; digest H4): β1 splits the face of
/// the refined triangle by the new edge σ1^5 and the new face σ2^2. The
/// printed R = [I4 ; (0 0 1 −1)], R[δ̃0] and [δ̃̃1]. The paper prints no
/// S_i, T_i for Example 10; by its rule (term 1 the split cell, term 2
/// the added one) S1[δ̃1]T1 and S2[δ̃1]T2 are the two printed rows of [δ̃̃1].
#[test]
fn examples_9_and_10_beta1_r_and_refined_coboundaries_as_printed() -> TestResult {
    let delta0 = from_rows(&[
        &[-1, 0, 0, 1],
        &[-1, 1, 0, 0],
        &[0, -1, 1, 0],
        &[0, 0, 1, -1],
    ]);
    let delta1 = from_rows(&[&[-1, 1, 1, -1]]);
    let b = [transpose(&delta0), transpose(&delta1)];
    // The new face σ2^2 takes σ1^3 and σ1^4 (the rows of [δ̃̃1]).
    let m = MakeMatrices::new(&b, 2, 0, &[2, 3])?;
    let r = m.r().ok_or("β1 gives δ0 a row")?;
    assert_eq!(
        dense(r),
        rows(&[
            &[1, 0, 0, 0],
            &[0, 1, 0, 0],
            &[0, 0, 1, 0],
            &[0, 0, 0, 1],
            &[0, 0, 1, -1]
        ])
    );
    let refined = m.coboundaries(&[delta0, delta1.clone()])?;
    assert_eq!(
        dense(&refined[0]),
        rows(&[
            &[-1, 0, 0, 1],
            &[-1, 1, 0, 0],
            &[0, -1, 1, 0],
            &[0, 0, 1, -1],
            &[0, -1, 0, 1]
        ])
    );
    assert_eq!(
        dense(&refined[1]),
        rows(&[&[-1, 1, 0, 0, 1], &[0, 0, 1, -1, -1]])
    );
    let term = |i: usize| -> Result<Vec<Vec<i8>>, &str> {
        let s = m.s(i).ok_or("S")?;
        let t = m.t(i).ok_or("T")?;
        Ok(dense(&(&(s * &delta1) * t)))
    };
    assert_eq!(term(1)?, rows(&[&[-1, 1, 0, 0, 1], &[0, 0, 0, 0, 0]]));
    assert_eq!(term(2)?, rows(&[&[0, 0, 0, 0, 0], &[0, 0, 1, -1, -1]]));
    assert_eq!(term(3)?, rows(&[&[0; 5], &[0; 5]]));
    Ok(())
}

/// Seed 000 §3 and §5 on Examples 5–10 (digest H4, H8): the Hasse matrix
/// H = [δ0 | δ1ᵀ] of the triangle (d = 2: rows K1, columns K0 ⊕ K2) grows
/// 3×4 → 4×5 → 5×6 under η, χ = columns − rows = 1 throughout, and each H
/// is the printed δ's in block form. The Betti numbers stay (1, 0, 0) (a
/// disk), and κ undoes each step exactly.
#[test]
fn examples_5_to_10_hasse_matrix_grows_under_eta() -> TestResult {
    let (delta0, delta1) = triangle();
    let b0 = vec![transpose(&delta0), transpose(&delta1)];
    let h0 = hasse_matrix(&b0);
    assert_eq!(
        dense(&h0),
        rows(&[&[-1, 0, 1, -1], &[-1, 1, 0, 1], &[0, -1, 1, 1]])
    );
    // Remark 1: β0(H) = [(S1 S2 S3)δ0(T1;T2;T3) | "R" δ1ᵀ], where the
    // upper block is transposed, so its "R" is our Cᵀ: (δ1 C)ᵀ = Cᵀ δ1ᵀ.
    let h1 = eta(&h0, &[3, 3, 1], 1, 0, &[2])?;
    assert_eq!(
        dense(&h1),
        rows(&[
            &[-1, 0, 0, 1, -1],
            &[-1, 1, 0, 0, 1],
            &[0, -1, 1, 0, 1],
            &[0, 0, 1, -1, -1]
        ])
    );
    let h2 = eta(&h1, &[4, 4, 1], 2, 0, &[2, 3])?;
    assert_eq!(
        dense(&h2),
        rows(&[
            &[-1, 0, 0, 1, -1, 0],
            &[-1, 1, 0, 0, 1, 0],
            &[0, -1, 1, 0, 0, 1],
            &[0, 0, 1, -1, 0, -1],
            &[0, -1, 0, 1, 1, -1]
        ])
    );
    for h in [&h0, &h1, &h2] {
        assert_eq!(h.cols() as i64 - h.rows() as i64, 1);
    }
    // The same stages through make, and back through kill (H8).
    let b1 = make(&b0, 1, 0, &[2])?.boundaries;
    let b2 = make(&b1, 2, 0, &[2, 3])?.boundaries;
    for (b, h) in [(&b0, &h0), (&b1, &h1), (&b2, &h2)] {
        assert_eq!(&hasse_matrix(b), h);
        assert_eq!(betti(b), vec![1, 0, 0]);
        assert_eq!(euler_characteristic(&cell_counts(b)), 1);
    }
    assert_eq!(kill(&b2, 2, 0, 1)?.boundaries, b1);
    assert_eq!(kill(&b1, 1, 0, 3)?.boundaries, b0);
    Ok(())
}

// ------------------------------------------------------- make, by hand

/// β⁰ moving the tail: edge v0 → v1 split at v2 with v0 going to the new
/// half. Both halves keep the direction v0 → v1: e0 = v2 → v1 (by hand:
/// ∂e0 = v1 − v2) and e1 = v0 → v2 (∂e1 = v2 − v0).
#[test]
fn beta0_moving_the_tail_keeps_the_direction() -> TestResult {
    let b = vec![from_rows(&[&[-1], &[1]])];
    let out = make(&b, 1, 0, &[0])?;
    assert_eq!(
        dense(&out.boundaries[0]),
        rows(&[&[0, -1], &[1, 0], &[-1, 1]])
    );
    let m = MakeMatrices::new(&b, 1, 0, &[0])?;
    assert_eq!(m.boundaries(&b)?, out.boundaries);
    assert_eq!(kill(&out.boundaries, 1, 0, 1)?.boundaries, b);
    Ok(())
}

// -------------------------------------------------------- kill, by hand

/// A unit square with the diagonal e4 = v0 → v2: f0 = (v0 v1 v2) with
/// ∂f0 = e0 + e1 − e4, f1 = (v0 v2 v3) with ∂f1 = e4 − e2 − e3 (edges
/// e0 = v0→v1, e1 = v1→v2, e2 = v3→v2, e3 = v0→v3). Merging across e4, by
/// hand: σ = 1, ∂m = e0 + e1 − e2 − e3, and ψ pushes the diagonal onto
/// the rest of f1's boundary, ψ(e4) = e3 + e2 (v0 → v3 → v2).
#[test]
fn kill_two_triangles_into_a_square() -> TestResult {
    let d1 = from_rows(&[
        &[-1, 0, 0, -1, -1],
        &[1, -1, 0, 0, 0],
        &[0, 1, 1, 0, 1],
        &[0, 0, -1, 1, 0],
    ]);
    let d2 = from_rows(&[&[1, 0], &[1, 0], &[0, -1], &[0, -1], &[-1, 1]]);
    assert!(is_zero(&(&d1 * &d2)));
    let out = kill(&[d1.clone(), d2.clone()], 2, 0, 1)?;
    assert_eq!((out.facet, out.sigma), (4, 1));
    assert_eq!(
        dense(&out.boundaries[0]),
        rows(&[
            &[-1, 0, 0, -1],
            &[1, -1, 0, 0],
            &[0, 1, 1, 0],
            &[0, 0, -1, 1]
        ])
    );
    assert_eq!(dense(&out.boundaries[1]), rows(&[&[1], &[1], &[-1], &[-1]]));
    // ψ_1: identity on e0..e3, e4 ↦ e2 + e3; ψ_2: f0 ↦ m, f1 ↦ 0.
    assert_eq!(
        dense(&out.psi[1]),
        rows(&[
            &[1, 0, 0, 0, 0],
            &[0, 1, 0, 0, 0],
            &[0, 0, 1, 0, 1],
            &[0, 0, 0, 1, 1]
        ])
    );
    assert_eq!(dense(&out.psi[2]), rows(&[&[1, 0]]));
    // ζ_2: m ↦ f0 + f1.
    assert_eq!(dense(&out.zeta[2]), rows(&[&[1], &[1]]));
    check_kill(&[d1, d2], &out);
    Ok(())
}

/// Two edges e0 = v0 → v1 and e1 = v2 → v1 pointing at each other, merged
/// across v1: by hand σ = −1, ∂m = ∂e0 − ∂e1 = v2 − v0 (v2 renumbered 1),
/// ψ_0(v1) = v2, the far end of the removed edge.
#[test]
fn kill_two_edges_with_opposite_directions() -> TestResult {
    let b = vec![from_rows(&[&[-1, 0], &[1, 1], &[0, -1]])];
    let out = kill(&b, 1, 0, 1)?;
    assert_eq!((out.facet, out.sigma), (1, -1));
    assert_eq!(dense(&out.boundaries[0]), rows(&[&[-1], &[1]]));
    assert_eq!(dense(&out.psi[0]), rows(&[&[1, 0, 0], &[0, 1, 1]]));
    assert_eq!(dense(&out.zeta[1]), rows(&[&[1], &[-1]]));
    check_kill(&b, &out);
    Ok(())
}

#[test]
fn kill_refuses_invalid_merges() -> TestResult {
    let (delta0, delta1) = triangle();
    let tri = [transpose(&delta0), transpose(&delta1)];
    assert!(matches!(
        kill(&tri, 3, 0, 1),
        Err(SplitError::DimensionOutOfRange { p: 3, dim: 2 })
    ));
    assert!(matches!(
        kill(&tri, 1, 0, 3),
        Err(SplitError::CellOutOfRange { p: 1, cell: 3, .. })
    ));
    assert!(matches!(
        kill(&tri, 1, 2, 2),
        Err(SplitError::SameCell { p: 1, cell: 2 })
    ));
    // Merging σ1^1 and σ1^2 across σ0^1 leaves a 2-gon face bounded by the
    // merged edge and σ1^3, which share both their endpoints.
    let digon = kill(&tri, 1, 0, 1)?;
    assert_eq!(betti(&digon.boundaries), vec![1, 0, 0]);
    assert_eq!(
        kill(&digon.boundaries, 1, 0, 1),
        Err(SplitError::NotAdjacent {
            p: 1,
            a: 0,
            b: 1,
            shared: vec![0, 1]
        })
    );
    // Three edges out of v0: v0 has degree 3.
    let star = from_rows(&[&[-1, -1, -1], &[1, 0, 0], &[0, 1, 0], &[0, 0, 1]]);
    assert_eq!(
        kill(&[star], 1, 0, 1),
        Err(SplitError::FacetHasOtherCofaces {
            p: 1,
            facet: 0,
            a: 0,
            b: 1,
            other: 2
        })
    );
    // A = v0 v1 v2 v3 and B = v1 v0 v4 v3 v5 share the edge e0 = v0 → v1
    // and also the vertex v3: their union is a pinched annulus.
    let d1 = from_rows(&[
        &[-1, 0, 0, 1, -1, 0, 0, 0],
        &[1, -1, 0, 0, 0, 0, 0, 1],
        &[0, 1, -1, 0, 0, 0, 0, 0],
        &[0, 0, 1, -1, 0, 1, -1, 0],
        &[0, 0, 0, 0, 1, -1, 0, 0],
        &[0, 0, 0, 0, 0, 0, 1, -1],
    ]);
    let d2 = from_rows(&[
        &[1, -1],
        &[1, 0],
        &[1, 0],
        &[1, 0],
        &[0, 1],
        &[0, 1],
        &[0, 1],
        &[0, 1],
    ]);
    assert!(is_zero(&(&d1 * &d2)));
    assert!(matches!(
        kill(&[d1, d2], 2, 0, 1),
        Err(SplitError::NotACell {
            p: 2,
            a: 0,
            b: 1,
            ..
        })
    ));
    // A face whose boundary is not a cycle (∂∂ ≠ 0 at σ0^2): its edges
    // σ1^2 and σ1^3 cannot be merged coherently.
    let bad = [transpose(&delta0), transpose(&from_rows(&[&[-1, 1, -1]]))];
    assert!(matches!(
        kill(&bad, 1, 1, 2),
        Err(SplitError::NotACell {
            p: 1,
            a: 1,
            b: 2,
            ..
        })
    ));
    Ok(())
}

// ------------------------------------------------ invariants (digest H8)

/// Everything a kill must satisfy, checked against the input alone:
/// ∂∂ = 0, χ and the Betti numbers kept, ∂̃ψ = ψ∂, ∂ζ = ζ∂, ψζ = id.
fn check_kill(before: &[CsMat<i8>], out: &hasse_complex::kill::Kill) {
    let after = &out.boundaries;
    let n = before.len();
    for p in 1..n {
        assert!(is_zero(&(&after[p - 1] * &after[p])), "∂∂ ≠ 0 at {p}");
    }
    assert_eq!(
        euler_characteristic(&cell_counts(after)),
        euler_characteristic(&cell_counts(before))
    );
    assert_eq!(betti(after), betti(before));
    for p in 1..=n {
        let left = &after[p - 1] * &out.psi[p];
        let right = &out.psi[p - 1] * &before[p - 1];
        assert_eq!(dense(&left), dense(&right), "∂ψ ≠ ψ∂ at {p}");
        let left = &before[p - 1] * &out.zeta[p];
        let right = &out.zeta[p - 1] * &after[p - 1];
        assert_eq!(dense(&left), dense(&right), "∂ζ ≠ ζ∂ at {p}");
    }
    for (q, (psi, zeta)) in out.psi.iter().zip(&out.zeta).enumerate() {
        assert_eq!(dense(&(psi * zeta)), identity(psi.rows()), "ψζ ≠ id at {q}");
    }
}

/// One make checked against its matrix form and its inverse: the matrix
/// form and η reproduce make; the identities S1 + S2 + S3 = ζ_p,
/// T1 + T2 = T3 = ζ_{p−1}ᵀ and C = ζ_pᵀ hold; kill restores the input and
/// returns make's ζ; χ and the Betti numbers are kept.
fn check_make(b: &[CsMat<i8>], p: usize, cell: usize, moved: &[usize]) -> Vec<CsMat<i8>> {
    let made = make(b, p, cell, moved).expect("a valid make");
    let m = MakeMatrices::new(b, p, cell, moved).expect("same checks as make");
    assert_eq!(m.boundaries(b).expect("shapes fit"), made.boundaries);
    let h = hasse_matrix(b);
    assert_eq!(
        m.hasse(&h).expect("shapes fit"),
        hasse_matrix(&made.boundaries)
    );
    assert_eq!(
        eta(&h, &cell_counts(b), p, cell, moved).expect("valid"),
        hasse_matrix(&made.boundaries)
    );
    let sum = |a: &CsMat<i8>, c: &CsMat<i8>| a + c;
    let s = |i| m.s(i).expect("1 ≤ i ≤ 3");
    let t = |i| m.t(i).expect("1 ≤ i ≤ 3");
    assert_eq!(dense(&sum(&sum(s(1), s(2)), s(3))), dense(&made.zeta[p]));
    assert_eq!(dense(&sum(t(1), t(2))), dense(t(3)));
    assert_eq!(dense(t(3)), dense(&transpose(&made.zeta[p - 1])));
    assert_eq!(dense(m.c()), dense(&transpose(&made.zeta[p])));
    for q in 1..b.len() {
        assert!(is_zero(&(&made.boundaries[q - 1] * &made.boundaries[q])));
    }
    assert_eq!(betti(&made.boundaries), betti(b));
    let back = kill(&made.boundaries, p, cell, cell_counts(b)[p]).expect("κ undoes β");
    assert_eq!(back.boundaries, b);
    assert_eq!(back.zeta, made.zeta);
    check_kill(&made.boundaries, &back);
    made.boundaries
}

/// The vertices of q-cell `cell`, descending through the boundaries.
fn vertices(b: &[CsMat<i8>], q: usize, cell: usize) -> Vec<usize> {
    let mut cells = vec![cell];
    for k in (1..=q).rev() {
        let csc = b[k - 1].to_csc();
        let mut below: Vec<usize> = cells
            .iter()
            .filter_map(|&c| csc.outer_view(c))
            .flat_map(|col| col.indices().to_vec())
            .collect();
        below.sort_unstable();
        below.dedup();
        cells = below;
    }
    cells
}

/// A corner cut of p-cell `cell`: the facets that contain its `pick`-th
/// vertex (or, with `complement`, those that do not).
fn corner(b: &[CsMat<i8>], p: usize, cell: usize, pick: usize, complement: bool) -> Vec<usize> {
    let corners = vertices(b, p, cell);
    let v = corners[pick % corners.len()];
    let csc = b[p - 1].to_csc();
    let facets: Vec<usize> = csc
        .outer_view(cell)
        .map_or(Vec::new(), |c| c.indices().to_vec());
    facets
        .into_iter()
        .filter(|&f| vertices(b, p - 1, f).contains(&v) != complement)
        .collect()
}

/// The generated complexes of the property tests, with their Betti
/// numbers (known shapes: segment, disks, annulus, balls).
fn generated(kind: usize) -> (Complex, Vec<usize>) {
    let x = uniform_axis(2, 0.0, 1.0).expect("axis");
    match kind % 6 {
        0 => (interval(3, 0.0, 1.0).expect("interval"), vec![1, 0]),
        1 => (
            rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).expect("grid"),
            vec![1, 0, 0],
        ),
        2 => (kuhn(&[x.clone(), x]).expect("kuhn"), vec![1, 0, 0]),
        3 => (annulus(0.5, 1.0, 1, 6).expect("annulus"), vec![1, 1, 0]),
        4 => (
            box3(2, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).expect("box"),
            vec![1, 0, 0, 0],
        ),
        _ => (
            kuhn(&[x.clone(), x.clone(), x]).expect("kuhn"),
            vec![1, 0, 0, 0],
        ),
    }
}

/// Kill across interior facets and degree-2 vertices of generated meshes
/// (not produced by make): every pair that qualifies, each checked alone.
#[test]
fn kill_on_generated_meshes_keeps_the_invariants() {
    for kind in 0..6 {
        let (k, known) = generated(kind);
        let b = boundaries_of(&k);
        assert_eq!(betti(&b), known);
        let mut merged = 0;
        for p in 1..=b.len() {
            // (p−1)-cells with exactly two cofaces: the candidates.
            for row in b[p - 1].outer_iterator() {
                if let &[a, c] = row.indices() {
                    // Both orders: keeping the later cell renumbers it.
                    for (keep, remove) in [(a, c), (c, a)] {
                        if let Ok(out) = kill(&b, p, keep, remove) {
                            assert_eq!(betti(&out.boundaries), known);
                            check_kill(&b, &out);
                            merged += 1;
                        }
                    }
                }
            }
        }
        assert!(merged > 0, "complex {kind}: nothing to merge");
    }
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// Up to three random corner-cut makes on a generated complex:
        /// each agrees with its matrix form and η, keeps χ and the Betti
        /// numbers of the shape (digest H8), and kill undoes it; killing
        /// in reverse order returns the original complex.
        #[test]
        fn random_makes_match_the_matrix_form_and_kill_undoes_them(
            kind in 0usize..6,
            steps in proptest::collection::vec((any::<u32>(), any::<u32>(), any::<u32>(), any::<bool>()), 1..4),
        ) {
            let (k, known) = generated(kind);
            let original = boundaries_of(&k);
            let mut stages = vec![original.clone()];
            let mut undo = Vec::new();
            for (pp, cc, vv, complement) in steps {
                let b = stages.last().cloned().unwrap_or_default();
                let n = b.len();
                let p = 1 + pp as usize % n;
                let cell = cc as usize % cell_counts(&b)[p];
                let moved = corner(&b, p, cell, vv as usize, complement);
                if make(&b, p, cell, &moved).is_err() {
                    // Every facet contains that corner: no proper cut.
                    continue;
                }
                let next = check_make(&b, p, cell, &moved);
                prop_assert_eq!(betti(&next), known.clone());
                undo.push((p, cell, cell_counts(&b)[p]));
                stages.push(next);
            }
            let mut b = stages.pop().unwrap_or_default();
            while let Some((p, keep, remove)) = undo.pop() {
                b = kill(&b, p, keep, remove).expect("κ undoes β").boundaries;
            }
            prop_assert_eq!(b, original);
        }
    }
}

/// hasse_blocks inverts hasse_matrix and refuses matrices of the wrong
/// shape: the Hasse matrix of the 2×1×1 box is (k1 + k3) × (k0 + k2).
#[test]
fn hasse_blocks_round_trip_and_shape_errors() -> TestResult {
    let (k, _) = generated(4);
    let b = boundaries_of(&k);
    let counts = cell_counts(&b);
    // 2×1×1 hexahedra: 12 vertices, 20 edges, 11 faces, 2 cells (by hand).
    assert_eq!(counts, vec![12, 20, 11, 2]);
    let h = hasse_matrix(&b);
    assert_eq!(h.shape(), (22, 23));
    let delta = hasse_blocks(&h, &counts)?;
    for (d, bd) in delta.iter().zip(&b) {
        assert_eq!(d, &transpose(bd));
    }
    assert!(matches!(
        hasse_blocks(&h, &[12, 20, 11, 3]),
        Err(SplitError::Shape { .. })
    ));
    Ok(())
}

/// make refuses cuts whose new cell would not be a cell. On the unit
/// square, two opposite edges end at four vertices (no path), two adjacent
/// ones at two (a path: the diagonal cut). On the unit cube, one face, two
/// adjacent faces, three faces around a corner and a U of three faces are
/// discs bounded by one cycle of 4, 6, 6 and 8 edges; two opposite faces
/// are bounded by two 4-cycles, and the band of four side faces by the top
/// and bottom squares (an annulus): both refused. Counts by hand.
#[test]
fn make_refuses_cuts_that_bound_no_cell() -> TestResult {
    let square = boundaries_of(&rectangle(1, 1, [0.0, 1.0], [0.0, 1.0])?);
    let facets = |b: &[CsMat<i8>], p: usize| -> Vec<usize> {
        let col = b[p - 1].to_csc();
        col.outer_view(0)
            .map(|c| c.indices().to_vec())
            .unwrap_or_default()
    };
    let edges = facets(&square, 2);
    let d1 = square[0].to_csc();
    let ends = |e: usize| -> Vec<usize> {
        d1.outer_view(e)
            .map(|c| c.indices().to_vec())
            .unwrap_or_default()
    };
    let shares = |a: usize, b: usize| ends(a).iter().any(|v| ends(b).contains(v));
    let opposite = edges
        .iter()
        .copied()
        .find(|&e| e != edges[0] && !shares(e, edges[0]))
        .ok_or("no opposite edge")?;
    let adjacent = edges
        .iter()
        .copied()
        .find(|&e| e != edges[0] && shares(e, edges[0]))
        .ok_or("no adjacent edge")?;
    assert!(matches!(
        make(&square, 2, 0, &[edges[0], opposite]),
        Err(SplitError::BadFacetSelection { .. })
    ));
    check_make(&square, 2, 0, &[edges[0], adjacent]);

    let cube = boundaries_of(&box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0])?);
    let faces = facets(&cube, 3);
    assert_eq!(faces.len(), 6);
    // A face's axis: the coordinate its centroid pins to 0 or 1, read from
    // the face's vertices through the generated complex.
    let k = box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0])?;
    let side = |f: usize| -> (usize, bool) {
        let c = k.centroid_of(2, f);
        let axis = (0..3)
            .find(|&a| (c[a] - 0.5).abs() > 0.25)
            .unwrap_or(usize::MAX);
        (axis, c.get(axis).is_some_and(|&x| x > 0.5))
    };
    let face = |axis: usize, high: bool| -> Result<usize, String> {
        faces
            .iter()
            .copied()
            .find(|&f| side(f) == (axis, high))
            .ok_or_else(|| format!("no face on axis {axis}"))
    };
    let (x0, x1, y0, y1, z0, z1) = (
        face(0, false)?,
        face(0, true)?,
        face(1, false)?,
        face(1, true)?,
        face(2, false)?,
        face(2, true)?,
    );
    for disc in [vec![z0], vec![z0, x0], vec![z0, x0, y0], vec![z0, x0, x1]] {
        check_make(&cube, 3, 0, &disc);
    }
    for (cut, why) in [
        (vec![z0, z1], "two cycles"),
        (vec![x0, x1, y0, y1], "an annulus"),
    ] {
        match make(&cube, 3, 0, &cut) {
            Err(SplitError::BadFacetSelection { reason, .. }) => {
                assert!(reason.contains("more than one cycle"), "{why}: {reason}")
            }
            other => panic!("{why}: {:?}", other.map(|_| ())),
        }
    }
    Ok(())
}
