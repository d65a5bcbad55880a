//! Convergence of every method on a manufactured Poisson problem, printed
//! as tables: u = sin(πx) sin(πy) + xy on the unit square with Dirichlet
//! data, then the same on randomly distorted quadrilaterals, where the
//! two-point flux loses consistency and the mimetic method does not, and
//! on random Voronoi polygons (virtual elements, mimetic, and the two-point
//! flux with its unknowns at the sites or at the centroids) and jittered
//! Delaunay triangulations (two-point flux at the circumcentres). On the
//! random meshes h is the mean cell size sqrt(1/N), not the largest
//! diameter, which jumps with the worst cell.
//!
//! cargo run --release -p hasse-solver --example poisson_convergence

use hasse_complex::dual::DualKind;
use hasse_complex::{generate, Complex};
use hasse_solver::metric::Method;
use hasse_solver::physics::diffusion::{errors, flux_error, CellPoints, Diffusion};
use hasse_solver::physics::BoundaryKind;
use hasse_solver::physics::Conductivity;
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
    let levels: Vec<(Complex, CellPoints, f64)> = meshes
        .iter()
        .map(|m| (m.clone(), CellPoints::Centroids, m.mesh_size()))
        .collect();
    table_at(title, method, &levels);
}

/// One table row per (mesh, cell points of FV, h).
fn table_at(title: &str, method: Method, levels: &[(Complex, CellPoints, f64)]) {
    let exact: hasse_solver::physics::ScalarFn =
        Arc::new(|x: &[f64]| (PI * x[0]).sin() * (PI * x[1]).sin() + x[0] * x[1]);
    let gradient: hasse_solver::physics::VectorFn = Arc::new(|x: &[f64]| {
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
    for (mesh, points, h) in levels {
        let mut p = problem(method);
        p.cell_points = points.clone();
        let h = *h;
        let solution = p.solve(mesh).expect("solves");
        let e = errors(mesh, &solution, &exact, Some(&gradient));
        let q = flux_error(mesh, &solution, &p, &gradient);
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
    let voronoi: Vec<(Complex, CellPoints, f64)> = [64, 256, 1024, 4096, 16384]
        .iter()
        .map(|&n| {
            let (mesh, sites) =
                generate::voronoi_with_sites(n, [0.0, 1.0], [0.0, 1.0], 1, 0).expect("voronoi");
            let sites = CellPoints::Given(sites.iter().flatten().copied().collect());
            (mesh, sites, (1.0 / n as f64).sqrt())
        })
        .collect();
    let at_centroids: Vec<(Complex, CellPoints, f64)> = voronoi
        .iter()
        .map(|(m, _, h)| (m.clone(), CellPoints::Centroids, *h))
        .collect();
    table_at(
        "FE (VEM), random Voronoi polygons",
        Method::Fe,
        &at_centroids,
    );
    table_at(
        "FV mimetic (hybrid), random Voronoi polygons",
        Method::FvMimetic,
        &at_centroids,
    );
    table_at(
        "FV two-point at the sites, random Voronoi polygons",
        Method::Fv,
        &voronoi,
    );
    table_at(
        "FV two-point at the centroids, random Voronoi polygons",
        Method::Fv,
        &at_centroids,
    );
    let delaunay: Vec<(Complex, CellPoints, f64)> = levels
        .iter()
        .map(|&m| {
            // Interior grid points moved by a deterministic pseudo-random
            // 30% of h; boundary points evenly spaced.
            let h = 1.0 / m as f64;
            let wobble = |k: usize| ((k as f64 * 12.9898).sin() * 43758.5453).fract();
            let mut points = Vec::new();
            for j in 0..=m {
                for i in 0..=m {
                    let (mut x, mut y) = (i as f64 * h, j as f64 * h);
                    if (1..m).contains(&i) && (1..m).contains(&j) {
                        x += 0.3 * h * wobble(2 * (i + 1000 * j));
                        y += 0.3 * h * wobble(2 * (i + 1000 * j) + 1);
                    }
                    points.push([x, y]);
                }
            }
            let mesh = generate::delaunay(&points).expect("delaunay");
            (mesh, CellPoints::Circumcentres, h)
        })
        .collect();
    table_at(
        "FV two-point at the circumcentres, jittered Delaunay triangles",
        Method::Fv,
        &delaunay,
    );
}
