//! Poisson through the canonical form with a direct solve, next to a plain
//! faer factorisation of the same operator built by hand in the same run.
//!
//! For each grid it prints: complex build, metric (Ω) construction,
//! assembly of Aᵀ Ω A, symbolic + numeric factorisation and solve through
//! hasse; then the same five/seven-point matrix assembled directly as
//! triplets and factorised the same way (LLᵀ through `DirectSolver` with
//! the automatic ordering, which each line names; `benches/multigrid.rs`
//! compares the orderings). For nodal FE the hand-built matrix is the Q1
//! stiffness from the square's or cube's element matrix, checked entry by
//! entry against hasse's. Ratios are hasse / plain.
//!
//! `cargo bench --bench poisson_direct` runs the headline sizes (2D
//! 1000×1000, 3D 60³; several GB of memory and minutes of time);
//! `cargo bench --bench poisson_direct -- small` runs 2D 200×200 and 3D 20³.

use faer::sparse::{SparseColMat, Triplet};
use hasse_complex::{generate, Complex};
use hasse_solver::la::direct::{DirectSolver, Factorization};
use hasse_solver::metric::{fe, fv};
use hasse_solver::operator::Canonical;
use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{max_difference, peak_memory_gib, plain_matrix, plain_q1_matrix, seconds};
use std::sync::Arc;

fn factor_and_solve(matrix: &SparseColMat<usize, f64>) -> (f64, f64, f64, String) {
    let rhs = vec![1.0; matrix.nrows()];
    let t = Instant::now();
    let solver = DirectSolver::analyze(matrix.as_ref(), Factorization::Llt).expect("analysis");
    let symbolic = seconds(t);
    let t = Instant::now();
    let factor = solver.factorize(matrix.as_ref()).expect("SPD");
    let numeric = seconds(t);
    let t = Instant::now();
    factor.solve(&rhs).expect("solve");
    let ordering = solver.ordering().map_or("COLAMD".into(), |o| o.to_string());
    (symbolic, numeric, seconds(t), ordering)
}

fn run(label: &str, complex: &Complex, n: usize, method: &str) {
    let d = complex.dim();
    let t = Instant::now();
    let cells = complex.cell_count(d);
    // A scalar conductivity, as `Diffusion` keeps it.
    let tensors = vec![1.0; cells];
    let (incidence, metric) = match method {
        "fv" => (
            Arc::clone(complex.boundary(d)),
            fv::two_point(complex, &tensors).expect("metric"),
        ),
        _ => (
            Arc::clone(complex.coboundary(0)),
            fe::stiffness_metric(complex, &tensors).expect("metric"),
        ),
    };
    let metric_time = seconds(t);
    let t = Instant::now();
    let mut canonical = Canonical::new(incidence, metric).expect("canonical");
    let pattern_time = seconds(t);
    let t = Instant::now();
    let matrix = canonical.assemble_owned();
    let values_time = seconds(t);
    // Nodal FE keeps every vertex (no Dirichlet elimination here); pin one
    // vertex through a unit diagonal shift so LLᵀ applies to both methods.
    let pin = |matrix: &SparseColMat<usize, f64>| {
        let mut triplets: Vec<Triplet<usize, usize, f64>> = matrix
            .triplet_iter()
            .map(|t| Triplet::new(t.row, t.col, *t.val))
            .collect();
        triplets.push(Triplet::new(0, 0, 1.0));
        SparseColMat::try_new_from_triplets(matrix.nrows(), matrix.ncols(), &triplets)
            .expect("valid")
    };
    let matrix = if method == "fe" { pin(&matrix) } else { matrix };
    let (symbolic, numeric, solve, ordering) = factor_and_solve(&matrix);
    let assembly = metric_time + pattern_time + values_time;
    let hasse_total = assembly + symbolic + numeric + solve;
    println!(
        "{label:<22} {method:<3} unknowns {:>9}  Ω {metric_time:>7.3}s  pattern {pattern_time:>7.3}s  values {values_time:>7.3}s  symbolic {symbolic:>7.3}s  numeric {numeric:>7.3}s  solve {solve:>7.3}s  ({ordering})",
        matrix.nrows()
    );
    if method == "fv" {
        let t = Instant::now();
        let plain = plain_matrix(n, d);
        let plain_build = seconds(t);
        let (ps, pn, pv, plain_ordering) = factor_and_solve(&plain);
        let plain_total = plain_build + ps + pn + pv;
        println!(
            "{label:<22} plain: build {plain_build:.3}s  symbolic {ps:.3}s  numeric {pn:.3}s  solve {pv:.3}s ({plain_ordering}) | assembly/factorisation {:.3} | hasse total / plain total {:.3}",
            assembly / (symbolic + numeric),
            hasse_total / plain_total
        );
    } else {
        // The Q1 matrix of the same grid built by hand, checked against
        // hasse's entry by entry (to rounding: Gauss points, mapped
        // gradients and A_c⁺ carry a few ulps), pinned the same way.
        let t = Instant::now();
        let plain = plain_q1_matrix(n, d);
        let plain_build = seconds(t);
        let plain = pin(&plain);
        let scale = plain.val().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let difference = max_difference(&matrix, &plain);
        assert!(
            difference <= 1e-12 * scale,
            "{label}: hasse's Q1 matrix and the hand-built one differ by {difference:e}"
        );
        let (ps, pn, pv, plain_ordering) = factor_and_solve(&plain);
        let plain_total = plain_build + ps + pn + pv;
        println!(
            "{label:<22} plain Q1: build {plain_build:.3}s  symbolic {ps:.3}s  numeric {pn:.3}s  solve {pv:.3}s ({plain_ordering}) | assembly/factorisation {:.3} | hasse total / plain total {:.3}",
            assembly / (symbolic + numeric),
            hasse_total / plain_total
        );
    }
    println!(
        "{label:<22} peak memory so far {:.2} GiB",
        peak_memory_gib()
    );
}

fn main() {
    // `cargo bench` passes --bench; `cargo test --all-targets` does not, and
    // then only a smoke-sized run checks that the benchmark still works.
    let args: Vec<String> = std::env::args().collect();
    let benching = args.iter().any(|a| a == "--bench");
    let small = args.iter().any(|a| a == "small");
    let (n2, n3) = match (benching, small) {
        (false, _) => (16, 4),
        (true, true) => (200, 20),
        (true, false) => (1000, 60),
    };
    let t = Instant::now();
    let square = generate::rectangle(n2, n2, [0.0, 1.0], [0.0, 1.0]).expect("grid");
    println!("2D {n2}x{n2} complex built in {:.3}s", seconds(t));
    run(&format!("2D {n2}x{n2}"), &square, n2, "fv");
    run(&format!("2D {n2}x{n2}"), &square, n2, "fe");
    drop(square);
    let t = Instant::now();
    let cube = generate::box3(n3, n3, n3, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).expect("grid");
    println!("3D {n3}^3 complex built in {:.3}s", seconds(t));
    run(&format!("3D {n3}^3"), &cube, n3, "fv");
    run(&format!("3D {n3}^3"), &cube, n3, "fe");
}
