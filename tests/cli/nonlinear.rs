//! Nonlinear diffusion through the `hasse` binary: the shipped case
//! converges at second order with a `newton` summary line, the monitor
//! prints one line per iteration, a run that does not converge exits 1
//! with its residual history and writes nothing, and `hasse check`
//! refuses bad nonlinear input at its key.

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
