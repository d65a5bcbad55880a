//! Advection–diffusion −∇·(K∇u) + ∇·(v u) = f on cell-centred finite
//! volumes: the steady boundary layer against its exact exponential
//! profile, conservation in a closed box, orders of the upwind and limited
//! schemes on a smooth translated profile, the limiter's maximum
//! principle, and the Krylov solvers against LU.

use hasse_complex::generate::{interval, rectangle};
use hasse_complex::Complex;
use hasse_solver::la::krylov::KrylovOptions;
use hasse_solver::physics::transport::{
    FaceFlux, KrylovMethod, KrylovPreconditioner, LinearSolver, Scheme, TimeStepping, Transport,
};
use hasse_solver::physics::{BoundaryKind, Conductivity};
use std::f64::consts::PI;
use std::sync::Arc;

use crate::orders::order;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

/// u = (1 − e^{Pe x}) / (1 − e^{Pe}) solves −u'' + Pe u' = 0 with u(0) = 0,
/// u(1) = 1; written with e^{Pe (x − 1)} so that Pe = 1000 does not
/// overflow.
fn layer(pe: f64, x: f64) -> f64 {
    ((pe * (x - 1.0)).exp() - (-pe).exp()) / (1.0 - (-pe).exp())
}

/// The boundary-layer problem on a one-cell-thick strip [0, 1] × [0, 1/n]
/// (K = 1, v = (Pe, 0), u = 0 at x = 0 and 1 at x = 1, the long sides
/// insulated): its solution is the 1D profile [`layer`].
fn boundary_layer(pe: f64) -> Transport {
    Transport::new(
        Some(Conductivity::Scalar(Arc::new(|_| 1.0))),
        FaceFlux::Velocity(Arc::new(move |_| [pe, 0.0, 0.0])),
        Arc::new(|_| 0.0),
    )
    .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    .with_boundary("xmax", BoundaryKind::Dirichlet(Arc::new(|_| 1.0)))
}

fn strip(n: usize) -> Result<Complex> {
    Ok(rectangle(n, 1, [0.0, 1.0], [0.0, 1.0 / n as f64])?)
}

/// max |u_c − u(x_c)| over the cells.
fn max_error(mesh: &Complex, values: &[f64], exact: impl Fn(&[f64]) -> f64) -> f64 {
    let d = mesh.embedding_dim();
    let n = mesh.dim();
    values
        .iter()
        .zip(mesh.centroid(n).chunks(d))
        .map(|(u, x)| (u - exact(x)).abs())
        .fold(0.0, f64::max)
}

/// Σ |u_c − u(x_c)| |c|: the L¹ error of the cell values.
fn l1_error(mesh: &Complex, values: &[f64], exact: impl Fn(&[f64]) -> f64) -> f64 {
    let d = mesh.embedding_dim();
    let n = mesh.dim();
    values
        .iter()
        .zip(mesh.centroid(n).chunks(d))
        .zip(mesh.measure(n))
        .map(|((u, x), v)| (u - exact(x)).abs() * v)
        .sum()
}

#[test]
fn boundary_layer_converges_at_first_order_for_pe_10_and_100() -> Result {
    // Upwinding adds the numerical diffusion Pe h / 2: the error is O(h)
    // once the cells resolve the layer (cell Péclet ≤ 1 here).
    for (pe, sizes) in [(10.0, [80, 160, 320]), (100.0, [400, 800, 1600])] {
        let mut h = Vec::new();
        let mut e = Vec::new();
        for n in sizes {
            let mesh = strip(n)?;
            let u = boundary_layer(pe).solve(&mesh)?;
            h.push(1.0 / n as f64);
            e.push(max_error(&mesh, &u.values, |x| layer(pe, x[0])));
            assert!((u.peclet.max - pe / n as f64).abs() < 1e-9 * pe);
        }
        let p = order(&h, &e);
        eprintln!("Pe = {pe}: max errors {e:?}, order {p:.3}");
        assert!(
            (p - 1.0).abs() < 0.15,
            "Pe = {pe}: order {p:.3}, errors {e:?}"
        );
    }
    Ok(())
}

#[test]
fn boundary_layer_at_pe_1000_does_not_oscillate() -> Result {
    // 50 cells: cell Péclet 20. Central differences would oscillate with
    // an O(1) amplitude; the upwind operator is an M-matrix, so u stays
    // within its boundary values 0 and 1 and increases monotonically
    // towards the layer, up to the LU solve's rounding (eps ‖u‖ ≈ 1e-16;
    // values of −6e-18 appear where the exact discrete value is 1e-30).
    let mesh = strip(50)?;
    let u = boundary_layer(1000.0).solve(&mesh)?.values;
    let rounding = 1e-15;
    assert!(
        u.iter().all(|v| (-rounding..=1.0 + rounding).contains(v)),
        "{u:?}"
    );
    assert!(u.windows(2).all(|w| w[0] <= w[1] + rounding), "{u:?}");
    // Far from the layer the exact profile is e^{−1000·0.2} ≈ 0, and the
    // upwind values decay like (1 + Pe_h)^{−k} away from x = 1.
    assert!(u[..40].iter().all(|&v| v < 1e-10));
    Ok(())
}

#[test]
fn krylov_solvers_equal_lu_to_their_tolerance() -> Result {
    let mesh = strip(400)?;
    let lu = boundary_layer(100.0).solve(&mesh)?;
    for method in [KrylovMethod::Gmres, KrylovMethod::Bicgstab] {
        let options = KrylovOptions {
            tolerance: 1e-12,
            max_iterations: 500,
            restart: 30,
        };
        let solver = LinearSolver::Krylov {
            method,
            options,
            preconditioner: KrylovPreconditioner::Ilu0,
        };
        let krylov = boundary_layer(100.0).with_solver(solver).solve(&mesh)?;
        let report = krylov.iterations.ok_or("a Krylov report")?;
        // ILU(0) of a tridiagonal matrix (one cell across) is its exact LU:
        // one or two iterations.
        assert!(report.iterations <= 3, "{method:?}: {}", report.iterations);
        assert!(report.relative_residual <= 1e-12);
        let difference = krylov
            .values
            .iter()
            .zip(&lu.values)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(difference < 1e-10, "{method:?}: {difference:e}");
    }
    // On a 2D grid ILU(0) drops fill: more iterations, same answer.
    let mesh = rectangle(24, 24, [0.0, 1.0], [0.0, 1.0])?;
    let problem = || {
        Transport::new(
            Some(Conductivity::Scalar(Arc::new(|_| 0.01))),
            FaceFlux::Velocity(Arc::new(|x: &[f64]| [1.0 + x[1], 0.5, 0.0])),
            Arc::new(|x: &[f64]| (PI * x[0]).sin()),
        )
        .with_boundary(
            "boundary",
            BoundaryKind::Dirichlet(Arc::new(|x: &[f64]| x[1])),
        )
    };
    let lu = problem().solve(&mesh)?;
    for method in [KrylovMethod::Gmres, KrylovMethod::Bicgstab] {
        let options = KrylovOptions {
            tolerance: 1e-11,
            max_iterations: 300,
            restart: 30,
        };
        let krylov = problem()
            .with_solver(LinearSolver::Krylov {
                method,
                options,
                preconditioner: KrylovPreconditioner::Ilu0,
            })
            .solve(&mesh)?;
        let iterations = krylov.iterations.ok_or("a Krylov report")?.iterations;
        eprintln!("{method:?} on the 24² grid: {iterations} iterations");
        assert!(iterations <= 60, "{method:?}: {iterations}");
        let difference = krylov
            .values
            .iter()
            .zip(&lu.values)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(difference < 1e-8, "{method:?}: {difference:e}");
    }
    Ok(())
}

/// The cellular flow v = (sin πx cos πy, −cos πx sin πy): divergence free
/// and tangent to the walls of the unit square (v·n = 0 there).
fn cellular() -> FaceFlux {
    FaceFlux::Velocity(Arc::new(|x: &[f64]| {
        [
            (PI * x[0]).sin() * (PI * x[1]).cos(),
            -(PI * x[0]).cos() * (PI * x[1]).sin(),
            0.0,
        ]
    }))
}

fn blob(x: &[f64]) -> f64 {
    (-50.0 * ((x[0] - 0.3).powi(2) + (x[1] - 0.5).powi(2))).exp()
}

#[test]
fn closed_box_conserves_mass_to_rounding() -> Result {
    // No boundary condition is needed (no inflow) and none is given: the
    // walls are insulated for the diffusion too, so Σ |c| u is invariant.
    let mesh = rectangle(16, 16, [0.0, 1.0], [0.0, 1.0])?;
    for conductivity in [None, Some(Conductivity::Scalar(Arc::new(|_| 0.01)))] {
        let problem = Transport::new(conductivity.clone(), cellular(), Arc::new(|_| 0.0));
        // The operator itself: 1ᵀ M = 0, every column of M sums to zero
        // (each face enters its two cells with opposite signs).
        let system = problem.assemble(&mesh)?;
        for j in 0..system.matrix.ncols() {
            let range = system.matrix.col_range(j);
            let sum: f64 = system.matrix.val()[range].iter().sum();
            assert!(sum.abs() < 1e-15, "column {j}: {sum:e}");
        }
        for (scheme, theta, dt) in [
            (Scheme::Upwind, 1.0, 0.02),
            (Scheme::Upwind, 0.5, 0.02),
            (Scheme::Limited, 0.0, 0.01),
        ] {
            let stepping = TimeStepping {
                dt,
                steps: 200,
                theta,
                scheme,
                keep_every: 200,
            };
            let run = problem.solve_transient(&mesh, &blob, &stepping)?;
            let m0 = run.mass[0];
            let drift = run
                .mass
                .iter()
                .map(|m| (m - m0).abs() / m0)
                .fold(0.0, f64::max);
            // 200 steps of sums over 256 cells: a few hundred roundings of
            // 1.1e-16 at most.
            eprintln!("{scheme:?} θ = {theta}: relative mass drift {drift:e}");
            assert!(drift < 1e-12, "{scheme:?} θ = {theta}: drift {drift:e}");
            // The blob did move (the test is not of a field at rest).
            let (first, last) = (&run.levels[0].1, &run.levels[1].1);
            let moved = first
                .iter()
                .zip(last)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(moved > 0.1, "{scheme:?}: moved {moved}");
        }
    }
    Ok(())
}

/// The Gaussian translated at speed 1 along x, centre 0.35 at t = 0:
/// e^{−((x − 0.35 − t)/0.07)²}, below 1.5e-11 at both ends of [0, 1] for
/// t ≤ 0.3, so the inflow value 0 is exact to that level.
fn gaussian(x: f64, t: f64) -> f64 {
    (-((x - 0.35 - t) / 0.07).powi(2)).exp()
}

/// L¹ errors at t = 0.3 on `sizes` cells of [0, 1] with Courant number
/// `courant`.
fn translated(scheme: Scheme, courant: f64, sizes: &[usize]) -> Result<(Vec<f64>, Vec<f64>)> {
    let (mut h, mut e) = (Vec::new(), Vec::new());
    for &n in sizes {
        let mesh = interval(n, 0.0, 1.0)?;
        let problem = Transport::new(
            None,
            FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])),
            Arc::new(|_| 0.0),
        )
        .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
        let dx = 1.0 / n as f64;
        let steps = (0.3 / (courant * dx)).round() as usize;
        let dt = 0.3 / steps as f64;
        let stepping = TimeStepping {
            dt,
            steps,
            theta: 0.0,
            scheme,
            keep_every: steps,
        };
        let run = problem.solve_transient(&mesh, &|x| gaussian(x[0], 0.0), &stepping)?;
        let (t, u) = run.levels.last().ok_or("a last level")?;
        h.push(dx);
        e.push(l1_error(&mesh, u, |x| gaussian(x[0], *t)));
    }
    Ok((h, e))
}

#[test]
fn upwind_is_first_order_and_limited_about_second_order_in_l1() -> Result {
    // Forward Euler upwind at Courant ½: modified equation u_t + u_x =
    // (h/4) u_xx, an O(h) error.
    let (h, e) = translated(Scheme::Upwind, 0.5, &[400, 800, 1600])?;
    let p = order(&h, &e);
    eprintln!("upwind L1 errors {e:?}, order {p:.3}");
    assert!((p - 1.0).abs() < 0.15, "upwind order {p:.3}, errors {e:?}");
    // The limited scheme (SSP-RK2) at Courant 0.4: second order on smooth
    // data, less at the peak where the limiter clips the slope.
    let (h, e_limited) = translated(Scheme::Limited, 0.4, &[200, 400, 800])?;
    let p = order(&h, &e_limited);
    eprintln!("limited L1 errors {e_limited:?}, order {p:.3}");
    assert!(
        p > 1.7 && p < 2.3,
        "limited order {p:.3}, errors {e_limited:?}"
    );
    Ok(())
}

#[test]
fn limiter_creates_no_new_extrema() -> Result {
    // A square step advected diagonally on a 2D grid with inflow value 0:
    // every level must stay within [0, 1] (the initial and inflow range).
    let mesh = rectangle(32, 32, [0.0, 1.0], [0.0, 1.0])?;
    let step = |x: &[f64]| {
        if (0.15..0.4).contains(&x[0]) && (0.15..0.4).contains(&x[1]) {
            1.0
        } else {
            0.0
        }
    };
    let problem = || {
        Transport::new(
            None,
            FaceFlux::Velocity(Arc::new(|_| [1.0, 0.5, 0.0])),
            Arc::new(|_| 0.0),
        )
        .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
        .with_boundary("ymin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    };
    // Four faces a cell: N_c Δt F / |c| = 4 · 1 · Δt / h ≤ 1 needs Δt ≤ h/4;
    // 0.9 of it.
    let stepping = |scheme, theta| TimeStepping {
        dt: 0.9 / 32.0 / 4.0,
        steps: 40,
        theta,
        scheme,
        keep_every: 1,
    };
    let limited = problem().solve_transient(&mesh, &step, &stepping(Scheme::Limited, 0.0))?;
    assert!(limited.positivity <= 1.0 + 1e-12);
    let mut peak_limited: f64 = 0.0;
    for (t, u) in &limited.levels {
        let (lo, hi) = u
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            });
        assert!(lo >= -1e-14 && hi <= 1.0 + 1e-14, "t = {t}: [{lo:e}, {hi}]");
        peak_limited = hi;
    }
    // The test can tell limiting from smearing: first-order upwind loses
    // more of the plateau over the same steps.
    let upwind = problem().solve_transient(&mesh, &step, &stepping(Scheme::Upwind, 0.0))?;
    let peak_upwind = upwind
        .levels
        .last()
        .map(|(_, u)| u.iter().fold(0.0f64, |m, v| m.max(*v)))
        .ok_or("a level")?;
    eprintln!("plateau after 40 steps: limited {peak_limited}, upwind {peak_upwind}");
    assert!(
        peak_limited > peak_upwind,
        "{peak_limited} vs {peak_upwind}"
    );
    Ok(())
}

#[test]
fn explicit_steps_past_their_limit_are_refused() -> Result {
    let mesh = interval(10, 0.0, 1.0)?;
    let problem = Transport::new(
        None,
        FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])),
        Arc::new(|_| 0.0),
    )
    .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
    // Courant Δt v / h = 0.2 / 0.1 = 2 > 1 for forward Euler; the limited
    // scheme's 2 faces · 0.06 / 0.1 = 1.2 > 1.
    for (scheme, dt) in [(Scheme::Upwind, 0.2), (Scheme::Limited, 0.06)] {
        let stepping = TimeStepping {
            dt,
            steps: 1,
            theta: 0.0,
            scheme,
            keep_every: 1,
        };
        let error = problem
            .solve_transient(&mesh, &|_| 0.0, &stepping)
            .expect_err("unstable step");
        assert!(error.to_string().contains("unstable"), "{error}");
    }
    // Backward Euler takes the same step (Courant 2, reported).
    let stepping = TimeStepping {
        dt: 0.2,
        steps: 1,
        theta: 1.0,
        scheme: Scheme::Upwind,
        keep_every: 1,
    };
    let run = problem.solve_transient(&mesh, &|_| 0.0, &stepping)?;
    assert!((run.courant - 2.0).abs() < 1e-12);
    Ok(())
}

#[test]
fn open_domain_balances_inflow_outflow_and_source() -> Result {
    // Steady pure advection with a source: by the divergence theorem
    // ∮ v·n u = ∫ f, i.e. Σ_out F_f u_c − Σ_in |F_f| g = Σ f |c|, summed
    // here from the solution and the face fluxes on the boundary faces
    // alone (the interior fluxes must cancel exactly).
    let mesh = rectangle(12, 9, [0.0, 1.0], [0.0, 0.75])?;
    let g = |x: &[f64]| 1.0 + x[0] + x[1];
    let problem = Transport::new(
        None,
        FaceFlux::Velocity(Arc::new(|x: &[f64]| [1.0 + x[1], 0.5, 0.0])),
        Arc::new(|x: &[f64]| 2.0 + x[0]),
    )
    .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(g)))
    .with_boundary("ymin", BoundaryKind::Dirichlet(Arc::new(g)));
    let solution = problem.solve(&mesh)?;
    let top = mesh.boundary(2);
    let d = mesh.embedding_dim();
    let centroids = mesh.centroid(1);
    let mut net_outflow = 0.0;
    let mut scale = 0.0;
    for (f, row) in top.outer_iterator().enumerate() {
        if row.nnz() != 1 {
            continue;
        }
        let (c, &s) = row.iter().next().ok_or("a cell")?;
        let out = f64::from(s) * solution.face_flux[f];
        let value = if out > 0.0 {
            solution.values[c]
        } else {
            g(&centroids[f * d..(f + 1) * d])
        };
        net_outflow += out * value;
        scale += (out * value).abs();
    }
    // ∫ (2 + x) over [0, 1] × [0, 0.75] = 0.75 · 2.5, exact for the
    // centroid rule (f is linear).
    let source = 0.75 * 2.5;
    assert!(
        (net_outflow - source).abs() < 1e-13 * scale,
        "{net_outflow} vs {source}"
    );
    Ok(())
}

#[test]
fn multigrid_of_the_diffusion_part_preconditions_independently_of_h() -> Result {
    // Diffusion-dominated (K = 1, |v| ≈ 1, cell Péclet ≤ 1/32): a V-cycle
    // of Aᵀ Ω_K A is a spectrally equivalent preconditioner of the whole
    // operator, so GMRES needs about as many iterations on 64² as on 32²
    // cells, and returns LU's solution to its tolerance.
    let problem = || {
        Transport::new(
            Some(Conductivity::Scalar(Arc::new(|_| 1.0))),
            FaceFlux::Velocity(Arc::new(|_| [1.0, 0.5, 0.0])),
            Arc::new(|_| 1.0),
        )
        .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    };
    // Coarse levels down to 64 unknowns, so that the 32² and 64² grids
    // get real hierarchies (the default factorises up to 4000).
    let multigrid = hasse_solver::multigrid::MultigridOptions {
        coarse_size: 64,
        ..Default::default()
    };
    let mut counts = Vec::new();
    for n in [32, 64] {
        let mesh = rectangle(n, n, [0.0, 1.0], [0.0, 1.0])?;
        let lu = problem().solve(&mesh)?;
        let solver = LinearSolver::Krylov {
            method: KrylovMethod::Gmres,
            options: KrylovOptions {
                tolerance: 1e-10,
                max_iterations: 200,
                restart: 30,
            },
            preconditioner: KrylovPreconditioner::DiffusionMultigrid(multigrid.clone()),
        };
        let krylov = problem().with_solver(solver).solve(&mesh)?;
        let iterations = krylov.iterations.ok_or("a Krylov report")?.iterations;
        let scale = lu.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let difference = krylov
            .values
            .iter()
            .zip(&lu.values)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(difference < 1e-8 * scale, "{n}²: {difference:e}");
        counts.push(iterations);
    }
    eprintln!("GMRES + multigrid of the diffusion part: iterations {counts:?} on 32², 64²");
    assert!(counts[1] <= 20 && counts[1] <= counts[0] + 3, "{counts:?}");
    // In time the V-cycle is of V/Δt + θ Aᵀ Ω_K A: backward Euler levels
    // equal those of the LU path to the solver tolerance.
    let mesh = rectangle(32, 32, [0.0, 1.0], [0.0, 1.0])?;
    let stepping = TimeStepping {
        dt: 0.01,
        steps: 5,
        theta: 1.0,
        scheme: Scheme::Upwind,
        keep_every: 5,
    };
    let lu = problem().solve_transient(&mesh, &blob, &stepping)?;
    let krylov = problem()
        .with_solver(LinearSolver::Krylov {
            method: KrylovMethod::Bicgstab,
            options: KrylovOptions {
                tolerance: 1e-12,
                max_iterations: 200,
                restart: 30,
            },
            preconditioner: KrylovPreconditioner::DiffusionMultigrid(multigrid.clone()),
        })
        .solve_transient(&mesh, &blob, &stepping)?;
    let (a, b) = (&lu.levels[1].1, &krylov.levels[1].1);
    let difference = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(difference < 1e-9, "transient: {difference:e}");
    // Pure advection has no diffusion part to build it from.
    let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0])?;
    let advection = Transport::new(
        None,
        FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])),
        Arc::new(|_| 0.0),
    )
    .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    .with_solver(LinearSolver::Krylov {
        method: KrylovMethod::Bicgstab,
        options: KrylovOptions::default(),
        preconditioner: KrylovPreconditioner::DiffusionMultigrid(multigrid),
    });
    assert!(matches!(
        advection.solve(&mesh),
        Err(hasse_solver::physics::transport::TransportError::NoDiffusion)
    ));
    Ok(())
}
