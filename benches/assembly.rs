//! Where the assembly of δΩ∂ spends its time, next to a hand-built
//! triplet list of the same matrix in the same run.
//!
//! For each case it prints the time to compute the primal geometry the
//! methods read (cached in the complex, so computed first and apart), the
//! whole `Diffusion::assemble` (Ω, boundary data, source load, pattern and
//! values) on the warm complex, then its parts through the
//! public API: the metric Ω, `Canonical::new` (the sparsity pattern; for
//! the nodal cases `Canonical::with_cell_blocks`, as `Diffusion` builds it) and
//! `Canonical::assemble_owned` (the values), each with its page faults. For the
//! structured cell-centred cases the same 5/7-point matrix is also built by
//! hand as triplets and compressed by faer, the floor any assembly is
//! measured against; for 2D Q1 the nodal matrix is built by hand from the
//! square's element matrix. Elasticity on tetrahedra shows the dense-block case (12×12
//! element matrices written over 18 edge rows).
//!
//! `cargo bench --bench assembly` runs 2D 1000² (FV, FE Q1), 3D 60³ (FV),
//! 3D 40³ (FE Q1) and Kuhn tetrahedra 16³ (elasticity);
//! `cargo bench --bench assembly -- CASE` runs one of them. Without
//! `--bench` (as under `cargo test --all-targets`) it runs small sizes and
//! checks the hand-built matrix against hasse's.

use hasse_complex::{generate, Complex};
use hasse_solver::metric::Method;
use hasse_solver::metric::{fe, fv, isotropic};
use hasse_solver::operator::Canonical;
use hasse_solver::physics::diffusion::Diffusion;
use hasse_solver::physics::elasticity::{Coefficient, ElasticBoundary, Elasticity, Material};
use hasse_solver::physics::BoundaryKind;
use hasse_solver::physics::Conductivity;
use std::sync::Arc;
use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{
    cpu_and_faults, max_difference, peak_memory_gib, plain_matrix, plain_q1_matrix, seconds,
};

fn poisson(method: Method) -> Diffusion {
    Diffusion::new(
        method,
        Conductivity::Scalar(Arc::new(|_| 1.0)),
        Arc::new(|_| 1.0),
    )
    .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
}

/// Largest |a − b| over the entries of two matrices with the same pattern.
fn diffusion_case(label: &str, complex: &Complex, method: Method, plain: Option<usize>) {
    let d = complex.dim();
    // The primal geometry the methods read, computed once per complex and
    // cached: timed apart so that the rest is the assembly proper.
    let started = Instant::now();
    let _ = (
        complex.measure(d),
        complex.centroid(d),
        complex.measure(d - 1),
        complex.centroid(d - 1),
        complex.normal(),
    );
    let geometry = seconds(started);
    let started = Instant::now();
    let (cpu_before, faults_before) = cpu_and_faults();
    let system = poisson(method).assemble(complex).expect("assembly");
    let whole = seconds(started);
    let (cpu_after, faults_after) = cpu_and_faults();

    let cells = complex.cell_count(d);
    let tensors = vec![isotropic(1.0); cells];
    let faults = || cpu_and_faults().1;
    let (t, faults_start) = (Instant::now(), faults());
    let (incidence, metric) = match method {
        Method::Fv => (
            Arc::clone(complex.boundary(d)),
            fv::two_point(complex, &tensors).expect("metric"),
        ),
        _ => (
            Arc::clone(complex.coboundary(0)),
            fe::stiffness_metric(complex, &tensors).expect("metric"),
        ),
    };
    let metric_seconds = seconds(t);
    let (t, faults_metric) = (Instant::now(), faults());
    let mut canonical = match method {
        Method::Fv => Canonical::new(incidence, metric),
        _ => Canonical::with_cell_blocks(incidence, metric, complex),
    }
    .expect("canonical");
    let pattern_seconds = seconds(t);
    let (t, faults_pattern) = (Instant::now(), faults());
    let matrix = canonical.assemble_owned();
    let values_seconds = seconds(t);
    let faults_values = faults();
    print!(
        "{label:<26} unknowns {:>8} nnz {:>9} | geometry {geometry:>6.3}s | Diffusion::assemble {whole:>6.3}s (cpu {:.2}s, {}k page faults) | Ω {metric_seconds:>6.3}s ({}k)  pattern {pattern_seconds:>6.3}s ({}k)  values {values_seconds:>6.3}s ({}k)",
        matrix.nrows(),
        matrix.val().len(),
        cpu_after - cpu_before,
        (faults_after - faults_before) / 1000,
        (faults_metric - faults_start) / 1000,
        (faults_pattern - faults_metric) / 1000,
        (faults_values - faults_pattern) / 1000,
    );
    if method == Method::Fe && d == 2 {
        // Nodal Q1 on the unit grid (no boundary condition): the element
        // matrix is the same for every cell, so a hand-written assembly is
        // one triplet list of 16 entries per cell.
        let n = (cells as f64).sqrt().round() as usize;
        let t = Instant::now();
        let hand = plain_q1_matrix(n, 2);
        let plain_seconds = seconds(t);
        let difference = max_difference(&matrix, &hand);
        // Rounding only: the Gauss points, the mapped gradients and A_c⁺
        // (an SVD) each carry a few ulps; 1e-12 relative is the issue's
        // "exact to rounding".
        assert!(
            difference <= 1e-12 * 8.0 / 3.0,
            "{label}: hasse's Q1 matrix and the hand-built one differ by {difference:e}"
        );
        print!(
            " | hand-built Q1 triplets {plain_seconds:>6.3}s  ratio {:>5.2}",
            whole / plain_seconds
        );
    }
    if let Some(n) = plain {
        let t = Instant::now();
        let hand = plain_matrix(n, d);
        let plain_seconds = seconds(t);
        let difference = max_difference(&system.matrix, &hand);
        let scale = hand.val().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            difference <= 1e-12 * scale,
            "{label}: hasse and the hand-built matrix differ by {difference:e}"
        );
        print!(
            " | hand-built triplets {plain_seconds:>6.3}s  ratio {:>5.2}",
            whole / plain_seconds
        );
    }
    println!(" | peak {:.2} GiB", peak_memory_gib());
}

fn elasticity_case(label: &str, complex: &Complex) {
    let material = Material::Lame {
        lambda: Coefficient::constant(1.0),
        mu: Coefficient::constant(1.0),
    };
    let problem = Elasticity::new(material, Arc::new(|_| [0.0, 0.0, -1.0])).with_boundary(
        "boundary",
        ElasticBoundary::Displacement(Arc::new(|_| [0.0; 3])),
    );
    let t = Instant::now();
    let system = problem.assemble(complex).expect("assembly");
    let whole = seconds(t);
    println!(
        "{label:<26} unknowns {:>8} nnz {:>9} | Elasticity::assemble {whole:>6.3}s | peak {:.2} GiB",
        system.matrix.nrows(),
        system.matrix.val().len(),
        peak_memory_gib()
    );
}

fn run(case: &str, scale: usize) {
    let t = Instant::now();
    let unit = [0.0, 1.0];
    let (complex, n) = match case {
        "2d-fv" | "2d-fe" => {
            let n = 1000 / scale;
            (generate::rectangle(n, n, unit, unit).expect("grid"), n)
        }
        "3d-fv" => {
            let n = 60 / scale;
            (generate::box3(n, n, n, unit, unit, unit).expect("grid"), n)
        }
        "3d-fe" => {
            let n = 40 / scale;
            (generate::box3(n, n, n, unit, unit, unit).expect("grid"), n)
        }
        "tet-elasticity" => {
            let n = 16 / scale.min(4);
            let axis = generate::uniform_axis(n, 0.0, 1.0).expect("axis");
            (
                generate::kuhn(&[axis.clone(), axis.clone(), axis]).expect("grid"),
                n,
            )
        }
        other => panic!("unknown case {other}: 2d-fv 2d-fe 3d-fv 3d-fe tet-elasticity"),
    };
    let label = format!("{case} n={n}");
    println!("{label:<26} complex built in {:.3}s", seconds(t));
    match case {
        "2d-fv" | "3d-fv" => diffusion_case(&label, &complex, Method::Fv, Some(n)),
        "2d-fe" | "3d-fe" => diffusion_case(&label, &complex, Method::Fe, None),
        _ => elasticity_case(&label, &complex),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let benching = args.iter().any(|a| a == "--bench");
    let scale = if benching { 1 } else { 20 };
    let chosen: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let all = ["2d-fv", "2d-fe", "3d-fv", "3d-fe", "tet-elasticity"];
    for case in if chosen.is_empty() { &all[..] } else { &chosen } {
        run(case, scale);
    }
}
