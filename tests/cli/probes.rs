//! Probes (issue 29, item 3): the solution at points and along lines as
//! each method represents it, against values derived by hand:
//!
//! - `cases/two-materials.toml` has the exact solution u = 20x/21 on
//!   x ≤ 1 and 20/21 + (x − 1)/21 beyond, linear in each cell, so P1/Q1
//!   interpolation and the hybrid method's cell value plus face-fitted
//!   gradient reproduce it everywhere;
//! - `cases/poisson-square.toml` (u = sin πx sin πy): a Q1 probe is off by
//!   at most the nodal error plus the interpolation error,
//!   h²/8 (|u_xx| + |u_yy|) ≤ 2π²/(8·32²) = 2.4e-3 at h = 1/32.

use crate::hasse::hasse;
use crate::scratch::Scratch;
use std::path::Path;

/// `case` with `extra` appended, in a scratch directory.
fn case_with(dir: &Path, case: &str, extra: &str) -> String {
    std::fs::create_dir_all(dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join(case)).unwrap();
    let path = dir.join("probed.toml");
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    path.to_str().unwrap().to_string()
}

/// Run with output to `stem`; the rows of `<stem>.probes.csv` after the
/// header, split at commas.
fn probe_rows(case: &str, stem: &Path, sets: &[&str]) -> Vec<Vec<String>> {
    let mut args = vec!["run", case, "-q", "-o", stem.to_str().unwrap()];
    for s in sets {
        args.extend(["--set", s]);
    }
    let out = hasse(&args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut name = stem.file_name().unwrap().to_os_string();
    name.push(".probes.csv");
    let csv = std::fs::read_to_string(stem.with_file_name(name)).unwrap();
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

fn exact_plate(x: f64) -> f64 {
    if x <= 1.0 {
        20.0 * x / 21.0
    } else {
        20.0 / 21.0 + (x - 1.0) / 21.0
    }
}

const PLATE_PROBES: &str = r#"
[[output.probe]]
name = "vertex"
at = [1.25, 0.5]

[[output.probe]]
name = "line"
from = [0.0, 0.3]
to = [2.0, 0.3]
points = 9
"#;

#[test]
fn probes_reproduce_the_piecewise_linear_plate() {
    let dir = Scratch::new("probes_plate");
    let case = case_with(&dir, "cases/two-materials.toml", PLATE_PROBES);
    for method in ["fe", "fv-mimetic"] {
        let set = format!("problem.method=\"{method}\"");
        let rows = probe_rows(&case, &dir.join(method), &[&set]);
        assert_eq!(
            rows.len(),
            1 + 9,
            "{method}: the point and the line's 9 points"
        );
        for row in &rows {
            let (x, u): (f64, f64) = (row[2].parse().unwrap(), row[4].parse().unwrap());
            assert!((u - exact_plate(x)).abs() < 1e-12, "{method}: {row:?}");
        }
    }
    // A probe at a vertex is the nodal value itself, bit for bit: vertex
    // (1.25, 0.5) of the 8 × 4 grid on [0, 2] × [0, 1], numbered by the
    // library's generator.
    let mesh = hasse_complex::generate::rectangle(8, 4, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let v = (0..mesh.cell_count(0))
        .find(|&v| mesh.vertices().point(v) == [1.25, 0.5])
        .unwrap();
    let rows = probe_rows(&case, &dir.join("fe-vertex"), &[]);
    let file = hdf5::File::open(dir.join("fe-vertex.h5")).unwrap();
    let u = file
        .dataset("steps/0/u")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    assert_eq!(rows[0][4], format!("{:e}", u[v]));
}

#[test]
fn probes_are_within_the_methods_error_on_a_smooth_solution() {
    let dir = Scratch::new("probes_smooth");
    let extra = "[[output.probe]]\nat = [0.3, 0.7]\n\n[[output.probe]]\nat = [0.51, 0.49]\n";
    let case = case_with(&dir, "cases/poisson-square.toml", extra);
    let exact =
        |x: f64, y: f64| (std::f64::consts::PI * x).sin() * (std::f64::consts::PI * y).sin();
    // fe: nodal error 8.0e-4 (the README's summary) plus 2.4e-3 of Q1
    // interpolation; fv: cell value plus gradient, the same O(h²) bound.
    for method in ["fe", "fv"] {
        let set = format!("problem.method=\"{method}\"");
        for row in probe_rows(&case, &dir.join(method), &[&set]) {
            let (x, y, u): (f64, f64, f64) = (
                row[2].parse().unwrap(),
                row[3].parse().unwrap(),
                row[4].parse().unwrap(),
            );
            let error = (u - exact(x, y)).abs();
            // A cell's value alone would be off by up to h|∇u| ≈ 0.05.
            assert!(error < 3.2e-3, "{method} at ({x}, {y}): error {error:e}");
        }
    }
}

#[test]
fn heat_probes_record_every_saved_level() {
    let dir = Scratch::new("probes_heat");
    let case = case_with(
        &dir,
        "cases/heat-square.toml",
        "[[output.probe]]\nat = [0.5, 0.5]\n",
    );
    let rows = probe_rows(&case, &dir.join("heat"), &[]);
    // One row per saved level, each with its time first.
    let h5 = hdf5::File::open(dir.join("heat.h5")).unwrap();
    let levels = h5.group("steps").unwrap().member_names().unwrap().len();
    assert_eq!(rows.len(), levels);
    let times: Vec<f64> = rows.iter().map(|r| r[0].parse().unwrap()).collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
}

#[test]
fn probes_outside_the_mesh_are_refused_with_their_point() {
    let dir = Scratch::new("probes_outside");
    let case = case_with(
        &dir,
        "cases/two-materials.toml",
        "[[output.probe]]\nfrom = [1.0, 0.5]\nto = [3.0, 0.5]\npoints = 3\n",
    );
    let out = hasse(&["check", &case]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("the probe point [3.0, 0.5] (point 2 of the line) is outside the mesh"),
        "{stderr}"
    );
    let bad = case_with(
        &dir,
        "cases/two-materials.toml",
        "[[output.probe]]\nat = [0.5]\nto = [1, 1]\n",
    );
    let stderr = String::from_utf8_lossy(&hasse(&["check", &bad]).stderr).into_owned();
    assert!(
        stderr.contains("a probe is a point, `at = [x, y]`, or a line"),
        "{stderr}"
    );
}

/// The Hodge decomposition of the constant field F = (2, −1) on the unit
/// square: ω = R₁F is exact (F = ∇(2x − y) and the square has β₁ = 0), so
/// the exact part is ω and the coexact and harmonic parts vanish. The
/// Whitney map reproduces constant 1-forms on every triangle, and the
/// least-squares vector of a square is exact for constant fields, so a
/// probe of `omega` and of `exact` anywhere is (2, −1) to rounding of the
/// Poisson solve (≈ 1e-15 × cond; 1e-10 leaves room for it at h = 1/8),
/// and the other parts are 0 to the same tolerance.
#[test]
fn form_probes_reproduce_a_constant_field_by_its_whitney_vector() {
    let dir = Scratch::new("probes_forms");
    std::fs::create_dir_all(&*dir).unwrap();
    for (cells, method) in [
        ("simplex", "dec-barycentric"),
        ("cuboid", "dec-barycentric"),
    ] {
        let case = dir.join(format!("decomposition-{cells}.toml"));
        std::fs::write(
            &case,
            format!(
                r#"[mesh]
generator = "rectangle"
n = [8, 8]
cells = "{cells}"

[problem]
kind = "hodge-decomposition"
method = "{method}"
field = ["2", "-1"]

[[output.probe]]
name = "inside"
at = [0.3, 0.7]

[[output.probe]]
name = "diagonal"
from = [0.0, 0.0]
to = [1.0, 1.0]
points = 5
"#
            ),
        )
        .unwrap();
        let stem = dir.join(format!("out-{cells}"));
        let rows = probe_rows(case.to_str().unwrap(), &stem, &[]);
        assert_eq!(rows.len(), 6, "{rows:?}");
        let mut name = stem.file_name().unwrap().to_os_string();
        name.push(".probes.csv");
        let csv = std::fs::read_to_string(stem.with_file_name(name)).unwrap();
        let header = csv.lines().next().unwrap();
        assert_eq!(
            header,
            "probe,point,x,y,omega_x,omega_y,exact_x,exact_y,coexact_x,coexact_y,harmonic_x,harmonic_y",
            "{cells}"
        );
        for row in &rows {
            let v: Vec<f64> = row[4..].iter().map(|s| s.parse().unwrap()).collect();
            let expected = [2.0, -1.0, 2.0, -1.0, 0.0, 0.0, 0.0, 0.0];
            for (got, want) in v.iter().zip(expected) {
                assert!((got - want).abs() < 1e-10, "{cells}: {row:?}");
            }
        }
    }
}

/// Probes of an elasticity case are refused by `hasse check` with the
/// kinds that have them.
#[test]
fn probes_of_kinds_without_them_are_refused() {
    let dir = Scratch::new("probes_refused");
    let case = case_with(
        &dir,
        "cases/elasticity-square.toml",
        "[[output.probe]]\nat = [0.5, 0.5]\n",
    );
    let out = hasse(&["check", &case]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(
            "probes are evaluated for diffusion and heat problems, and for the forms of maxwell"
        ),
        "{stderr}"
    );
}
