//! Poisson −Δu = f, u = 0 on the boundary, cell-centred (two-point flux)
//! on the unit square/cube: hasse's assembly, direct solve and
//! multigrid-CG next to baselines in the same run.
//!
//! Every (case, phase) runs in a child process of its own so that its peak
//! memory (VmHWM) is its own. Phases:
//!
//! - `mg`: complex, assembly (Ω, Aᵀ Ω A, b), multigrid setup and CG to
//!   relative residual 1e-8 (geometric hierarchy from the grid, continued
//!   algebraically down to 4000 unknowns), smoothed cell prolongation.
//! - `mg-pc`: the same with the piecewise-constant cell prolongation and
//!   the coarse correction doubled (sparser coarse levels, cheaper setup).
//! - `direct`: complex, assembly, faer LLᵀ through hasse (analysis,
//!   factorisation, solve).
//! - `plain`: the same 5/7-point matrix built by hand as triplets and
//!   factorised with faer LLᵀ, without hasse.
//! - `export`: the assembled matrix and right-hand side in Matrix Market
//!   format, for `scripts/pyamg_baseline.py` (pyamg smoothed aggregation).
//!
//! Each child prints one line `RESULT case phase key=value …`; the parent
//! (and `scripts/bench`) turn them into a table.
//!
//! `cargo bench --bench multigrid` runs 2D 1000², 3D 60³ and 3D 100³
//! (the direct phases of 100³ only with `HASSE_BENCH_DIRECT_100=1`: tens
//! of GB of fill and minutes); `HASSE_BENCH_LARGE=1` adds 2D 2000².
//! `cargo bench --bench multigrid -- CASE PHASE [DIR]` runs one phase
//! (`DIR`: where `export` writes). Without `--bench` (as under
//! `cargo test --all-targets`) it runs a 2D 64² and 3D 16³ smoke test.

use faer::sparse::{SparseColMat, Triplet};
use hasse_complex::{generate, Complex};
use hasse_solver::diffusion::{
    solve_with_fixed, Assembled, BoundaryKind, Conductivity, Diffusion, Iterative, Method,
    Preconditioning,
};
use hasse_solver::iterative::CgOptions;
use hasse_solver::linear::{relative_residual, DirectSolver, Factorization};
use hasse_solver::multigrid::{CellProlongation, Hierarchy, MultigridOptions};
use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

fn seconds(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Peak resident memory of this process so far, in GiB.
fn peak_memory_gib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map_or(f64::NAN, |kib| kib / (1024.0 * 1024.0))
}

/// (dimension, cells per axis) of a case name such as `3d-100`.
fn parse_case(case: &str) -> Option<(usize, usize)> {
    let (d, n) = case.split_once("d-")?;
    Some((d.parse().ok()?, n.parse().ok()?))
}

fn mesh(d: usize, n: usize) -> Complex {
    match d {
        2 => generate::rectangle(n, n, [0.0, 1.0], [0.0, 1.0]).expect("grid"),
        _ => generate::box3(n, n, n, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).expect("grid"),
    }
}

fn problem() -> Diffusion {
    Diffusion::new(
        Method::Fv,
        Conductivity::Scalar(Arc::new(|_| 1.0)),
        Arc::new(|_| 1.0),
    )
    .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
}

/// Complex and assembly, timed.
fn build(d: usize, n: usize) -> (Assembled, f64, f64) {
    let t = Instant::now();
    let complex = mesh(d, n);
    let complex_seconds = seconds(t);
    let system = problem().assemble(&complex).expect("assembly");
    let assembly_seconds = system.assembly_seconds;
    (system, complex_seconds, assembly_seconds)
}

/// The cell-centred 5/7-point operator on an n^d unit grid with Dirichlet
/// ghosts, as the two-point flux gives it (λ = 1): |F|/h between cells,
/// 2|F|/h at the boundary. Built without hasse.
fn plain_matrix(n: usize, d: usize) -> SparseColMat<usize, f64> {
    let h = 1.0 / n as f64;
    let face = h.powi(d as i32 - 1);
    let interior = face / h;
    let boundary = 2.0 * face / h;
    let cells = n.pow(d as u32);
    let stride: Vec<usize> = (0..d).map(|a| n.pow(a as u32)).collect();
    let mut triplets = Vec::with_capacity(cells * (2 * d + 1));
    for c in 0..cells {
        let mut diagonal = 0.0;
        for &step in &stride {
            let i = (c / step) % n;
            for (exists, other) in [(i > 0, c.wrapping_sub(step)), (i + 1 < n, c + step)] {
                if exists {
                    triplets.push(Triplet::new(c, other, -interior));
                    diagonal += interior;
                } else {
                    diagonal += boundary;
                }
            }
        }
        triplets.push(Triplet::new(c, c, diagonal));
    }
    SparseColMat::try_new_from_triplets(cells, cells, &triplets).expect("valid triplets")
}

fn phase(case: &str, phase: &str, dir: &str) -> String {
    let (d, n) = parse_case(case).unwrap_or_else(|| panic!("case {case}: use 2d-N or 3d-N"));
    let started = Instant::now();
    let fields = match phase {
        "mg" | "mg-pc" => {
            let (system, complex_s, assembly_s) = build(d, n);
            let cell_prolongation = if phase == "mg" {
                CellProlongation::Smoothed
            } else {
                CellProlongation::Constant { correction: 2.0 }
            };
            let settings = Iterative {
                options: CgOptions {
                    tolerance: 1e-8,
                    max_iterations: 500,
                },
                initial: None,
                preconditioner: Preconditioning::Multigrid {
                    hierarchy: Hierarchy::Grid { cells: vec![n; d] },
                    options: MultigridOptions {
                        cell_prolongation,
                        ..MultigridOptions::default()
                    },
                },
            };
            let (_, report, cg) = solve_with_fixed(
                &system.matrix,
                &system.rhs,
                &system.fixed,
                Factorization::Llt,
                Some(&settings),
            )
            .expect("MG-CG");
            let cg = cg.expect("iterative report");
            format!(
                "unknowns={} complex={complex_s:.3} assembly={assembly_s:.3} setup={:.3} solve={:.3} iterations={} residual={:.2e}",
                report.unknowns, report.numeric_seconds, cg.seconds, cg.iterations, cg.relative_residual
            )
        }
        "direct" => {
            let (system, complex_s, assembly_s) = build(d, n);
            let t = Instant::now();
            let solver = DirectSolver::analyse(system.matrix.as_ref(), Factorization::Llt)
                .expect("analysis");
            let factor = solver.factorize(system.matrix.as_ref()).expect("SPD");
            let factor_s = seconds(t);
            let t = Instant::now();
            let x = factor.solve(&system.rhs).expect("solve");
            let solve_s = seconds(t);
            format!(
                "unknowns={} complex={complex_s:.3} assembly={assembly_s:.3} factor={factor_s:.3} solve={solve_s:.3} residual={:.2e}",
                system.rhs.len(),
                relative_residual(system.matrix.as_ref(), &x, &system.rhs)
            )
        }
        "plain" => {
            let t = Instant::now();
            let matrix = plain_matrix(n, d);
            let build_s = seconds(t);
            let rhs = vec![n.pow(d as u32) as f64; matrix.nrows()]
                .iter()
                .map(|v| 1.0 / v)
                .collect::<Vec<_>>();
            let t = Instant::now();
            let solver =
                DirectSolver::analyse(matrix.as_ref(), Factorization::Llt).expect("analysis");
            let factor = solver.factorize(matrix.as_ref()).expect("SPD");
            let factor_s = seconds(t);
            let t = Instant::now();
            let x = factor.solve(&rhs).expect("solve");
            let solve_s = seconds(t);
            format!(
                "unknowns={} assembly={build_s:.3} factor={factor_s:.3} solve={solve_s:.3} residual={:.2e}",
                rhs.len(),
                relative_residual(matrix.as_ref(), &x, &rhs)
            )
        }
        "export" => {
            let (system, _, _) = build(d, n);
            let path = format!("{dir}/{case}");
            write_matrix_market(&format!("{path}.mtx"), &system.matrix).expect("write matrix");
            let mut f = std::io::BufWriter::new(
                std::fs::File::create(format!("{path}.rhs.mtx")).expect("create rhs"),
            );
            writeln!(f, "%%MatrixMarket matrix array real general").expect("write");
            writeln!(f, "{} 1", system.rhs.len()).expect("write");
            for v in &system.rhs {
                writeln!(f, "{v:e}").expect("write");
            }
            format!("file={path}.mtx")
        }
        other => panic!("unknown phase {other}: mg, direct, plain or export"),
    };
    format!(
        "RESULT {case} {phase} {fields} total={:.3} peak_gib={:.3}",
        seconds(started),
        peak_memory_gib()
    )
}

/// The lower triangle in Matrix Market coordinate format (symmetric).
fn write_matrix_market(path: &str, m: &SparseColMat<usize, f64>) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    let lower: usize = (0..m.ncols())
        .map(|j| {
            m.row_idx()[m.col_range(j)]
                .iter()
                .filter(|&&i| i >= j)
                .count()
        })
        .sum();
    writeln!(f, "%%MatrixMarket matrix coordinate real symmetric")?;
    writeln!(f, "{} {} {lower}", m.nrows(), m.ncols())?;
    for j in 0..m.ncols() {
        let range = m.col_range(j);
        for (&i, &v) in m.row_idx()[range.clone()].iter().zip(&m.val()[range]) {
            if i >= j {
                writeln!(f, "{} {} {v:e}", i + 1, j + 1)?;
            }
        }
    }
    f.flush()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let positional: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    if positional.len() >= 2 {
        let dir = positional.get(2).map_or(".", |s| s.as_str());
        println!("{}", phase(positional[0], positional[1], dir));
        return;
    }
    let benching = args.iter().any(|a| a == "--bench");
    let env = |k: &str| std::env::var(k).is_ok_and(|v| v == "1");
    let mut cases: Vec<(&str, Vec<&str>)> = if benching {
        vec![
            ("2d-1000", vec!["mg", "mg-pc", "direct", "plain"]),
            ("3d-60", vec!["mg", "mg-pc", "direct", "plain"]),
            (
                "3d-100",
                if env("HASSE_BENCH_DIRECT_100") {
                    vec!["mg", "mg-pc", "direct", "plain"]
                } else {
                    vec!["mg", "mg-pc"]
                },
            ),
        ]
    } else {
        vec![
            ("2d-64", vec!["mg", "mg-pc", "direct", "plain"]),
            ("3d-16", vec!["mg", "mg-pc", "direct", "plain"]),
        ]
    };
    if benching && env("HASSE_BENCH_LARGE") {
        cases.push(("2d-2000", vec!["mg", "mg-pc", "direct", "plain"]));
    }
    let exe = std::env::current_exe().expect("own executable");
    for (case, phases) in cases {
        for p in phases {
            let out = std::process::Command::new(&exe)
                .args([case, p])
                .output()
                .expect("run a phase");
            let text = String::from_utf8_lossy(&out.stdout);
            match text.lines().find(|l| l.starts_with("RESULT")) {
                Some(line) => println!("{line}"),
                None => println!(
                    "RESULT {case} {p} failed: {}",
                    String::from_utf8_lossy(&out.stderr)
                        .lines()
                        .last()
                        .unwrap_or("")
                ),
            }
        }
    }
}
