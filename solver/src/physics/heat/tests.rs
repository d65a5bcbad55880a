//! Unit tests of the θ-scheme's refusals and invariants.

use super::*;
use hasse_complex::generate::rectangle;

fn heat(dt: f64, theta: f64) -> Heat {
    Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), dt).with_theta(theta)
}

#[test]
fn bad_steps_and_thetas_are_refused() {
    let mesh = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).expect("test setup");
    let one: ScalarFn = Arc::new(|_| 1.0);
    for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            heat(dt, 1.0).run(&mesh, &*one, 1, 1),
            Err(HeatError::TimeStep { .. })
        ));
    }
    for theta in [-0.1, 1.5, f64::NAN] {
        assert!(matches!(
            heat(0.1, theta).run(&mesh, &*one, 1, 1),
            Err(HeatError::Theta { .. })
        ));
    }
    let nan: ScalarFn = Arc::new(|_| f64::NAN);
    assert!(matches!(
        heat(0.1, 1.0).run(&mesh, &*nan, 1, 1),
        Err(HeatError::NonFinite {
            datum: Datum::Initial,
            ..
        })
    ));
    let bad_source = heat(0.1, 1.0).with_source(TimeFn::Varying(Arc::new(|_, t| {
        if t > 0.15 {
            f64::NAN
        } else {
            0.0
        }
    })));
    assert!(matches!(
        bad_source.run(&mesh, &*one, 3, 1),
        Err(HeatError::Diffusion(DiffusionError::NonFinite {
            datum: Datum::Source,
            ..
        }))
    ));
    let hybrid = Heat::new(Method::FvMimetic, Conductivity::Scalar(one.clone()), 0.1);
    assert!(matches!(
        hybrid.run(&mesh, &*one, 1, 1),
        Err(HeatError::Unsupported { .. })
    ));
}

#[test]
fn an_unstable_scheme_reports_the_overflow_and_the_levels_before_it() {
    // Forward Euler with Δt far above h²/4: each step multiplies the
    // highest mode by about 1 − Δt λ_max ≈ −100, so it overflows.
    let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).expect("test setup");
    let h = heat(0.05, 0.0).with_boundary(
        "boundary",
        HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
    );
    let initial = |x: &[f64]| x[0] * (1.0 - x[0]) * x[1] * (1.0 - x[1]);
    let mut levels = Vec::new();
    let result = h.run_observed(&mesh, &initial, 1000, 10, &mut |event| {
        if let HeatEvent::Level { time, field, .. } = event {
            assert!(field.iter().all(|v| v.is_finite()));
            levels.push(time);
        }
    });
    let Err(HeatError::Overflow { time, .. }) = result else {
        panic!("expected a non-finite temperature, got {result:?}");
    };
    assert!(levels.len() >= 2 && time > *levels.last().expect("test setup"));
    assert!(time < 1000.0 * 0.05);
}

#[test]
fn insulated_domain_keeps_its_heat() {
    // No flux, no source: Σ mᵢ uᵢ is conserved exactly by every θ, since
    // 1ᵀK = 0 (K·1 = 0 and K symmetric).
    let mesh = rectangle(5, 4, [0.0, 1.0], [0.0, 2.0]).expect("test setup");
    let initial: ScalarFn = Arc::new(|x| x[0] * x[0] + x[1]);
    for theta in [0.0, 0.5, 1.0] {
        let h = heat(0.001, theta);
        let mass = h.mass(&mesh).expect("test setup");
        let history = h.run(&mesh, &*initial, 20, 0).expect("test setup");
        let total = |u: &[f64]| u.iter().zip(&mass).map(|(a, m)| a * m).sum::<f64>();
        let (start, end) = (total(&history.fields[0]), total(&history.fields[1]));
        assert!(
            (start - end).abs() < 1e-13 * start.abs(),
            "θ = {theta}: {start} → {end}"
        );
    }
}

/// The projection start on a discrete eigenvector: nodal P1 on [0, 1] with
/// u = 0 at both ends has the lumped mass h and the stiffness
/// tridiag(−1, 2, −1)/h on the interior vertices, and sin(kπx) sampled at
/// them is an eigenvector of the stiffness with eigenvalue μ/h,
/// μ = 2 − 2cos(kπh). Backward Euler then multiplies it by
/// ρ = 1/(1 + Δt μ/h²) each step, so every level lies in the span of u⁰:
/// projected onto it, every step starts from its answer and conjugate
/// gradients take no iteration, where the extrapolated start needs at
/// least one on the first step (it starts from u⁰ itself).
#[test]
fn projected_start_solves_an_eigenvector_without_iterations() {
    use crate::multigrid::{Hierarchy, SolverChoice};
    use hasse_complex::generate::interval;
    let (cells, k, dt, steps, tolerance) = (32usize, 3.0, 1e-3, 10usize, 1e-10);
    let mesh = interval(cells, 0.0, 1.0).expect("test setup");
    let pi = std::f64::consts::PI;
    let run = |projection: usize| {
        let mut heat = Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), dt)
            .with_boundary(
                "boundary",
                HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
            )
            .with_solver(
                SolverChoice::Multigrid(Hierarchy::Grid { cells: vec![cells] }),
                tolerance,
                &mesh,
            );
        heat.projection = projection;
        heat.run(&mesh, &|x| (k * pi * x[0]).sin(), steps, 0)
            .expect("heat run")
    };
    let projected = run(Heat::PROJECTION);
    let extrapolated = run(0);
    assert_eq!(projected.iterations.expect("iterative").total, 0);
    assert!(extrapolated.iterations.expect("iterative").total >= 1);
    let h = 1.0 / cells as f64;
    let mu = 2.0 - 2.0 * (k * pi * h).cos();
    let rho = 1.0 / (1.0 + dt * mu / (h * h));
    // Each solve errs by at most κ·tol·‖x‖₂ (relative residual tol), with
    // κ ≤ 1 + 4Δt/h² by Gershgorin on h/Δt + tridiag(−1, 2, −1)/h, and
    // the step operator L⁻¹M/Δt (M = hI) does not amplify earlier errors:
    // after n steps at most n·κ·tol·‖u⁰‖₂, ‖u⁰‖₂ ≤ √(cells − 1).
    let kappa = 1.0 + 4.0 * dt / (h * h);
    let bound = steps as f64 * kappa * tolerance * ((cells - 1) as f64).sqrt();
    let vertices = mesh.vertices().as_slice().to_vec();
    for history in [&projected, &extrapolated] {
        let last = history.fields.last().expect("levels");
        for (x, u) in vertices.iter().zip(last) {
            let exact = rho.powi(steps as i32) * (k * pi * x).sin();
            assert!((u - exact).abs() <= bound, "x = {x}: {u} vs {exact}");
        }
    }
}

/// Warm-started multigrid levels against the direct path's on data that
/// do not stay in any span (a source and boundary values varying in
/// time): FV on the unit square, M = h²I, L = M/Δt + K with
/// K's rows summing in absolute value to at most 8 (interior 4 + 4·1,
/// boundary 3 + 2 + 3, corner 2 + 4 + 2: a Dirichlet face's
/// transmissibility is 2), so κ(L) ≤ 1 + 8Δt/h² (Gershgorin). Each solve
/// errs by at most κ·tol·‖uⁿ⁺¹‖₂, L⁻¹M/Δt does not amplify (M is a
/// multiple of I), and after n steps the levels differ by at most
/// n·κ·tol·max‖u‖₂ (plus the direct path's rounding).
#[test]
fn projected_and_extrapolated_starts_give_the_direct_levels() {
    use crate::multigrid::{Hierarchy, SolverChoice};
    let (cells, dt, steps, tolerance) = (32usize, 1e-3, 20usize, 1e-8);
    let mesh = rectangle(cells, cells, [0.0, 1.0], [0.0, 1.0]).expect("test setup");
    let problem = || {
        Heat::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), dt)
            .with_source(TimeFn::Varying(Arc::new(|x, t| {
                (3.0 * x[0] + 40.0 * t).sin() * (2.0 * x[1]).cos()
            })))
            .with_boundary(
                "boundary",
                HeatBoundary::Dirichlet(TimeFn::Varying(Arc::new(|x, t| x[0] * (25.0 * t).cos()))),
            )
    };
    let initial = |x: &[f64]| x[0] * (1.0 - x[1]);
    let direct = problem().run(&mesh, &initial, steps, 1).expect("direct");
    let h = 1.0 / cells as f64;
    let kappa = 1.0 + 8.0 * dt / (h * h);
    let largest = direct
        .fields
        .iter()
        .map(|u| u.iter().map(|v| v * v).sum::<f64>().sqrt())
        .fold(0.0f64, f64::max);
    let bound = steps as f64 * kappa * tolerance * largest;
    for projection in [Heat::PROJECTION, 2, 0] {
        let mut heat = problem().with_solver(
            SolverChoice::Multigrid(Hierarchy::Grid {
                cells: vec![cells, cells],
            }),
            tolerance,
            &mesh,
        );
        heat.projection = projection;
        let multigrid = heat.run(&mesh, &initial, steps, 1).expect("multigrid");
        assert_eq!(multigrid.fields.len(), direct.fields.len());
        for (a, b) in direct.fields.iter().zip(&multigrid.fields) {
            let difference = a
                .iter()
                .zip(b)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            assert!(
                difference <= bound,
                "projection {projection}: {difference:e} > {bound:e}"
            );
        }
    }
}

/// The projection is exact on its span: with x₁, x₂ added (and their
/// right-hand sides b = L x formed here by hand), the start for
/// b = L(2x₁ − 3x₂) is 2x₁ − 3x₂, and a level already in the span adds no
/// vector.
#[test]
fn projection_is_exact_on_its_span() {
    use super::projection::Projection;
    // L = tridiag(−1, 4, −1) on 5 unknowns.
    let n = 5;
    let multiply = |x: &[f64], y: &mut [f64]| {
        for i in 0..n {
            let left = if i > 0 { x[i - 1] } else { 0.0 };
            let right = if i + 1 < n { x[i + 1] } else { 0.0 };
            y[i] = 4.0 * x[i] - left - right;
        }
    };
    let apply = |x: &[f64]| {
        let mut y = vec![0.0; n];
        multiply(x, &mut y);
        y
    };
    let x1 = [1.0, 2.0, 0.5, -1.0, 3.0];
    let x2 = [0.0, 1.0, -2.0, 1.0, 0.25];
    let zero = [0.0; 5];
    let mut projection = Projection::new(4);
    assert!(!projection.for_step(0.1));
    projection.add(&x1, &[], &[], &multiply);
    let (b2, mut start) = (apply(&x2), vec![0.0; n]);
    assert!(projection.guess(&b2, &mut start));
    projection.add(&x2, &b2, &zero, &multiply);
    assert_eq!(projection.len(), 2);
    let target: Vec<f64> = x1.iter().zip(&x2).map(|(a, b)| 2.0 * a - 3.0 * b).collect();
    let b = apply(&target);
    assert!(projection.guess(&b, &mut start));
    for (s, t) in start.iter().zip(&target) {
        // Values of size ≤ 10, two Gram–Schmidt passes: rounding only.
        assert!((s - t).abs() < 1e-13, "{s} vs {t}");
    }
    projection.add(&target, &b, &zero, &multiply);
    assert_eq!(projection.len(), 2);
    // A new step size has a new L: the basis starts again.
    assert!(!projection.for_step(0.2));
    assert_eq!(projection.len(), 0);
}
