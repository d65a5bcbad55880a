//! Advection–diffusion through the `hasse` binary: the shipped boundary
//! layer against its exact profile (first order, LU = GMRES = BiCGStab),
//! the rotating case keeps u in [0, 1] and its mass, and `hasse check`
//! refuses a method other than fv or fe, SUPG keys on fv, a velocity of
//! the wrong dimension and an inflow face without a Dirichlet value; the
//! shipped SUPG case is exact at the vertices where Galerkin oscillates.

use crate::hasse::{hasse, summary};

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

const LAYER: &str = "cases/transport-boundary-layer.toml";
const ROTATING: &str = "cases/transport-rotating.toml";
const SUPG: &str = "cases/transport-supg.toml";

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

/// Upwinding adds the numerical diffusion Pe h / 2 to −u'' + Pe u' = 0:
/// the max error against (e^{Pe(x−1)} − e^{−Pe})/(1 − e^{−Pe}) halves with
/// h once the cells resolve the layer well (cell Péclet ≪ 1; at the
/// shipped 200 cells, cell Péclet ½, the next halving gives only 0.81):
/// 800 → 1600 cells at Pe = 100 must give order 1 ± 0.15. The Krylov
/// solvers give LU's values to their tolerance 1e-12 (the same error to
/// printed digits) on the shipped mesh.
#[test]
fn boundary_layer_is_first_order_and_krylov_equals_lu() -> Result {
    let shipped = summary(LAYER, &[]);
    let coarse = summary(LAYER, &["mesh.n=[800,1]", "mesh.y=[0,0.00125]"]);
    let fine = summary(LAYER, &["mesh.n=[1600,1]", "mesh.y=[0,0.000625]"]);
    let order = (reported(&coarse, "error", "max")? / reported(&fine, "error", "max")?).log2();
    assert!(
        (order - 1.0).abs() < 0.15,
        "order {order}\n{coarse}\n{fine}"
    );
    // Cell Péclet Pe h = 0.5 on every cell of the shipped mesh.
    assert!(
        shipped.contains("cell Péclet |v|h/K 5.000e-1 to 5.000e-1"),
        "{shipped}"
    );
    let ec = reported(&shipped, "error", "max")?;
    for solver in ["gmres", "bicgstab"] {
        let krylov = summary(
            LAYER,
            &[
                &format!("solver.type=\"{solver}\""),
                "solver.tolerance=1e-12",
            ],
        );
        let e = reported(&krylov, "error", "max")?;
        assert!((e - ec).abs() <= 1e-9, "{solver}: {e} vs {ec}\n{krylov}");
        assert!(
            krylov.contains(&format!("{solver} with ILU(0)")),
            "{krylov}"
        );
    }
    // A V-cycle of the diffusion part as the preconditioner: the same.
    let multigrid = summary(
        LAYER,
        &[
            "solver.type=\"gmres\"",
            "solver.preconditioner=\"multigrid\"",
            "solver.tolerance=1e-12",
        ],
    );
    let e = reported(&multigrid, "error", "max")?;
    assert!(
        (e - ec).abs() <= 1e-9,
        "multigrid: {e} vs {ec}\n{multigrid}"
    );
    assert!(
        multigrid.contains("gmres with multigrid of the diffusion part"),
        "{multigrid}"
    );
    Ok(())
}

/// Pure advection with the limited scheme: the run keeps the mass Σ|c|u
/// while the rotating bodies stay inside the square (the Gaussian's tail at
/// the walls is below e^{−0.0625/0.005} ≈ 4e-6), and u within the initial
/// range [0, 1] (checked on the written last level).
#[test]
fn rotating_case_keeps_mass_and_bounds() -> Result {
    let dir = crate::scratch::Scratch::new("transport-rotating");
    let stem = dir.join("rot");
    let stem_text = stem.to_str().ok_or("path")?;
    // A quarter turn on the shipped mesh keeps the test short.
    let out = hasse(&["run", ROTATING, "--set", "time.steps=200", "-o", stem_text]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mass = stdout
        .lines()
        .find(|l| l.contains("mass Σ|c|u"))
        .ok_or("a mass line")?;
    let masses = mass
        .split("mass Σ|c|u")
        .nth(1)
        .and_then(|rest| rest.split(", u in").next())
        .ok_or("masses")?;
    let numbers: Vec<f64> = masses
        .split('→')
        .filter_map(|w| w.trim().parse().ok())
        .collect();
    let [first, last] = numbers[..] else {
        return Err(format!("two masses in `{mass}`").into());
    };
    assert!((first - last).abs() < 1e-5 * first, "{mass}");
    let courant: f64 = stdout
        .lines()
        .find(|l| l.contains("Courant"))
        .and_then(|l| l.split(" max ").nth(1))
        .and_then(|w| w.split_whitespace().next())
        .ok_or("a Courant line")?
        .parse()?;
    assert!(courant < 1.0, "{stdout}");
    let file = hdf5::File::open(stem.with_extension("h5"))?;
    // 200 steps of 0.00125 saving every 100th: t = 0, 0.125, 0.25.
    let times: Vec<f64> = file.attr("times")?.read_raw()?;
    assert_eq!(times.len(), 3, "{times:?}");
    let u: Vec<f64> = file.dataset("steps/2/u")?.read_raw()?;
    assert_eq!(u.len(), 50 * 50);
    let (lo, hi) = u
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    assert!(lo >= -1e-12 && hi <= 1.0 + 1e-12, "[{lo}, {hi}]");
    Ok(())
}

/// The shipped SUPG case: Q1 elements on the boundary layer at element
/// Péclet 5 (Pe = 200, h = 1/20, Pe_h = Pe h/2). SUPG with the optimal τ
/// is nodally exact in 1D (Brooks & Hughes 1982), and the Q1 strip with
/// insulated long sides is the 1D problem: the max vertex error is
/// rounding (≤ 1e-12). Plain Galerkin is central differencing there: the
/// nodal ratio (1 + Pe_h)/(1 − Pe_h) = −3/2 < 0 makes it oscillate, with
/// an error of order 1 (measured max 0.67 at the vertices), and the run
/// warns.
#[test]
fn supg_case_is_exact_at_the_vertices_and_galerkin_oscillates() -> Result {
    let supg = summary(SUPG, &[]);
    let error = reported(&supg, "error", "max")?;
    assert!(error <= 1e-12, "{supg}");
    assert!(
        supg.contains("element Péclet |v|h/(2K) 5.000e0 to 5.000e0"),
        "{supg}"
    );
    assert!(supg.contains("SUPG (optimal τ)"), "{supg}");
    let galerkin = summary(SUPG, &["problem.stabilisation=\"none\""]);
    let error = reported(&galerkin, "error", "max")?;
    assert!(error > 0.5, "{galerkin}");
    assert!(galerkin.contains("plain Galerkin oscillates"), "{galerkin}");
    // In time from u = x, backward Euler with dt = 0.01: the slowest mode
    // of the operator decays at a rate ≥ Pe²/4 = 10⁴, so each step damps
    // it by 1/(1 + 100) and 50 steps leave the steady, nodally exact
    // solution to rounding.
    let stepped = summary(
        SUPG,
        &[
            "problem.initial=\"x\"",
            "time.dt=0.01",
            "time.steps=50",
            "time.theta=1",
        ],
    );
    let error = reported(&stepped, "error", "max")?;
    assert!(error <= 1e-12, "{stepped}");
    assert!(
        stepped.contains("50 steps of dt = 0.01 (nodal elements, SUPG"),
        "{stepped}"
    );
    Ok(())
}

fn check_fails(sets: &[&str], expected: &str) -> Result {
    let mut args = vec!["check", LAYER];
    for s in sets {
        args.extend(["--set", s]);
    }
    let out = hasse(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(stderr.contains(expected), "{args:?}: {stderr}");
    Ok(())
}

#[test]
fn check_refuses_bad_transport_input() -> Result {
    check_fails(
        &["problem.method=dec"],
        "transport is discretised by cell-centred finite volumes (fv) or nodal finite elements (fe)",
    )?;
    // SUPG belongs to nodal elements; nodal elements are steady and need
    // diffusion.
    check_fails(
        &["problem.stabilisation=\"supg\""],
        "problem.stabilisation applies to nodal finite elements (method = \"fe\") only",
    )?;
    check_fails(
        &["problem.method=fe", "problem.conductivity=0"],
        "nodal finite elements (method = \"fe\") need a positive conductivity",
    )?;
    check_fails(
        &["problem.method=fe", "problem.scheme=\"upwind\""],
        "nodal elements (method = \"fe\") take problem.stabilisation",
    )?;
    check_fails(
        &["problem.velocity=[\"1\", \"0\", \"0\"]"],
        "`problem.velocity`: the velocity has 3 components, but the mesh lives in 2 dimensions",
    )?;
    // Reversed flow enters through x = 1, where the case gives a Dirichlet
    // value, and leaves through x = 0: fine. Flow along +y enters through
    // the bottom side, which has no condition.
    check_fails(
        &["problem.velocity=[\"0\", \"1\"]"],
        "flow enters the domain through face",
    )?;
    check_fails(
        &["solver.type=\"multigrid\""],
        "a transport system is nonsymmetric",
    )?;
    check_fails(
        &["problem.scheme=\"limited\""],
        "the limited scheme steps in time",
    )?;
    check_fails(
        &["solver.preconditioner=\"multigrid\""],
        "a preconditioner is chosen for solver.type = \"gmres\" or \"bicgstab\" only",
    )?;
    check_fails(
        &[
            "solver.type=\"gmres\"",
            "solver.preconditioner=\"multigrid\"",
            "problem.conductivity=0",
        ],
        "a pure advection problem has none",
    )?;
    let out = hasse(&[
        "check",
        LAYER,
        "--set",
        "problem.velocity=[\"-100\", \"0\"]",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Ok(())
}
