//! The de Rham map R_k and the Whitney map W_k.
//!
//! Independent facts checked:
//! - Stokes' theorem: d R_{k} = R_{k+1} d on polynomial fields (d of a
//!   function is its gradient, of a vector field's circulation its curl
//!   flux, of a flux its divergence), exact once the quadrature integrates
//!   the polynomials exactly (degree ≤ 4 here, the rules reach 5).
//! - The lowest-order Whitney forms on a simplex span P₁⁻Λᵏ, which holds
//!   the constant k-forms and, for k = 1 in 2D, the rotation a + b(−y, x);
//!   R_k W_k = I, so W_k R_k reproduces those fields at every point.
//! - On a flat triangle of a surface, R₁ of a constant ambient field sees
//!   only its tangential part, so W₁ R₁ F = F − (F·n)n.
//! - The interpolation error of a smooth field is O(h) for Whitney 1-forms
//!   (Hiptmair, Acta Numerica 2002, Thm 3.14), so ∇θ/2π on the annulus
//!   converges at first order in L².
//! - Σ_T R_n(ρ)_T = ∫ ρ (measure of the box for ρ = 1).

use approx::assert_abs_diff_eq;
use hasse_complex::generate::{kuhn, perturb, sphere, uniform_axis};
use hasse_complex::{Complex, TopCells, Vertices};
use hasse_solver::physics::forms::whitney_map::{cell_vectors, de_rham, interpolate, Field, Proxy};
use std::error::Error;
use std::f64::consts::PI;

type Result<T = ()> = std::result::Result<T, Box<dyn Error>>;

/// (d R_k)(c) on every (k+1)-cell: δᵏ applied to the cochain.
fn d(complex: &Complex, k: usize, c: &[f64]) -> Vec<f64> {
    complex
        .coboundary(k)
        .outer_iterator()
        .map(|row| row.iter().map(|(j, &s)| f64::from(s) * c[j]).sum())
        .collect()
}

fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn vector(p: Proxy) -> [f64; 3] {
    match p {
        Proxy::Vector(v) => v,
        Proxy::Scalar(s) => panic!("expected a vector proxy, got the number {s}"),
    }
}

/// A few points inside top cell `c`, by barycentric weights.
fn points_in(complex: &Complex, c: usize) -> Vec<[f64; 3]> {
    let p = complex.cell_points(complex.dim(), c);
    let weights: &[&[f64]] = match p.len() {
        3 => &[&[0.2, 0.3, 0.5], &[0.7, 0.1, 0.2], &[1.0 / 3.0; 3]],
        _ => &[&[0.1, 0.2, 0.3, 0.4], &[0.4, 0.3, 0.2, 0.1], &[0.25; 4]],
    };
    weights
        .iter()
        .map(|w| {
            let mut x = [0.0; 3];
            for (point, weight) in p.iter().zip(w.iter()) {
                for a in 0..3 {
                    x[a] += weight * point[a];
                }
            }
            x
        })
        .collect()
}

/// Stokes in 3D on a perturbed Kuhn box: d R₀ φ = R₁ ∇φ, d R₁ F = R₂ curl F,
/// d R₂ G = R₃ div G, all to rounding (values O(1), measured ≤ 1e-15).
#[test]
fn de_rham_commutes_with_d_in_3d() -> Result {
    let x = uniform_axis(3, 0.0, 1.0)?;
    let k = perturb(&kuhn(&[x.clone(), x.clone(), x])?, 0.2, 3)?;
    let phi = |p: &[f64]| p[0] * p[0] * p[1] + p[2].powi(3) - p[0] * p[1] * p[2];
    let grad = |p: &[f64]| {
        let (x, y, z) = (p[0], p[1], p[2]);
        [2.0 * x * y - y * z, x * x - x * z, 3.0 * z * z - x * y]
    };
    let f = |p: &[f64]| [p[1] * p[2], p[0] * p[0], p[0] * p[1] * p[2]];
    let curl_f = |p: &[f64]| {
        let (x, y, z) = (p[0], p[1], p[2]);
        [x * z, y - y * z, 2.0 * x - z]
    };
    let g = |p: &[f64]| [p[0] * p[1], p[1] * p[2] * p[2], p[0].powi(3) * p[2]];
    let div_g = |p: &[f64]| p[1] + p[2] * p[2] + p[0].powi(3);
    let r0 = de_rham(&k, 0, Field::Scalar(&phi))?;
    let r1_grad = de_rham(&k, 1, Field::Vector(&grad))?;
    assert!(max_difference(&d(&k, 0, &r0), &r1_grad) < 1e-14);
    let r1 = de_rham(&k, 1, Field::Vector(&f))?;
    let r2_curl = de_rham(&k, 2, Field::Vector(&curl_f))?;
    assert!(max_difference(&d(&k, 1, &r1), &r2_curl) < 1e-14);
    let r2 = de_rham(&k, 2, Field::Vector(&g))?;
    let r3_div = de_rham(&k, 3, Field::Scalar(&div_g))?;
    assert!(max_difference(&d(&k, 2, &r2), &r3_div) < 1e-14);
    // Exactness d R₁ ∇φ = 0: integer sums of exact line integrals.
    assert!(d(&k, 1, &r1_grad).iter().all(|v| v.abs() < 1e-14));
    Ok(())
}

/// Whitney forms reproduce what they span: constants for k = 0, 1, 2, 3 in
/// 3D and the rotation (−y, x) in 2D, at points inside every cell.
#[test]
fn whitney_reproduces_constant_fields_and_rotations() -> Result {
    let x = uniform_axis(3, 0.0, 1.0)?;
    let box3 = perturb(&kuhn(&[x.clone(), x.clone(), x.clone()])?, 0.2, 5)?;
    let constant = |_: &[f64]| [0.3, -1.2, 2.0];
    for k in [1, 2] {
        let c = de_rham(&box3, k, Field::Vector(&constant))?;
        for t in 0..box3.cell_count(3) {
            for p in points_in(&box3, t) {
                let v = vector(interpolate(&box3, k, &c, t, &p)?);
                for (got, want) in v.iter().zip(constant(&p)) {
                    assert_abs_diff_eq!(*got, want, epsilon = 1e-13);
                }
            }
        }
        for v in cell_vectors(&box3, k, &c)? {
            assert_abs_diff_eq!(v[2], 2.0, epsilon = 1e-13);
        }
    }
    // P1 for k = 0: a linear function; c_T/|T| for the density.
    let linear = |p: &[f64]| 1.0 + 2.0 * p[0] - p[1] + 0.5 * p[2];
    let c0 = de_rham(&box3, 0, Field::Scalar(&linear))?;
    let c3 = de_rham(&box3, 3, Field::Scalar(&|_| 4.0))?;
    for t in 0..box3.cell_count(3) {
        for p in points_in(&box3, t) {
            let Proxy::Scalar(u) = interpolate(&box3, 0, &c0, t, &p)? else {
                panic!("a function")
            };
            assert_abs_diff_eq!(u, linear(&p), epsilon = 1e-13);
            let Proxy::Scalar(rho) = interpolate(&box3, 3, &c3, t, &p)? else {
                panic!("a density")
            };
            assert_abs_diff_eq!(rho, 4.0, epsilon = 1e-13);
        }
    }
    let y = uniform_axis(4, -1.0, 1.0)?;
    let plane = perturb(&kuhn(&[y.clone(), y])?, 0.25, 9)?;
    let rotation = |p: &[f64]| [1.0 - p[1], 0.5 + p[0], 0.0];
    let c = de_rham(&plane, 1, Field::Vector(&rotation))?;
    for t in 0..plane.cell_count(2) {
        for p in points_in(&plane, t) {
            let v = vector(interpolate(&plane, 1, &c, t, &p)?);
            assert_abs_diff_eq!(v[0], rotation(&p)[0], epsilon = 1e-13);
            assert_abs_diff_eq!(v[1], rotation(&p)[1], epsilon = 1e-13);
        }
    }
    Ok(())
}

/// On the icosphere a constant ambient field comes back as its projection
/// on each (flat) triangle's plane.
#[test]
fn whitney_on_a_surface_is_the_tangential_part() -> Result {
    let k = sphere(1.0, 2)?;
    let f = [0.4, -0.3, 1.1];
    let c = de_rham(&k, 1, Field::Vector(&|_| f))?;
    let vectors = cell_vectors(&k, 1, &c)?;
    for (t, v) in vectors.iter().enumerate() {
        let p = k.cell_points(2, t);
        let (a, b) = (
            [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]],
            [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]],
        );
        let mut n = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let norm = n.iter().map(|x| x * x).sum::<f64>().sqrt();
        n.iter_mut().for_each(|x| *x /= norm);
        let normal = f.iter().zip(&n).map(|(x, y)| x * y).sum::<f64>();
        for i in 0..3 {
            assert_abs_diff_eq!(v[i], f[i] - normal * n[i], epsilon = 1e-13);
        }
    }
    Ok(())
}

/// A triangulated annulus 1 ≤ r ≤ 2: the polar grid's quads cut along a
/// diagonal.
fn triangulated_annulus(n_radial: usize, n_angular: usize) -> Result<Complex> {
    let mut points = Vec::new();
    for i in 0..=n_radial {
        let r = 1.0 + i as f64 / n_radial as f64;
        for j in 0..n_angular {
            let angle = 2.0 * PI * j as f64 / n_angular as f64;
            points.push([r * angle.cos(), r * angle.sin()]);
        }
    }
    let index = |i: usize, j: usize| (j % n_angular) + n_angular * i;
    let mut triangles = Vec::new();
    for i in 0..n_radial {
        for j in 0..n_angular {
            let (a, b, c, d) = (
                index(i, j),
                index(i, j + 1),
                index(i + 1, j),
                index(i + 1, j + 1),
            );
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    Ok(Complex::build(
        Vertices::from_points(&points)?,
        TopCells::simplices(triangles),
    )?)
}

/// ‖W₁ R₁ F − F‖_L² for F = ∇θ/2π = (−y, x)/(2π r²), by the edge-midpoint
/// rule on each triangle (exact for quadratics: the error's rate is the
/// interpolation's, not the rule's).
fn annulus_error(n_radial: usize, n_angular: usize) -> Result<f64> {
    let k = triangulated_annulus(n_radial, n_angular)?;
    let field = |p: &[f64]| {
        let r2 = p[0] * p[0] + p[1] * p[1];
        [-p[1] / (2.0 * PI * r2), p[0] / (2.0 * PI * r2), 0.0]
    };
    let c = de_rham(&k, 1, Field::Vector(&field))?;
    // ∇θ/2π has period 1 around the hole: the de Rham cochain sums to 1
    // around the inner ring (the quadrature is not exact here, only close).
    let ring: f64 = (0..n_angular)
        .map(|j| {
            let e = k
                .find_cell(1, &[j, (j + 1) % n_angular])
                .expect("a ring edge");
            let sign = if j + 1 < n_angular { 1.0 } else { -1.0 };
            sign * c[e]
        })
        .sum();
    assert_abs_diff_eq!(ring, 1.0, epsilon = 1e-8);
    let mut squared = 0.0;
    for t in 0..k.cell_count(2) {
        let p = k.cell_points(2, t);
        let area = k.measure(2)[t];
        for (i, j) in [(0, 1), (1, 2), (0, 2)] {
            let x = [(p[i][0] + p[j][0]) / 2.0, (p[i][1] + p[j][1]) / 2.0];
            let v = vector(interpolate(&k, 1, &c, t, &x)?);
            let exact = field(&x);
            squared += area / 3.0 * ((v[0] - exact[0]).powi(2) + (v[1] - exact[1]).powi(2));
        }
    }
    Ok(squared.sqrt())
}

/// First order: the observed rates between 4×32, 8×64 and 16×128 meshes
/// (measured 1.00 and 1.00) within ±0.15 of 1.
#[test]
fn whitney_interpolation_of_the_angle_form_converges_at_first_order() -> Result {
    let errors = [
        annulus_error(4, 32)?,
        annulus_error(8, 64)?,
        annulus_error(16, 128)?,
    ];
    eprintln!("‖W₁R₁F − F‖ on 4×32, 8×64, 16×128: {errors:?}");
    for pair in errors.windows(2) {
        let rate = (pair[0] / pair[1]).log2();
        eprintln!("rate {rate:.3}");
        assert!(
            (rate - 1.0).abs() < 0.15,
            "rate {rate} from errors {errors:?}"
        );
    }
    Ok(())
}

/// Σ R_n(ρ) = ∫ ρ over boxes, integrals done by hand below: ρ = 1 gives
/// the measure, polynomials their exact integrals (the rules reach degree
/// 6 on triangles, 5 on tetrahedra).
#[test]
fn de_rham_of_a_density_sums_to_its_integral() -> Result {
    let plane = perturb(
        &kuhn(&[uniform_axis(4, 0.0, 2.0)?, uniform_axis(3, 0.0, 3.0)?])?,
        0.2,
        1,
    )?;
    let ones: f64 = de_rham(&plane, 2, Field::Scalar(&|_| 1.0))?.iter().sum();
    assert_abs_diff_eq!(ones, 6.0, epsilon = 1e-13);
    // ∫∫ x dx dy over [0, 2] × [0, 3] = 2 · 3 = 6; ∫∫ x² y = (8/3)(9/2) = 12.
    let moment: f64 = de_rham(&plane, 2, Field::Scalar(&|p| p[0]))?.iter().sum();
    assert_abs_diff_eq!(moment, 6.0, epsilon = 1e-13);
    let quadratic: f64 = de_rham(&plane, 2, Field::Scalar(&|p| p[0] * p[0] * p[1]))?
        .iter()
        .sum();
    assert_abs_diff_eq!(quadratic, 12.0, epsilon = 1e-12);
    let solid = kuhn(&[
        uniform_axis(2, 0.0, 1.0)?,
        uniform_axis(2, 0.0, 2.0)?,
        uniform_axis(3, 0.0, 3.0)?,
    ])?;
    let volume: f64 = de_rham(&solid, 3, Field::Scalar(&|_| 1.0))?.iter().sum();
    assert_abs_diff_eq!(volume, 6.0, epsilon = 1e-13);
    // ∫ z⁴ over [0, 1] × [0, 2] × [0, 3] = 2 · 3⁵/5 = 97.2 (degree 4).
    let quartic: f64 = de_rham(&solid, 3, Field::Scalar(&|p| p[2].powi(4)))?
        .iter()
        .sum();
    assert_abs_diff_eq!(quartic, 97.2, epsilon = 1e-11);
    // A vector field for a density is refused.
    assert!(de_rham(&solid, 3, Field::Vector(&|_| [1.0; 3])).is_err());
    Ok(())
}
