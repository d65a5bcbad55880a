//! Transient heat by the θ-scheme, checked against figures derived by hand.
//!
//! - On a uniform grid of the unit square with u = 0 on the boundary, the
//!   sampled φ = sin(πx) sin(πy) is an exact eigenvector of the lumped
//!   problem, K φ = λ_h M φ (sine vectors diagonalise the 1D second
//!   difference and the 1D P1 mass matrix; the boundary ghost of the
//!   cell-centred schemes at h/2 is the odd reflection). With c = cos(πh):
//!   five-point stencils (FV, FD on boxes; P1 and DEC on the Kuhn
//!   triangulation, whose hypotenuses have zero cotangent weight)
//!   λ_h = 2(2 − 2c)/h²; Q1 on squares, K = K₁⊗M₁ + M₁⊗K₁ with
//!   K₁φ₁ = (2 − 2c)/h φ₁ and M₁φ₁ = h(4 + 2c)/6 φ₁, lumped mass h², so
//!   λ_h = 2(2 − 2c)(4 + 2c)/(6h²). One θ-step multiplies φ by
//!   R = (1 − (1−θ)Δt λ_h)/(1 + θΔt λ_h) (solve (1/Δt + θλ)a' = (1/Δt −
//!   (1−θ)λ)a), and the semi-discrete solution is exp(−λ_h t) φ, so the
//!   error of the θ-scheme is purely temporal.
//! - Solutions linear in space and in time are reproduced exactly by every
//!   θ (the scheme is exact for the semi-discrete solution when that is
//!   linear in t); adding t² (spatially constant, pure Neumann so K·1 = 0)
//!   leaves CN exact and gives backward Euler the error Δt Σ₁ᴺ 2t_k − T² =
//!   T Δt exactly.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use hasse_complex::generate::{kuhn, rectangle, uniform_axis};
use hasse_complex::Complex;
use hasse_solver::metric::Method;
use hasse_solver::physics::heat::{Heat, HeatBoundary, HeatError, TimeFn};
use hasse_solver::physics::Conductivity;
use hasse_solver::physics::ScalarFn;
use std::f64::consts::PI;
use std::sync::Arc;

fn unit() -> Conductivity {
    Conductivity::Scalar(Arc::new(|_| 1.0))
}

fn sine() -> ScalarFn {
    Arc::new(|x| (PI * x[0]).sin() * (PI * x[1]).sin())
}

fn zero_boundary(heat: Heat) -> Heat {
    heat.with_boundary(
        "boundary",
        HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
    )
}

struct Case {
    name: &'static str,
    method: Method,
    mesh: Complex,
    /// Discrete eigenvalue of φ.
    lambda: f64,
}

fn cases(n: usize) -> Vec<Case> {
    let h = 1.0 / n as f64;
    let c = (PI * h).cos();
    let five_point = 2.0 * (2.0 - 2.0 * c) / (h * h);
    let q1 = 2.0 * (2.0 - 2.0 * c) * (4.0 + 2.0 * c) / (6.0 * h * h);
    let square = || rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let axis = uniform_axis(n, 0.0, 1.0).unwrap();
    let triangles = || kuhn(&[axis.clone(), axis.clone()]).unwrap();
    vec![
        Case {
            name: "fv (boxes)",
            method: Method::Fv,
            mesh: square(),
            lambda: five_point,
        },
        Case {
            name: "fd (boxes)",
            method: Method::Fd,
            mesh: square(),
            lambda: five_point,
        },
        Case {
            name: "fe Q1 (boxes)",
            method: Method::Fe,
            mesh: square(),
            lambda: q1,
        },
        Case {
            name: "fe P1 (Kuhn)",
            method: Method::Fe,
            mesh: triangles(),
            lambda: five_point,
        },
        Case {
            name: "dec (Kuhn)",
            method: Method::Dec(hasse_complex::dual::DualKind::Circumcentric),
            mesh: triangles(),
            lambda: five_point,
        },
    ]
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

#[test]
fn one_step_multiplies_the_discrete_eigenvector_by_the_amplification_factor() {
    let dt = 0.01;
    let steps = 10;
    for case in cases(12) {
        for theta in [1.0, 0.5, 0.75] {
            let heat = zero_boundary(Heat::new(case.method, unit(), dt).with_theta(theta));
            let history = heat.run(&case.mesh, &*sine(), steps, 1).unwrap();
            let r = (1.0 - (1.0 - theta) * dt * case.lambda) / (1.0 + theta * dt * case.lambda);
            let phi = &history.fields[0];
            for (k, field) in history.fields.iter().enumerate() {
                let expected: Vec<f64> = phi.iter().map(|p| r.powi(k as i32) * p).collect();
                let diff: Vec<f64> = field.iter().zip(&expected).map(|(a, b)| a - b).collect();
                let error = max_abs(&diff) / max_abs(phi);
                assert!(
                    error < 1e-12,
                    "{} θ = {theta}, step {k}: relative error {error:e}",
                    case.name
                );
            }
        }
    }
}

/// Max-norm error at T against exp(−λ_h T) φ, relative to max |φ|.
fn temporal_error(case: &Case, theta: f64, t_end: f64, steps: usize) -> f64 {
    let heat =
        zero_boundary(Heat::new(case.method, unit(), t_end / steps as f64).with_theta(theta));
    let history = heat.run(&case.mesh, &*sine(), steps, 0).unwrap();
    assert_abs_diff_eq!(history.times[1], t_end, epsilon = 1e-12);
    let decay = (-case.lambda * t_end).exp();
    let phi = &history.fields[0];
    let diff: Vec<f64> = history.fields[1]
        .iter()
        .zip(phi)
        .map(|(u, p)| u - decay * p)
        .collect();
    max_abs(&diff) / max_abs(phi)
}

#[test]
fn backward_euler_is_first_and_crank_nicolson_second_order_in_time() {
    let t_end = 0.1;
    let levels: Vec<usize> = (0..5).map(|k| 20 << k).collect();
    let all = cases(16);
    // fv (cell-centred) and fe Q1 (nodal).
    for case in [&all[0], &all[2]] {
        for (theta, expected, scheme) in
            [(1.0, 1.0, "backward Euler"), (0.5, 2.0, "Crank–Nicolson")]
        {
            let errors: Vec<f64> = levels
                .iter()
                .map(|&s| temporal_error(case, theta, t_end, s))
                .collect();
            println!("{} {scheme}:", case.name);
            println!("  {:>6} {:>12} {:>7}", "steps", "error", "order");
            for (k, (&s, &e)) in levels.iter().zip(&errors).enumerate() {
                if k == 0 {
                    println!("  {s:>6} {e:>12.4e}");
                    continue;
                }
                let order = (errors[k - 1] / e).log2();
                println!("  {s:>6} {e:>12.4e} {order:>7.3}");
                assert!(
                    abs_diff_eq!(order, expected, epsilon = 0.15),
                    "{} {scheme}: order {order} between {} and {s} steps",
                    case.name,
                    levels[k - 1]
                );
            }
        }
    }
}

/// u = (1 + t)(x + y): ∂u/∂t − Δu = x + y; Dirichlet data the exact values.
fn linear_dirichlet(method: Method, theta: f64, dt: f64) -> Heat {
    Heat::new(method, unit(), dt)
        .with_theta(theta)
        .with_source(TimeFn::Steady(Arc::new(|x| x[0] + x[1])))
        .with_boundary(
            "boundary",
            HeatBoundary::Dirichlet(TimeFn::Varying(Arc::new(|x, t| (1.0 + t) * (x[0] + x[1])))),
        )
}

fn points(mesh: &Complex, nodal: bool) -> Vec<Vec<f64>> {
    let n = mesh.dim();
    if nodal {
        (0..mesh.cell_count(0))
            .map(|v| mesh.vertices().point(v).to_vec())
            .collect()
    } else {
        mesh.centroid(n).chunks(2).map(<[f64]>::to_vec).collect()
    }
}

#[test]
fn linear_in_space_and_time_is_reproduced_exactly_with_moving_boundary_values() {
    let axis = uniform_axis(6, 0.0, 1.0).unwrap();
    let meshes = [
        (
            "fv",
            Method::Fv,
            rectangle(7, 5, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            false,
        ),
        (
            "fe Q1",
            Method::Fe,
            rectangle(7, 5, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            true,
        ),
        (
            "fe P1",
            Method::Fe,
            kuhn(&[axis.clone(), axis]).unwrap(),
            true,
        ),
    ];
    for (name, method, mesh, nodal) in &meshes {
        let xs = points(mesh, *nodal);
        for theta in [1.0, 0.5] {
            let history = linear_dirichlet(*method, theta, 0.05)
                .run(mesh, &|x: &[f64]| x[0] + x[1], 8, 1)
                .unwrap();
            assert_eq!(history.times.len(), 9);
            for (t, field) in history.times.iter().zip(&history.fields) {
                for (x, u) in xs.iter().zip(field) {
                    let exact = (1.0 + t) * (x[0] + x[1]);
                    assert!(
                        abs_diff_eq!(*u, exact, epsilon = 1e-12),
                        "{name} θ = {theta} t = {t} at {x:?}: {u} vs {exact}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_quadratic_in_time_part_gives_backward_euler_exactly_t_dt_and_crank_nicolson_nothing() {
    let (dt, steps) = (0.02, 10);
    let t_end = dt * steps as f64;
    // Cell-centred: u = (1 + t)(x + y) + t², f = x + y + 2t, time-dependent
    // Neumann data K∇u·n = ±(1 + t) on each side (pure Neumann).
    let mesh = rectangle(6, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let mut fv = Heat::new(Method::Fv, unit(), dt)
        .with_source(TimeFn::Varying(Arc::new(|x, t| x[0] + x[1] + 2.0 * t)));
    for (tag, sign) in [("xmin", -1.0), ("xmax", 1.0), ("ymin", -1.0), ("ymax", 1.0)] {
        fv = fv.with_boundary(
            tag,
            HeatBoundary::Neumann(TimeFn::Varying(Arc::new(move |_, t| sign * (1.0 + t)))),
        );
    }
    let exact_fv = |x: &[f64], t: f64| (1.0 + t) * (x[0] + x[1]) + t * t;
    // Nodal: u = 1 + t², f = 2t, insulated (the lumped mass integrates the
    // constant source exactly, ∫φᵢ = mᵢ).
    let fe =
        Heat::new(Method::Fe, unit(), dt).with_source(TimeFn::Varying(Arc::new(|_, t| 2.0 * t)));
    let exact_fe = |_: &[f64], t: f64| 1.0 + t * t;
    type Exact<'a> = &'a dyn Fn(&[f64], f64) -> f64;
    let runs: [(&str, Heat, bool, Exact, ScalarFn); 2] = [
        ("fv", fv, false, &exact_fv, Arc::new(|x| x[0] + x[1])),
        ("fe", fe, true, &exact_fe, Arc::new(|_| 1.0)),
    ];
    for (name, heat, nodal, exact, initial) in runs {
        let xs = points(&mesh, nodal);
        for (theta, expected_error) in [(1.0, t_end * dt), (0.5, 0.0)] {
            let history = heat
                .clone()
                .with_theta(theta)
                .run(&mesh, &*initial, steps, 0)
                .unwrap();
            for (x, u) in xs.iter().zip(&history.fields[1]) {
                let error = u - exact(x, t_end);
                assert!(
                    abs_diff_eq!(error, expected_error, epsilon = 1e-12),
                    "{name} θ = {theta} at {x:?}: error {error:e}, expected {expected_error:e}"
                );
            }
        }
    }
}

#[test]
fn saved_levels_are_cochains_of_the_unknowns_degree() {
    let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    let heat = zero_boundary(Heat::new(Method::Fe, unit(), 0.01));
    let history = heat.run(&mesh, &*sine(), 7, 3).unwrap();
    // t₀, steps 3 and 6, and the last one (7).
    assert_eq!(history.times.len(), 4);
    assert_abs_diff_eq!(history.times[3], 0.07, epsilon = 1e-15);
    // Nodal: 0-cochains on the 25 vertices; cell-centred: 2-cochains on
    // the 16 squares.
    assert_eq!((history.degree, history.fields[2].len()), (0, 25));
    let fv = zero_boundary(Heat::new(Method::Fv, unit(), 0.01));
    let cells = fv.run(&mesh, &*sine(), 1, 1).unwrap();
    assert_eq!((cells.degree, cells.fields[1].len()), (2, 16));
    // Errors are typed.
    assert!(matches!(
        Heat::new(Method::Fe, unit(), 0.0).run(&mesh, &*sine(), 1, 1),
        Err(HeatError::TimeStep { .. })
    ));
}

/// Time-varying data are re-evaluated on the first assembly's operator
/// (`Diffusion::data`): the right-hand side and the fixed values must be
/// those of a full assembly at that time, for every boundary kind and for
/// nodal, cell-centred and hybrid unknowns.
#[test]
fn data_on_the_kept_operator_equal_a_full_assembly() {
    let mesh = rectangle(5, 4, [0.0, 1.0], [0.0, 0.8]).unwrap();
    let varying = |scale: f64| -> TimeFn {
        TimeFn::Varying(Arc::new(move |x: &[f64], t: f64| {
            scale * (1.0 + t) * (x[0] + 2.0 * x[1] * x[1]) + t.sin()
        }))
    };
    for method in [Method::Fe, Method::Fv, Method::FvMimetic, Method::Fd] {
        let heat = Heat::new(method, unit(), 0.1)
            .with_source(varying(3.0))
            .with_boundary("xmin", HeatBoundary::Dirichlet(varying(1.0)))
            .with_boundary("xmax", HeatBoundary::Neumann(varying(-0.5)))
            .with_boundary(
                "ymin",
                HeatBoundary::Robin {
                    alpha: Arc::new(|x: &[f64]| 2.0 + x[0]),
                    value: varying(0.7),
                },
            );
        let first = heat.at(0.0).assemble(&mesh).unwrap();
        for t in [0.25, 1.5] {
            let full = heat.at(t).assemble(&mesh).unwrap();
            let (rhs, fixed) = heat.at(t).data(&mesh, &first).unwrap();
            let scale = full.rhs.iter().fold(0.0f64, |m, b| m.max(b.abs()));
            assert!(scale > 0.1, "{method:?}: the data must matter");
            for (i, (a, b)) in rhs.iter().zip(&full.rhs).enumerate() {
                assert!(
                    abs_diff_eq!(a, b, epsilon = 1e-14 * scale),
                    "{method:?}, t = {t}, unknown {i}: {a} vs {b}"
                );
            }
            assert_eq!(fixed, full.fixed, "{method:?}, t = {t}");
        }
    }
}

/// Conjugate gradients preconditioned by multigrid, started from the
/// previous level, reproduce the amplification factor of the θ-scheme as
/// the factorisation does: the levels are R^k φ (see the module notes) up
/// to the CG tolerance. With ‖b − Lx‖ ≤ 10⁻¹⁰‖b‖ and L = M/Δt + θK, whose
/// condition number is below 1 + θΔtλ_max ≤ 1 + 8Δt/h² = 2.2 here (λ_max
/// of the five-point and P1 stencils is under 8/h²; Q1's is smaller), the
/// relative error of a level is at most 2.2·10⁻¹⁰ per step, 10⁻⁸ after ten.
#[test]
fn multigrid_stepping_gives_the_amplification_factor_of_each_step() {
    use hasse_solver::multigrid::{Hierarchy, SolverChoice};
    let (n, dt, steps) = (16, 1e-3, 10);
    for case in cases(n) {
        let grid = case.mesh.cell_count(2) == n * n;
        let mut choices = vec![("amg", SolverChoice::Multigrid(Hierarchy::Algebraic))];
        if grid {
            choices.push((
                "grid",
                SolverChoice::Multigrid(Hierarchy::Grid { cells: vec![n, n] }),
            ));
        }
        for (name, choice) in choices {
            for theta in [1.0, 0.5] {
                let heat = zero_boundary(Heat::new(case.method, unit(), dt).with_theta(theta))
                    .with_solver(choice.clone(), 1e-10, &case.mesh);
                let history = heat.run(&case.mesh, &*sine(), steps, 1).unwrap();
                let iterations = history
                    .iterations
                    .expect("an iterative run counts iterations");
                assert_eq!(iterations.solves, steps);
                // Warm-started from the previous level, which is within
                // O(Δt) of the answer, a handful of V-cycles suffice.
                assert!(
                    iterations.max <= 8,
                    "{} {name} θ = {theta}: {} iterations",
                    case.name,
                    iterations.max
                );
                let r = (1.0 - (1.0 - theta) * dt * case.lambda) / (1.0 + theta * dt * case.lambda);
                let phi = &history.fields[0];
                for (k, field) in history.fields.iter().enumerate() {
                    let diff: Vec<f64> = field
                        .iter()
                        .zip(phi)
                        .map(|(u, p)| u - r.powi(k as i32) * p)
                        .collect();
                    let error = max_abs(&diff) / max_abs(phi);
                    assert!(
                        error < 1e-8,
                        "{} {name} θ = {theta}, step {k}: relative error {error:e}",
                        case.name
                    );
                }
            }
        }
    }
}

/// Adaptive steps on the discrete eigenvector φ: the θ-scheme with steps
/// h_k multiplies φ by Π R(λh_k) exactly, whatever steps the control
/// chose, and its true local error per step is |R(λh) − e^{−λh}| relative
/// to the level before (φ decays). For backward Euler the estimate
/// ½|u − u_FE| is ½x²/(1+x) with x = λh, never below the true error
/// 1/(1+x) − e^{−x} (equal to leading order x²/2, smaller beyond), so no
/// accepted step exceeds the tolerance. For Crank–Nicolson the AB2
/// difference estimates the true error x³/12 to leading order, with a
/// relative correction O(x) ≤ 0.1 at the steps a tolerance of 10⁻⁵
/// allows (x³/12 ≈ 10⁻⁵ gives x ≈ 0.05), so 1.5× the tolerance bounds it.
#[test]
fn adaptive_steps_keep_the_true_local_error_within_the_tolerance() {
    use hasse_solver::physics::heat::Adaptive;
    let (dt, end) = (1e-4, 0.1);
    let steps = (end / dt) as usize;
    for case in cases(12) {
        for (theta, tolerance, bound) in [(1.0, 1e-3, 1.0), (1.0, 1e-4, 1.0), (0.5, 1e-5, 1.5)] {
            let heat = zero_boundary(Heat::new(case.method, unit(), dt).with_theta(theta))
                .with_adaptive(Adaptive { tolerance });
            let history = heat.run(&case.mesh, &*sine(), steps, 0).unwrap();
            let report = history.adaptive.expect("an adaptive run reports its steps");
            let label = format!("{} θ = {theta}, tolerance {tolerance:e}", case.name);
            assert_eq!(report.step_sizes.len(), history.steps, "{label}");
            assert!(
                history.steps < steps / 2,
                "{label}: {} steps",
                history.steps
            );
            let total: f64 = report.step_sizes.iter().sum();
            assert_abs_diff_eq!(total, end, epsilon = 1e-12);
            assert_abs_diff_eq!(*history.times.last().unwrap(), end, epsilon = 1e-12);
            let amplification =
                |h: f64| (1.0 - (1.0 - theta) * h * case.lambda) / (1.0 + theta * h * case.lambda);
            for (k, &h) in report.step_sizes.iter().enumerate() {
                let local = (amplification(h) - (-case.lambda * h).exp()).abs();
                assert!(
                    local <= bound * tolerance * (1.0 + 1e-9),
                    "{label}: step {k} of {h:e} has local error {local:e}"
                );
            }
            let product: f64 = report
                .step_sizes
                .iter()
                .map(|&h| amplification(h))
                .product();
            let phi = &history.fields[0];
            let last = history.fields.last().unwrap();
            let diff: Vec<f64> = last.iter().zip(phi).map(|(u, p)| u - product * p).collect();
            assert!(
                max_abs(&diff) / max_abs(phi) < 1e-12,
                "{label}: the levels are not Π R(λh_k) φ"
            );
        }
    }
}

/// Backward Euler's local error grows like h² and Crank–Nicolson's like
/// h³, so a tolerance 64× smaller asks for steps 8× (BE) or 4× (CN)
/// smaller. The control's steps are Δt₀·2ʲ and its estimates scale by
/// 4 (BE) or 8 (CN) per level to leading order, so 64× shifts the level
/// by exactly 3 or 2 and the step counts by 8 or 4, up to the few steps
/// the control takes to grow from Δt₀ and the last, shortened one.
#[test]
fn adaptive_step_counts_follow_the_scheme_order() {
    use hasse_solver::physics::heat::Adaptive;
    let case = cases(12).remove(0);
    let count = |theta: f64, tolerance: f64| {
        zero_boundary(Heat::new(case.method, unit(), 1e-5).with_theta(theta))
            .with_adaptive(Adaptive { tolerance })
            .run(&case.mesh, &*sine(), 20_000, 0)
            .unwrap()
            .steps as f64
    };
    let be = count(1.0, 1e-5) / count(1.0, 6.4e-4);
    let cn = count(0.5, 1e-6) / count(0.5, 6.4e-5);
    println!("step-count ratios at a 64× smaller tolerance: BE {be}, CN {cn}");
    assert!((7.0..9.0).contains(&be), "backward Euler: ratio {be}");
    assert!((3.5..4.5).contains(&cn), "Crank–Nicolson: ratio {cn}");
}

/// Conservation: summed over the free unknowns, the θ-scheme's equations
/// say that the stored heat's change, the θ-mix of the outflow and the
/// θ-mix of the sources balance exactly, whatever the mesh size, so the
/// balance of every step must close to rounding (10⁻¹¹ relative) for
/// every method, with Dirichlet, Neumann and Robin faces and data that
/// change in time.
#[test]
fn every_step_of_every_method_closes_its_heat_balance() {
    let boxes = rectangle(8, 6, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let axis_x = uniform_axis(8, 0.0, 2.0).unwrap();
    let axis_y = uniform_axis(6, 0.0, 1.0).unwrap();
    let triangles = kuhn(&[axis_x, axis_y]).unwrap();
    let circumcentric = Method::Dec(hasse_complex::dual::DualKind::Circumcentric);
    for (name, method, mesh) in [
        ("fv", Method::Fv, &boxes),
        ("fd", Method::Fd, &boxes),
        ("fe Q1", Method::Fe, &boxes),
        ("fe P1", Method::Fe, &triangles),
        ("dec", circumcentric, &triangles),
    ] {
        for theta in [1.0, 0.5] {
            let heat = Heat::new(method, unit(), 0.01)
                .with_theta(theta)
                .with_source(TimeFn::Varying(Arc::new(|x, t| 1.0 + t * x[0])))
                .with_boundary(
                    "xmin",
                    HeatBoundary::Dirichlet(TimeFn::Varying(Arc::new(|x, t| t * x[1]))),
                )
                .with_boundary(
                    "ymax",
                    HeatBoundary::Neumann(TimeFn::Varying(Arc::new(|x, t| t.sin() + x[0]))),
                )
                .with_boundary(
                    "xmax",
                    HeatBoundary::Robin {
                        alpha: Arc::new(|_| 2.0),
                        value: TimeFn::Steady(Arc::new(|_| 1.0)),
                    },
                );
            let history = heat.run(mesh, &|x| x[0] * x[1], 5, 1).unwrap();
            for k in 1..history.times.len() {
                let (t, u) = (&history.times, &history.fields);
                let balance = heat
                    .step_balance(mesh, (t[k - 1], &u[k - 1]), (t[k], &u[k]))
                    .unwrap();
                assert!(
                    balance.relative < 1e-11,
                    "{name} θ = {theta}, step {k}: {balance:?}"
                );
                assert!(
                    balance.sources > 1.0,
                    "{name}: the source heats: {balance:?}"
                );
            }
        }
    }
}
