//! The SPLIT of one cell as a composition of make operators β: the same
//! complex and the same chain map ζ as the geometric SPLIT, integers
//! exactly, up to the orientation SPLIT gives its new cells.

use hasse_complex::generate::{box3, kuhn, rectangle, uniform_axis};
use hasse_complex::split::{split, split_by_makes, Hyperplane, SplitOptions};
use hasse_complex::Complex;
use sprs::CsMat;

fn dense(m: &CsMat<i8>) -> Vec<Vec<i32>> {
    let mut out = vec![vec![0; m.cols()]; m.rows()];
    for (&v, (i, j)) in m.iter() {
        out[i][j] += i32::from(v);
    }
    out
}

/// SPLIT `cell` of `k` by `plane` both ways; the diagonal signs D_p that
/// carry the makes' orientation to SPLIT's must give ∂_split =
/// D_{p−1} ∂_made D_p and ζ_split = D_p ζ_made, entry by entry.
fn same_split(k: &Complex, cell: usize, plane: &Hyperplane) -> usize {
    let options = SplitOptions::default();
    let (fine, r) = split(k, plane, Some(&[cell]), options).unwrap();
    let made = split_by_makes(k, cell, plane, options.snap).unwrap();
    assert_eq!(
        made.zeta.iter().map(|z| z.rows()).collect::<Vec<_>>(),
        fine.cell_counts()
    );
    let mut signs: Vec<Vec<i32>> = vec![vec![1; fine.cell_count(0)]];
    for p in 1..=k.dim() {
        let theirs = dense(fine.boundary(p));
        let mine = dense(&made.boundaries[p - 1]);
        let below = &signs[p - 1];
        // D_p[j] from the first non-zero entry of column j.
        let here: Vec<i32> = (0..fine.cell_count(p))
            .map(|j| {
                let i = (0..mine.len()).find(|&i| mine[i][j] != 0).unwrap();
                theirs[i][j] * mine[i][j] * below[i]
            })
            .collect();
        for (i, row) in mine.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                assert_eq!(theirs[i][j], below[i] * v * here[j], "∂_{p} ({i}, {j})");
            }
        }
        signs.push(here);
    }
    for (p, d) in signs.iter().enumerate() {
        let theirs = dense(r.zeta(p));
        let mine = dense(&made.zeta[p]);
        for (i, row) in mine.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                assert_eq!(theirs[i][j], d[i] * v, "ζ_{p} ({i}, {j})");
            }
        }
    }
    made.makes.len()
}

#[test]
fn split_of_a_square_is_three_makes() {
    // x = 0.3 + 0.2 y crosses the bottom and top sides of the left square
    // (β⁰ twice) and the square (β¹ once); it misses the right square.
    let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let plane = Hyperplane::new(&[1.0, -0.2], 0.3).unwrap();
    assert_eq!(same_split(&k, 0, &plane), 3);
    // A plane through the shared side's interior: the neighbour gets the
    // new vertex (hanging) from the copied row of ∂₂.
    let plane = Hyperplane::new(&[1.0, 1.0], 1.5).unwrap();
    assert_eq!(same_split(&k, 0, &plane), 3);
}

#[test]
fn split_of_a_triangle_in_a_kuhn_mesh() {
    let x = uniform_axis(2, 0.0, 1.0).unwrap();
    let k = kuhn(&[x.clone(), x]).unwrap();
    // x = 0.3 − 0.1 y ∈ (0.2, 0.3) crosses the four triangles of the left
    // column (each spans x ∈ [0, 0.5]) and none of the right one.
    let plane = Hyperplane::new(&[1.0, 0.1], 0.3).unwrap();
    let mut crossed = 0;
    for cell in 0..k.cell_count(2) {
        // A crossed triangle: two sides and the triangle, 3 makes.
        let makes = same_split(&k, cell, &plane);
        assert!(makes == 0 || makes == 3, "cell {cell}: {makes} makes");
        crossed += usize::from(makes == 3);
    }
    assert_eq!(crossed, 4);
}

#[test]
fn split_of_a_cube_is_nine_makes() {
    // x + 0.3 y + 0.2 z = 0.6 cuts the 4 edges of the unit cube along x
    // (0.6 − 0.3y − 0.2z ∈ (0.1, 0.6) ⊂ (0, 1)): 4 β⁰; the 4 faces
    // around x (β¹ each); then the cube (β²): 9 makes.
    let k = box3(1, 1, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    let plane = Hyperplane::new(&[1.0, 0.3, 0.2], 0.6).unwrap();
    assert_eq!(same_split(&k, 0, &plane), 9);
}
