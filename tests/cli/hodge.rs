//! `kind = "hodge-laplacian"` through the `hasse` binary: the shipped
//! cases report the kernel next to the Betti number and the eigenvalues
//! their headers derive, and `hasse check` refuses a degree above the
//! mesh's dimension with the key's line before anything is solved.

use crate::hasse::{hasse, summary};
use std::error::Error;

type Result<T = ()> = std::result::Result<T, Box<dyn Error>>;

/// The relative errors of the modes table (fourth column).
fn relative_errors(stdout: &str) -> Vec<f64> {
    stdout
        .lines()
        .skip_while(|l| !l.starts_with("modes"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().nth(3)?.parse().ok())
        .collect()
}

/// hodge-sphere.toml: ker Δ₀ = constants (β₀ = 1); l = 1 (λ = 2, three
/// times) to 1e-6 relative on the 3-times subdivided icosphere (measured
/// 4.1e-7), l = 2 (λ = 6) within 1% (measured 5.7e-3, second order in h,
/// see tests/physics/forms.rs). Δ₁ there has no kernel (β₁ = 0).
#[test]
fn sphere_case_reports_kernel_and_spherical_harmonics() -> Result {
    let out = summary("cases/hodge-sphere.toml", &[]);
    assert!(
        out.contains("dim ker Δ_0 = 1 (eigenvalue 0 to rounding), β_0 = 1"),
        "{out}"
    );
    let errors = relative_errors(&out);
    assert_eq!(errors.len(), 8, "{out}");
    assert!(errors[..3].iter().all(|e| *e < 1e-6), "{errors:?}");
    assert!(errors[3..].iter().all(|e| *e < 1e-2), "{errors:?}");
    let out = summary(
        "cases/hodge-sphere.toml",
        &["problem.degree=1", "mesh.subdivisions=2"],
    );
    assert!(
        out.contains("dim ker Δ_1 = 0 (eigenvalue 0 to rounding), β_1 = 0"),
        "{out}"
    );
    Ok(())
}

/// hodge-torus-flat.toml: ker Δ₁ = β₁ = 2, and the four lowest nonzero
/// eigenvalues are (4/h²) sin²(π/16), the periodic five-point value, to
/// rounding (1e-12 relative).
#[test]
fn flat_torus_case_has_two_harmonic_forms() -> Result {
    let out = summary("cases/hodge-torus-flat.toml", &[]);
    assert!(
        out.contains("dim ker Δ_1 = 2 (eigenvalue 0 to rounding), β_1 = 2"),
        "{out}"
    );
    let errors = relative_errors(&out);
    assert_eq!(errors.len(), 4, "{out}");
    assert!(errors.iter().all(|e| *e < 1e-12), "{errors:?}");
    Ok(())
}

/// A degree above the dimension is refused by `hasse check` (exit 2) with
/// the override named; so is an unknown boundary condition, with the
/// closest name suggested.
#[test]
fn check_refuses_a_degree_out_of_range() -> Result {
    let out = hasse(&[
        "check",
        "cases/hodge-sphere.toml",
        "--set",
        "problem.degree=3",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--set problem.degree=3: `problem.degree`: degree 3 is out of range: the mesh is 2-dimensional, so 0 ≤ degree ≤ 2"),
        "{stderr}"
    );
    let out = hasse(&[
        "check",
        "cases/hodge-torus-flat.toml",
        "--set",
        "problem.boundary=essentail",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("did you mean \"essential\"?"), "{stderr}");
    Ok(())
}

/// Other kinds are refused on the flat torus, whose wrapped cells only
/// the forms layer measures unwrapped, at the generator's line.
#[test]
fn other_kinds_are_refused_on_the_flat_torus() -> Result {
    let dir = std::env::temp_dir().join(format!("hasse-cli-hodge-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let file = dir.join("flat-diffusion.toml");
    let text = "[mesh]\ngenerator = \"torus-flat\"\nn = [4, 4]\n[problem]\nmethod = \"fe\"\nsource = \"0\"\n";
    std::fs::write(&file, text)?;
    let shown = file.to_string_lossy().into_owned();
    let out = hasse(&["check", &shown]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("{shown}:2:13: `mesh.generator`: a periodic mesh")),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
