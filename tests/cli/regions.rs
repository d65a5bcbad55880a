//! Data per region (issue 29, item 1): conductivities and sources given
//! per tag of top cells, regions defined by conditions, and the refusals
//! of values that do not fit the mesh's tags, made by `hasse check`
//! before anything is solved.
//!
//! The exact solutions are derived by hand in `cases/two-materials.toml`
//! (piecewise linear, flux continuous across x = 1) and below (a source
//! on the left half only).

use crate::hasse::{hasse, summary};
use std::path::Path;

fn with_sets<'a>(mut args: Vec<&'a str>, sets: &[&'a str]) -> Vec<&'a str> {
    for s in sets {
        args.extend(["--set", s]);
    }
    args
}

/// The largest error at the unknowns' points, from the summary's `error`
/// line of `hasse run` (output off).
fn max_error(sets: &[&str]) -> f64 {
    max_error_of("cases/two-materials.toml", sets)
}

/// [`max_error`] of another case file.
fn max_error_of(case: &str, sets: &[&str]) -> f64 {
    let stdout = summary(case, sets);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("error "))
        .unwrap_or_else(|| panic!("no error line in:\n{stdout}"));
    let after = line.split("max ").nth(1).expect("a max error");
    after
        .split([',', ' '])
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("cannot read the max error of `{line}`"))
}

/// `hasse check` of the two-material case with overrides: must fail; its
/// stderr.
fn refused(sets: &[&str]) -> String {
    let args = with_sets(vec!["check", "cases/two-materials.toml"], sets);
    let out = hasse(&args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "hasse {args:?} should fail");
    stderr
}

/// A case on [0, 2] × [0, 1] (8 × 4 squares) with the regions `left`
/// (x < 1) and `right` (x > 1), then `body`, in a scratch directory (kept
/// while the returned guard lives); its path.
fn halves_case(name: &str, body: &str) -> (crate::scratch::Scratch, String) {
    let dir = crate::scratch::Scratch::new(name);
    std::fs::create_dir_all(&*dir).unwrap();
    let path = dir.join("halves.toml");
    std::fs::write(&path, format!("{HALVES}{body}")).unwrap();
    let path = path.to_str().unwrap().to_string();
    (dir, path)
}

const HALVES: &str = r#"[mesh]
generator = "rectangle"
n = [8, 4]
x = [0, 2]

[regions]
left = "x < 1"
right = "x > 1"

"#;

#[test]
fn two_materials_are_exact_for_methods_that_reproduce_piecewise_linear_fields() {
    // fe: nodal values; fv and fv-mimetic: cell (and face) values. The
    // solution is linear in each material with the interface on a mesh
    // line, so each is exact up to rounding (a few ulps of u ≤ 1, with
    // condition numbers ~ 20 · n²).
    for method in ["fe", "fv", "fv-mimetic"] {
        let set = format!("problem.method=\"{method}\"");
        let error = max_error(&[&set]);
        assert!(error < 1e-12, "{method}: max error {error:e}");
    }
    // The same plate on triangles (fe) is exact too.
    let error = max_error(&["mesh.cells=\"simplex\""]);
    assert!(error < 1e-12, "fe on triangles: max error {error:e}");
    // One conductivity everywhere is wrong by O(1): the check can fail.
    let uniform = max_error(&["problem.conductivity=1"]);
    assert!(uniform > 0.1, "uniform conductivity: max error {uniform:e}");
}

#[test]
fn a_source_per_region_is_integrated_over_its_own_cells() {
    // K = 1, f = 2 on x < 1 and 0 beyond, u(0) = u(2) = 0, insulated top
    // and bottom: u = 3x/2 − x² on [0, 1] and (2 − x)/2 on [1, 2] (u and
    // u′ continuous at 1). Q1 on a grid reduces to 1D P1, which is exact
    // at the nodes.
    let error = max_error(&[
        "problem.conductivity=1",
        "problem.source={ insulation = 2, default = 0 }",
        "boundary.1.value=0",
        "exact.solution=\"if(x < 1, 1.5*x - x^2, (2 - x)/2)\"",
    ]);
    assert!(error < 1e-12, "max error {error:e}");
}

#[test]
fn values_that_do_not_fit_the_regions_are_refused_before_solving() {
    // A cell in no listed region and no default: the first such cell,
    // and the tags of top cells the mesh has.
    let e = refused(&["problem.conductivity={ copper = 20 }"]);
    assert!(e.contains("`problem.conductivity`"), "{e}");
    assert!(e.contains("top cell 0"), "{e}");
    assert!(
        e.contains("the mesh's tags of top cells: copper, insulation"),
        "{e}"
    );
    // A region the mesh does not have.
    let e = refused(&["problem.conductivity={ steel = 1, default = 2 }"]);
    assert!(e.contains("no tag `steel` in the mesh"), "{e}");
    // A boundary tag is not a region.
    let e = refused(&["problem.source={ xmin = 1, default = 0 }"]);
    assert!(e.contains("tag `xmin` names 1-cells"), "{e}");
    // Overlapping regions give a cell two values.
    let e = refused(&[
        "regions.left_half=\"x < 1.5\"",
        "problem.conductivity={ copper = 20, left_half = 1 }",
    ]);
    assert!(e.contains("is in both `copper` and `left_half`"), "{e}");
    // A region defined by a condition may not reuse a tag's name, and
    // must select some cell.
    let e = refused(&["regions.xmin=\"x < 1\""]);
    assert!(
        e.contains("`regions.xmin`") && e.contains("already has a tag `xmin`"),
        "{e}"
    );
    let e = refused(&["regions.nowhere=\"x > 5\""]);
    assert!(e.contains("holds at no top cell's centroid"), "{e}");
    // Keys that take one expression say where tables are accepted.
    let e = refused(&["boundary.0.value={ copper = 1 }"]);
    assert!(
        e.contains("values per region") && e.contains("not accepted here"),
        "{e}"
    );
}

#[test]
fn heat_with_a_conductivity_per_region_settles_on_the_two_material_profile() {
    // Backward Euler from u = 0 with dt = 1000: each step divides the
    // slowest mode by 1 + λ₁ dt with λ₁ ≥ (π/4)²·1 for this plate, so
    // after 5 steps the transient is below (1 + 600)⁻⁵ ≈ 1e-14 of the steady profile of
    // `two-materials.toml`.
    // Heat takes no flux quantity (yet): the case without its quantities.
    let dir = crate::scratch::Scratch::new("regions_heat");
    std::fs::create_dir_all(&*dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("cases/two-materials.toml")).unwrap();
    let steady = text.split("[[output.quantity]]").next().unwrap();
    let case = dir.join("plate.toml");
    std::fs::write(&case, steady).unwrap();
    for method in ["fv", "fe"] {
        let set = format!("problem.method=\"{method}\"");
        let error = max_error_of(
            case.to_str().unwrap(),
            &[
                "problem.kind=\"heat\"",
                "problem.initial=0",
                "time.dt=1000",
                "time.steps=5",
                &set,
            ],
        );
        assert!(error < 1e-12, "heat {method}: max error {error:e}");
    }
}

/// Mixed Darcy with a permeability per region (`left` = 1, `right` = 20,
/// split at x = 1, a mesh line) and pressures 0 and 1 at the ends: the
/// exact pressure is piecewise linear, p = 20x/21 then 20/21 + (x − 1)/21,
/// with the same flux 20/21 in both (continuity of K p'). The mimetic and
/// barycentric flux masses reproduce a constant flux and a cell-wise linear
/// pressure, so both errors are rounding (ulps of p ≤ 1 times condition
/// numbers ~ 20 · n², far below 1e-12). A cell without a permeability is
/// refused by `hasse check` with the mesh's regions.
#[test]
fn darcy_takes_a_permeability_per_region() {
    let (_dir, case) = halves_case(
        "regions_darcy",
        r#"[problem]
kind = "darcy"
method = "mimetic"
permeability = { left = 1, right = 20 }
source = { left = 0, default = 0 }

[[boundary]]
tag = "xmin"
type = "pressure"
value = 0

[[boundary]]
tag = "xmax"
type = "pressure"
value = 1

[exact]
solution = "if(x < 1, 20*x/21, 20/21 + (x - 1)/21)"
gradient = ["if(x < 1, 20/21, 1/21)", "0"]
"#,
    );
    let case = case.as_str();
    for method in ["mimetic", "dec-barycentric"] {
        let set = format!("problem.method=\"{method}\"");
        let stdout = summary(case, &[&set]);
        let error = max_error_of(case, &[&set]);
        assert!(error < 1e-12, "{method}: max error {error:e}\n{stdout}");
        let flux = stdout
            .lines()
            .find_map(|l| l.strip_prefix("flux error L2 "))
            .and_then(|v| v.trim().parse::<f64>().ok())
            .unwrap_or_else(|| panic!("no flux error in\n{stdout}"));
        assert!(flux < 1e-12, "{method}: flux error {flux:e}\n{stdout}");
    }
    let out = hasse(&["check", case, "--set", "problem.permeability={ left = 1 }"]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{e}");
    assert!(
        e.contains("`problem.permeability`")
            && e.contains("the mesh's tags of top cells: left, right"),
        "{e}"
    );
}

/// A coupled pair with a, b, c per region: u = 1, v = ½ everywhere (the
/// Dirichlet data) solve −∇·∇u + a u − b v = f, −∇·∇v − b u + c v = g
/// exactly when f = a − b/2 and g = −b + c/2 in each region: left (a, b,
/// c) = (3, 1, 4) gives f = 2.5, g = 1; right (5, 2, 6) gives f = 4, g = 1.
/// Constants are in the kernel of every diffusion operator, and the
/// lumped reaction and the load share each cell's volume alike, so fe and
/// fv reproduce them to rounding; the regions swapped for a, the error is
/// of order one (measured 0.13), so the test sees the regions.
#[test]
fn coupled_reaction_coefficients_per_region() {
    let (_dir, case) = halves_case(
        "regions_coupled",
        r#"[problem]
kind = "coupled"
a = { left = 3, right = 5 }
b = { left = 1, right = 2 }
c = { left = 4, default = 6 }

[[field]]
name = "u"
method = "fe"
source = { left = 2.5, right = 4 }
exact = "1"

[[field.boundary]]
tag = "boundary"
type = "dirichlet"
value = 1

[[field]]
name = "v"
method = "fe"
source = 1
exact = "0.5"

[[field.boundary]]
tag = "boundary"
type = "dirichlet"
value = 0.5
"#,
    );
    let case = case.as_str();
    let max_errors = |sets: &[&str]| -> Vec<f64> {
        summary(case, sets)
            .lines()
            .filter(|l| l.starts_with("error "))
            .filter_map(|l| l.split("max ").nth(1)?.trim().parse().ok())
            .collect()
    };
    for method in ["fe", "fv"] {
        let sets = [
            format!("field.0.method=\"{method}\""),
            format!("field.1.method=\"{method}\""),
        ];
        let errors = max_errors(&[&sets[0], &sets[1]]);
        assert_eq!(errors.len(), 2, "{method}: {errors:?}");
        assert!(errors.iter().all(|e| *e < 1e-12), "{method}: {errors:?}");
    }
    let swapped = max_errors(&["problem.a={ left = 5, right = 3 }"]);
    assert!(swapped[0] > 0.1, "{swapped:?}");
    let out = hasse(&["check", case, "--set", "problem.a={ left = 3 }"]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{e}");
    assert!(
        e.contains("`problem.a`") && e.contains("is in none of the regions left"),
        "{e}"
    );
}

/// Conductivity tensors per region on the plate of
/// `cases/two-materials.toml` (exact solution derived there: u = 20x/21
/// for x ≤ 1, 20/21 + (x − 1)/21 beyond). With K = diag(1, 1) | diag(20,
/// 20) the problem is the scalar one. With K = diag(1, 7) | diag(20, ½)
/// it is still the same: u depends on x only and the plate is insulated
/// top and bottom, so only K_xx enters −(K_xx u′)′ = 0 and the flux
/// continuity K_xx u′ = 20/21. Both solutions are piecewise linear with
/// the interface on a mesh line, which fe and fv reproduce to rounding
/// (errors < 1e-12, as for the scalars in the test above); the scalar run
/// meets the same bound, so the runs agree to 2e-12.
#[test]
fn conductivity_tensors_per_region_reproduce_the_two_material_plate() {
    for conductivity in [
        "problem.conductivity={ insulation = [[1, 0], [0, 1]], copper = [[20, 0], [0, 20]] }",
        "problem.conductivity={ insulation = 1, copper = [[20, 0], [0, 20]] }",
        "problem.conductivity={ insulation = [[1, 0], [0, 7]], copper = [[20, 0], [0, 0.5]] }",
        "problem.conductivity={ insulation = [[1, 0], [0, \"7 + y\"]], default = [[20, 0], [0, 0.5]] }",
    ] {
        for method in ["fe", "fv", "fv-mimetic"] {
            let set = format!("problem.method=\"{method}\"");
            let error = max_error(&[&set, conductivity]);
            assert!(error < 1e-12, "{method}, {conductivity}: max error {error:e}");
        }
        // Triangles (P1) too.
        let error = max_error(&["mesh.cells=\"simplex\"", conductivity]);
        assert!(error < 1e-12, "fe on triangles, {conductivity}: {error:e}");
    }
    // The regions matter: swapped, the solution is another one.
    let swapped = max_error(&[
        "problem.conductivity={ insulation = [[20, 0], [0, 1]], copper = [[1, 0], [0, 20]] }",
    ]);
    assert!(swapped > 0.1, "swapped tensors: max error {swapped:e}");
}

/// A tensor per region is checked per cell as a global tensor is: not
/// symmetric (constant entries, when read), not positive definite
/// (K_yy = y − ½ < 0 at the lower cells' centroids), a region without a
/// value (with the mesh's tags), tensors of different sizes.
#[test]
fn tensors_per_region_that_do_not_fit_are_refused_before_solving() {
    let e = refused(&["problem.conductivity={ insulation = [[1, 0.5], [0, 1]], copper = 20 }"]);
    assert!(
        e.contains("`problem.conductivity.insulation`") && e.contains("not symmetric"),
        "{e}"
    );
    let e =
        refused(&["problem.conductivity={ insulation = [[1, 0], [0, \"y - 0.5\"]], copper = 20 }"]);
    assert!(
        e.contains("`problem.conductivity`") && e.contains("positive definite"),
        "{e}"
    );
    let e = refused(&["problem.conductivity={ copper = [[20, 0], [0, 20]] }"]);
    assert!(
        e.contains("top cell 0") && e.contains("the mesh's tags of top cells: copper, insulation"),
        "{e}"
    );
    let e = refused(&["problem.conductivity={ copper = [[20, 0], [0, 20]], default = [[1]] }"]);
    assert!(e.contains("a 2×2 tensor but `default` a 1×1 one"), "{e}");
}

/// Darcy's permeability takes tensors per region the same way: with
/// K = diag(1, 3) | diag(20, ⅕) and p depending on x only, the pressure and
/// flux are those of `darcy_takes_a_permeability_per_region` (only K_xx
/// acts), reproduced to rounding by the mimetic mixed method.
#[test]
fn darcy_takes_a_permeability_tensor_per_region() {
    let (_dir, case) = halves_case(
        "regions_darcy_tensor",
        r#"[problem]
kind = "darcy"
method = "mimetic"
permeability = { left = [[1, 0], [0, 3]], right = [[20, 0], [0, 0.2]] }
source = 0

[[boundary]]
tag = "xmin"
type = "pressure"
value = 0

[[boundary]]
tag = "xmax"
type = "pressure"
value = 1

[exact]
solution = "if(x < 1, 20*x/21, 20/21 + (x - 1)/21)"
gradient = ["if(x < 1, 20/21, 1/21)", "0"]
"#,
    );
    let stdout = summary(&case, &[]);
    let error = max_error_of(&case, &[]);
    assert!(error < 1e-12, "max error {error:e}\n{stdout}");
    let flux = stdout
        .lines()
        .find_map(|l| l.strip_prefix("flux error L2 "))
        .and_then(|v| v.trim().parse::<f64>().ok())
        .unwrap_or_else(|| panic!("no flux error in\n{stdout}"));
    assert!(flux < 1e-12, "flux error {flux:e}\n{stdout}");
}
