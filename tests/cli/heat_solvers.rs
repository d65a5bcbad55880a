//! Heat cases solved by multigrid-preconditioned CG and with adaptive
//! steps, through the `hasse` binary: the shipped case meets its exact
//! solution, the report holds the step sizes, the summary names the
//! solver, and bad combinations are refused at `hasse check`.

use crate::hasse::hasse;
use crate::scratch::Scratch;
use hdf5::types::VarLenUnicode;

const CASE: &str = "cases/heat-adaptive.toml";

fn report(stem: &std::path::Path) -> serde_json::Value {
    let file = hdf5::File::open(stem.with_extension("h5")).expect("the output file");
    let report = file
        .dataset("provenance/report")
        .expect("a run report")
        .read_scalar::<VarLenUnicode>()
        .expect("a string");
    serde_json::from_str(report.as_str()).expect("JSON")
}

/// On a 32×32 grid the FV error of the slow mode is about
/// (πh)²/12·u ≈ 8·10⁻⁴·u in the max norm (the five-point eigenvalue's
/// relative error, carried over t), so at t = 0.2, where u ≤ e^{−0.4π²}
/// ≈ 0.0193, the error must be below 5·10⁻⁵; a time error of the
/// tolerance per step (10⁻⁴ relative, over a few dozen steps) stays
/// below that.
#[test]
fn the_adaptive_multigrid_case_meets_its_exact_solution_with_growing_steps() {
    let dir = Scratch::new("heat_adaptive");
    let stem = dir.join("heat");
    let out = hasse(&[
        "run",
        CASE,
        "--set",
        "mesh.n=[32,32]",
        "-o",
        stem.to_str().expect("a UTF-8 path"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("CG with geometric multigrid"), "{stdout}");
    assert!(stdout.contains("adaptive steps"), "{stdout}");
    let report = report(&stem);
    let time = &report["time"];
    let sizes: Vec<f64> = time["adaptive"]["step_sizes"]
        .as_array()
        .expect("the accepted step sizes")
        .iter()
        .map(|v| v.as_f64().expect("a number"))
        .collect();
    assert_eq!(sizes.len() as u64, time["steps"].as_u64().expect("steps"));
    let total: f64 = sizes.iter().sum();
    assert!((total - 0.2).abs() < 1e-12, "steps add up to {total}");
    // The first step is dt or, rejected, a power-of-two part of it; once
    // the fast mode has died out the steps are far larger (the control
    // doubles them at most once a step).
    let first = 1e-4 / sizes[0];
    assert!(
        first >= 1.0 && first.log2().fract() == 0.0,
        "first step {:e}",
        sizes[0]
    );
    let largest = sizes.iter().fold(0.0f64, |m, &h| m.max(h));
    assert!(largest >= 1.6e-3, "largest step {largest:e}");
    for pair in sizes.windows(2) {
        assert!(pair[1] <= 2.0 * pair[0] * (1.0 + 1e-12), "{pair:?}");
    }
    assert!(sizes.len() < 2000 / 10, "{} steps", sizes.len());
    let iterations = &time["iterations"];
    assert!(
        iterations["max"].as_u64().expect("max iterations") <= 10,
        "{iterations}"
    );
    let errors = report["errors_per_level"]
        .as_array()
        .expect("errors per level");
    let last = errors.last().expect("a last level");
    assert!((last["time"].as_f64().expect("a time") - 0.2).abs() < 1e-12);
    let max = last["max"].as_f64().expect("the max error");
    assert!(max < 5e-5, "max error {max:e} at t = 0.2");
}

/// The direct path and multigrid take the same adaptive steps on the
/// same case: the step sizes depend only on the levels, which agree to
/// the CG tolerance.
#[test]
fn direct_and_multigrid_stepping_agree_on_the_adaptive_case() {
    let run = |solver: &str| {
        let dir = Scratch::new(&format!("heat_adaptive_{solver}"));
        let stem = dir.join("heat");
        let out = hasse(&[
            "run",
            CASE,
            "--set",
            "mesh.n=[16,16]",
            "--set",
            &format!("solver.type=\"{solver}\""),
            "-o",
            stem.to_str().expect("a UTF-8 path"),
            "-q",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        report(&stem)
    };
    let direct = run("direct");
    let multigrid = run("multigrid");
    assert_eq!(
        direct["time"]["adaptive"]["step_sizes"],
        multigrid["time"]["adaptive"]["step_sizes"]
    );
    assert!(direct["time"]["iterations"].is_null());
    let error = |r: &serde_json::Value| {
        r["errors_per_level"]
            .as_array()
            .and_then(|e| e.last())
            .and_then(|e| e["max"].as_f64())
            .expect("a last error")
    };
    // Levels agree to the CG tolerance (10⁻¹⁰ relative residual, on a
    // system with condition number below 10): far below the error itself.
    assert!((error(&direct) - error(&multigrid)).abs() < 1e-9 * error(&direct).max(1e-3));
}

#[test]
fn bad_adaptive_and_solver_settings_are_refused_at_check() {
    let dir = Scratch::new("heat_adaptive_refusals");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(CASE),
    )
    .expect("the shipped case");
    // θ < ½: the control's estimate does not know the scheme's error.
    let explicit = dir.join("explicit.toml");
    let replaced = text.replace("scheme = \"crank-nicolson\"", "theta = 0.25");
    assert_ne!(replaced, text);
    std::fs::create_dir_all(&*dir).expect("a scratch directory");
    std::fs::write(&explicit, replaced).expect("a scratch case");
    let explicit = explicit.to_str().expect("a UTF-8 path").to_string();
    for (case, sets, words) in [
        (
            explicit.as_str(),
            vec![],
            vec!["time.adaptive", "θ in [0.5, 1]", ":"],
        ),
        (
            CASE,
            vec!["time.adaptive.tolerance=0"],
            vec!["time.adaptive.tolerance", "(0, 1)"],
        ),
        (
            CASE,
            vec!["time.adaptive.tol=1e-3"],
            vec!["time.adaptive.tol", "did you mean `tolerance`"],
        ),
        (CASE, vec!["solver.type=\"petsc\""], vec!["solver.type"]),
    ] {
        let mut args = vec!["check", case];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let out = hasse(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{sets:?} was accepted");
        for w in words {
            assert!(stderr.contains(w), "{sets:?}: no `{w}` in\n{stderr}");
        }
    }
    // Elasticity still factorises: the iterative solvers serve diffusion
    // and heat.
    let out = hasse(&[
        "check",
        "cases/elasticity-square.toml",
        "--set",
        "solver.type=\"multigrid\"",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("diffusion and heat"), "{stderr}");
}

/// u = x + t solves ∂u/∂t − Δu = 1 on the unit square with u = t at
/// x = 0, u = 1 + t at x = 1 and no flux through y = 0, 1; every method
/// here reproduces it exactly (linear in space and time). The physical
/// flux −∇u·n is 1 out through x = 0 and −1 through x = 1. Cell-centred
/// FV reports exactly that at every level. Nodal FE reports the residual
/// flux f_v − (Aᵀ Ω A u)_v of the Dirichlet vertices, read as a steady
/// state at the level: the physical flux plus the source m_v f = m_v
/// loaded in their dual cells (whose storage m_v u̇ it would balance in
/// time), Σ m_v along a side being h/2 = 1/16.
#[test]
fn heat_fluxes_through_tags_are_reported_at_every_level_and_the_balance_closes() {
    let dir = Scratch::new("heat_fluxes");
    std::fs::create_dir_all(&*dir).expect("a scratch directory");
    let case = dir.join("plate.toml");
    std::fs::write(
        &case,
        r#"
[mesh]
generator = "rectangle"
n = [8, 4]

[problem]
kind = "heat"
method = "fv"
source = 1
initial = "x"

[[boundary]]
tag = "xmin"
type = "dirichlet"
value = "t"

[[boundary]]
tag = "xmax"
type = "dirichlet"
value = "1 + t"

[time]
dt = 0.05
steps = 4

[exact]
solution = "x + t"

[[output.quantity]]
type = "flux"
tag = "xmin"

[[output.quantity]]
type = "flux"
tag = "xmax"
"#,
    )
    .expect("a scratch case");
    for (method, xmin, xmax) in [
        ("fv", 1.0, -1.0),
        ("fe", 1.0 + 1.0 / 16.0, -1.0 + 1.0 / 16.0),
    ] {
        let stem = dir.join(format!("plate-{method}"));
        let m = format!("problem.method=\"{method}\"");
        let out = hasse(&[
            "run",
            case.to_str().expect("a UTF-8 path"),
            "--set",
            &m,
            "-o",
            stem.to_str().expect("a UTF-8 path"),
            "-q",
        ]);
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report = report(&stem);
        let quantities = report["quantities"].as_array().expect("quantities");
        for (q, want) in quantities.iter().zip([xmin, xmax]) {
            let values = q["values"].as_array().expect("a value per level");
            assert_eq!(values.len(), 5, "{method}: t = 0 and 4 steps");
            for v in values {
                let v = v.as_f64().expect("a number");
                assert!(
                    (v - want).abs() < 1e-12,
                    "{method} {}: {v} vs {want}",
                    q["name"]
                );
            }
        }
        let balance = report["balance"]["relative"].as_f64().expect("a balance");
        assert!(balance < 1e-12, "{method}: balance {balance:e}");
    }
}
