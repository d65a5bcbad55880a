//! `kind = "hodge-decomposition"` in every degree and with the Whitney
//! star (the mixed saddle-point solve) through the `hasse` binary.

use crate::dec::{assert_check_refuses, numbers_after};
use crate::hasse::summary;
use std::error::Error;

type Result<T = ()> = std::result::Result<T, Box<dyn Error>>;

/// hodge-decomposition-box3d.toml (Kuhn box, Whitney star): the parts are
/// M-orthogonal and their squared norms add up, to 1e-12 relative
/// (rounding of refined solves); β₁ = 0 leaves no harmonic part (1e-10 of
/// ‖ω‖); and the exact and coexact norms approach the L² norms of
/// ∇(xyz), √(3 · 1/9) = 0.57735, and of curl A, π (∫ of each squared
/// component is π²/4, π²/2 and π²/4; the cross term ∫ sin²πy cos πz cos πx
/// vanishes), within 5% on 6 × 6 × 6 cubes (measured 0.5955, 3.1% above,
/// and 3.0821, 1.9% below; second order in h, see
/// tests/physics/hodge_decomposition.rs). Measured products ≤ 3.4e-17,
/// Pythagoras 1.4e-15, harmonic 4.9e-16.
#[test]
fn box_whitney_decomposition() -> Result {
    let out = summary("cases/hodge-decomposition-box3d.toml", &[]);
    let products = numbers_after(&out, "/ ‖ω‖² = ");
    assert_eq!(products.len(), 4, "{out}");
    assert!(products.iter().all(|p| *p < 1e-12), "{products:?}\n{out}");
    let total = numbers_after(&out, "‖ω‖_⋆ = ")[0];
    let exact = numbers_after(&out, "‖exact‖_⋆ = ")[0];
    let coexact = numbers_after(&out, "‖coexact‖_⋆ = ")[0];
    let harmonic = numbers_after(&out, "‖harmonic‖_⋆ = ")[0];
    assert!(harmonic < 1e-10 * total, "{out}");
    assert!((exact / (1.0f64 / 3.0).sqrt() - 1.0).abs() < 0.05, "{out}");
    assert!((coexact / std::f64::consts::PI - 1.0).abs() < 0.05, "{out}");
    assert!(out.contains("mixed saddle-point system"), "{out}");
    Ok(())
}

/// The other degrees of the same case: k = 2 (fluxes of F), k = 0 and
/// k = 3 (a scalar field). Orthogonality to 1e-12 in each. For k = 0 the
/// harmonic part is the M₀-mean of ω per component, here of the vertex
/// values of f = x + y + z: the Whitney 0-mass integrates the P1
/// interpolant exactly, which is f itself (linear), so the mean is
/// ∫f / |box| = 3/2 and its M₀-norm 3/2 · √|box| = 1.5. For k = 3 the box
/// has boundary, every 3-cochain is exact and the harmonic part is 0.
#[test]
fn box_decomposition_in_every_degree() -> Result {
    for (sets, harmonic_norm) in [
        (vec!["problem.degree=2"], None),
        (
            vec!["problem.degree=0", "problem.field=\"x + y + z\""],
            Some(1.5),
        ),
        (
            vec!["problem.degree=3", "problem.field=\"x*y*z\""],
            Some(0.0),
        ),
    ] {
        let out = summary("cases/hodge-decomposition-box3d.toml", &sets);
        let products = numbers_after(&out, "/ ‖ω‖² = ");
        assert_eq!(products.len(), 4, "{sets:?}: {out}");
        assert!(
            products.iter().all(|p| *p < 1e-12),
            "{sets:?}: {products:?}"
        );
        if let Some(expected) = harmonic_norm {
            let total = numbers_after(&out, "‖ω‖_⋆ = ")[0];
            let harmonic = numbers_after(&out, "‖harmonic‖_⋆ = ")[0];
            assert!(
                (harmonic - expected).abs() < 1e-12 * total,
                "{sets:?}: {out}"
            );
        }
    }
    Ok(())
}

/// A field that does not fit the degree, and a degree above the mesh's
/// dimension, are refused by `hasse check` (exit 2) at their keys.
#[test]
fn check_refuses_a_field_of_the_wrong_kind() -> Result {
    let refused = [
        (
            vec!["problem.degree=0"],
            "3 expression(s), but 0-cochains on this 3-dimensional mesh in R^3 are the de Rham map of a function",
        ),
        (
            vec!["problem.degree=2", "problem.field=\"x\""],
            "1 expression(s), but 2-cochains on this 3-dimensional mesh in R^3 are the de Rham map of a vector field (its fluxes through the faces)",
        ),
        (
            vec!["problem.degree=4"],
            "degree 4 is out of range: the mesh is 3-dimensional, so 0 ≤ degree ≤ 3",
        ),
    ];
    for (sets, message) in refused {
        assert_check_refuses("cases/hodge-decomposition-box3d.toml", &sets, message);
    }
    Ok(())
}

/// `cochain = "FILE"`: ω read as values instead of a field. An exact
/// cochain ω = d₀a (a the vertex values x y + z, d₀ the integer
/// coboundary of the same icosphere built here) is all exact part: the
/// exact part's norm equals ‖ω‖ and the other two vanish (d₁d₀ = 0 and
/// ⟨d a, h⟩ = 0 for every co-closed h, independent of the solves), to
/// 1e-12 relative. A file with a wrong count is refused by `hasse check`.
#[test]
fn a_cochain_read_from_a_file_is_decomposed() -> Result {
    use hasse_complex::generate::sphere;
    let dir = crate::scratch::Scratch::new("decomposition-cochain");
    std::fs::create_dir_all(&*dir)?;
    let mesh = sphere(1.0, 3)?;
    let a: Vec<f64> = (0..mesh.cell_count(0))
        .map(|v| {
            let p = mesh.vertices().point(v);
            p[0] * p[1] + p[2]
        })
        .collect();
    let omega: Vec<String> = mesh
        .coboundary(0)
        .outer_iterator()
        .map(|row| row.iter().map(|(j, &s)| f64::from(s) * a[j]).sum::<f64>())
        .map(|w| format!("{w:.17e}"))
        .collect();
    let file = dir.join("omega.txt");
    std::fs::write(&file, format!("# d₀(xy + z)\n{}\n", omega.join("\n")))?;
    let case = dir.join("exact.toml");
    std::fs::write(
        &case,
        "[mesh]\ngenerator = \"sphere\"\nsubdivisions = 3\n[problem]\nkind = \"hodge-decomposition\"\nmethod = \"dec\"\ncochain = \"omega.txt\"\n",
    )?;
    let case = case.to_str().ok_or("path")?;
    let out = summary(case, &[]);
    assert!(out.contains("ω from "), "{out}");
    let total = numbers_after(&out, "‖ω‖_⋆ = ")[0];
    let exact = numbers_after(&out, "‖exact‖_⋆ = ")[0];
    let coexact = numbers_after(&out, "‖coexact‖_⋆ = ")[0];
    let harmonic = numbers_after(&out, "‖harmonic‖_⋆ = ")[0];
    assert!((exact / total - 1.0).abs() < 1e-12, "{out}");
    assert!(coexact < 1e-12 * total && harmonic < 1e-12 * total, "{out}");

    // A cochain of the wrong length, and a field given as well.
    std::fs::write(&file, "1 2 3\n")?;
    assert_check_refuses(
        case,
        &[],
        "omega.txt holds 3 values, but the 1-cochain ω needs one per 1-cell: the mesh has 1920",
    );
    assert_check_refuses(
        case,
        &["problem.field=[\"x\", \"y\", \"z\"]"],
        "give ω either as a field (its de Rham cochain) or as a cochain file, not both",
    );
    Ok(())
}
