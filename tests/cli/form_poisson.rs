//! The Poisson problem for k-forms from case files (`kind = "diffusion"`
//! with `degree` ≥ 1) through the `hasse` binary.

use crate::dec::{assert_check_refuses, numbers_after};
use crate::hasse::{hasse, summary};
use std::error::Error;

type Result<T = ()> = std::result::Result<T, Box<dyn Error>>;

const CASE: &str = "cases/poisson-1-form.toml";

/// The L2 figure of a summary (‖u − R u‖_⋆).
fn l2(out: &str) -> f64 {
    let line = out.lines().find_map(|l| l.strip_prefix("error      L2 "));
    let figure = line.and_then(|l| l.split(',').next()?.trim().parse().ok());
    figure.unwrap_or_else(|| panic!("no L2 error in\n{out}"))
}

/// poisson-1-form.toml: u = ∇φ + curl ψ (its comment derives f and the
/// natural conditions by hand), both parts of Δ₁. The star-norm error of
/// the cochain halves twice per halving of h (second order; measured
/// 3.905e-2 → 9.758e-3 with the barycentric star on squares, 9.87e-2 →
/// 2.64e-2 for Whitney forms on Kuhn triangles), and is below 4% of
/// ‖u‖ = π √(5/4 + 1/2) ≈ 4.16 on the 16 × 16 mesh.
#[test]
fn one_forms_converge_at_second_order_from_a_case_file() -> Result {
    for method in [
        vec!["problem.method=\"dec-barycentric\""],
        vec!["problem.method=\"whitney\"", "mesh.cells=\"simplex\""],
        vec![
            "problem.method=\"whitney\"",
            "mesh.cells=\"simplex\"",
            "problem.boundary=\"essential\"",
            // u = ∇(sin πx sin 2πy) + curl(cos πx cos πy): zero tangential
            // trace and div u = −5π² sin πx sin 2πy = 0 on the boundary.
            "exact.solution=[\"pi*cos(pi*x)*sin(2*pi*y) - pi*cos(pi*x)*sin(pi*y)\", \"2*pi*sin(pi*x)*cos(2*pi*y) + pi*sin(pi*x)*cos(pi*y)\"]",
            "problem.source=[\"5*pi^2*pi*cos(pi*x)*sin(2*pi*y) - 2*pi^2*pi*cos(pi*x)*sin(pi*y)\", \"5*pi^2*2*pi*sin(pi*x)*cos(2*pi*y) + 2*pi^2*pi*sin(pi*x)*cos(pi*y)\"]",
        ],
    ] {
        let coarse = summary(CASE, &method);
        let mut finer = method.clone();
        finer.push("mesh.n=[32, 32]");
        let fine = summary(CASE, &finer);
        let order = (l2(&coarse) / l2(&fine)).log2();
        assert!(order > 1.85, "{method:?}: order {order}\n{coarse}\n{fine}");
        assert!(l2(&coarse) < 0.04 * 4.16, "{method:?}: {coarse}");
        assert!(coarse.contains("0 harmonic 1-forms"), "{coarse}");
    }
    Ok(())
}

/// On the annulus 1 < r < 2 the harmonic 1-form is ∇θ = (−y, x)/r². A
/// source that is only c∇θ has nothing in the range of Δ₁: its harmonic
/// part is all of it (ratio 1 to rounding: R∇θ is exactly discrete
/// harmonic on the polar mesh, see tests/physics/form_poisson.rs), the run
/// warns, and the solution is 0.
#[test]
fn a_harmonic_source_is_reported_and_taken_out() -> Result {
    let out = summary(
        CASE,
        &[
            "mesh.generator=\"annulus\"",
            "mesh.n=[8, 64]",
            "mesh.inner_radius=1.0",
            "mesh.outer_radius=2.0",
            "problem.source=[\"-3*y/(x^2 + y^2)\", \"3*x/(x^2 + y^2)\"]",
            "exact.solution=[\"0\", \"0\"]",
        ],
    );
    assert!(out.contains("1 harmonic 1-forms (β_1 = 1)"), "{out}");
    let ratio = numbers_after(&out, "‖P_ℌ f‖/‖f‖ = ")[0];
    assert!((ratio - 1.0).abs() < 1e-12, "{out}");
    assert!(
        out.contains("warning    the source has a harmonic part"),
        "{out}"
    );
    assert!(l2(&out) < 1e-12, "{out}");
    Ok(())
}

/// What `hasse check` refuses before solving, each with its key.
#[test]
fn check_refuses_what_a_form_problem_cannot_take() {
    // Keys of scalar diffusion.
    assert_check_refuses(
        CASE,
        &["problem.conductivity=2"],
        "`problem.conductivity`: not used by kind = \"diffusion\" with degree = 1",
    );
    // Two expressions for the 2-form of a 3D box (a flux field needs 3).
    assert_check_refuses(
        CASE,
        &[
            "mesh.generator=\"box\"",
            "mesh.n=[2, 2, 2]",
            "problem.degree=2",
        ],
        "2 expression(s), but 2-cochains on this 3-dimensional mesh",
    );
    // A degree above the mesh's dimension.
    assert_check_refuses(CASE, &["problem.degree=3"], "problem.degree");
    // An unknown boundary condition.
    assert_check_refuses(
        CASE,
        &["problem.boundary=\"dirichlet\""],
        "problem.boundary",
    );
}

/// [[boundary]] tables are refused: the condition is problem.boundary.
#[test]
fn boundary_tables_are_refused() -> Result {
    let dir = crate::scratch::Scratch::new("form-boundary-tables");
    std::fs::create_dir_all(&*dir)?;
    let case = dir.join("forms.toml");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join(CASE))?
        + "\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n";
    std::fs::write(&case, text)?;
    let out = hasse(&["check", case.to_str().ok_or("path")?]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("takes its one condition from problem.boundary"),
        "{stderr}"
    );
    Ok(())
}
