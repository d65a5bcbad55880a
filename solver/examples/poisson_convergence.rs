//! Convergence of every method on a manufactured Poisson problem, printed
//! as tables: u = sin(πx) sin(πy) + xy on the unit square with Dirichlet
//! data, then the same on randomly distorted quadrilaterals, where the
//! two-point flux loses consistency and the mimetic method does not.
//!
//! cargo run --release -p hasse-solver --example poisson_convergence

use hasse_complex::dual::DualKind;
use hasse_complex::{generate, Complex};
use hasse_solver::diffusion::{errors, flux_error, BoundaryKind, Conductivity, Diffusion, Method};
use std::f64::consts::PI;
use std::sync::Arc;

fn problem(method: Method) -> Diffusion {
    let exact = Arc::new(|x: &[f64]| (PI * x[0]).sin() * (PI * x[1]).sin() + x[0] * x[1]);
    Diffusion::new(
        method,
        Conductivity::Scalar(Arc::new(|_| 1.0)),
        Arc::new(|x: &[f64]| 2.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin()),
    )
    .with_boundary("boundary", BoundaryKind::Dirichlet(exact))
}

fn table(title: &str, method: Method, meshes: &[Complex]) {
    let exact: hasse_solver::diffusion::ScalarFn =
        Arc::new(|x: &[f64]| (PI * x[0]).sin() * (PI * x[1]).sin() + x[0] * x[1]);
    let gradient: hasse_solver::diffusion::VectorFn = Arc::new(|x: &[f64]| {
        [
            PI * (PI * x[0]).cos() * (PI * x[1]).sin() + x[1],
            PI * (PI * x[0]).sin() * (PI * x[1]).cos() + x[0],
            0.0,
        ]
    });
    println!("{title}");
    println!(
        "  {:>8} {:>10} {:>12} {:>6} {:>12} {:>6}",
        "unknowns", "h", "L2 error", "order", "flux error", "order"
    );
    let mut previous: Option<(f64, f64, Option<f64>)> = None;
    let p = problem(method);
    for mesh in meshes {
        let solution = p.solve(mesh).expect("solves");
        let e = errors(mesh, &solution, &exact, Some(&gradient));
        let q = flux_error(mesh, &solution, &p, &gradient);
        let h = mesh.mesh_size();
        let rate = |now: f64, before: f64, h0: f64| (now / before).ln() / (h / h0).ln();
        let (l2_rate, q_rate) = match previous {
            Some((h0, e0, q0)) => (
                format!("{:.2}", rate(e.l2, e0, h0)),
                q.zip(q0)
                    .map_or("-".into(), |(q, q0)| format!("{:.2}", rate(q, q0, h0))),
            ),
            None => ("-".into(), "-".into()),
        };
        println!(
            "  {:>8} {:>10.4e} {:>12.4e} {:>6} {:>12} {:>6}",
            solution.unknowns(),
            h,
            e.l2,
            l2_rate,
            q.map_or("-".into(), |q| format!("{q:.4e}")),
            q_rate
        );
        previous = Some((h, e.l2, q));
    }
}

fn main() {
    let levels = [8, 16, 32, 64, 128];
    let squares: Vec<Complex> = levels
        .iter()
        .map(|&n| generate::rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("grid"))
        .collect();
    let triangles: Vec<Complex> = levels
        .iter()
        .map(|&n| {
            let axis = generate::uniform_axis(n, 0.0, 1.0).expect("axis");
            generate::kuhn(&[axis.clone(), axis]).expect("grid")
        })
        .collect();
    table("FD five-point, squares", Method::Fd, &squares);
    table("FV two-point, squares", Method::Fv, &squares);
    table("FV mimetic (hybrid), squares", Method::FvMimetic, &squares);
    table("FE Q1, squares", Method::Fe, &squares);
    table("FE P1, Kuhn triangles", Method::Fe, &triangles);
    table(
        "DEC circumcentric, Kuhn triangles",
        Method::Dec(DualKind::Circumcentric),
        &triangles,
    );
    let distorted: Vec<Complex> = levels
        .iter()
        .enumerate()
        .map(|(k, &n)| {
            let grid = generate::rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("grid");
            generate::perturb(&grid, 0.3, 100 + k as u64).expect("perturb")
        })
        .collect();
    table(
        "FV two-point, distorted quads (30% of h)",
        Method::Fv,
        &distorted,
    );
    table(
        "FV mimetic (hybrid), distorted quads (30% of h)",
        Method::FvMimetic,
        &distorted,
    );
    table("FE Q1, distorted quads (30% of h)", Method::Fe, &distorted);
}
