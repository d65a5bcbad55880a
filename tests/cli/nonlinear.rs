//! Nonlinear diffusion through the `hasse` binary: the shipped case
//! converges at second order with a `newton` summary line, the monitor
//! prints one line per iteration, a run that does not converge exits 1
//! with its residual history and writes nothing, and `hasse check`
//! refuses bad nonlinear input at its key; the same for nonlinear heat
//! (`kind = "heat"` with k(u) and r(u)), whose θ-scheme is measured
//! against the ODE u' = −u³ and a manufactured solution.

use crate::hasse::{hasse, summary};
use crate::scratch::Scratch;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

const CASE: &str = "cases/nonlinear-diffusion.toml";

/// The number after `label` on the summary line starting with `line`.
fn reported(stdout: &str, line: &str, label: &str) -> Result<f64> {
    let text = stdout
        .lines()
        .find(|l| l.starts_with(line))
        .ok_or_else(|| format!("no `{line}` line in\n{stdout}"))?;
    let after = text
        .split(label)
        .nth(1)
        .ok_or_else(|| format!("no `{label}` in `{text}`"))?;
    let word = after
        .split_whitespace()
        .next()
        .ok_or("nothing after the label")?;
    Ok(word.trim_end_matches(',').parse()?)
}

/// P1 (the case's method) is second order in L²: the quadrature L² error
/// falls by 2² per halving of h; over 16² → 32² the observed order must be
/// within DESIGN.md's ±0.15 of 2. Newton needs few steps from u = 0 (6
/// measured; quadratic convergence from 5 to 1e-14 cannot take many more).
#[test]
fn shipped_case_converges_at_second_order() -> Result {
    let monitor = "solver.nonlinear.monitor=false";
    let coarse = summary(CASE, &["mesh.n=[16,16]", monitor]);
    let fine = summary(CASE, &[monitor]);
    let order = (reported(&coarse, "error", "L2")? / reported(&fine, "error", "L2")?).log2();
    assert!(
        (order - 2.0).abs() < 0.15,
        "order {order}\n{coarse}\n{fine}"
    );
    let iterations = reported(&fine, "newton", "newton")?;
    assert!(iterations <= 8.0, "{fine}");
    assert!(fine.contains("1 symbolic analysis"), "{fine}");
    Ok(())
}

/// `monitor = true` (the shipped case's) prints `newton k:` lines on stderr,
/// one per iteration and one for the initial guess.
#[test]
fn monitor_prints_one_line_per_iteration() -> Result {
    let out = hasse(&["run", CASE, "--set", "output.write=false"]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines = stderr.lines().filter(|l| l.starts_with("newton ")).count();
    let iterations = reported(&stdout, "newton", "newton")?;
    assert_eq!(lines as f64, iterations + 1.0, "{stderr}");
    assert!(stderr.contains("rate"), "{stderr}");
    Ok(())
}

/// A reaction −20 eᵘ has no solution with these data (the Bratu problem's
/// λ_c is about 3.5 for the unit interval and 6.8 for the unit square, both
/// far below 20): Newton fails, the run exits 1 with the residual history
/// and leaves no output file.
#[test]
fn no_convergence_exits_1_without_output() -> Result {
    let dir = Scratch::new("nonlinear-no-convergence");
    let stem = dir.join("out");
    let stem_text = stem.to_str().ok_or("path")?;
    let out = hasse(&[
        "run",
        CASE,
        "--set",
        "problem.reaction=\"-20*exp(u)\"",
        "--set",
        "solver.nonlinear.max_iterations=5",
        "-o",
        stem_text,
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("newton did not converge"), "{stderr}");
    assert!(stderr.contains("residual history"), "{stderr}");
    assert!(stderr.matches('→').count() >= 5, "{stderr}");
    assert!(!stem.with_extension("h5").exists());
    assert!(!stem.with_extension("xdmf").exists());
    Ok(())
}

/// Bad input is refused by `hasse check` (exit 2) at its key.
#[test]
fn check_refuses_bad_nonlinear_input() {
    let cases: &[(&str, &[&str])] = &[
        // u where the solution is not allowed.
        (
            "problem.source=\"u*x\"",
            &[
                "`problem.source`",
                "unknown variable `u`",
                "only in the conductivity and reaction",
            ],
        ),
        // A key [solver.nonlinear] does not have.
        (
            "solver.nonlinear.maxiter=3",
            &[
                "`solver.nonlinear.maxiter`: unknown key",
                "did you mean `max_iterations`?",
            ],
        ),
        (
            "solver.nonlinear.method=\"secant\"",
            &["`solver.nonlinear.method`", "unknown nonlinear method"],
        ),
        // No derivative through if(…).
        (
            "problem.conductivity=\"if(u > 0, 1, 2)\"",
            &["`problem.conductivity`", "cannot differentiate"],
        ),
        // Methods without a diagonal Ω.
        (
            "problem.method=fv-mimetic",
            &["`problem.method`", "diagonal"],
        ),
    ];
    for (set, says) in cases {
        let out = hasse(&["check", CASE, "--set", set]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {stderr}");
        for s in *says {
            assert!(stderr.contains(s), "{set}: `{s}` not in {stderr}");
        }
    }
    // Q1 elements (P1 only): found with the mesh.
    let out = hasse(&["check", CASE, "--set", "mesh.cells=cuboid"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("not diagonal"), "{stderr}");
}

const HEAT: &str = "cases/nonlinear-heat.toml";

/// The ODE limit: with zero flux on the whole boundary (insulated), no
/// source and a uniform start u₀ = 1, every unknown follows u' = −u³ (the
/// differences Au vanish, so does the flux whatever k(u) is), whose
/// solution is u(t) = 1/√(1 + 2t). At t = 1 the θ-scheme's error is
/// O(Δt) for backward Euler and O(Δt²) for Crank–Nicolson (both are
/// consistent of those orders and stable for this dissipative ODE); over
/// Δt = 1/20, 1/40, 1/80 the observed orders must be within DESIGN.md's
/// ±0.15 of 1 and 2. `max` is the largest |u − exact| over the unknowns,
/// all equal here.
#[test]
fn heat_ode_limit_orders() -> Result {
    let sets = [
        "mesh.n=[2,2]",
        "problem.source=0",
        "problem.initial=1",
        "boundary.0.type=\"neumann\"",
        "boundary.0.value=0",
        "exact.solution=\"1/sqrt(1 + 2*t)\"",
        "time.end=1",
    ];
    for (scheme, expected) in [("backward-euler", 1.0), ("crank-nicolson", 2.0)] {
        let (mut h, mut e) = (Vec::new(), Vec::new());
        for steps in [20, 40, 80] {
            let dt = 1.0 / steps as f64;
            let scheme_set = format!("time.scheme=\"{scheme}\"");
            let dt_set = format!("time.dt={dt}");
            let mut all: Vec<&str> = sets.to_vec();
            all.extend([scheme_set.as_str(), dt_set.as_str()]);
            let out = summary(HEAT, &all);
            h.push(dt);
            e.push(reported(&out, "error", "max")?);
        }
        let p = crate::orders::order(&h, &e);
        eprintln!("{scheme}: errors at t = 1 {e:?}, order {p}");
        assert!(
            (p - expected).abs() < 0.15,
            "{scheme}: order {p}, errors {e:?}"
        );
    }
    Ok(())
}

/// The shipped case's manufactured solution u = 1 + e^(−t) w with
/// w = sin πx sin πy + xy (source and Dirichlet values both move with t),
/// Crank–Nicolson and Δt = 0.2/n refined with h = 1/n: the error at t = 0.2 is
/// O(h²) in space (P1 on triangles, the two-point flux on squares, both
/// second order at the unknowns' points) plus O(Δt²) = O(h²) in time, so
/// it falls by 2² per halving: the observed order over n = 16 → 32 must
/// be within ±0.15 of 2 for fe and fv. Newton needs few iterations per
/// step from the last level (3 measured; quadratic convergence from a
/// residual O(Δt) to 1e-10 cannot take more than 5).
#[test]
fn heat_manufactured_second_order() -> Result {
    for (method, cells) in [("fe", "simplex"), ("fv", "cuboid")] {
        let mut errors = Vec::new();
        for n in [16, 32] {
            let out = summary(
                HEAT,
                &[
                    &format!("problem.method={method}"),
                    &format!("mesh.cells={cells}"),
                    &format!("mesh.n=[{n},{n}]"),
                    &format!("time.dt={}", 0.2 / n as f64),
                    "time.end=0.2",
                ],
            );
            errors.push(reported(&out, "error", "L2")?);
            // "(3.0 per step, at most 3)": the digits after "at most ".
            let most: usize = out
                .split("at most ")
                .nth(1)
                .and_then(|t| t.split(|c: char| !c.is_ascii_digit()).next())
                .ok_or("no `at most` in the newton line")?
                .parse()?;
            assert!(most <= 5, "{out}");
            assert!(out.contains("1 symbolic analysis"), "{out}");
        }
        let order = (errors[0] / errors[1]).log2();
        assert!(
            (order - 2.0).abs() < 0.15,
            "{method}: order {order}, errors {errors:?}"
        );
    }
    Ok(())
}

/// `monitor = true` prints one `step n newton k:` line per iteration and
/// one for each step's starting guess: total iterations + steps lines.
#[test]
fn heat_monitor_prints_steps_and_iterations() -> Result {
    let out = hasse(&[
        "run",
        HEAT,
        "--set",
        "output.write=false",
        "--set",
        "solver.nonlinear.monitor=true",
    ]);
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let total = reported(&stdout, "newton", "newton")?;
    let lines = stderr.lines().filter(|l| l.starts_with("step ")).count();
    // 10 steps (dt = 0.025 to 0.25).
    assert_eq!(lines as f64, total + 10.0, "{stderr}");
    assert!(stderr.contains("step 10 newton   0:"), "{stderr}");
    Ok(())
}

/// A reaction 10 u⁵ and one iteration allowed: the first step cannot
/// reach the tolerance (its first residual is O(1) and Newton's first
/// step leaves a residual of the order of its square), so the run exits
/// 1 naming the step, its time and the residual history, and writes no
/// output (no level is streamed).
#[test]
fn heat_no_convergence_exits_1_without_output() -> Result {
    let dir = Scratch::new("nonlinear-heat-no-convergence");
    let stem = dir.join("out");
    let stem_text = stem.to_str().ok_or("path")?;
    let out = hasse(&[
        "run",
        HEAT,
        "--set",
        "problem.reaction=\"10*u^5\"",
        "--set",
        "solver.nonlinear.max_iterations=1",
        "-o",
        stem_text,
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("time step 1 (t = 0.025)"), "{stderr}");
    assert!(stderr.contains("newton did not converge"), "{stderr}");
    assert!(stderr.contains("residual history"), "{stderr}");
    // The directory may not even have been made; if it was, it is empty
    // (no final output, no partial output of completed levels).
    let left: Vec<_> = std::fs::read_dir(&*dir)
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.file_name()).collect())
        .unwrap_or_default();
    assert!(left.is_empty(), "files left: {left:?}");
    Ok(())
}

/// Bad nonlinear heat input is refused by `hasse check` (exit 2) at its
/// key, before stepping.
#[test]
fn check_refuses_bad_nonlinear_heat_input() {
    let cases: &[(&str, &[&str])] = &[
        (
            "problem.reaction=\"if(u > 0, u, 0)\"",
            &["`problem.reaction`", "cannot differentiate"],
        ),
        (
            "problem.conductivity=\"1 + u^2 + t\"",
            &["`problem.conductivity`", "may not depend on t"],
        ),
        (
            "problem.reaction=\"t*u^3\"",
            &["`problem.reaction`", "may not depend on t"],
        ),
        (
            "problem.source={ left = \"1\", default = \"0\" }",
            &["`problem.source`", "per region"],
        ),
        (
            "problem.conductivity={ left = \"2\", default = \"1\" }",
            &["`problem.conductivity`", "per region"],
        ),
        (
            "boundary.0.type=\"robin\"",
            &["`boundary[0].type`", "Robin"],
        ),
        (
            "time.adaptive={ tolerance = 1e-3 }",
            &["`time.adaptive`", "constant steps"],
        ),
        ("solver.type=\"multigrid\"", &["`solver.type`", "direct LU"]),
        // Q1 elements: Ω not diagonal, found with the mesh.
        ("mesh.cells=cuboid", &["`problem.method`", "not diagonal"]),
    ];
    for (set, says) in cases {
        let mut args = vec!["check", HEAT, "--set", set];
        if set.starts_with("boundary.0.type") {
            args.extend(["--set", "boundary.0.alpha=1"]);
        }
        let out = hasse(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {stderr}");
        for s in *says {
            assert!(stderr.contains(s), "{set}: `{s}` not in {stderr}");
        }
    }
}

/// θ = 0 (explicit) has no Newton step to take: `hasse check` refuses it
/// at `time.theta` with the mesh, before stepping.
#[test]
fn check_refuses_explicit_nonlinear_heat() -> Result {
    let dir = Scratch::new("nonlinear-heat-theta0");
    std::fs::create_dir_all(&*dir)?;
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(HEAT);
    let text =
        std::fs::read_to_string(shipped)?.replace("scheme = \"crank-nicolson\"", "theta = 0.0");
    let case = dir.join("theta0.toml");
    std::fs::write(&case, text)?;
    let out = hasse(&["check", case.to_str().ok_or("path")?]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("`time.theta`"), "{stderr}");
    assert!(stderr.contains("θ in (0, 1]"), "{stderr}");
    Ok(())
}

/// `[solver.nonlinear] linear = "krylov"` (Newton–Krylov) converges to the
/// solution of the default LU steps: both stop at a relative residual of
/// 1e-10 or below, so their L² errors against the exact solution agree to
/// far better than 1e-8 relative (measured: all printed digits equal), in
/// as many steps (6 here) and with one symbolic analysis (of the
/// preconditioner's LLᵀ instead of the LU).
#[test]
fn krylov_newton_steps_reach_the_direct_solution() -> Result {
    let direct = summary("cases/nonlinear-diffusion.toml", &[]);
    let krylov = summary(
        "cases/nonlinear-diffusion.toml",
        &["solver.nonlinear.linear=\"krylov\""],
    );
    let (a, b) = (
        reported(&direct, "error", "L2")?,
        reported(&krylov, "error", "L2")?,
    );
    assert!((a - b).abs() <= 1e-8 * a, "{direct}\n{krylov}");
    let steps = |out: &str| reported(out, "newton", "newton");
    assert_eq!(steps(&direct)?, steps(&krylov)?, "{direct}\n{krylov}");
    assert!(krylov.contains("1 symbolic analysis"), "{krylov}");
    // The multigrid-preconditioned variant: the same steps and error, and
    // no symbolic analysis of a Newton matrix (the V-cycle replaces the
    // LLᵀ; only its own coarsest level is factorised).
    let multigrid = summary(
        "cases/nonlinear-diffusion.toml",
        &["solver.nonlinear.linear=\"krylov-multigrid\""],
    );
    let c = reported(&multigrid, "error", "L2")?;
    assert!((a - c).abs() <= 1e-8 * a, "{direct}\n{multigrid}");
    assert_eq!(steps(&direct)?, steps(&multigrid)?, "{direct}\n{multigrid}");
    assert!(multigrid.contains("0 symbolic analysis"), "{multigrid}");
    Ok(())
}
