//! The diffusion problem through every method: manufactured solutions with
//! observed convergence orders, boundary conditions of each kind, pure
//! Neumann, anisotropy, conservation, and bad input.
//!
//! Expected orders are the theory's (second order in L² for the field on
//! uniform/admissible meshes, first order for gradients); observed orders
//! are least-squares slopes of log(error) against log(h) over four levels.

use hasse_complex::dual::DualKind;
use hasse_complex::{generate, Complex};
use hasse_solver::diffusion::{
    conservation_residual, errors, flux_error, BoundaryKind, Conductivity, Diffusion,
    DiffusionError, Method, ScalarFn, VectorFn,
};
use std::f64::consts::PI;
use std::sync::Arc;

fn scalar(f: impl Fn(&[f64]) -> f64 + Send + Sync + 'static) -> ScalarFn {
    Arc::new(f)
}

fn vector(f: impl Fn(&[f64]) -> [f64; 3] + Send + Sync + 'static) -> VectorFn {
    Arc::new(f)
}

/// Least-squares slope of log e against log h.
fn order(h: &[f64], e: &[f64]) -> f64 {
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = e.iter().map(|v| v.ln()).collect();
    let m = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / m, y.iter().sum::<f64>() / m);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// u = sin(πx) sin(πy) + xy on the unit square; −Δu = 2π² sin sin.
fn square_problem(method: Method) -> (Diffusion, ScalarFn, VectorFn) {
    let exact = scalar(|x| (PI * x[0]).sin() * (PI * x[1]).sin() + x[0] * x[1]);
    let gradient = vector(|x| {
        [
            PI * (PI * x[0]).cos() * (PI * x[1]).sin() + x[1],
            PI * (PI * x[0]).sin() * (PI * x[1]).cos() + x[0],
            0.0,
        ]
    });
    let source = scalar(|x| 2.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin());
    let problem = Diffusion::new(method, Conductivity::Scalar(scalar(|_| 1.0)), source)
        .with_boundary("boundary", BoundaryKind::Dirichlet(exact.clone()));
    (problem, exact, gradient)
}

/// u = sin(πx) sin(πy) sin(πz) + xyz on the unit cube.
fn cube_problem(method: Method) -> (Diffusion, ScalarFn, VectorFn) {
    let exact =
        scalar(|x| (PI * x[0]).sin() * (PI * x[1]).sin() * (PI * x[2]).sin() + x[0] * x[1] * x[2]);
    let gradient = vector(|x| {
        let (s, c) = (|t: f64| (PI * t).sin(), |t: f64| (PI * t).cos());
        [
            PI * c(x[0]) * s(x[1]) * s(x[2]) + x[1] * x[2],
            PI * s(x[0]) * c(x[1]) * s(x[2]) + x[0] * x[2],
            PI * s(x[0]) * s(x[1]) * c(x[2]) + x[0] * x[1],
        ]
    });
    let source =
        scalar(|x| 3.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin() * (PI * x[2]).sin());
    let problem = Diffusion::new(method, Conductivity::Scalar(scalar(|_| 1.0)), source)
        .with_boundary("boundary", BoundaryKind::Dirichlet(exact.clone()));
    (problem, exact, gradient)
}

struct Study {
    h: Vec<f64>,
    l2: Vec<f64>,
    gradient: Vec<f64>,
    flux: Vec<f64>,
}

fn study(
    meshes: impl IntoIterator<Item = Complex>,
    problem: &Diffusion,
    exact: &ScalarFn,
    gradient: &VectorFn,
) -> Study {
    let mut s = Study {
        h: vec![],
        l2: vec![],
        gradient: vec![],
        flux: vec![],
    };
    for mesh in meshes {
        let solution = problem.solve(&mesh).unwrap();
        assert!(solution.report.relative_residual < 1e-10);
        let e = errors(&mesh, &solution, exact, Some(gradient));
        s.h.push(mesh.mesh_size());
        s.l2.push(e.l2);
        s.gradient.push(e.gradient_l2);
        if let Some(q) = flux_error(&mesh, &solution, problem, gradient) {
            s.flux.push(q);
        }
    }
    s
}

fn assert_order(name: &str, s: &Study, field: f64, gradient: Option<f64>) {
    let observed = order(&s.h, &s.l2);
    assert!(
        (observed - field).abs() <= 0.15,
        "{name}: L² order {observed:.3}, expected {field} ± 0.15 (errors {:?})",
        s.l2
    );
    if let Some(expected) = gradient {
        let observed = order(&s.h, &s.gradient);
        assert!(
            observed >= expected - 0.15,
            "{name}: gradient order {observed:.3}, expected at least {expected} − 0.15 (errors {:?})",
            s.gradient
        );
    }
}

fn squares(levels: &[usize]) -> Vec<Complex> {
    levels
        .iter()
        .map(|&n| generate::rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap())
        .collect()
}

fn triangles(levels: &[usize]) -> Vec<Complex> {
    levels
        .iter()
        .map(|&n| {
            let axis = generate::uniform_axis(n, 0.0, 1.0).unwrap();
            generate::kuhn(&[axis.clone(), axis]).unwrap()
        })
        .collect()
}

const LEVELS_2D: [usize; 4] = [8, 16, 32, 64];
const LEVELS_3D: [usize; 4] = [3, 6, 12, 24];

#[test]
fn second_order_in_2d_for_every_method() {
    for (name, method, meshes) in [
        ("fd on squares", Method::Fd, squares(&LEVELS_2D)),
        ("fv on squares", Method::Fv, squares(&LEVELS_2D)),
        (
            "fv-mimetic on squares",
            Method::FvMimetic,
            squares(&LEVELS_2D),
        ),
        ("fe (Q1) on squares", Method::Fe, squares(&LEVELS_2D)),
        ("fe (P1) on triangles", Method::Fe, triangles(&LEVELS_2D)),
        (
            "dec on triangles",
            Method::Dec(DualKind::Circumcentric),
            triangles(&LEVELS_2D),
        ),
    ] {
        let (problem, exact, gradient) = square_problem(method);
        let s = study(meshes, &problem, &exact, &gradient);
        assert_order(name, &s, 2.0, Some(1.0));
        if !s.flux.is_empty() {
            let observed = order(&s.h, &s.flux);
            assert!(
                observed >= 0.85,
                "{name}: flux order {observed:.3} (errors {:?})",
                s.flux
            );
        }
    }
}

#[test]
fn second_order_in_3d_for_every_method() {
    let cubes = || {
        LEVELS_3D
            .iter()
            .map(|&n| generate::box3(n, n, n, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap())
            .collect::<Vec<_>>()
    };
    let tets = || {
        LEVELS_3D
            .iter()
            .map(|&n| {
                let axis = generate::uniform_axis(n, 0.0, 1.0).unwrap();
                generate::kuhn(&[axis.clone(), axis.clone(), axis]).unwrap()
            })
            .collect::<Vec<_>>()
    };
    for (name, method, meshes) in [
        ("fd on cubes", Method::Fd, cubes()),
        ("fv on cubes", Method::Fv, cubes()),
        ("fv-mimetic on cubes", Method::FvMimetic, cubes()),
        ("fe (Q1) on cubes", Method::Fe, cubes()),
        ("fe (P1) on tetrahedra", Method::Fe, tets()),
        (
            "dec on tetrahedra",
            Method::Dec(DualKind::Circumcentric),
            tets(),
        ),
    ] {
        let (problem, exact, gradient) = cube_problem(method);
        let s = study(meshes, &problem, &exact, &gradient);
        assert_order(name, &s, 2.0, Some(1.0));
    }
}

#[test]
fn consistent_methods_converge_on_distorted_quads() {
    // Interior vertices moved by up to 25% of the local edge length, a
    // different random field on every level.
    let meshes = || {
        LEVELS_2D
            .iter()
            .enumerate()
            .map(|(k, &n)| {
                let grid = generate::rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
                generate::perturb(&grid, 0.25, 17 + k as u64).unwrap()
            })
            .collect::<Vec<_>>()
    };
    for (name, method) in [("fv-mimetic", Method::FvMimetic), ("fe (Q1)", Method::Fe)] {
        let (problem, exact, gradient) = square_problem(method);
        let s = study(meshes(), &problem, &exact, &gradient);
        assert_order(&format!("{name} on distorted quads"), &s, 2.0, Some(1.0));
    }
}

#[test]
fn neumann_robin_and_mixed_boundaries() {
    // u = x² + 3y + xy, −Δu = −2. Dirichlet on xmin, Neumann on xmax and ymax,
    // Robin (α = 2) on ymin. Outward normals: xmax (+x), ymax (+y), ymin (−y).
    let u = scalar(|x| x[0] * x[0] + 3.0 * x[1] + x[0] * x[1]);
    let ux = |x: &[f64]| 2.0 * x[0] + x[1];
    let uy = |x: &[f64]| 3.0 + x[0];
    for (name, method, meshes) in [
        ("fv", Method::Fv, squares(&LEVELS_2D)),
        ("fv-mimetic", Method::FvMimetic, squares(&LEVELS_2D)),
        ("fe (Q1)", Method::Fe, squares(&LEVELS_2D)),
        ("fe (P1)", Method::Fe, triangles(&LEVELS_2D)),
        (
            "dec",
            Method::Dec(DualKind::Circumcentric),
            triangles(&LEVELS_2D),
        ),
    ] {
        let problem = Diffusion::new(
            method,
            Conductivity::Scalar(scalar(|_| 1.0)),
            scalar(|_| -2.0),
        )
        .with_boundary("xmin", BoundaryKind::Dirichlet(u.clone()))
        .with_boundary("xmax", BoundaryKind::Neumann(scalar(move |x| ux(x))))
        .with_boundary("ymax", BoundaryKind::Neumann(scalar(move |x| uy(x))))
        .with_boundary(
            "ymin",
            BoundaryKind::Robin {
                alpha: scalar(|_| 2.0),
                value: {
                    let u = u.clone();
                    scalar(move |x| -uy(x) + 2.0 * u(x))
                },
            },
        );
        let gradient = vector(move |x| [ux(x), uy(x), 0.0]);
        let s = study(meshes, &problem, &u, &gradient);
        // A quadratic solution: the errors are small but still second order,
        // except where a method is exact (then the error is at rounding level).
        if s.l2.iter().all(|&e| e < 1e-11) {
            continue;
        }
        assert_order(&format!("{name}, mixed boundaries"), &s, 2.0, None);
    }
}

#[test]
fn anisotropic_tensor_coefficient() {
    // K = [[2, 0.5], [0.5, 1]], u = sin(πx) sin(πy):
    // −∇·(K∇u) = π² (2 + 1) sin sin − 2·0.5 π² cos cos.
    let tensor = [[2.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let exact = scalar(|x| (PI * x[0]).sin() * (PI * x[1]).sin());
    let gradient = vector(|x| {
        [
            PI * (PI * x[0]).cos() * (PI * x[1]).sin(),
            PI * (PI * x[0]).sin() * (PI * x[1]).cos(),
            0.0,
        ]
    });
    let source = scalar(|x| {
        let (s, c) = (|t: f64| (PI * t).sin(), |t: f64| (PI * t).cos());
        3.0 * PI * PI * s(x[0]) * s(x[1]) - PI * PI * c(x[0]) * c(x[1])
    });
    for (name, method, meshes) in [
        ("fe (P1)", Method::Fe, triangles(&LEVELS_2D)),
        ("fe (Q1)", Method::Fe, squares(&LEVELS_2D)),
        ("fv-mimetic", Method::FvMimetic, squares(&LEVELS_2D)),
        (
            "dec (Whitney star)",
            Method::Dec(DualKind::Circumcentric),
            triangles(&LEVELS_2D),
        ),
    ] {
        let problem = Diffusion::new(
            method,
            Conductivity::Tensor(Arc::new(move |_| tensor)),
            source.clone(),
        )
        .with_boundary("boundary", BoundaryKind::Dirichlet(exact.clone()));
        let s = study(meshes, &problem, &exact, &gradient);
        assert_order(&format!("{name}, anisotropic"), &s, 2.0, Some(1.0));
    }
}

#[test]
fn pure_neumann_is_solved_with_zero_mean() {
    // u = cos(πx) cos(πy): ∂u/∂n = 0 on the whole boundary, ∫f = 0.
    let exact = scalar(|x| (PI * x[0]).cos() * (PI * x[1]).cos());
    let gradient = vector(|x| {
        [
            -PI * (PI * x[0]).sin() * (PI * x[1]).cos(),
            -PI * (PI * x[0]).cos() * (PI * x[1]).sin(),
            0.0,
        ]
    });
    let source = scalar(|x| 2.0 * PI * PI * (PI * x[0]).cos() * (PI * x[1]).cos());
    for (name, method, meshes) in [
        ("fv", Method::Fv, squares(&LEVELS_2D)),
        ("fe (P1)", Method::Fe, triangles(&LEVELS_2D)),
        (
            "dec",
            Method::Dec(DualKind::Circumcentric),
            triangles(&LEVELS_2D),
        ),
        ("fv-mimetic", Method::FvMimetic, squares(&LEVELS_2D)),
    ] {
        let problem = Diffusion::new(
            method,
            Conductivity::Scalar(scalar(|_| 1.0)),
            source.clone(),
        );
        let mesh = &meshes[0];
        let solution = problem.solve(mesh).unwrap();
        assert!(solution.pure_neumann, "{name}");
        let s = study(meshes, &problem, &exact, &gradient);
        assert_order(&format!("{name}, pure Neumann"), &s, 2.0, None);
    }
    // Incompatible data (f = 1, no boundary flux) is refused with the imbalance.
    let mesh = generate::rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let problem = Diffusion::new(
        Method::Fv,
        Conductivity::Scalar(scalar(|_| 1.0)),
        scalar(|_| 1.0),
    );
    assert!(matches!(
        problem.solve(&mesh),
        Err(DiffusionError::IncompatibleNeumann { .. })
    ));
}

#[test]
fn finite_volume_fluxes_are_conservative_to_rounding() {
    let mesh = generate::perturb(
        &generate::rectangle(16, 16, [0.0, 1.0], [0.0, 1.0]).unwrap(),
        0.3,
        5,
    )
    .unwrap();
    let (problem, _, _) = square_problem(Method::Fv);
    let solution = problem.solve(&mesh).unwrap();
    let residual = conservation_residual(&mesh, &solution, &problem.source);
    let scale = 2.0 * PI * PI / 256.0;
    assert!(
        residual.iter().all(|r| r.abs() < 1e-11 * scale.max(1.0)),
        "{residual:?}"
    );
}

#[test]
fn bad_input_is_named() {
    let mesh = generate::rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let problem = Diffusion::new(
        Method::Fv,
        Conductivity::Scalar(scalar(|_| 1.0)),
        scalar(|_| 0.0),
    )
    .with_boundary("left", BoundaryKind::Dirichlet(scalar(|_| 0.0)));
    let err = problem.solve(&mesh).unwrap_err();
    assert!(matches!(err, DiffusionError::UnknownTag { .. }));
    assert!(err.to_string().contains("xmin"), "{err}");
    let problem = Diffusion::new(
        Method::Fe,
        Conductivity::Scalar(scalar(|x| x[0] - 0.5)),
        scalar(|_| 0.0),
    )
    .with_boundary("boundary", BoundaryKind::Dirichlet(scalar(|_| 0.0)));
    let err = problem.solve(&mesh).unwrap_err();
    assert!(err.to_string().contains("positive"), "{err}");
    let problem = Diffusion::new(
        Method::Fv,
        Conductivity::Scalar(scalar(|_| 1.0)),
        scalar(|x| 1.0 / (x[0] - x[0])),
    )
    .with_boundary("boundary", BoundaryKind::Dirichlet(scalar(|_| 0.0)));
    assert!(matches!(
        problem.solve(&mesh),
        Err(DiffusionError::NonFinite { .. })
    ));
}
