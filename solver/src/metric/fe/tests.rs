//! Tests of the finite-element metrics.

use super::q1::{affine_jacobian, corner_sign};
use super::*;
use crate::metric::isotropic;
use hasse_complex::{TopCells, Vertices};

/// What a test returns: a failed step is its error.
type TestResult = Result<(), Box<dyn std::error::Error>>;

fn weights(complex: &Complex) -> Vec<f64> {
    let cells = complex.cell_count(complex.dim());
    let omega = stiffness_metric(complex, &vec![isotropic(1.0); cells])
        .expect("unit conductivity on a valid mesh");
    let dense = omega.to_dense();
    (0..omega.size()).map(|e| dense[e][e]).collect()
}

fn angle(apex: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (u, v) = (
        [a[0] - apex[0], a[1] - apex[1]],
        [b[0] - apex[0], b[1] - apex[1]],
    );
    (u[0] * v[1] - u[1] * v[0])
        .abs()
        .atan2(u[0] * v[0] + u[1] * v[1])
}

#[test]
fn right_triangle_has_no_weight_on_the_hypotenuse() -> TestResult {
    let v = Vertices::from_points(&[[0.0, 0.0], [3.0, 0.0], [0.0, 2.0]])?;
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]]))?;
    let w = weights(&k);
    let hypotenuse = k.find_cell(1, &[1, 2]).ok_or("no such edge")?;
    assert!(w[hypotenuse].abs() < 1e-15);
    // Leg {0,1} is opposite the angle at 2: cot = 2/3, weight 1/3.
    assert!((w[k.find_cell(1, &[0, 1]).ok_or("no such edge")?] - 1.0 / 3.0).abs() < 1e-15);
    assert!((w[k.find_cell(1, &[0, 2]).ok_or("no such edge")?] - 0.75).abs() < 1e-15);
    Ok(())
}

#[test]
fn triangle_weights_are_half_cotangents() -> TestResult {
    let p = [[0.1, -0.2], [2.3, 0.4], [0.7, 1.9]];
    let v = Vertices::from_points(&p)?;
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]]))?;
    let w = weights(&k);
    for (a, b, o) in [(0, 1, 2), (1, 2, 0), (0, 2, 1)] {
        let e = k.find_cell(1, &[a, b]).ok_or("no such edge")?;
        let expected = 0.5 / angle(p[o], p[a], p[b]).tan();
        assert!(
            (w[e] - expected).abs() < 1e-14,
            "{a}{b}: {} vs {expected}",
            w[e]
        );
    }
    Ok(())
}

#[test]
fn tetrahedron_weights_are_opposite_edge_cotangents() -> TestResult {
    let p = [
        [0.0, 0.0, 0.0],
        [1.2, 0.1, -0.1],
        [0.3, 0.9, 0.2],
        [0.2, 0.3, 1.1],
    ];
    let v = Vertices::from_points(&p)?;
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]]))?;
    let w = weights(&k);
    let sub3 = |a: usize, b: usize| [p[a][0] - p[b][0], p[a][1] - p[b][1], p[a][2] - p[b][2]];
    let cross3 = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let dot3 = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
        // Opposite edge {c, d}; the dihedral angle there is between the
        // faces {c, d, a} and {c, d, b}.
        let others: Vec<usize> = (0..4).filter(|&i| i != a && i != b).collect();
        let (c, d) = (others[0], others[1]);
        let axis = sub3(d, c);
        let unit = dot3(axis, axis).sqrt();
        let reject = |x: usize| {
            let r = sub3(x, c);
            let t = dot3(r, axis) / (unit * unit);
            [r[0] - t * axis[0], r[1] - t * axis[1], r[2] - t * axis[2]]
        };
        let (ra, rb) = (reject(a), reject(b));
        let phi = dot3(cross3(ra, rb), cross3(ra, rb))
            .sqrt()
            .atan2(dot3(ra, rb));
        let expected = unit / phi.tan() / 6.0;
        let e = k.find_cell(1, &[a, b]).ok_or("no such edge")?;
        assert!(
            (w[e] - expected).abs() < 1e-14,
            "{a}{b}: {} vs {expected}",
            w[e]
        );
    }
    Ok(())
}

#[test]
fn unit_square_q1_block_reproduces_the_element_matrix() -> TestResult {
    let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])?;
    let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]]))?;
    let omega = stiffness_metric(&k, &[isotropic(1.0)])?;
    assert_eq!(omega.block_count(), 1);
    let op = crate::operator::Canonical::new(k.coboundary(0), omega)?;
    let m = op.assemble().to_dense();
    // 4/6 on the diagonal, −1/6 along edges, −2/6 across the diagonal.
    for i in 0..4usize {
        for j in 0..4usize {
            let expected = match (i ^ j).count_ones() {
                0 => 4.0 / 6.0,
                1 => -1.0 / 6.0,
                _ => -2.0 / 6.0,
            };
            assert!((m[(i, j)] - expected).abs() < 1e-14, "({i},{j})");
        }
    }
    Ok(())
}

/// uᵀ M v for the one-cell operator M = Aᵀ Ω A of Q1 on the cell with
/// corners `x0 + Σ_{a ∈ l} axes[a]` (corner l in tensor order, stored
/// as vertex (5 l + 2) mod 2ⁿ) and conductivity `k`, for corner values
/// `modes` given per tensor corner.
fn one_cell_forms(x0: [f64; 3], axes: &[[f64; 3]], k: Tensor, modes: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = axes.len();
    let corners = 1usize << n;
    let vertex = |l: usize| (5 * l + 2) % corners;
    let mut coordinates = vec![0.0; corners * n];
    for i in 0..n {
        for (l, x) in coordinate_mode(x0, axes, i).into_iter().enumerate() {
            coordinates[vertex(l) * n + i] = x;
        }
    }
    let v = Vertices::new(n, coordinates).expect("finite coordinates");
    let cell: Vec<usize> = (0..corners).map(vertex).collect();
    let complex = Complex::build(v, TopCells::cuboids([cell])).expect("one valid cuboid");
    let omega = stiffness_metric(&complex, &[k]).expect("a positive definite K");
    let m = crate::operator::Canonical::new(complex.coboundary(0), omega)
        .expect("δ⁰ and Ω fit")
        .assemble()
        .to_dense();
    let by_vertex = |mode: &[f64]| {
        let mut u = vec![0.0; corners];
        for (l, &value) in mode.iter().enumerate() {
            u[vertex(l)] = value;
        }
        u
    };
    modes
        .iter()
        .map(|a| {
            let u = by_vertex(a);
            modes
                .iter()
                .map(|b| {
                    let w = by_vertex(b);
                    (0..corners)
                        .map(|i| (0..corners).map(|j| u[i] * m[(i, j)] * w[j]).sum::<f64>())
                        .sum()
                })
                .collect()
        })
        .collect()
}

/// The corner values (tensor order) of ξ_a ξ_b … on [−1, 1]ⁿ for the
/// reference axes in `axes`.
fn reference_mode(n: usize, axes: &[usize]) -> Vec<f64> {
    (0..1usize << n)
        .map(|l| axes.iter().map(|&a| corner_sign(l, a)).product())
        .collect()
}

/// The corner values (tensor order) of the physical coordinate x_i on
/// the cell of [`one_cell_forms`].
fn coordinate_mode(x0: [f64; 3], axes: &[[f64; 3]], i: usize) -> Vec<f64> {
    (0..1usize << axes.len())
        .map(|l| {
            x0[i]
                + (0..axes.len())
                    .filter(|&a| (l >> a) & 1 == 1)
                    .map(|a| axes[a][i])
                    .sum::<f64>()
        })
        .collect()
}

fn assert_forms(label: &str, forms: &[Vec<f64>], expected: &[&[f64]]) {
    for (a, row) in expected.iter().enumerate() {
        for (b, &value) in row.iter().enumerate() {
            assert!(
                (forms[a][b] - value).abs() < 1e-13,
                "{label} ({a}, {b}): {} vs {value}",
                forms[a][b]
            );
        }
    }
}

#[test]
fn q1_on_parallelograms_is_the_exact_galerkin_stiffness() -> TestResult {
    // A sheared cell, edges e1 = (2, 0), e2 = (1, 1) from (0.5, −1),
    // area 2, with k = [[2, ½], [½, 1]]. By hand: J = [e1 e2]/2,
    // det J = ½, J⁻¹ = [[1, −1], [0, 2]], C = det J · J⁻¹ k J⁻ᵀ =
    // [[1, −½], [−½, 2]]. Linear u, v: uᵀ M v = area · ∇uᵀ k ∇v, so
    // 4, 1, 2 for (x, x), (x, y), (y, y). The hourglass ξ1ξ2 has
    // ∇̂ = (ξ2, ξ1): ∫ over [−1, 1]² of ξ2² C11 + ξ1² C22 = 4/3 · 3 = 4,
    // and it is orthogonal to linear modes and constants.
    let x0 = [0.5, -1.0, 0.0];
    let axes = [[2.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
    let k = [[2.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0; 3]];
    let modes = [
        coordinate_mode(x0, &axes, 0),
        coordinate_mode(x0, &axes, 1),
        reference_mode(2, &[0, 1]),
        vec![1.0; 4],
    ];
    assert_forms(
        "2D",
        &one_cell_forms(x0, &axes, k, &modes),
        &[
            &[4.0, 1.0, 0.0, 0.0],
            &[1.0, 2.0, 0.0, 0.0],
            &[0.0, 0.0, 4.0, 0.0],
            &[0.0; 4],
        ],
    );
    // A parallelepiped: e1 = (2, 0, 0), e2 = (0, 2, 0), e3 = (1, 0, 2),
    // volume 8, k = I. J = [e1 e2 e3]/2 has det 1 and J⁻¹ rows
    // (1, 0, −½), (0, 1, 0), (0, 0, 1), so C = J⁻¹ J⁻ᵀ has C11 = 5/4,
    // C13 = −½, C22 = C33 = 1 and C12 = C23 = 0. Over [−1, 1]³ with
    // ∫ ξ² = 8/3 and ∫ ξ²η² = 8/9: ξ1ξ2 gives 8/3 (C11 + C22) = 6,
    // ξ1ξ3 gives 6, ξ2ξ3 gives 16/3, ξ1ξ2ξ3 gives 8/9 · 13/4 = 26/9;
    // ξ1ξ2 against ξ2ξ3 is ∫ ξ2² C13 = −4/3; u = x gives the volume.
    let x0 = [1.0, 0.0, -2.0];
    let axes = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 0.0, 2.0]];
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let modes = [
        reference_mode(3, &[0, 1]),
        reference_mode(3, &[0, 2]),
        reference_mode(3, &[1, 2]),
        reference_mode(3, &[0, 1, 2]),
        coordinate_mode(x0, &axes, 0),
        vec![1.0; 8],
    ];
    assert_forms(
        "3D",
        &one_cell_forms(x0, &axes, identity, &modes),
        &[
            &[6.0, 0.0, -4.0 / 3.0, 0.0, 0.0, 0.0],
            &[0.0, 6.0, 0.0, 0.0, 0.0, 0.0],
            &[-4.0 / 3.0, 0.0, 16.0 / 3.0, 0.0, 0.0, 0.0],
            &[0.0, 0.0, 0.0, 26.0 / 9.0, 0.0, 0.0],
            &[0.0, 0.0, 0.0, 0.0, 8.0, 0.0],
            &[0.0; 6],
        ],
    );
    Ok(())
}

#[test]
fn only_parallelograms_and_parallelepipeds_take_the_constant_jacobian() -> TestResult {
    let square = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let jacobian = affine_jacobian::<4>(&square).ok_or("a degenerate square")?;
    assert_eq!(
        (
            jacobian[0][0],
            jacobian[0][1],
            jacobian[1][0],
            jacobian[1][1]
        ),
        (0.5, 0.0, 0.0, 0.5)
    );
    // Corner 3 moved by 10⁻¹², far above 16 ulp of the unit size: a
    // trapezoid, for the Gauss rule.
    let mut moved = square;
    moved[3][0] += 1e-12;
    assert!(affine_jacobian::<4>(&moved).is_none());
    // A unit cube with only corner 7 (all three axes) moved.
    let mut cube = [[0.0; 3]; 8];
    for (l, p) in cube.iter_mut().enumerate() {
        for (a, x) in p.iter_mut().enumerate() {
            *x = ((l >> a) & 1) as f64;
        }
    }
    assert!(affine_jacobian::<8>(&cube).is_some());
    cube[7][2] -= 1e-12;
    assert!(affine_jacobian::<8>(&cube).is_none());
    Ok(())
}

/// Unit cells of an `sides` grid (2 or 3 axes) with vertex v renumbered
/// (7 v + 3) mod |V|, so that neighbouring cells see their vertices in
/// different sorted orders and have different local incidences: the
/// last cell's tensor order and A_c⁺ are reused when it matches and
/// found again when not. Returns the complex and each cell's corners
/// in tensor order, renumbered.
fn scrambled_grid(sides: &[usize]) -> (Complex, Vec<Vec<usize>>) {
    let n = sides.len();
    let stride: Vec<usize> = (0..n)
        .map(|a| sides[..a].iter().map(|s| s + 1).product())
        .collect();
    let count: usize = sides.iter().map(|s| s + 1).product();
    assert!(count % 7 != 0);
    let renumber = |v: usize| (7 * v + 3) % count;
    let mut points = vec![[0.0; 3]; count];
    for v in 0..count {
        for a in 0..n {
            points[renumber(v)][a] = ((v / stride[a]) % (sides[a] + 1)) as f64;
        }
    }
    let mut cells = Vec::new();
    let cell_count: usize = sides.iter().product();
    for c in 0..cell_count {
        let mut base = 0;
        let mut rest = c;
        for a in 0..n {
            base += (rest % sides[a]) * stride[a];
            rest /= sides[a];
        }
        let corners: Vec<usize> = (0..1usize << n)
            .map(|l| {
                let offset: usize = (0..n)
                    .filter(|&a| (l >> a) & 1 == 1)
                    .map(|a| stride[a])
                    .sum();
                renumber(base + offset)
            })
            .collect();
        cells.push(corners);
    }
    let coordinates: Vec<f64> = points.iter().flat_map(|p| p[..n].to_vec()).collect();
    let vertices = Vertices::new(n, coordinates).expect("finite coordinates");
    let complex =
        Complex::build(vertices, TopCells::cuboids(cells.clone())).expect("valid cuboids");
    (complex, cells)
}

#[test]
fn q1_on_a_scrambled_numbering_is_the_element_matrix_summed() -> TestResult {
    // The unit square's and the unit cube's Q1 stiffness, by the number
    // of local axes along which corners i and j differ: 2/3, −1/6, −1/3
    // in 2D; 1/3, 0, −1/12, −1/12 in 3D.
    for (sides, element) in [
        (vec![5, 4], vec![2.0 / 3.0, -1.0 / 6.0, -1.0 / 3.0]),
        (
            vec![3, 3, 2],
            vec![1.0 / 3.0, 0.0, -1.0 / 12.0, -1.0 / 12.0],
        ),
    ] {
        let (k, cells) = scrambled_grid(&sides);
        let omega = stiffness_metric(&k, &vec![isotropic(1.0); cells.len()])?;
        let m = crate::operator::Canonical::new(k.coboundary(0), omega)?
            .assemble()
            .to_dense();
        let vertices = k.cell_count(0);
        let mut expected = vec![vec![0.0; vertices]; vertices];
        for corners in &cells {
            for (l, &u) in corners.iter().enumerate() {
                for (q, &w) in corners.iter().enumerate() {
                    expected[u][w] += element[(l ^ q).count_ones() as usize];
                }
            }
        }
        for u in 0..vertices {
            for w in 0..vertices {
                assert!(
                    (m[(u, w)] - expected[u][w]).abs() < 1e-14,
                    "{sides:?}: ({u}, {w}) is {} instead of {}",
                    m[(u, w)],
                    expected[u][w]
                );
            }
        }
    }
    Ok(())
}

/// A 6 × 5 grid of [0, 3] × [0, 2] with its interior vertices moved
/// (by a fixed pattern, up to 0.15 of a cell): convex quadrilaterals
/// that are not parallelograms, so the Gauss points see four maps.
fn distorted_quads() -> Complex {
    let k = hasse_complex::generate::rectangle(6, 5, [0.0, 3.0], [0.0, 2.0]).expect("a valid grid");
    let moved: Vec<[f64; 2]> = (0..k.cell_count(0))
        .map(|v| {
            let p = k.vertices().point(v);
            let inside = p[0] > 0.0 && p[0] < 3.0 && p[1] > 0.0 && p[1] < 2.0;
            let s = if inside { 0.15 * 0.5 } else { 0.0 };
            let t = v as f64;
            [p[0] + s * (1.7 * t).sin(), p[1] + s * (2.3 * t).cos()]
        })
        .collect();
    k.with_vertices(Vertices::from_points(&moved).expect("finite points"))
        .expect("the same number of vertices")
}

#[test]
fn stiffness_and_load_together_are_the_two_apart() -> TestResult {
    let f = |x: &[f64]| 1.0 + 2.0 * x[0] - x[1];
    let quads = distorted_quads();
    let axis = hasse_complex::generate::uniform_axis(3, 0.0, 1.0)?;
    let hexes = hasse_complex::generate::box3(3, 2, 2, [0.0, 1.0], [0.0, 2.0], [0.0, 1.0])?;
    let tets = hasse_complex::generate::kuhn(&[axis.clone(), axis.clone(), axis])?;
    for k in [&quads, &hexes, &tets] {
        let n = k.dim();
        let cells = k.cell_count(n);
        let tensors: Vec<Tensor> = (0..cells)
            .map(|c| isotropic(1.0 + (c % 3) as f64))
            .collect();
        let (omega, b) = stiffness_and_load(k, &tensors, &f)?;
        assert_eq!(omega, stiffness_metric(k, &tensors)?);
        assert_eq!(b, load(k, &f)?);
        // Independently: the shares of a linear f sum to its integral,
        // which the tensor Gauss rule and the P1 rules give exactly;
        // ∫ f = |Ω| f(centre of mass).
        let (volume, centre) = match n {
            2 => (6.0, [1.5, 1.0]),
            _ if k.cell_count(n) == 12 => (2.0, [0.5, 1.0]),
            _ => (1.0, [0.5, 0.5]),
        };
        let expected = volume * f(&centre);
        let total: f64 = b.iter().sum();
        assert!(
            (total - expected).abs() < 1e-12 * expected,
            "{total} against {expected}"
        );
    }
    Ok(())
}

#[test]
fn stiffness_and_load_report_what_they_report_apart() -> TestResult {
    let k = hasse_complex::generate::rectangle(40, 25, [0.0, 1.0], [0.0, 1.0])?;
    let mut tensors = vec![isotropic(1.0); 1000];
    tensors[700] = isotropic(f64::MAX);
    // A source that fails at a cell before the bad stiffness: the
    // stiffness error still comes first, as when computed apart.
    let f = |x: &[f64]| {
        if x[0] < 0.1 && x[1] < 0.1 {
            f64::NAN
        } else {
            1.0
        }
    };
    let error = stiffness_and_load(&k, &tensors, &f).unwrap_err();
    assert!(
        matches!(
            error,
            MetricError::UnsupportedCell {
                method: "Q1",
                cell: 700,
                ..
            }
        ),
        "{error:?}"
    );
    // With a sound stiffness the source's first bad cell is named.
    let error = stiffness_and_load(&k, &vec![isotropic(1.0); 1000], &f).unwrap_err();
    // The same error (compared as text: the NaN it carries is unequal to
    // itself).
    assert_eq!(
        format!("{error:?}"),
        format!("{:?}", load(&k, &f).unwrap_err())
    );
    // Cell 0 is the corner square [0, 0.025] × [0, 0.04]: its first
    // quadrature point has x, y < 0.1, where f is NaN.
    assert!(
        matches!(&error, MetricError::NonFiniteSource { cell: 0, point, value }
            if value.is_nan() && point[0] < 0.025 && point[1] < 0.04),
        "{error:?}"
    );
    Ok(())
}

#[test]
fn non_cube_octagon_falls_back_to_the_virtual_element() -> TestResult {
    // Eight vertices in 2D are not a Q1 cell.
    let p: Vec<[f64; 2]> = (0..8)
        .map(|i| {
            let t = std::f64::consts::PI * i as f64 / 4.0;
            [t.cos(), t.sin()]
        })
        .collect();
    let v = Vertices::from_points(&p)?;
    let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4, 5, 6, 7]]))?;
    let top = Topology::new(&k, "test")?;
    assert!(matches!(top.element(0, Route::ByShape), Ok(Element::Vem)));
    Ok(())
}

#[test]
fn the_first_bad_cell_in_cell_order_is_reported() -> TestResult {
    // A conductivity near the largest double passes the tensor check
    // (finite, symmetric, positive) but overflows the local stiffness
    // of cells 300 and 700 of a 40 × 25 grid. Cells are computed in
    // parallel parts; the error must still name the first bad cell,
    // whatever part finishes first.
    let k = hasse_complex::generate::rectangle(40, 25, [0.0, 1.0], [0.0, 1.0])?;
    let mut tensors = vec![isotropic(1.0); 1000];
    tensors[300] = isotropic(f64::MAX);
    tensors[700] = isotropic(f64::MAX);
    for _ in 0..5 {
        let error = stiffness_metric(&k, &tensors).unwrap_err();
        assert!(
            matches!(
                error,
                MetricError::UnsupportedCell {
                    method: "Q1",
                    cell: 300,
                    ..
                }
            ),
            "{error:?}"
        );
    }
    Ok(())
}

#[test]
fn bad_input_is_a_typed_error() -> TestResult {
    let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])?;
    let k = Complex::build(v, TopCells::simplices([[0, 1, 2]]))?;
    assert!(matches!(
        stiffness_metric(&k, &[] as &[Tensor]),
        Err(MetricError::CoefficientCount { count: 0, cells: 1 })
    ));
    assert!(matches!(
        load(&k, &|x: &[f64]| 1.0 / (x[0] - x[0])),
        Err(MetricError::NonFiniteSource { cell: 0, .. })
    ));
    Ok(())
}

#[test]
fn a_cell_edge_count_is_its_edge_list_length() -> TestResult {
    use hasse_complex::generate::{box3, interval, rectangle, voronoi};
    // A polygon has as many edges as vertices; a hexahedron 12 edges.
    let polygons = voronoi(40, [0.0, 1.0], [0.0, 1.0], 11, 2)?;
    let quads = rectangle(3, 2, [0.0, 1.0], [0.0, 1.0])?;
    let hexes = box3(2, 2, 1, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0])?;
    let line = interval(3, 0.0, 1.0)?;
    let mut scratch = Vec::new();
    for (k, expected) in [
        (&polygons, None),
        (&quads, Some(4)),
        (&hexes, Some(12)),
        (&line, Some(1)),
    ] {
        let top = Topology::new(k, "test")?;
        for c in 0..k.cell_count(k.dim()) {
            let count = top.edge_count(c, &mut scratch);
            let expected = expected.unwrap_or_else(|| k.cell_vertices(2, c).len());
            assert_eq!(count, expected, "cell {c} of a {}-complex", k.dim());
            let mut edges = Vec::new();
            top.edges_into(c, &mut edges);
            assert_eq!(count, edges.len());
        }
    }
    Ok(())
}

#[test]
fn stiffness_and_load_in_one_pass_equal_the_two_passes() -> TestResult {
    use hasse_complex::generate::rectangle;
    let k = rectangle(3, 2, [0.0, 3.0], [0.0, 1.0])?;
    let tensors = vec![isotropic(1.0); 6];
    let f = |x: &[f64]| 1.0 + x[0];
    let (omega, b) = stiffness_and_load(&k, &tensors, &f)?;
    assert_eq!(omega, stiffness_metric(&k, &tensors)?);
    assert_eq!(b, load(&k, &f)?);
    Ok(())
}
