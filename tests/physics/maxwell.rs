//! Maxwell resonant cavity: curl-curl eigenvalues on 1-cochains with
//! perfectly conducting walls.
//!
//! Reference values are analytic: on [0, π]^d the cavity eigenvalues are
//! ω² = Σ mᵢ² (2D: m, n ≥ 0 not both 0; 3D: at most one index 0, two
//! polarisations when none is), and the DEC (Yee) scheme on a uniform grid
//! of spacing h has the exact discrete eigenvalues (4/h²) Σ sin²(mᵢh/2),
//! second-order accurate. The spurious-mode checks compare the Krylov
//! solver with a dense generalised eigensolve (nalgebra) of the same K, M.

use approx::{abs_diff_eq, assert_abs_diff_eq, assert_relative_eq, relative_eq};
use hasse_complex::dual::DualKind;
use hasse_complex::generate::{box3, delaunay, interval, kuhn, rectangle, uniform_axis};
use hasse_solver::la::eigen::EigenError;
use hasse_solver::physics::maxwell::{Cavity, Mass, MaxwellError};
use nalgebra::DMatrix;
use std::f64::consts::PI;

/// The `count` smallest analytic eigenvalues of the [0, π]^dim cavity
/// and their grid counterparts for n cells per side, with multiplicity.
fn analytic(dim: usize, n: usize, count: usize) -> (Vec<f64>, Vec<f64>) {
    let h = PI / n as f64;
    let s = |m: usize| 4.0 / (h * h) * (m as f64 * h / 2.0).sin().powi(2);
    let mut modes: Vec<(usize, f64, f64)> = Vec::new();
    let top = 6;
    if dim == 2 {
        for a in 0..top {
            for b in 0..top {
                if a + b > 0 {
                    modes.push((a * a + b * b, (a * a + b * b) as f64, s(a) + s(b)));
                }
            }
        }
    } else {
        for a in 0..top {
            for b in 0..top {
                for c in 0..top {
                    let zeros = [a, b, c].iter().filter(|&&m| m == 0).count();
                    let polarisations = match zeros {
                        0 => 2,
                        1 => 1,
                        _ => 0,
                    };
                    for _ in 0..polarisations {
                        let q = a * a + b * b + c * c;
                        modes.push((q, q as f64, s(a) + s(b) + s(c)));
                    }
                }
            }
        }
    }
    modes.sort_by(|x, y| x.0.cmp(&y.0).then(x.2.total_cmp(&y.2)));
    modes.truncate(count);
    (
        modes.iter().map(|m| m.1).collect(),
        modes.iter().map(|m| m.2).collect(),
    )
}

fn square(n: usize) -> Cavity {
    let k = rectangle(n, n, [0.0, PI], [0.0, PI]).unwrap();
    Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap()
}

fn cube(n: usize) -> Cavity {
    let k = box3(n, n, n, [0.0, PI], [0.0, PI], [0.0, PI]).unwrap();
    Cavity::new(&k, DualKind::Barycentric, Mass::Hodge).unwrap()
}

#[test]
fn square_cavity_converges_at_second_order() {
    // 1, 1, 2, 4, 4, 5, 5, 8: clusters of multiplicity 1 and 2.
    let count = 8;
    let levels = [8, 16, 32, 64];
    let mut errors = Vec::new();
    for &n in &levels {
        let cavity = square(n);
        let modes = cavity.modes(count, &cavity.default_options()).unwrap();
        let (exact, discrete) = analytic(2, n, count);
        assert_eq!(exact, vec![1.0, 1.0, 2.0, 4.0, 4.0, 5.0, 5.0, 8.0]);
        for (got, want) in modes.eigenvalues.iter().zip(&discrete) {
            // The solver finds the grid's own spectrum to solver accuracy.
            assert!(
                relative_eq!(got, want, epsilon = 0.0, max_relative = 1e-7),
                "n={n}: {got} vs grid {want}"
            );
        }
        println!("n={n:3} ω² = {:?}", modes.eigenvalues);
        errors.push(
            modes
                .eigenvalues
                .iter()
                .zip(&exact)
                .map(|(g, e)| (g - e).abs() / e)
                .collect::<Vec<_>>(),
        );
    }
    for (l, pair) in errors.windows(2).enumerate() {
        for (j, (coarse, fine)) in pair[0].iter().zip(&pair[1]).enumerate() {
            let order = (coarse / fine).log2();
            println!(
                "mode {j} levels {}→{}: order {order:.4}",
                levels[l],
                levels[l + 1]
            );
            assert!(
                abs_diff_eq!(order, 2.0, epsilon = 0.15),
                "mode {j}: order {order}"
            );
        }
    }
}

#[test]
fn cube_cavity_eigenvalues_and_multiplicities() {
    // 2 (×3), 3 (×2), 5 (×6): the discrete multiplicities are exact because
    // the grid has the cube's symmetry.
    let count = 11;
    let mut previous: Option<Vec<f64>> = None;
    for n in [4, 8] {
        let cavity = cube(n);
        let modes = cavity.modes(count, &cavity.default_options()).unwrap();
        let (exact, discrete) = analytic(3, n, count);
        assert_eq!(
            exact,
            vec![2.0, 2.0, 2.0, 3.0, 3.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0]
        );
        for (got, want) in modes.eigenvalues.iter().zip(&discrete) {
            assert!(
                relative_eq!(got, want, epsilon = 0.0, max_relative = 1e-7),
                "n={n}: {got} vs grid {want}"
            );
        }
        let errors: Vec<f64> = modes
            .eigenvalues
            .iter()
            .zip(&exact)
            .map(|(g, e)| (g - e).abs() / e)
            .collect();
        println!("n={n} ω² = {:?}", modes.eigenvalues);
        // Stated tolerance: the Yee error h²Σm⁴/(12Σm²) ≤ 4.5% at n = 8.
        if n == 8 {
            assert!(errors.iter().all(|&e| e < 0.045), "{errors:?}");
        }
        if let Some(coarse) = previous {
            for (c, f) in coarse.iter().zip(&errors) {
                let order = (c / f).log2();
                assert!(abs_diff_eq!(order, 2.0, epsilon = 0.15), "order {order}");
            }
        }
        previous = Some(errors);
    }
}

/// Every eigenvalue of the pencil (K, M), ascending, by a dense solve:
/// C = L⁻¹ K L⁻ᵀ with M = LLᵀ.
fn dense_spectrum(cavity: &Cavity) -> Vec<f64> {
    let dense = |a: faer::sparse::SparseColMatRef<'_, usize, f64>| {
        let mut d = DMatrix::<f64>::zeros(a.nrows(), a.ncols());
        for j in 0..a.ncols() {
            let range = a.col_range(j);
            for (&i, &v) in a.row_idx()[range.clone()].iter().zip(&a.val()[range]) {
                d[(i, j)] += v;
            }
        }
        d
    };
    let (k, m) = (dense(cavity.stiffness()), dense(cavity.mass()));
    let l = m.cholesky().expect("M is positive definite").l();
    let li = l.clone().try_inverse().unwrap();
    let c: DMatrix<f64> = &li * k * li.transpose();
    let c: DMatrix<f64> = (&c + c.transpose()) * 0.5;
    let mut values: Vec<f64> = c.symmetric_eigenvalues().iter().copied().collect();
    values.sort_by(f64::total_cmp);
    values
}

/// No spurious modes: the dense spectrum has exactly `gradient_count`
/// eigenvalues at zero, and above them exactly the Krylov modes.
fn check_no_spurious(cavity: &Cavity, count: usize) {
    let all = dense_spectrum(cavity);
    let largest = *all.last().unwrap();
    let zeros = all.iter().filter(|&&l| l.abs() < 1e-9 * largest).count();
    assert_eq!(zeros, cavity.gradient_count());
    let modes = cavity.modes(count, &cavity.default_options()).unwrap();
    let first = modes.eigenvalues[0];
    // Nothing between the null space and the first physical mode …
    assert!(all[zeros] > 1e-3 * first);
    // … and the next `count` are the Krylov ones, multiplicities included.
    for (dense, krylov) in all[zeros..zeros + count].iter().zip(&modes.eigenvalues) {
        assert_relative_eq!(dense, krylov, epsilon = 0.0, max_relative = 1e-7);
    }
    // The physical fields are M-orthogonal to every interior gradient.
    for field in &modes.fields {
        let me = hasse_solver_mass_apply(cavity, field);
        for v in 0..cavity.gradient_count() {
            let mut phi = vec![0.0; cavity.gradient_count()];
            phi[v] = 1.0;
            let g = cavity.gradient(&phi);
            let overlap: f64 = g.iter().zip(&me).map(|(a, b)| a * b).sum();
            assert_abs_diff_eq!(overlap, 0.0, epsilon = 1e-9);
        }
    }
}

fn hasse_solver_mass_apply(cavity: &Cavity, x: &[f64]) -> Vec<f64> {
    let m = cavity.mass();
    let mut y = vec![0.0; m.nrows()];
    for (j, &xj) in x.iter().enumerate() {
        let range = m.col_range(j);
        for (&i, &v) in m.row_idx()[range.clone()].iter().zip(&m.val()[range]) {
            y[i] += v * xj;
        }
    }
    y
}

#[test]
fn no_spurious_modes_square_and_cube() {
    let s = square(6);
    assert_eq!(s.gradient_count(), 25);
    check_no_spurious(&s, 8);
    let c = cube(3);
    assert_eq!(c.gradient_count(), 8);
    check_no_spurious(&c, 5);
}

#[test]
fn nedelec_on_triangles_has_no_spurious_modes() {
    // Kuhn triangles (right-angled) with the Whitney mass: lowest-order
    // Nédélec edge elements. The circumcentric ⋆₂ = 1/|f| needs no
    // well-centredness, the Whitney ⋆₁ is positive definite.
    let x = uniform_axis(6, 0.0, PI).unwrap();
    let k = kuhn(&[x.clone(), x]).unwrap();
    let cavity = Cavity::new(&k, DualKind::Circumcentric, Mass::Whitney).unwrap();
    check_no_spurious(&cavity, 6);

    // An unstructured Delaunay triangulation of the square.
    let mut points = Vec::new();
    let n = 7;
    for i in 0..=n {
        for j in 0..=n {
            // Interior points jittered deterministically; boundary kept straight.
            let jitter = |a: usize, b: usize| {
                if a == 0 || a == n || b == 0 || b == n {
                    0.0
                } else {
                    0.25 * (((a * 7 + b * 13) % 11) as f64 / 11.0 - 0.5)
                }
            };
            points.push([
                PI * (i as f64 + jitter(i, j)) / n as f64,
                PI * (j as f64 + jitter(j, i)) / n as f64,
            ]);
        }
    }
    let k = delaunay(&points).unwrap();
    let cavity = Cavity::new(&k, DualKind::Circumcentric, Mass::Whitney).unwrap();
    check_no_spurious(&cavity, 6);
}

#[test]
fn nedelec_kuhn_converges_to_the_square_eigenvalues() {
    let mut previous: Option<Vec<f64>> = None;
    for n in [8, 16, 32] {
        let x = uniform_axis(n, 0.0, PI).unwrap();
        let k = kuhn(&[x.clone(), x]).unwrap();
        let cavity = Cavity::new(&k, DualKind::Circumcentric, Mass::Whitney).unwrap();
        let modes = cavity.modes(5, &cavity.default_options()).unwrap();
        let exact = [1.0, 1.0, 2.0, 4.0, 4.0];
        let errors: Vec<f64> = modes
            .eigenvalues
            .iter()
            .zip(exact)
            .map(|(g, e)| (g - e).abs() / e)
            .collect();
        println!("Kuhn/Whitney n={n} ω² = {:?}", modes.eigenvalues);
        if let Some(coarse) = previous {
            for (c, f) in coarse.iter().zip(&errors) {
                let order = (c / f).log2();
                assert!(
                    abs_diff_eq!(order, 2.0, epsilon = 0.15),
                    "order {order}: {coarse:?} → {errors:?}"
                );
            }
        }
        previous = Some(errors);
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let cavity = square(2);
    // 4 interior edges, 1 interior vertex: 3 physical modes.
    assert_eq!((cavity.unknowns(), cavity.physical_count()), (4, 3));
    let options = cavity.default_options();
    for requested in [5, 4] {
        assert!(matches!(
            cavity.modes(requested, &options),
            Err(MaxwellError::Eigen(EigenError::TooManyModes { requested: r, available: 3 })) if r == requested
        ));
    }
    assert!(matches!(
        cavity.modes(0, &options),
        Err(MaxwellError::Eigen(EigenError::NoModes))
    ));
    // All three physical modes of the 2×2 grid: 4/h² · (1, 1, 2) with h = π/2.
    let all = cavity.modes(3, &options).unwrap();
    let s = 4.0 / (PI / 2.0).powi(2) * (PI / 4.0).sin().powi(2);
    for (got, want) in all.eigenvalues.iter().zip([s, s, 2.0 * s]) {
        assert_relative_eq!(*got, want, epsilon = 0.0, max_relative = 1e-9);
    }

    let line = interval(4, 0.0, 1.0).unwrap();
    assert!(matches!(
        Cavity::new(&line, DualKind::Barycentric, Mass::Hodge),
        Err(MaxwellError::Dimension { dim: 1 })
    ));

    // Circumcentric ⋆₁ vanishes on the diagonals of right-angled Kuhn
    // triangles: a singular mass, refused with a hint.
    let x = uniform_axis(4, 0.0, 1.0).unwrap();
    let k = kuhn(&[x.clone(), x]).unwrap();
    let err = Cavity::new(&k, DualKind::Circumcentric, Mass::Hodge)
        .err()
        .unwrap();
    assert!(
        matches!(err, MaxwellError::NonPositiveStar { p: 1, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("Whitney"));

    // A Whitney mass needs simplices.
    assert!(matches!(
        Cavity::new(
            &rectangle(3, 3, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            DualKind::Barycentric,
            Mass::Whitney
        ),
        Err(MaxwellError::Metric(_))
    ));
}

#[test]
fn a_cavity_with_a_hole_has_one_static_field() {
    // The annulus is a cavity with one hole: β₁ = 1, so one static field
    // (H¹(Ω, ∂Ω) ≅ H₁(Ω) by Lefschetz duality), curl-free (K e = 0) and
    // M-orthogonal to every gradient, before the nonzero ω². The square
    // has none.
    let annulus = hasse_complex::generate::annulus(0.5, 1.0, 8, 32).unwrap();
    let cavity = Cavity::new(&annulus, DualKind::Barycentric, Mass::Hodge).unwrap();
    assert_eq!(cavity.static_count(), 1);
    let modes = cavity.modes(2, &cavity.default_options()).unwrap();
    assert_eq!(modes.static_fields.len(), 1);
    assert_eq!(modes.eigenvalues.len(), 2);
    assert!(
        modes.eigenvalues.iter().all(|&w| w > 1.0),
        "{:?}",
        modes.eigenvalues
    );
    let e = &modes.static_fields[0];
    let multiply = |a: faer::sparse::SparseColMatRef<'_, usize, f64>, x: &[f64]| {
        let mut y = vec![0.0; a.nrows()];
        for (j, xj) in x.iter().enumerate() {
            let range = a.col_range(j);
            for (&i, v) in a.row_idx()[range.clone()].iter().zip(&a.val()[range]) {
                y[i] += v * xj;
            }
        }
        y
    };
    let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
    let k_norm = (0..cavity.stiffness().ncols())
        .map(|j| {
            cavity.stiffness().val()[cavity.stiffness().col_range(j)]
                .iter()
                .map(|v| v.abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    // Curl-free to rounding of ‖K‖‖e‖.
    assert!(norm(&multiply(cavity.stiffness(), e)) <= 1e-10 * k_norm * norm(e));
    // Removing gradients leaves it unchanged: it is M-orthogonal to them.
    let mut projected = e.clone();
    cavity.remove_gradients(&mut projected).unwrap();
    let moved: Vec<f64> = projected.iter().zip(e).map(|(a, b)| a - b).collect();
    assert!(norm(&moved) <= 1e-10 * norm(e));
    let square = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let plain = Cavity::new(&square, DualKind::Barycentric, Mass::Hodge).unwrap();
    assert_eq!(plain.static_count(), 0);
    assert!(plain
        .modes(2, &plain.default_options())
        .unwrap()
        .static_fields
        .is_empty());
}
