//! Poisson −Δu = f, u = 0 on the boundary, on the unit square/cube:
//! hasse's complex construction, assembly, direct solve and multigrid-CG
//! next to baselines in the same run.
//!
//! Every (case, phase) runs in a child process of its own so that its peak
//! memory (VmHWM) is its own. Structured cases `2d-N`, `3d-N` (N cells per
//! axis, cell-centred two-point flux) have the phases:
//!
//! - `mg`: complex, assembly (Ω, Aᵀ Ω A, b), multigrid setup and CG to
//!   relative residual 1e-8 (geometric hierarchy from the grid, continued
//!   algebraically down to 4000 unknowns), smoothed cell prolongation.
//! - `mg-pc`: the same with the piecewise-constant cell prolongation and
//!   the coarse correction doubled (sparser coarse levels, cheaper setup).
//! - `sa`: the same with smoothed aggregation from the matrix alone
//!   (`Hierarchy::Algebraic`, what `solver.type = "amg"` runs): the row
//!   to set against pyamg, which sees the same matrix.
//! - `direct`: complex, assembly, faer LLᵀ through hasse (analysis,
//!   factorisation, solve) with the automatic fill-reducing ordering.
//! - `solve`: complex, then `Diffusion::solve` as a case file runs it
//!   (the analysis of M's pattern beside the assembly, factorisation,
//!   solve, fluxes and checks), timed whole, with the automatic ordering
//!   or the one `HASSE_BENCH_ORDERING` names (`amd`, `nd`, `geometric`).
//! - `plain`: the same 5/7-point matrix built by hand as triplets and
//!   factorised with faer's own LLᵀ (AMD ordering), without hasse.
//! - `q1-solve`: complex, then nodal Q1 `Diffusion::solve` (u = 0 on the
//!   boundary vertices), timed whole, as `solve` for the cell-centred one.
//! - `q1-assembly`: complex, then the nodal Q1 `Diffusion::assemble`
//!   alone (geometry, Ω with the load, pattern, values, boundary data) on
//!   both cores: the assembly's own cost, which `q1-solve` overlaps with
//!   the analysis on the other core.
//! - `q1-plain`: the Q1 stiffness on the interior vertices built by hand
//!   from the element matrix of the square or cube, factorised with faer's
//!   own LLᵀ (AMD ordering), without hasse.
//! - `amd`, `nd`: the hand-built matrix factorised through hasse's
//!   `DirectSolver` with the AMD or the nested-dissection (METIS) ordering:
//!   analysis, factorisation, solve, factor entries and peak memory.
//! - `export`: the assembled matrix and right-hand side in Matrix Market
//!   format, for `scripts/pyamg_baseline.py` (pyamg smoothed aggregation).
//!
//! Unstructured cases `delaunay-COUNT` (≈ COUNT triangles, `k`/`m`
//! suffixes: `delaunay-1m`) triangulate a jittered grid of points with
//! `generate::delaunay` and solve nodal P1 (u = 0 on the hull), phases:
//!
//! - `amg`: complex, FE assembly, smoothed-aggregation multigrid
//!   (`Hierarchy::Algebraic`) and CG to relative residual 1e-8.
//! - `dec`: the same with DEC's circumcentric Hodge star (on a Delaunay
//!   mesh the same matrix, by a different assembly).
//! - `direct`: complex, FE assembly, LLᵀ through `solve_with_fixed`.
//! - `solve`: complex, then nodal P1 `Diffusion::solve`, timed whole (as
//!   the structured cases' `solve`).
//! - `plain`: the P1 cotangent matrix on the interior vertices built from
//!   coordinates and vertex triples alone, factorised by faer's own LLᵀ.
//! - `amd`, `nd`: that matrix through `DirectSolver` with AMD or nested
//!   dissection, as for the structured cases.
//! - `export`: the system on the interior vertices for pyamg.
//! - `check`: hasse's FE and DEC matrices, load and solution against the
//!   plain ones, entry by entry (it panics when they disagree).
//!
//! Unstructured 3D cases `kuhn-N` (N cubes per axis, each cut into 6
//! Kuhn tetrahedra, interior vertices moved by up to 0.2 of the shortest
//! edge at them, seed 1: the "perturbed Kuhn box" of the AMG tables) solve
//! nodal P1 (u = 0 on the boundary, (N − 1)³ unknowns), phases:
//!
//! - `amg`: complex, FE assembly, smoothed-aggregation multigrid
//!   (`Hierarchy::Algebraic`) and CG to relative residual 1e-8, with the
//!   solve's own peak memory (complex dropped) as for a Delaunay case.
//! - `export`: the system on the interior vertices for the baselines
//!   (pyamg, hypre through petsc4py).
//!
//! Each child prints one line `RESULT case phase key=value …`; the parent
//! (and `scripts/bench`) turn them into a table.
//!
//! `cargo bench --bench multigrid` runs 2D 1000², 3D 60³, 3D 100³ (the
//! direct phases of 100³ only with `HASSE_BENCH_DIRECT_100=1`: tens of GB
//! of fill and minutes) and the Delaunay mesh of 10⁶ triangles;
//! `HASSE_BENCH_LARGE=1` adds 2D 2000²; `HASSE_BENCH_CASES="delaunay-1m
//! 3d-60"` runs only the cases listed (any size: `delaunay-250k`, `2d-500`).
//! `cargo bench --bench multigrid -- CASE PHASE [DIR]` runs one phase
//! (`DIR`: where `export` writes).
//! Without `--bench` (as under `cargo test --all-targets`) it runs a 2D
//! 64², 3D 16³ and Delaunay 2·10⁴-triangle smoke test, and fails when a
//! phase fails.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use hasse_complex::dual::DualKind;
use hasse_complex::{generate, Complex};
use hasse_solver::la::direct::{relative_residual, DirectSolver, Factorization};
use hasse_solver::la::iterative::CgOptions;
use hasse_solver::la::ordering::Ordering;
use hasse_solver::metric::Method;
use hasse_solver::multigrid::{CellProlongation, Hierarchy, MultigridOptions};
use hasse_solver::physics::diffusion::{
    solve_with_fixed, Assembled, Diffusion, Iterative, Preconditioning,
};
use hasse_solver::physics::BoundaryKind;
use hasse_solver::physics::Conductivity;
use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

#[path = "common/measure.rs"]
mod measure;
use measure::{peak_memory_gib, plain_matrix, plain_q1_matrix, seconds};

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

fn phase(case: &str, phase: &str, dir: &str) -> String {
    if let Some(side) = parse_delaunay(case) {
        return delaunay_phase(case, side, phase, dir);
    }
    if let Some(n) = case.strip_prefix("kuhn-").and_then(|n| n.parse().ok()) {
        return kuhn_phase(case, n, phase, dir);
    }
    let (d, n) =
        parse_case(case).unwrap_or_else(|| panic!("case {case}: use 2d-N, 3d-N or delaunay-COUNT"));
    let started = Instant::now();
    let fields = match phase {
        "mg" | "mg-pc" | "sa" => {
            let (system, complex_s, assembly_s) = build(d, n);
            let cell_prolongation = if phase == "mg-pc" {
                CellProlongation::Constant { correction: 2.0 }
            } else {
                CellProlongation::Smoothed
            };
            let hierarchy = if phase == "sa" {
                Hierarchy::Algebraic
            } else {
                Hierarchy::Grid { cells: vec![n; d] }
            };
            let settings = Iterative {
                options: CgOptions {
                    tolerance: 1e-8,
                    max_iterations: 500,
                },
                initial: None,
                preconditioner: Preconditioning::Multigrid {
                    hierarchy,
                    options: MultigridOptions {
                        cell_prolongation,
                        ..MultigridOptions::default()
                    },
                },
            };
            // The complex is gone (`build` keeps the system alone): the
            // solve's peak is the matrix, b and the hierarchy, what the
            // baselines' processes hold.
            let reset = reset_peak_memory();
            let (_, report, cg) = solve_with_fixed(
                &system.matrix,
                &system.rhs,
                &system.fixed,
                Factorization::Llt,
                Ordering::Automatic,
                Some(&settings),
            )
            .expect("MG-CG");
            let solve_peak = if reset { peak_memory_gib() } else { f64::NAN };
            let cg = cg.expect("iterative report");
            format!(
                "unknowns={} complex={complex_s:.3} assembly={assembly_s:.3} setup={:.3} solve={:.3} iterations={} residual={:.2e} solve_peak_gib={solve_peak:.3}",
                report.unknowns, report.numeric_seconds, cg.seconds, cg.iterations, cg.relative_residual
            )
        }
        "direct" => {
            let (system, complex_s, assembly_s) = build(d, n);
            let t = Instant::now();
            let solver = DirectSolver::analyze(system.matrix.as_ref(), Factorization::Llt)
                .expect("analysis");
            let factor = solver.factorize(system.matrix.as_ref()).expect("SPD");
            let factor_s = seconds(t);
            let t = Instant::now();
            let x = factor.solve(&system.rhs).expect("solve");
            let solve_s = seconds(t);
            format!(
                "unknowns={} ordering={} complex={complex_s:.3} assembly={assembly_s:.3} analysis={:.3} factor={factor_s:.3} solve={solve_s:.3} entries={} residual={:.2e}",
                system.rhs.len(),
                short_name(solver.ordering()),
                solver.symbolic_seconds,
                solver.factor_entries().unwrap_or(0),
                relative_residual(system.matrix.as_ref(), &x, &system.rhs)
            )
        }
        "solve" | "q1-solve" => {
            // Diffusion::solve as a case file runs it: assembly with the
            // analysis beside it, factorisation, solve, fluxes and checks.
            let t = Instant::now();
            let complex = mesh(d, n);
            let complex_s = seconds(t);
            let problem = match phase {
                "solve" => problem(),
                _ => nodal_problem(Method::Fe),
            };
            format!("complex={complex_s:.3} {}", whole_solve(problem, &complex))
        }
        "q1-assembly" => {
            let t = Instant::now();
            let complex = mesh(d, n);
            let complex_s = seconds(t);
            let system = nodal_problem(Method::Fe)
                .assemble(&complex)
                .expect("assembly");
            format!(
                "unknowns={} complex={complex_s:.3} assembly={:.3} nnz={}",
                system.fixed.iter().filter(|g| g.is_none()).count(),
                system.assembly_seconds,
                system.matrix.compute_nnz(),
            )
        }
        "plain" | "q1-plain" => {
            let t = Instant::now();
            let matrix = match phase {
                "plain" => plain_matrix(n, d),
                _ => interior_block(&plain_q1_matrix(n, d), n, d),
            };
            let build_s = seconds(t);
            let rhs = plain_rhs(&matrix, n, d);
            let (x, factor_s, solve_s) = plain_faer_llt(&matrix, &rhs);
            format!(
                "unknowns={} assembly={build_s:.3} factor={factor_s:.3} solve={solve_s:.3} residual={:.2e}",
                rhs.len(),
                relative_residual(matrix.as_ref(), &x, &rhs)
            )
        }
        "amd" | "nd" => {
            let matrix = plain_matrix(n, d);
            let rhs = plain_rhs(&matrix, n, d);
            ordered_llt(&matrix, &rhs, phase)
        }
        "export" => {
            let (system, _, _) = build(d, n);
            let path = format!("{dir}/{case}");
            write_matrix_market(&format!("{path}.mtx"), &system.matrix).expect("write matrix");
            write_vector_market(&format!("{path}.rhs.mtx"), &system.rhs).expect("write rhs");
            format!("file={path}.mtx")
        }
        other => {
            panic!("unknown phase {other}: mg, mg-pc, direct, solve, plain, q1-solve, q1-assembly, q1-plain, amd, nd or export")
        }
    };
    format!(
        "RESULT {case} {phase} {fields} total={:.3} peak_gib={:.3}",
        seconds(started),
        peak_memory_gib()
    )
}

/// The block of a matrix on the (n + 1)^d grid vertices (numbered as in
/// `plain_q1_matrix`) off the boundary, renumbered in increasing order, as
/// the solve keeps it after dropping the Dirichlet vertices.
fn interior_block(m: &SparseColMat<usize, f64>, n: usize, d: usize) -> SparseColMat<usize, f64> {
    let side = n + 1;
    let mut index = vec![usize::MAX; m.nrows()];
    let mut free = 0;
    for (v, slot) in index.iter_mut().enumerate() {
        if (0..d).all(|a| (1..n).contains(&(v / side.pow(a as u32) % side))) {
            *slot = free;
            free += 1;
        }
    }
    block_on(m, &index, free)
}

/// The block of `m` on the unknowns with `index[i] != usize::MAX`, which
/// are numbered `index[i]` in it (`size` of them).
fn block_on(
    m: &SparseColMat<usize, f64>,
    index: &[usize],
    size: usize,
) -> SparseColMat<usize, f64> {
    let mut triplets = Vec::with_capacity(m.compute_nnz());
    for j in (0..m.ncols()).filter(|&j| index[j] != usize::MAX) {
        let range = m.col_range(j);
        for (&i, &v) in m.row_idx()[range.clone()].iter().zip(&m.val()[range]) {
            if index[i] != usize::MAX {
                triplets.push(Triplet::new(index[i], index[j], v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(size, size, &triplets).expect("valid triplets")
}

/// b = h^d: the load of f = 1 on a cell, and on an interior vertex of
/// the Q1 grid (a 2^−d share of each of its 2^d cells).
fn plain_rhs(matrix: &SparseColMat<usize, f64>, n: usize, d: usize) -> Vec<f64> {
    vec![1.0 / n.pow(d as u32) as f64; matrix.nrows()]
}

/// `Diffusion::solve` on `complex` with the bench's ordering, timed whole,
/// as `unknowns=… whole=… …` fields.
fn whole_solve(mut problem: Diffusion, complex: &Complex) -> String {
    problem.ordering = bench_ordering();
    let t = Instant::now();
    let solution = problem.solve(complex).expect("solve");
    let whole_s = seconds(t);
    let report = &solution.report;
    format!(
        "unknowns={} ordering={} whole={whole_s:.3} assembly={:.3} analysis={:.3} numeric={:.3} solve={:.3} beside={} entries={} flops={:.3e} residual={:.2e}",
        report.unknowns,
        short_name(report.ordering),
        solution.assembly_seconds,
        report.symbolic_seconds,
        report.numeric_seconds,
        report.solve_seconds,
        solution.analyzed_during_assembly,
        report.factor_entries.unwrap_or(0),
        report.factor_flops.unwrap_or(f64::NAN),
        report.relative_residual
    )
}

/// The ordering of the whole solves (`solve`, `q1-solve`, a Delaunay
/// case's `solve`): `HASSE_BENCH_ORDERING` = `auto` (the default), `amd`,
/// `nd` or `geometric`, to measure one ordering against another.
fn bench_ordering() -> Ordering {
    match std::env::var("HASSE_BENCH_ORDERING").as_deref() {
        Ok("amd") => Ordering::Amd,
        Ok("nd") => Ordering::NestedDissection,
        Ok("geometric") => Ordering::Geometric,
        Ok("auto") | Err(_) => Ordering::Automatic,
        Ok(other) => panic!("HASSE_BENCH_ORDERING={other}: use auto, amd, nd or geometric"),
    }
}

fn short_name(ordering: Option<Ordering>) -> &'static str {
    match ordering {
        Some(Ordering::NestedDissection) => "nd",
        Some(Ordering::Amd) => "amd",
        Some(Ordering::Geometric) => "geometric",
        _ => "other",
    }
}

/// LLᵀ of `matrix` through `DirectSolver` with the ordering of phase `amd`
/// or `nd`; the peak memory is the analysis, factorisation and solve's own
/// (the matrix build before it is forgotten).
fn ordered_llt(matrix: &SparseColMat<usize, f64>, rhs: &[f64], phase: &str) -> String {
    let ordering = match phase {
        "nd" => Ordering::NestedDissection,
        _ => Ordering::Amd,
    };
    let reset = reset_peak_memory();
    let t = Instant::now();
    let solver = DirectSolver::analyze_with(matrix.as_ref(), Factorization::Llt, ordering)
        .expect("analysis");
    let analysis_s = seconds(t);
    let t = Instant::now();
    let factor = solver.factorize(matrix.as_ref()).expect("SPD");
    let numeric_s = seconds(t);
    let t = Instant::now();
    let x = factor.solve(rhs).expect("solve");
    let solve_s = seconds(t);
    let residual = relative_residual(matrix.as_ref(), &x, rhs);
    assert!(residual <= 1e-10, "{phase}: relative residual {residual:e}");
    format!(
        "unknowns={} nnz={} ordering={} analysis={analysis_s:.3} numeric={numeric_s:.3} factor={:.3} solve={solve_s:.3} entries={} residual={residual:.2e} solve_peak_gib={:.3}",
        rhs.len(),
        matrix.compute_nnz(),
        short_name(solver.ordering()),
        analysis_s + numeric_s,
        solver.factor_entries().unwrap_or(0),
        if reset { peak_memory_gib() } else { f64::NAN },
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

/// A column vector in Matrix Market array format.
fn write_vector_market(path: &str, v: &[f64]) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(f, "%%MatrixMarket matrix array real general")?;
    writeln!(f, "{} 1", v.len())?;
    for x in v {
        writeln!(f, "{x:e}")?;
    }
    f.flush()
}

/// Every phase of a structured grid case, in the order they run.
const GRID_PHASES: [&str; 11] = [
    "mg",
    "mg-pc",
    "sa",
    "direct",
    "solve",
    "plain",
    "q1-solve",
    "q1-assembly",
    "q1-plain",
    "amd",
    "nd",
];
/// Every phase of a perturbed Kuhn case.
const KUHN_PHASES: [&str; 1] = ["amg"];
/// Every phase of a Delaunay case.
const DELAUNAY_PHASES: [&str; 8] = [
    "check", "amg", "dec", "direct", "solve", "plain", "amd", "nd",
];

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
            ("2d-1000", GRID_PHASES.to_vec()),
            ("3d-60", GRID_PHASES.to_vec()),
            (
                "3d-100",
                if env("HASSE_BENCH_DIRECT_100") {
                    vec!["mg", "mg-pc", "sa", "direct", "solve", "plain"]
                } else {
                    vec!["mg", "mg-pc", "sa"]
                },
            ),
            ("kuhn-80", KUHN_PHASES.to_vec()),
            ("delaunay-1m", DELAUNAY_PHASES.to_vec()),
        ]
    } else {
        vec![
            ("2d-64", GRID_PHASES.to_vec()),
            ("3d-16", GRID_PHASES.to_vec()),
            ("kuhn-12", KUHN_PHASES.to_vec()),
            ("delaunay-20k", DELAUNAY_PHASES.to_vec()),
        ]
    };
    if benching && env("HASSE_BENCH_LARGE") {
        cases.push(("2d-2000", GRID_PHASES.to_vec()));
    }
    // HASSE_BENCH_CASES="delaunay-1m 3d-60" runs only these cases, with
    // the listed phases, or all phases of their kind for other sizes.
    let only = std::env::var("HASSE_BENCH_CASES").unwrap_or_default();
    if benching && !only.trim().is_empty() {
        cases = only
            .split_whitespace()
            .map(|name| {
                cases
                    .iter()
                    .find(|(c, _)| *c == name)
                    .cloned()
                    .unwrap_or_else(|| {
                        let phases = if parse_delaunay(name).is_some() {
                            DELAUNAY_PHASES.to_vec()
                        } else if name.starts_with("kuhn-") {
                            KUHN_PHASES.to_vec()
                        } else {
                            GRID_PHASES.to_vec()
                        };
                        (name, phases)
                    })
            })
            .collect();
    }
    let exe = std::env::current_exe().expect("own executable");
    let mut failed = 0;
    for (case, phases) in cases {
        for p in phases {
            let out = std::process::Command::new(&exe)
                .args([case, p])
                .output()
                .expect("run a phase");
            let text = String::from_utf8_lossy(&out.stdout);
            match text.lines().find(|l| l.starts_with("RESULT")) {
                Some(line) if out.status.success() => println!("{line}"),
                _ => {
                    failed += 1;
                    let stderr = String::from_utf8_lossy(&out.stderr);
                    eprintln!("{stderr}");
                    // The panic message (the line after "panicked at"), not
                    // the backtrace after it; an abort (out of memory) says
                    // why on its first line.
                    let lines: Vec<&str> = stderr.lines().collect();
                    let reason = lines
                        .iter()
                        .position(|l| l.contains("panicked at"))
                        .and_then(|i| lines.get(i + 1))
                        .or(lines.first())
                        .map_or("no output", |l| l.trim());
                    println!("RESULT {case} {p} failed: {reason}");
                }
            }
        }
    }
    // A benchmark run keeps going past a failed phase (its line says so in
    // the table); the smoke run is a test and must fail.
    if failed > 0 && !benching {
        std::process::exit(1);
    }
}

// ---------------------------------------------------------------------------
// Unstructured case: nodal P1 Poisson on a Delaunay triangulation.

/// Points per side of the jittered grid for a case `delaunay-COUNT`
/// (`COUNT` ≈ triangles, with a `k` or `m` suffix: `delaunay-1m`).
fn parse_delaunay(case: &str) -> Option<usize> {
    let count = case.strip_prefix("delaunay-")?;
    let (digits, scale) = match count.as_bytes().last()? {
        b'k' => (&count[..count.len() - 1], 1_000.0),
        b'm' => (&count[..count.len() - 1], 1_000_000.0),
        _ => (count, 1.0),
    };
    let triangles = digits.parse::<f64>().ok()? * scale;
    // An s×s point set triangulates into 2s² − 4s + 2 triangles (interior
    // points count twice, the 4(s−1) hull points once, minus 2).
    Some(((triangles / 2.0).sqrt().round() as usize + 1).max(3))
}

/// xorshift64*: a fixed stream of uniform numbers in [0, 1), so that every
/// phase (and pyamg, through the export) sees the same mesh.
struct Xorshift(u64);

impl Xorshift {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A side×side grid on the unit square with every point moved by up to
/// ±0.35 h per coordinate: no two points come closer than 0.3 h and no
/// disc of radius h is empty, so the Delaunay triangles are well shaped,
/// yet the connectivity is irregular. Boundary points only move along
/// their side and the corners stay, so the hull is the square and its
/// vertices are exactly those with a coordinate 0 or 1.
fn jittered_points(side: usize) -> Vec<[f64; 2]> {
    let h = 1.0 / (side - 1) as f64;
    let mut rng = Xorshift(0x9E37_79B9_7F4A_7C15);
    let coordinate = |i: usize, rng: &mut Xorshift, moves: bool| {
        let jitter = 0.7 * (rng.next() - 0.5) * h;
        match i {
            0 => 0.0,
            i if i == side - 1 => 1.0,
            i if moves => i as f64 * h + jitter,
            i => i as f64 * h,
        }
    };
    let mut points = Vec::with_capacity(side * side);
    for j in 0..side {
        let edge_row = j == 0 || j == side - 1;
        for i in 0..side {
            let edge_column = i == 0 || i == side - 1;
            let x = coordinate(i, &mut rng, !edge_column);
            let y = coordinate(j, &mut rng, !edge_row);
            points.push([x, y]);
        }
    }
    points
}

fn on_square_boundary(p: [f64; 2]) -> bool {
    p.iter().any(|&x| x == 0.0 || x == 1.0)
}

fn nodal_problem(method: Method) -> Diffusion {
    Diffusion::new(
        method,
        Conductivity::Scalar(Arc::new(|_| 1.0)),
        Arc::new(|_| 1.0),
    )
    .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
}

/// The Delaunay complex of the case, with the seconds `delaunay` took.
fn delaunay_complex(side: usize) -> (Vec<[f64; 2]>, Complex, f64) {
    let points = jittered_points(side);
    let t = Instant::now();
    let complex = generate::delaunay(&points).expect("Delaunay triangulation");
    (points, complex, seconds(t))
}

fn triangles_of(complex: &Complex) -> Vec<[usize; 3]> {
    (0..complex.cell_count(2))
        .map(|c| {
            let v = complex.cell_vertices(2, c);
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// The system on the free unknowns as `solve_with_fixed` forms it (free
/// unknowns in increasing index order), for the export and the agreement
/// check. The Dirichlet values are 0, so b needs no lifting.
fn free_block(system: &Assembled) -> (SparseColMat<usize, f64>, Vec<f64>) {
    assert!(system.fixed.iter().flatten().all(|&g| g == 0.0));
    let mut index = vec![usize::MAX; system.fixed.len()];
    let mut rhs = Vec::new();
    for (i, g) in system.fixed.iter().enumerate() {
        if g.is_none() {
            index[i] = rhs.len();
            rhs.push(system.rhs[i]);
        }
    }
    let matrix = block_on(&system.matrix, &index, rhs.len());
    (matrix, rhs)
}

/// The P1 stiffness matrix and load (f = 1) on the vertices off the square's
/// boundary, numbered in increasing vertex order, built from coordinates
/// and triangles alone: per triangle K_ij = (e_i · e_j) / (4|T|) with e_i
/// the edge opposite vertex i, oriented around the triangle; load |T|/3.
fn plain_p1(
    points: &[[f64; 2]],
    triangles: &[[usize; 3]],
) -> (SparseColMat<usize, f64>, Vec<f64>, Vec<usize>) {
    let mut index = vec![usize::MAX; points.len()];
    let mut free = 0;
    for (i, &p) in points.iter().enumerate() {
        if !on_square_boundary(p) {
            index[i] = free;
            free += 1;
        }
    }
    let mut rhs = vec![0.0; free];
    let mut triplets = Vec::with_capacity(9 * triangles.len());
    for t in triangles {
        let p = t.map(|v| points[v]);
        let edge = |a: usize, b: usize| [p[b][0] - p[a][0], p[b][1] - p[a][1]];
        let e = [edge(1, 2), edge(2, 0), edge(0, 1)];
        let area = 0.5 * (e[2][0] * e[1][1] - e[2][1] * e[1][0]).abs();
        for a in 0..3 {
            let ia = index[t[a]];
            if ia == usize::MAX {
                continue;
            }
            rhs[ia] += area / 3.0;
            for b in 0..3 {
                let ib = index[t[b]];
                if ib != usize::MAX {
                    let k = (e[a][0] * e[b][0] + e[a][1] * e[b][1]) / (4.0 * area);
                    triplets.push(Triplet::new(ia, ib, k));
                }
            }
        }
    }
    let matrix =
        SparseColMat::try_new_from_triplets(free, free, &triplets).expect("valid triplets");
    let free_vertices = (0..points.len())
        .filter(|&i| index[i] != usize::MAX)
        .collect();
    (matrix, rhs, free_vertices)
}

/// ‖b − M x‖₂ / ‖b‖₂ for M in full (both triangles) CSC storage.
fn plain_residual(m: &SparseColMat<usize, f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut r = b.to_vec();
    for (j, &xj) in x.iter().enumerate() {
        let range = m.col_range(j);
        for (&i, &v) in m.row_idx()[range.clone()].iter().zip(&m.val()[range]) {
            r[i] -= v * xj;
        }
    }
    let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    norm(&r) / norm(b)
}

/// faer's own LLᵀ (lower triangle, faer's default ordering), timed:
/// (solution, analysis + factorisation seconds, solve seconds).
fn plain_faer_llt(m: &SparseColMat<usize, f64>, b: &[f64]) -> (Vec<f64>, f64, f64) {
    let t = Instant::now();
    let symbolic = SymbolicLlt::try_new(m.symbolic(), Side::Lower).expect("analysis");
    let llt = Llt::try_new_with_symbolic(symbolic, m.as_ref(), Side::Lower).expect("SPD");
    let factor_s = seconds(t);
    let t = Instant::now();
    let mut x = Mat::from_fn(b.len(), 1, |i, _| b[i]);
    llt.solve_in_place(x.as_mut());
    let solve_s = seconds(t);
    ((0..b.len()).map(|i| x[(i, 0)]).collect(), factor_s, solve_s)
}

/// Forget the peak memory so far (Linux ≥ 4.0: writing 5 to clear_refs
/// resets VmHWM to the current resident size), so that a phase's peak
/// leaves out the setup it does not time.
fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn algebraic_cg() -> Iterative {
    Iterative {
        options: CgOptions {
            tolerance: 1e-8,
            max_iterations: 500,
        },
        initial: None,
        preconditioner: Preconditioning::Multigrid {
            hierarchy: Hierarchy::Algebraic,
            options: MultigridOptions::default(),
        },
    }
}

/// Largest |a − b| over the entries, relative to the largest |a|; infinite
/// when the patterns differ.
fn matrix_difference(a: &SparseColMat<usize, f64>, b: &SparseColMat<usize, f64>) -> f64 {
    if a.nrows() != b.nrows() || a.col_ptr() != b.col_ptr() || a.row_idx() != b.row_idx() {
        return f64::INFINITY;
    }
    vector_difference(a.val(), b.val())
}

fn vector_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale
}

/// The perturbed Kuhn box of a case `kuhn-N`, with the seconds it took.
fn kuhn_complex(n: usize) -> (Complex, f64) {
    let t = Instant::now();
    let axis = generate::uniform_axis(n, 0.0, 1.0).expect("axis");
    let grid = generate::kuhn(&[axis.clone(), axis.clone(), axis]).expect("Kuhn box");
    let complex = generate::perturb(&grid, 0.2, 1).expect("perturbed Kuhn box");
    (complex, seconds(t))
}

fn kuhn_phase(case: &str, n: usize, phase: &str, dir: &str) -> String {
    let started = Instant::now();
    let (complex, complex_s) = kuhn_complex(n);
    let counts = format!(
        "vertices={} tetrahedra={} complex={complex_s:.3}",
        complex.cell_count(0),
        complex.cell_count(3)
    );
    let system = nodal_problem(Method::Fe)
        .assemble(&complex)
        .expect("assembly");
    let fields = match phase {
        "amg" => {
            // The baselines hold the matrix alone: the solve's own peak is
            // read with the complex gone, as in a Delaunay case.
            drop(complex);
            let build_peak = peak_memory_gib();
            let reset = reset_peak_memory();
            let (_, report, cg) = solve_with_fixed(
                &system.matrix,
                &system.rhs,
                &system.fixed,
                Factorization::Llt,
                Ordering::Automatic,
                Some(&algebraic_cg()),
            )
            .expect("AMG-CG");
            let solve_peak = if reset { peak_memory_gib() } else { f64::NAN };
            let cg = cg.expect("iterative report");
            assert!(cg.relative_residual <= 1e-8, "AMG-CG residual {cg:?}");
            format!(
                "{counts} unknowns={} nnz={} assembly={:.3} setup={:.3} solve={:.3} iterations={} residual={:.2e} build_peak_gib={build_peak:.3} solve_peak_gib={solve_peak:.3}",
                report.unknowns,
                report.nonzeros,
                system.assembly_seconds,
                report.numeric_seconds,
                cg.seconds,
                cg.iterations,
                cg.relative_residual
            )
        }
        "export" => {
            let (matrix, rhs) = free_block(&system);
            let path = format!("{dir}/{case}");
            write_matrix_market(&format!("{path}.mtx"), &matrix).expect("write matrix");
            write_vector_market(&format!("{path}.rhs.mtx"), &rhs).expect("write rhs");
            format!("{counts} file={path}.mtx")
        }
        other => panic!("unknown phase {other}: amg or export"),
    };
    format!(
        "RESULT {case} {phase} {fields} total={:.3} peak_gib={:.3}",
        seconds(started),
        peak_memory_gib()
    )
}

fn delaunay_phase(case: &str, side: usize, phase: &str, dir: &str) -> String {
    let started = Instant::now();
    if phase == "amd" || phase == "nd" {
        let (points, triangles) = {
            let (points, complex, _) = delaunay_complex(side);
            (points, triangles_of(&complex))
        };
        let (matrix, rhs, _) = plain_p1(&points, &triangles);
        drop((points, triangles));
        let fields = ordered_llt(&matrix, &rhs, phase);
        return format!(
            "RESULT {case} {phase} {fields} total={:.3} peak_gib={:.3}",
            seconds(started),
            peak_memory_gib()
        );
    }
    if phase == "plain" {
        // The triangles come from hasse's complex (spade is not a
        // dependency the benches can reach); everything after this block
        // uses only coordinates and vertex triples.
        let (points, triangles) = {
            let (points, complex, _) = delaunay_complex(side);
            (points, triangles_of(&complex))
        };
        let reset = reset_peak_memory();
        let t = Instant::now();
        let (matrix, rhs, _) = plain_p1(&points, &triangles);
        let build_s = seconds(t);
        let (x, factor_s, solve_s) = plain_faer_llt(&matrix, &rhs);
        let fields = format!(
            "unknowns={} nnz={} assembly={build_s:.3} factor={factor_s:.3} solve={solve_s:.3} residual={:.2e} peak_reset={reset}",
            rhs.len(),
            matrix.compute_nnz(),
            plain_residual(&matrix, &x, &rhs)
        );
        return format!(
            "RESULT {case} {phase} {fields} total={:.3} peak_gib={:.3}",
            seconds(started),
            peak_memory_gib()
        );
    }
    let (points, complex, complex_s) = delaunay_complex(side);
    let counts = format!(
        "vertices={} triangles={} complex={complex_s:.3}",
        complex.cell_count(0),
        complex.cell_count(2)
    );
    let method = match phase {
        "dec" => Method::Dec(DualKind::Circumcentric),
        _ => Method::Fe,
    };
    let fields = match phase {
        "solve" => {
            // Diffusion::solve as a case file runs it, timed whole.
            format!("{counts} {}", whole_solve(nodal_problem(method), &complex))
        }
        "amg" | "dec" | "direct" => {
            let Assembled {
                matrix,
                rhs,
                fixed,
                assembly_seconds,
                ..
            } = nodal_problem(method).assemble(&complex).expect("assembly");
            // What pyamg and the plain baseline hold is the matrix alone:
            // the solve's own peak is read with the complex and the
            // canonical factors (A, Ω) gone.
            drop((complex, points));
            let build_peak = peak_memory_gib();
            let reset = reset_peak_memory();
            let iterative = (phase != "direct").then(algebraic_cg);
            let t = Instant::now();
            let (_, report, cg) = solve_with_fixed(
                &matrix,
                &rhs,
                &fixed,
                Factorization::Llt,
                Ordering::Automatic,
                iterative.as_ref(),
            )
            .expect("solve");
            let call_s = seconds(t);
            let solve_peak = if reset { peak_memory_gib() } else { f64::NAN };
            let peaks = format!("build_peak_gib={build_peak:.3} solve_peak_gib={solve_peak:.3}");
            let common = format!(
                "{counts} unknowns={} nnz={} assembly={assembly_seconds:.3}",
                report.unknowns, report.nonzeros
            );
            match cg {
                Some(cg) => {
                    assert!(cg.relative_residual <= 1e-8, "AMG-CG residual {cg:?}");
                    format!(
                        "{common} setup={:.3} solve={:.3} iterations={} residual={:.2e} {peaks}",
                        report.numeric_seconds, cg.seconds, cg.iterations, cg.relative_residual
                    )
                }
                None => {
                    assert!(report.relative_residual <= 1e-10, "{report:?}");
                    // `call` adds the elimination of the Dirichlet rows and
                    // the residual check to analysis, factorisation and solve.
                    format!(
                        "{common} ordering={} analysis={:.3} factor={:.3} solve={:.3} call={call_s:.3} residual={:.2e} {peaks}",
                        short_name(report.ordering),
                        report.symbolic_seconds,
                        report.symbolic_seconds + report.numeric_seconds,
                        report.solve_seconds,
                        report.relative_residual
                    )
                }
            }
        }
        "export" => {
            let system = nodal_problem(method).assemble(&complex).expect("assembly");
            let (matrix, rhs) = free_block(&system);
            let path = format!("{dir}/{case}");
            write_matrix_market(&format!("{path}.mtx"), &matrix).expect("write matrix");
            write_vector_market(&format!("{path}.rhs.mtx"), &rhs).expect("write rhs");
            format!("{counts} file={path}.mtx")
        }
        "check" => {
            // hasse's free block keeps the vertex order and the plain
            // matrix numbers the same vertices in the same order, so the
            // two compare entry by entry, not only through invariants.
            let fe = nodal_problem(Method::Fe).assemble(&complex).expect("FE");
            let dec = nodal_problem(Method::Dec(DualKind::Circumcentric))
                .assemble(&complex)
                .expect("DEC");
            let (fe_matrix, fe_rhs) = free_block(&fe);
            let (dec_matrix, _) = free_block(&dec);
            let (plain, plain_rhs, free) = plain_p1(&points, &triangles_of(&complex));
            let hasse_free: Vec<usize> = (0..fe.fixed.len())
                .filter(|&i| fe.fixed[i].is_none())
                .collect();
            assert_eq!(
                hasse_free, free,
                "hasse's Dirichlet vertices (tag 'boundary') are not those on the square's sides"
            );
            let fe_diff = matrix_difference(&fe_matrix, &plain);
            let dec_diff = matrix_difference(&dec_matrix, &plain);
            let rhs_diff = vector_difference(&plain_rhs, &fe_rhs);
            let (x_hasse, _, _) = solve_with_fixed(
                &fe.matrix,
                &fe.rhs,
                &fe.fixed,
                Factorization::Llt,
                Ordering::Automatic,
                None,
            )
            .expect("LLᵀ");
            let (x_plain, _, _) = plain_faer_llt(&plain, &plain_rhs);
            let x_hasse: Vec<f64> = free.iter().map(|&i| x_hasse[i]).collect();
            let x_diff = vector_difference(&x_plain, &x_hasse);
            let fields = format!(
                "{counts} unknowns={} nnz={}/{} fe_vs_plain={fe_diff:.1e} dec_vs_plain={dec_diff:.1e} rhs_vs_plain={rhs_diff:.1e} solution_vs_plain={x_diff:.1e}",
                free.len(),
                fe_matrix.compute_nnz(),
                plain.compute_nnz()
            );
            assert!(
                fe_diff <= 1e-12 && dec_diff <= 1e-12 && rhs_diff <= 1e-12 && x_diff <= 1e-9,
                "hasse and the plain P1 system disagree: {fields}"
            );
            fields
        }
        other => panic!("unknown phase {other}: amg, dec, direct, plain, amd, nd, export or check"),
    };
    let build_peak = fields
        .split_whitespace()
        .find_map(|f| f.strip_prefix("build_peak_gib="))
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap_or(0.0);
    format!(
        "RESULT {case} {phase} {fields} total={:.3} peak_gib={:.3}",
        seconds(started),
        peak_memory_gib().max(build_peak)
    )
}
