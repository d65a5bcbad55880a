//! Transient heat steps: one factorisation of M/Δt + θK, then many cheap
//! steps (K uⁿ, right-hand side, Dirichlet lift, two triangular solves).
//!
//! For cell-centred FV and nodal FE (Q1) on an n×n unit square with u = 0
//! on the boundary, Crank–Nicolson from sin(πx) sin(πy), it prints the
//! setup (complex, assembly), the symbolic + numeric factorisation and the
//! mean time per step. Steady data, so no per-step re-assembly.
//!
//! `cargo bench --bench heat_steps` runs 100×100 and 100 steps;
//! `cargo bench --bench heat_steps -- full` runs 500×500 and 1000 steps
//! (target: under 5 ms per step).

use hasse_complex::generate::rectangle;
use hasse_solver::metric::Method;
use hasse_solver::physics::heat::{Heat, HeatBoundary, TimeFn};
use hasse_solver::physics::Conductivity;
use std::f64::consts::PI;
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let full = std::env::args().any(|a| a == "full");
    let (n, steps) = if full { (500, 1000) } else { (100, 100) };
    println!("heat_steps: {n}×{n} unit square, {steps} Crank–Nicolson steps, Δt = 1e-4");
    let started = Instant::now();
    let mesh = rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("grid");
    println!("  complex: {:.3} s", started.elapsed().as_secs_f64());
    for (name, method) in [("fv", Method::Fv), ("fe", Method::Fe)] {
        let heat = Heat::new(method, Conductivity::Scalar(Arc::new(|_| 1.0)), 1e-4)
            .with_theta(0.5)
            .with_boundary(
                "boundary",
                HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
            );
        let started = Instant::now();
        let history = heat
            .run(
                &mesh,
                &|x: &[f64]| (PI * x[0]).sin() * (PI * x[1]).sin(),
                steps,
                0,
            )
            .expect("heat run");
        let total = started.elapsed().as_secs_f64();
        let stepping = history.seconds_per_step * steps as f64;
        let peak = history.fields[1].iter().fold(0.0f64, |m, u| m.max(u.abs()));
        println!(
            "  {name}: {} unknowns | assembly + setup {:.3} s | factorisation {:.3} s | {:.3} ms/step (of which solve {:.3} ms) | max u(T) = {peak:.6} (exp(−2π²T) = {:.6})",
            history.fields[0].len(),
            total - stepping - history.factorization_seconds,
            history.factorization_seconds,
            1e3 * history.seconds_per_step,
            1e3 * history.solve_seconds_per_step,
            (-2.0 * PI * PI * 1e-4 * steps as f64).exp(),
        );
    }
}
