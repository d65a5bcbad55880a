//! Transient heat steps: the direct path (one factorisation of M/Δt + θK,
//! then two triangular solves a step) against multigrid-preconditioned CG
//! started from the previous levels (Fischer's projection, and the linear
//! extrapolation it replaced), on the same grid in the same run.
//!
//! FV (cell-centred) on the unit square or cube with u = 0 on the boundary,
//! from sin(πx) sin(πy) (sin(πz)), steady data, backward Euler, Δt = 10⁻⁴,
//! CG to 10⁻⁸ on the grid's geometric multigrid.
//!
//! - `cargo bench --bench heat_steps` — 200², 50 steps: direct and
//!   multigrid per step, their ratio.
//! - `cargo bench --bench heat_steps -- full` — 500² (2.5·10⁵ unknowns),
//!   200 steps; target: multigrid per step ≤ 0.5× the direct path's
//!   triangular solves of the same system.
//! - `-- forced` (with or without `full`): the same with a source that
//!   circles the centre (a hot spot, one turn every 200 steps), so that
//!   the levels do not stay in a few modes as the decaying sines do.
//! - `cargo bench --bench heat_steps -- 3d` — the 100³ box (10⁶ unknowns,
//!   beyond a factorisation), 50 steps by multigrid; target: time per
//!   step ≤ 0.3× one cold steady multigrid solve (setup + solve) of the
//!   same grid; peak memory printed. `3d-60` runs 60³.

#[path = "common/measure.rs"]
mod measure;

use hasse_complex::generate::{box3, rectangle};
use hasse_complex::Complex;
use hasse_solver::metric::Method;
use hasse_solver::multigrid::{Hierarchy, SolverChoice};
use hasse_solver::physics::diffusion::Diffusion;
use hasse_solver::physics::heat::{Heat, HeatBoundary, History, TimeFn};
use hasse_solver::physics::{BoundaryKind, Conductivity};
use std::f64::consts::PI;
use std::sync::Arc;
use std::time::Instant;

const DT: f64 = 1e-4;
const TOLERANCE: f64 = 1e-8;

fn unit() -> Conductivity {
    Conductivity::Scalar(Arc::new(|_| 1.0))
}

fn heat() -> Heat {
    Heat::new(Method::Fv, unit(), DT).with_boundary(
        "boundary",
        HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
    )
}

/// A hot spot circling the centre once every 200 steps: data that keep
/// changing, so that no span of past levels holds the next one.
fn circling(x: &[f64], t: f64) -> f64 {
    let angle = 2.0 * PI * t / (200.0 * DT);
    let (cx, cy) = (0.5 + 0.25 * angle.cos(), 0.5 + 0.25 * angle.sin());
    let r2 = (x[0] - cx).powi(2) + (x[1] - cy).powi(2);
    100.0 * (-r2 / 0.01).exp()
}

fn sines(x: &[f64]) -> f64 {
    x.iter().map(|&xi| (PI * xi).sin()).product()
}

fn run(mesh: &Complex, heat: Heat, steps: usize) -> (History, f64) {
    let started = Instant::now();
    let history = heat.run(mesh, &sines, steps, 0).expect("heat run");
    (history, started.elapsed().as_secs_f64())
}

fn print(name: &str, history: &History, total: f64) {
    let iterations = history
        .iterations
        .map(|i| format!(" | CG iterations {:.1} per step (max {})", i.mean(), i.max))
        .unwrap_or_default();
    println!(
        "  {name}: {} unknowns | total {total:.3} s | setup {:.3} s | {:.3} ms/step (of which solve {:.3} ms){iterations}",
        history.fields[0].len(),
        history.factorization_seconds,
        1e3 * history.seconds_per_step,
        1e3 * history.solve_seconds_per_step,
    );
}

fn square(n: usize, steps: usize, forced: bool) {
    let source = if forced {
        ", source: a hot spot circling once every 200 steps"
    } else {
        ""
    };
    println!(
        "heat_steps: {n}×{n} unit square, FV, {steps} backward-Euler steps, Δt = {DT}{source}"
    );
    let heat = || {
        if forced {
            heat().with_source(TimeFn::Varying(Arc::new(circling)))
        } else {
            heat()
        }
    };
    let mesh = rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("grid");
    let (direct, direct_total) = run(&mesh, heat(), steps);
    print("direct LLᵀ", &direct, direct_total);
    let grid = Hierarchy::Grid { cells: vec![n, n] };
    let mut projected = heat().with_solver(SolverChoice::Multigrid(grid), TOLERANCE, &mesh);
    // HASSE_BENCH_PROJECTION=k keeps k levels instead of the default.
    if let Some(k) = std::env::var("HASSE_BENCH_PROJECTION")
        .ok()
        .and_then(|k| k.parse().ok())
    {
        projected.projection = k;
    }
    println!("  projection: {} levels", projected.projection);
    let (mg, mg_total) = run(&mesh, projected, steps);
    print("multigrid-CG", &mg, mg_total);
    // The start before Fischer's projection, for comparison: uⁿ
    // extrapolated along the last step.
    let mut extrapolated = heat().with_solver(
        SolverChoice::Multigrid(Hierarchy::Grid { cells: vec![n, n] }),
        TOLERANCE,
        &mesh,
    );
    extrapolated.projection = 0;
    let (old, old_total) = run(&mesh, extrapolated, steps);
    print("multigrid-CG, extrapolated start", &old, old_total);
    let difference = direct.fields[1]
        .iter()
        .zip(&mg.fields[1])
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!(
        "  ratio: multigrid step / direct triangular solves = {:.2} (target ≤ 0.5); whole step {:.2}; setup {:.2}; max |difference| at T {difference:.1e}",
        mg.seconds_per_step / direct.solve_seconds_per_step,
        mg.seconds_per_step / direct.seconds_per_step,
        mg.factorization_seconds / direct.factorization_seconds,
    );
    println!(
        "  extrapolated start: step / direct triangular solves = {:.2}",
        old.seconds_per_step / direct.solve_seconds_per_step,
    );
}

fn cube(n: usize, steps: usize) {
    println!("heat_steps: {n}³ unit cube, FV, {steps} backward-Euler steps, Δt = {DT}, multigrid-CG to {TOLERANCE:e}");
    let mesh = box3(n, n, n, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).expect("grid");
    let grid = || Hierarchy::Grid {
        cells: vec![n, n, n],
    };
    // One cold steady solve of the same grid: −Δu = 1, u = 0 on the
    // boundary, multigrid set up and CG from zero.
    let steady = Diffusion::new(Method::Fv, unit(), Arc::new(|_| 1.0))
        .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
        .with_solver(SolverChoice::Multigrid(grid()), TOLERANCE, &mesh);
    let started = Instant::now();
    let solution = steady.solve(&mesh).expect("steady solve");
    let steady_seconds = started.elapsed().as_secs_f64();
    let report = &solution.report;
    let cold = report.numeric_seconds + report.solve_seconds;
    println!(
        "  steady: assembly + setup + solve {steady_seconds:.3} s, of which multigrid setup {:.3} s + CG {:.3} s ({} iterations)",
        report.numeric_seconds,
        report.solve_seconds,
        solution.iterations.map_or(0, |i| i.iterations),
    );
    drop(solution);
    let (mg, total) = run(
        &mesh,
        heat().with_solver(SolverChoice::Multigrid(grid()), TOLERANCE, &mesh),
        steps,
    );
    print("multigrid-CG steps", &mg, total);
    println!(
        "  ratio: time per step / cold steady multigrid setup + solve = {:.3} (target ≤ 0.3) | peak memory {:.2} GiB",
        mg.seconds_per_step / cold,
        measure::peak_memory_gib(),
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let has = |a: &str| args.iter().any(|x| x == a);
    if has("3d") {
        cube(100, 50);
    } else if has("3d-60") {
        cube(60, 50);
    } else if has("full") {
        square(500, 200, has("forced"));
    } else {
        square(200, 50, has("forced"));
    }
}
