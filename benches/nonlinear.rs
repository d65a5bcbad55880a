//! Newton's method for nonlinear diffusion against the linear solve of the
//! same grid, in the same run (issue 31's target: the whole Newton solve
//! ≤ 4× the linear one).
//!
//! −∇·((1 + u²)∇u) = f on the unit square, two-point FV (cell-centred),
//! u = 0 on the boundary, f = 2π² sin πx sin πy (so u is O(1) and k(u)
//! varies by a factor of about 2). The linear baseline is −Δu = f on the
//! same grid by the same direct path (assembly, symbolic analysis, numeric
//! LLᵀ, solve). Newton runs twice: with a numeric LU of each step's
//! Jacobian (one symbolic analysis; J is not symmetric: the face weights'
//! derivative), and as Newton–Krylov (`NonlinearOptions::krylov`: GMRES on
//! J preconditioned by an LLᵀ of its symmetric part kept over the steps, or
//! by a smoothed-aggregation V-cycle of it: `KrylovPreconditioner`).
//!
//! - `cargo bench --bench nonlinear` — 300².
//! - `cargo bench --bench nonlinear -- full` — 1000² (10⁶ unknowns).

#[path = "common/measure.rs"]
mod measure;

use hasse_complex::generate::rectangle;
use hasse_solver::metric::Method;
use hasse_solver::physics::diffusion::Diffusion;
use hasse_solver::physics::nonlinear::{Coefficient, KrylovPreconditioner, NonlinearDiffusion};
use hasse_solver::physics::{BoundaryKind, Conductivity};
use measure::seconds;
use std::f64::consts::PI;
use std::sync::Arc;
use std::time::Instant;

fn source(x: &[f64]) -> f64 {
    2.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin()
}

fn main() {
    let full = std::env::args().any(|a| a == "full");
    let n = if full { 1000 } else { 300 };
    let started = Instant::now();
    let mesh = rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("the unit square");
    println!("{n}² cells, mesh {:.2} s", seconds(started));
    let zero = || BoundaryKind::Dirichlet(Arc::new(|_: &[f64]| 0.0));

    let started = Instant::now();
    let linear = Diffusion::new(
        Method::Fv,
        Conductivity::Scalar(Arc::new(|_| 1.0)),
        Arc::new(source),
    )
    .with_boundary("boundary", zero())
    .solve(&mesh)
    .expect("the linear solve");
    let linear_time = seconds(started);
    drop(linear);
    println!("linear −Δu = f (assembly + LLᵀ + solve): {linear_time:.2} s");

    for (krylov, preconditioner) in [
        (false, KrylovPreconditioner::Factor),
        (true, KrylovPreconditioner::Factor),
        (true, KrylovPreconditioner::Multigrid),
    ] {
        let started = Instant::now();
        let conductivity = Coefficient::new(
            Arc::new(|u: f64, _: &[f64]| 1.0 + u * u),
            Arc::new(|u: f64, _: &[f64]| 2.0 * u),
        );
        let mut problem = NonlinearDiffusion::new(Method::Fv, conductivity, Arc::new(source))
            .with_boundary("boundary", zero());
        problem.options.krylov = krylov;
        problem.options.preconditioner = preconditioner;
        let solved = problem.solve(&mesh).expect("Newton converges");
        let newton_time = seconds(started);
        let history: Vec<String> = solved.history.iter().map(|r| format!("{r:.1e}")).collect();
        let name = match (krylov, preconditioner) {
            (false, _) => "newton (LU per step)",
            (true, KrylovPreconditioner::Factor) => {
                "newton–krylov (GMRES, LLᵀ of the symmetric part)"
            }
            (true, KrylovPreconditioner::Multigrid) => {
                "newton–krylov (GMRES, AMG V-cycle of the symmetric part)"
            }
        };
        println!(
            "{name}: {newton_time:.2} s, {} iterations (residuals {})",
            solved.iterations(),
            history.join(", "),
        );
        let ratio = newton_time / linear_time;
        println!(
            "  ratio / linear = {ratio:.2} (target ≤ 4): {}",
            if ratio <= 4.0 { "met" } else { "not met" }
        );
    }
    println!("peak memory {:.2} GiB", measure::peak_memory_gib());
}
