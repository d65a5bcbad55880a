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
