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

/// `method = "supplied"`: the stars of the rectangle [0, 2] × [0, 1]
/// written by hand for the unit square's 8 × 8 grid (a metric the mesh's
/// coordinates do not have): ⋆₀ the vertex's share of the cell area
/// hx·hy (halved per boundary axis), ⋆₁ = dual length / length (hy/hx on
/// x-edges, hx/hy on y-edges, halved on the boundary), ⋆₂ = 1/(hx·hy),
/// hx = 2/8, hy = 1/8. Δ₀ with natural conditions is then the
/// vertex-centred Neumann Laplacian of the stretched grid, whose spectrum
/// is exactly (4/hx²) sin²(mπ/16) + (4/hy²) sin²(lπ/16) (cosine
/// eigenvectors, the 1D identity 2 − 2cos θ = 4 sin²(θ/2) at interior and
/// boundary rows alike): the first six to 1e-12 (measured ≤ 1.2e-14;
/// the eigensolver's error in λ is of the order of its residual squared).
#[test]
fn supplied_stars_give_the_stretched_grids_spectrum() -> Result {
    use hasse_complex::generate::rectangle;
    const N: usize = 8;
    let (hx, hy) = (2.0 / N as f64, 1.0 / N as f64);
    let dir = crate::scratch::Scratch::new("supplied-stars");
    std::fs::create_dir_all(&*dir)?;
    let mesh = rectangle(N, N, [0.0, 1.0], [0.0, 1.0])?;
    let point = |v: usize| mesh.vertices().point(v).to_vec();
    let on_side = |t: f64| t.abs() < 1e-12 || (t - 1.0).abs() < 1e-12;
    let half = |on: bool| if on { 0.5 } else { 1.0 };
    let star0: Vec<f64> = (0..mesh.cell_count(0))
        .map(|v| {
            let p = point(v);
            hx * hy * half(on_side(p[0])) * half(on_side(p[1]))
        })
        .collect();
    let star1: Vec<f64> = (0..mesh.cell_count(1))
        .map(|e| {
            let ends = mesh.cell_vertices(1, e);
            let (a, b) = (point(ends[0]), point(ends[1]));
            if (a[1] - b[1]).abs() < 1e-12 {
                hy * half(on_side(a[1])) / hx
            } else {
                hx * half(on_side(a[0])) / hy
            }
        })
        .collect();
    let star2 = vec![1.0 / (hx * hy); mesh.cell_count(2)];
    let mut files = Vec::new();
    for (k, star) in [star0, star1, star2].iter().enumerate() {
        let name = format!("star{k}.txt");
        let text: Vec<String> = star.iter().map(|v| format!("{v:.17e}")).collect();
        std::fs::write(dir.join(&name), format!("# ⋆_{k}\n{}\n", text.join("\n")))?;
        files.push(format!("\"{name}\""));
    }
    let one_d =
        |h: f64, m: usize| 4.0 / (h * h) * (m as f64 * std::f64::consts::PI / 16.0).sin().powi(2);
    let mut exact: Vec<f64> = (0..=N)
        .flat_map(|m| (0..=N).map(move |l| (m, l)))
        .map(|(m, l)| one_d(hx, m) + one_d(hy, l))
        .filter(|&l| l > 1e-9)
        .collect();
    exact.sort_by(f64::total_cmp);
    let exact: Vec<String> = exact[..6].iter().map(|l| format!("{l:.17e}")).collect();
    let case = dir.join("stretched.toml");
    std::fs::write(
        &case,
        format!(
            "[mesh]\ngenerator = \"rectangle\"\nn = [{N}, {N}]\n[problem]\nkind = \"hodge-laplacian\"\nmethod = \"supplied\"\nstars = [{}]\ndegree = 0\nmodes = 6\n[exact]\neigenvalues = [{}]\n",
            files.join(", "),
            exact.join(", ")
        ),
    )?;
    let out = summary(case.to_str().ok_or("path")?, &[]);
    assert!(out.contains("dim ker Δ_0 = 1"), "{out}");
    let errors = relative_errors(&out);
    assert_eq!(errors.len(), 6, "{out}");
    assert!(errors.iter().all(|e| *e < 1e-12), "{errors:?}\n{out}");

    // A file with a wrong count is refused by `hasse check`, with its
    // name and both counts; stars with a computed method are refused.
    std::fs::write(dir.join("star1.txt"), "1 2 3\n")?;
    let out = hasse(&["check", case.to_str().ok_or("path")?]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("star1.txt holds 3 values, but ⋆_1 needs one per 1-cell: the mesh has 144"),
        "{stderr}"
    );
    let out = hasse(&[
        "check",
        case.to_str().ok_or("path")?,
        "--set",
        "problem.method=\"dec\"",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("star files are read only with method = \"supplied\""),
        "{stderr}"
    );
    Ok(())
}
