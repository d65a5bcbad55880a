//! Coarsening by kill operators: undoing SPLIT refinements.

use approx::assert_relative_eq;
use hasse_complex::coarsen::{coarsen, coarsen_traced};
use hasse_complex::generate::{box3, rectangle};
use hasse_complex::refine::{refine_marked, uniform};
use hasse_complex::{Complex, TopCells, Vertices};
use sprs::CsMat;

/// Dense copy of an integer matrix.
fn dense(m: &CsMat<i8>) -> Vec<Vec<i32>> {
    let mut out = vec![vec![0; m.cols()]; m.rows()];
    for (&v, (i, j)) in m.iter() {
        out[i][j] += i32::from(v);
    }
    out
}

fn is_zero(m: &CsMat<i8>) -> bool {
    m.iter().all(|(&v, _)| v == 0)
}

/// A complex in a numbering that depends on geometry only: vertices sorted
/// by their coordinates (compared exactly), p-cells by the sorted list of
/// their new vertex numbers. Returns the coordinates and ∂_1 … ∂_n, dense.
fn canonical(k: &Complex) -> (Vec<Vec<f64>>, Vec<Vec<Vec<i32>>>) {
    let k0 = k.cell_count(0);
    let mut by_point: Vec<usize> = (0..k0).collect();
    by_point.sort_by(|&a, &b| {
        let (pa, pb) = (k.vertices().point(a), k.vertices().point(b));
        pa.iter()
            .zip(pb)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut vertex_rank = vec![0; k0];
    for (r, &v) in by_point.iter().enumerate() {
        vertex_rank[v] = r;
    }
    let coords = by_point
        .iter()
        .map(|&v| k.vertices().point(v).to_vec())
        .collect();
    // rank[p][i]: canonical position of p-cell i.
    let mut rank = vec![vertex_rank];
    for p in 1..=k.dim() {
        let keys: Vec<Vec<usize>> = (0..k.cell_count(p))
            .map(|i| {
                let mut key: Vec<usize> =
                    k.cell_vertices(p, i).iter().map(|&v| rank[0][v]).collect();
                key.sort_unstable();
                key
            })
            .collect();
        let mut order: Vec<usize> = (0..keys.len()).collect();
        order.sort_by(|&a, &b| keys[a].cmp(&keys[b]));
        let mut r = vec![0; keys.len()];
        for (pos, &i) in order.iter().enumerate() {
            r[i] = pos;
        }
        rank.push(r);
    }
    let boundaries = (1..=k.dim())
        .map(|p| {
            let b = k.boundary(p);
            let mut out = vec![vec![0; b.cols()]; b.rows()];
            for (&v, (i, j)) in b.iter() {
                out[rank[p - 1][i]][rank[p][j]] = i32::from(v);
            }
            out
        })
        .collect();
    (coords, boundaries)
}

/// ∂′ψ = ψ∂ in every dimension and ψζ = I (the maps of one coarsening).
fn check_chain_maps(fine: &Complex, coarse: &Complex, c: &hasse_complex::coarsen::Coarsening) {
    for p in 1..=fine.dim() {
        let left = &**coarse.boundary(p) * c.psi(p);
        let right = c.psi(p - 1) * &**fine.boundary(p);
        assert_eq!(dense(&left), dense(&right), "∂ψ = ψ∂ at p = {p}");
    }
    for p in 0..=fine.dim() {
        let id = c.psi(p) * c.zeta(p);
        assert_eq!(
            dense(&id),
            dense(&CsMat::eye(coarse.cell_count(p))),
            "ψζ = I at p = {p}"
        );
    }
}

#[test]
fn coarsening_a_uniform_split_of_a_4x4_rectangle_gives_it_back() {
    let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let (fine, r) = uniform(&k).unwrap();
    assert_eq!(fine.cell_counts(), vec![81, 144, 64]);
    let all: Vec<usize> = (0..16).collect();
    let mut steps = 0;
    let (coarse, c) = coarsen_traced(&fine, &r, &all, &mut |_, b| {
        steps += 1;
        for pair in b.windows(2) {
            assert!(is_zero(&(&pair[0] * &pair[1])), "∂∂ = 0 after kill {steps}");
        }
    })
    .unwrap();
    // By hand: 3 merges per square (4 quarters → 1) = 48 kills of 2-cells;
    // one centre vertex per square (16) and one midpoint per original edge
    // (40) = 56 kills of 1-cells. 81 − 56 = 25, 144 − 48 − 56 = 40,
    // 64 − 48 = 16: the 4×4 grid.
    assert_eq!(c.kills(), &[0, 56, 48]);
    assert_eq!(steps, 104);
    assert_eq!(coarse.cell_counts(), vec![25, 40, 16]);
    assert_eq!(coarse.euler_characteristic(), 1);
    // Same coordinates and the same ∂ matrices, integers exactly, after a
    // relabelling by coordinates.
    assert_eq!(canonical(&coarse), canonical(&k));
    // SPLIT keeps an index for one piece and appends the rest; the kills
    // keep the smaller index: the numbering comes back as well.
    for p in 1..=2 {
        assert_eq!(dense(coarse.boundary(p)), dense(k.boundary(p)), "∂_{p}");
    }
    assert_eq!(coarse.vertices().as_slice(), k.vertices().as_slice());
    check_chain_maps(&fine, &coarse, &c);
    // The boundary tag is carried over: the 16 outer edges of the grid.
    let tag = coarse.tag("boundary").unwrap();
    assert_eq!(tag.cells, k.tag("boundary").unwrap().cells);
}

/// The L-shape of three unit squares A = [0,1]², B = [1,2]×[0,1],
/// C = [0,1]×[1,2], re-entrant corner at (1, 1).
fn l_shape() -> Complex {
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [1.0, 0.0],
        [2.0, 0.0],
        [0.0, 1.0],
        [1.0, 1.0],
        [2.0, 1.0],
        [0.0, 2.0],
        [1.0, 2.0],
    ])
    .unwrap();
    Complex::build(
        v,
        TopCells::polygons([vec![0, 1, 4, 3], vec![1, 2, 5, 4], vec![3, 4, 7, 6]]),
    )
    .unwrap()
}

#[test]
fn partial_coarsening_of_a_refined_l_shape_keeps_hanging_vertices() {
    let k = l_shape();
    assert_eq!(k.cell_counts(), vec![8, 10, 3]);
    let (fine, r) = refine_marked(&k, &[0, 1, 2]).unwrap();
    // The 0.5-grid on the L: 5×5 points minus the 4 with x, y > 1 = 21
    // vertices, 12 quarters, χ = 1 gives 21 + 12 − 1 = 32 edges.
    assert_eq!(fine.cell_counts(), vec![21, 32, 12]);

    // B alone: its centre and the midpoints of its three sides on the
    // domain boundary go (bottom y = 0, right x = 2, the re-entrant side
    // y = 1); the midpoint (1, 0.5) of the side it shares with the still
    // refined A stays, a hanging vertex: B is a pentagon. 21 − 4 = 17
    // vertices, 12 − 3 = 9 cells, 17 + 9 − 1 = 25 edges.
    let (coarse, c) = coarsen(&fine, &r, &[1]).unwrap();
    assert_eq!(coarse.cell_counts(), vec![17, 25, 9]);
    assert_eq!(c.kills(), &[0, 4, 3]);
    let b = c.coarse_cell(2, 1).unwrap().0;
    let mut corners: Vec<[f64; 2]> = coarse
        .cell_vertices(2, b)
        .iter()
        .map(|&v| [coarse.vertices().point(v)[0], coarse.vertices().point(v)[1]])
        .collect();
    corners.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(
        corners,
        vec![[1.0, 0.0], [1.0, 0.5], [1.0, 1.0], [2.0, 0.0], [2.0, 1.0]]
    );
    assert_relative_eq!(coarse.measure(2)[b], 1.0, max_relative = 1e-15);
    check_chain_maps(&fine, &coarse, &c);

    // A and B: the midpoint (1, 0.5) between them goes too, since both
    // cells beside it are coarsened; A's side shared with the refined C
    // keeps its midpoint (0.5, 1). Removed: 2 centres, A's left and bottom,
    // B's bottom, right and top, and (1, 0.5): 21 − 8 = 13 vertices;
    // 12 − 6 = 6 cells; 13 + 6 − 1 = 18 edges.
    let (coarse, c) = coarsen(&fine, &r, &[0, 1]).unwrap();
    assert_eq!(coarse.cell_counts(), vec![13, 18, 6]);
    assert_eq!(c.kills(), &[0, 8, 6]);
    assert_eq!(coarse.euler_characteristic(), 1);
    check_chain_maps(&fine, &coarse, &c);
    // Total area 3, cell by cell.
    assert_relative_eq!(
        coarse.measure(2).iter().sum::<f64>(),
        3.0,
        max_relative = 1e-15
    );
}

#[test]
fn fields_move_back_conservatively() {
    let k = l_shape();
    let (fine, r) = refine_marked(&k, &[0, 1, 2]).unwrap();
    let (coarse, c) = coarsen(&fine, &r, &[0, 2]).unwrap();
    let d = 2;
    let centre = fine.centroid(2);
    // Cell averages of u = sin(3x) + y² sampled at the centroids.
    let u: Vec<f64> = (0..fine.cell_count(2))
        .map(|i| (3.0 * centre[i * d]).sin() + centre[i * d + 1].powi(2))
        .collect();
    let ubar = c.restrict_intensive(&fine, 2, &u).unwrap();
    // ∫u is the same on both meshes: Σ|c| ū_c = Σ|f| u_f (the weights add
    // up exactly for these dyadic areas; 1e-14 covers the summation order).
    let fine_integral: f64 = u.iter().zip(fine.measure(2)).map(|(u, m)| u * m).sum();
    let coarse_integral: f64 = ubar.iter().zip(coarse.measure(2)).map(|(u, m)| u * m).sum();
    assert_relative_eq!(fine_integral, coarse_integral, max_relative = 1e-14);
    // Amounts (u|f|) add up: the same integral again.
    let amounts: Vec<f64> = u.iter().zip(fine.measure(2)).map(|(u, m)| u * m).collect();
    let total: f64 = c.restrict_extensive(2, &amounts).unwrap().iter().sum();
    assert_relative_eq!(total, fine_integral, max_relative = 1e-14);
    // A constant stays constant, exactly.
    let constant = c.restrict_intensive(&fine, 2, &vec![0.7; u.len()]).unwrap();
    assert!(constant.iter().all(|&x| x == 0.7));
    // A linear nodal field restricts by injection: exact at the kept points.
    let linear = |x: &[f64]| 2.0 * x[0] - 3.0 * x[1] + 1.0;
    let nodal: Vec<f64> = (0..fine.cell_count(0))
        .map(|v| linear(fine.vertices().point(v)))
        .collect();
    let back = c.restrict_nodal(&nodal).unwrap();
    for (v, value) in back.iter().enumerate() {
        assert_eq!(*value, linear(coarse.vertices().point(v)));
    }
}

#[test]
fn restriction_is_the_transpose_of_split_prolongation() {
    // SPLIT's intensive transfer P (a quarter gets its parent's value):
    // R = M′⁻¹ Pᵀ M (M the cell areas) must be the coarsening's intensive
    // restriction, and R P = I.
    let k = rectangle(3, 2, [0.0, 3.0], [0.0, 1.0]).unwrap();
    let (fine, r) = uniform(&k).unwrap();
    let all: Vec<usize> = (0..6).collect();
    let (coarse, c) = coarsen(&fine, &r, &all).unwrap();
    let u: Vec<f64> = (0..fine.cell_count(2))
        .map(|i| 1.0 + (i as f64 * 0.37).cos())
        .collect();
    let mut expected = vec![0.0; 6];
    let fine_area = fine.measure(2);
    for (f, &uf) in u.iter().enumerate() {
        let (parent, sign) = r.parent(2, f).unwrap();
        expected[parent] += f64::from(sign) * fine_area[f] * uf;
    }
    for (e, area) in expected.iter_mut().zip(k.measure(2)) {
        *e /= area;
    }
    // The coarse numbering is the original one (see the 4×4 test).
    let restricted = c.restrict_intensive(&fine, 2, &u).unwrap();
    for (a, b) in restricted.iter().zip(&expected) {
        // Two ways of summing four terms of size ≤ 2: a few ulps.
        assert_relative_eq!(*a, *b, max_relative = 1e-14);
    }
    let coarse_values = [1.0, -2.0, 3.5, 0.25, 8.0, -1.0];
    let prolonged = r.intensive(&fine, 2, &coarse_values).unwrap();
    assert_eq!(
        c.restrict_intensive(&fine, 2, &prolonged).unwrap(),
        coarse_values
    );
    // Extensive: SPLIT shares an amount by area, the restriction adds it up.
    let shared = r.extensive(&fine, 2, &coarse_values).unwrap();
    let summed = c.restrict_extensive(2, &shared).unwrap();
    for (a, b) in summed.iter().zip(&coarse_values) {
        assert_relative_eq!(*a, *b, max_relative = 1e-15);
    }
    assert_eq!(coarse.cell_counts(), k.cell_counts());
}

#[test]
fn coarsening_a_uniform_split_of_a_box_gives_it_back() {
    let k = box3(2, 1, 1, [0.0, 2.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    let (fine, r) = uniform(&k).unwrap();
    // Two cubes in eight octants each: a 5×3×3 point grid.
    assert_eq!(fine.cell_count(0), 45);
    assert_eq!(fine.cell_count(3), 16);
    let mut checked = 0;
    let (coarse, c) = coarsen_traced(&fine, &r, &[0, 1], &mut |_, b| {
        checked += 1;
        for pair in b.windows(2) {
            assert!(is_zero(&(&pair[0] * &pair[1])));
        }
    })
    .unwrap();
    // By hand, per cube: 7 merges of octants remove 7 of its 12 interior
    // quarter faces; the other 5 go by merges of faces across interior
    // half-edges (5 of its 6), the last half-edge with the centre vertex.
    // Per square face of the grid (11 of them): 3 merges of quarters and
    // its centre vertex. Per edge (20): its midpoint. p = 3: 2 × 7 = 14;
    // p = 2: 2 × 5 + 11 × 3 = 43; p = 1: 2 + 11 + 20 = 33 (= 45 − 12
    // vertices removed).
    assert_eq!(c.kills(), &[0, 33, 43, 14]);
    assert_eq!(checked, 90);
    assert_eq!(coarse.cell_counts(), k.cell_counts());
    assert_eq!(coarse.euler_characteristic(), 1);
    assert_eq!(canonical(&coarse), canonical(&k));
    check_chain_maps(&fine, &coarse, &c);
}
