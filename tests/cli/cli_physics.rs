//! Transient heat, mixed Darcy and Maxwell cavity cases run through the
//! `hasse` binary: the shipped cases converge at the orders theory gives,
//! the cavity's eigenvalues equal the closed-form values of the Yee-type
//! grid, the output holds the time series and the modes, and bad
//! problem-kind input is refused with the key named.

use crate::hasse::hasse;
use approx::{abs_diff_eq, assert_relative_eq, relative_eq};
use std::f64::consts::PI;
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hasse-cli-physics-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Run `hasse run case` with overrides, output off; the summary.
pub(crate) fn run(case: &str, sets: &[String]) -> String {
    let mut args = vec!["run".to_string(), case.to_string()];
    args.extend(["--set".into(), "output.write=false".into()]);
    for s in sets {
        args.extend(["--set".into(), s.clone()]);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = hasse(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "hasse {args:?} failed ({:?}):\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// The number after `label` on the summary line starting with `line`.
pub(crate) fn reported(stdout: &str, line: &str, label: &str) -> f64 {
    let text = stdout
        .lines()
        .find(|l| l.starts_with(line))
        .unwrap_or_else(|| panic!("no `{line}` line in\n{stdout}"));
    let start = text
        .find(label)
        .unwrap_or_else(|| panic!("no {label} in {text}"))
        + label.len();
    text[start..]
        .trim_start()
        .split([',', ' ', ')'])
        .next()
        .unwrap()
        .parse()
        .unwrap_or_else(|e| panic!("{text}: {e}"))
}

fn order(e_coarse: f64, e_fine: f64, ratio: f64) -> f64 {
    (e_coarse / e_fine).ln() / ratio.ln()
}

// ---------------------------------------------------------------- heat

#[test]
fn heat_square_converges_at_second_order_in_space() {
    // dt small enough that the Crank–Nicolson error (≈ 1e-6 here) is far
    // below the spatial one on these meshes.
    let errors: Vec<f64> = [8, 16, 32]
        .iter()
        .map(|n| {
            let out = run(
                "cases/heat-square.toml",
                &[format!("mesh.n=[{n},{n}]"), "time.dt=0.00125".into()],
            );
            reported(&out, "error", "L2")
        })
        .collect();
    println!("heat-square, P1 + CN, n = 8, 16, 32: {errors:?}");
    for pair in errors.windows(2) {
        let p = order(pair[0], pair[1], 2.0);
        assert!(
            abs_diff_eq!(p, 2.0, epsilon = 0.15),
            "spatial order {p}: {errors:?}"
        );
    }
}

/// u = (x + 2y) e^{−t} is linear in space, so the two-point flux with
/// boundary faces at half-cell distance and the midpoint source are exact
/// and the only error left is the time scheme's: order 1 for backward
/// Euler, 2 for Crank–Nicolson.
const LINEAR_IN_SPACE: &str = r#"
[mesh]
generator = "rectangle"
n = [6, 6]

[problem]
kind = "heat"
method = "fv"
source = "-(x + 2*y) * exp(-t)"
initial = "x + 2*y"

[[boundary]]
tag = "boundary"
type = "dirichlet"
value = "(x + 2*y) * exp(-t)"

[time]
dt = 0.1
end = 1.0

[exact]
solution = "(x + 2*y) * exp(-t)"

[output]
write = false
"#;

#[test]
fn heat_time_orders_are_one_and_two() {
    let dir = scratch("time-orders");
    let case = dir.join("linear.toml");
    std::fs::write(&case, LINEAR_IN_SPACE).unwrap();
    let case = case.to_str().unwrap();
    for (scheme, expected) in [("backward-euler", 1.0), ("crank-nicolson", 2.0)] {
        let errors: Vec<f64> = [0.1, 0.05, 0.025, 0.0125]
            .iter()
            .map(|dt| {
                let out = run(
                    case,
                    &[format!("time.dt={dt}"), format!("time.scheme=\"{scheme}\"")],
                );
                reported(&out, "error", "L2")
            })
            .collect();
        println!("{scheme}: {errors:?}");
        for pair in errors.windows(2) {
            let p = order(pair[0], pair[1], 2.0);
            assert!(
                abs_diff_eq!(p, expected, epsilon = 0.15),
                "{scheme}: order {p}, errors {errors:?}"
            );
        }
    }
}

#[test]
fn heat_output_is_a_time_series_from_the_initial_field() {
    let dir = scratch("heat-output");
    let stem = dir.join("heat");
    let out = hasse(&[
        "run",
        "cases/heat-square.toml",
        "--set",
        "mesh.n=[8,8]",
        "-o",
        stem.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let printed_max = reported(&stdout, "error", "max");
    let file = hdf5::File::open(stem.with_extension("h5")).unwrap();
    // 20 steps of 0.005 saving every 2nd: t = 0, 0.01, …, 0.1.
    let times: Vec<f64> = file.attr("times").unwrap().read_raw().unwrap();
    assert_eq!(times.len(), 11);
    for (k, t) in times.iter().enumerate() {
        assert!(
            abs_diff_eq!(*t, 0.01 * k as f64, epsilon = 1e-12),
            "{times:?}"
        );
    }
    let vertices: Vec<f64> = file.dataset("mesh/vertices").unwrap().read_raw().unwrap();
    let u0: Vec<f64> = file.dataset("steps/0/u").unwrap().read_raw().unwrap();
    assert_eq!(u0.len(), 81);
    for (v, u) in u0.iter().enumerate() {
        let (x, y) = (vertices[3 * v], vertices[3 * v + 1]);
        let want = (PI * x).sin() * (PI * y).sin();
        assert!(
            abs_diff_eq!(*u, want, epsilon = 1e-14),
            "vertex {v}: {u} vs {want}"
        );
    }
    // The last level's error field is the one summarised on stdout, and
    // the boundary vertices carry the Dirichlet value t (x + y) exactly.
    let last: Vec<f64> = file.dataset("steps/10/u").unwrap().read_raw().unwrap();
    let error: Vec<f64> = file.dataset("steps/10/error").unwrap().read_raw().unwrap();
    let max = error.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    // Printed with 7 significant digits: rounding within 5e-7 relative.
    assert_relative_eq!(max, printed_max, epsilon = 0.0, max_relative = 1e-6);
    for (v, u) in last.iter().enumerate() {
        let (x, y) = (vertices[3 * v], vertices[3 * v + 1]);
        if x == 0.0 || y == 0.0 || x == 1.0 || y == 1.0 {
            assert!(
                abs_diff_eq!(*u, 0.1 * (x + y), epsilon = 1e-14),
                "vertex {v}"
            );
        }
    }
}

// ---------------------------------------------------------------- darcy

#[test]
fn darcy_layered_converges_and_conserves_mass() {
    let (mut pressure, mut flux) = (vec![], vec![]);
    for n in [8, 16, 32, 64] {
        let out = run("cases/darcy-layered.toml", &[format!("mesh.n=[{n},{n}]")]);
        pressure.push(reported(&out, "error", "L2"));
        flux.push(reported(&out, "flux error", "L2"));
        // Every cell's net outflow equals ∫f to rounding.
        let relative = reported(&out, "mass", "relative");
        assert!(relative < 1e-11, "n = {n}: conservation {relative}\n{out}");
    }
    println!("darcy-layered: pressure {pressure:?}, flux {flux:?}");
    let p = order(pressure[0], pressure[3], 8.0);
    let u = order(flux[0], flux[3], 8.0);
    assert!(
        abs_diff_eq!(p, 2.0, epsilon = 0.15),
        "pressure order {p}: {pressure:?}"
    );
    assert!(u >= 1.0 - 0.15, "flux order {u}: {flux:?}");
}

/// The same layered pressure in 3D (it does not depend on z): hexahedra
/// with the mimetic mass, second order for the pressure again.
#[test]
fn darcy_layered_converges_in_3d() {
    let mut pressure = vec![];
    for n in [4, 8, 16] {
        let out = run(
            "cases/darcy-layered.toml",
            &[
                "mesh.generator=\"box\"".into(),
                format!("mesh.n=[{n},{n},{n}]"),
            ],
        );
        pressure.push(reported(&out, "error", "L2"));
        let relative = reported(&out, "mass", "relative");
        assert!(relative < 1e-11, "n = {n}: conservation {relative}\n{out}");
    }
    println!("darcy-layered 3D: pressure {pressure:?}");
    let p = order(pressure[0], pressure[2], 4.0);
    assert!(
        abs_diff_eq!(p, 2.0, epsilon = 0.15),
        "pressure order {p}: {pressure:?}"
    );
}

#[test]
fn darcy_methods_all_run_on_the_layered_case() {
    // Each flux mass on the shipped 32² mesh and on 16²: second order in
    // the pressure, as darcy_layered_converges_and_conserves_mass shows
    // for the default method over 8²…64².
    for method in ["mimetic", "dec-barycentric"] {
        let l2 = |n: usize| {
            let out = run(
                "cases/darcy-layered.toml",
                &[
                    format!("problem.method=\"{method}\""),
                    format!("mesh.n=[{n},{n}]"),
                ],
            );
            reported(&out, "error", "L2")
        };
        let (coarse, fine) = (l2(16), l2(32));
        let p = order(coarse, fine, 2.0);
        assert!(
            abs_diff_eq!(p, 2.0, epsilon = 0.15),
            "{method}: pressure order {p} ({coarse} then {fine})"
        );
    }
}

// ---------------------------------------------------------------- maxwell

/// Parse the mode table: (ω², relative error or None) per mode.
fn modes(stdout: &str) -> Vec<(f64, Option<f64>)> {
    let start = stdout
        .lines()
        .position(|l| l.starts_with("modes"))
        .unwrap_or_else(|| panic!("no mode table in\n{stdout}"));
    stdout
        .lines()
        .skip(start + 1)
        .take_while(|l| l.starts_with("    "))
        .map(|l| {
            let parts: Vec<&str> = l.split_whitespace().collect();
            (parts[1].parse().unwrap(), parts[4].parse().ok())
        })
        .collect()
}

/// The first seven modes of the unit square's cavity, ascending: (m, n).
const SQUARE_MODES: [&[usize]; 7] = [
    &[1, 0],
    &[0, 1],
    &[1, 1],
    &[2, 0],
    &[0, 2],
    &[2, 1],
    &[1, 2],
];

/// ω² of the uniform-grid cavity with the barycentric Hodge star (the Yee
/// scheme): Σ over the mode's indices of (4/h²) sin²(mπh/2).
fn yee(indices: &[usize], h: f64) -> f64 {
    indices
        .iter()
        .map(|&m| 4.0 / (h * h) * (m as f64 * PI * h / 2.0).sin().powi(2))
        .sum()
}

#[test]
fn maxwell_square_modes_are_the_yee_values() {
    let out = run("cases/maxwell-square.toml", &["mesh.n=[16,16]".into()]);
    let got = modes(&out);
    let h = 1.0 / 16.0;
    let want = SQUARE_MODES.map(|m| yee(m, h));
    assert_eq!(got.len(), 7, "{out}");
    for (k, ((value, _), w)) in got.iter().zip(want).enumerate() {
        assert!(
            relative_eq!(*value, w, epsilon = 0.0, max_relative = 1e-8),
            "mode {}: {value} vs {w}",
            k + 1
        );
    }
}

#[test]
fn maxwell_square_converges_at_second_order_without_spurious_modes() {
    let coarse = modes(&run(
        "cases/maxwell-square.toml",
        &["mesh.n=[16,16]".into()],
    ));
    let fine = modes(&run("cases/maxwell-square.toml", &[]));
    for (k, (c, f)) in coarse.iter().zip(&fine).enumerate() {
        let (ec, ef) = (c.1.unwrap(), f.1.unwrap());
        let p = order(ec, ef, 2.0);
        assert!(
            abs_diff_eq!(p, 2.0, epsilon = 0.15),
            "mode {}: order {p}",
            k + 1
        );
        // Each relative error is the Yee scheme's own, |ω_h² − ω²| / ω²
        // with ω_h² the closed form of `yee` and ω² = π²(m² + n²), to the
        // 4 printed digits (a rounding of at most 5e-4 relative): a
        // spurious mode slipping in would shift the list.
        let want = |m: &[usize]| {
            let exact = PI * PI * m.iter().map(|&i| (i * i) as f64).sum::<f64>();
            (exact - yee(m, 1.0 / 32.0)) / exact
        };
        let w = want(SQUARE_MODES[k]);
        assert!(
            relative_eq!(ef, w, epsilon = 0.0, max_relative = 5e-4),
            "mode {}: relative error {ef}, Yee {w}",
            k + 1
        );
    }
}

#[test]
fn maxwell_modes_vanish_on_the_walls() {
    let dir = scratch("maxwell-output");
    let stem = dir.join("cavity");
    let out = hasse(&[
        "run",
        "cases/maxwell-square.toml",
        "--set",
        "mesh.n=[8,8]",
        "--set",
        "problem.modes=3",
        "-o",
        stem.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let file = hdf5::File::open(stem.with_extension("h5")).unwrap();
    // The wall edges of an 8×8 grid: 32 of 144.
    let walls: Vec<u64> = file
        .dataset("mesh/tags/boundary")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(walls.len(), 32);
    for k in 1..=3 {
        let e: Vec<f64> = file
            .dataset(&format!("steps/0/mode_{k}"))
            .unwrap()
            .read_raw()
            .unwrap();
        assert_eq!(e.len(), 144);
        assert!(walls.iter().all(|&w| e[w as usize] == 0.0));
        assert!(e.iter().any(|v| v.abs() > 1e-3));
    }
}

#[test]
fn maxwell_cube_modes_are_the_yee_values() {
    let out = run("cases/maxwell-cube.toml", &[]);
    let got = modes(&out);
    let h = 1.0 / 8.0;
    // (1,1,0) in three orientations, then (1,1,1) with two polarisations.
    let want = [
        yee(&[1, 1], h),
        yee(&[1, 1], h),
        yee(&[1, 1], h),
        yee(&[1, 1, 1], h),
        yee(&[1, 1, 1], h),
    ];
    assert_eq!(got.len(), 5, "{out}");
    for (k, ((value, _), w)) in got.iter().zip(want).enumerate() {
        assert!(
            relative_eq!(*value, w, epsilon = 0.0, max_relative = 1e-8),
            "mode {}: {value} vs {w}",
            k + 1
        );
    }
}

// ---------------------------------------------------------------- elasticity

#[test]
fn elasticity_square_converges_at_second_order() {
    // Q1 with one clamped side and tractions on three. A traction that
    // did not match the case's u would leave an O(1) error and no order.
    let errors: Vec<f64> = [8, 16, 32, 64]
        .iter()
        .map(|n| {
            let out = run(
                "cases/elasticity-square.toml",
                &[format!("mesh.n=[{n},{n}]")],
            );
            reported(&out, "error", "L2")
        })
        .collect();
    println!("elasticity-square: {errors:?}");
    let p = order(errors[0], errors[3], 8.0);
    assert!(
        abs_diff_eq!(p, 2.0, epsilon = 0.15),
        "order {p}: {errors:?}"
    );
    // The same case with the exact displacement on xmin and ymax instead of
    // their tractions (--set on the boundary entries) converges at second
    // order too, from 8² to 16².
    let clamped = |n: usize| {
        let out = run(
            "cases/elasticity-square.toml",
            &[
                format!("mesh.n=[{n},{n}]"),
                "boundary.1.type=\"displacement\"".into(),
                "boundary.1.value=[\"s\", \"px*py\"]".into(),
                "boundary.3.type=\"displacement\"".into(),
                "boundary.3.value=[\"s\", \"px*py\"]".into(),
            ],
        );
        reported(&out, "error", "L2")
    };
    let (coarse, fine) = (clamped(8), clamped(16));
    let p = order(coarse, fine, 2.0);
    assert!(
        abs_diff_eq!(p, 2.0, epsilon = 0.15),
        "clamped on xmin and ymax: order {p} ({coarse} then {fine})"
    );
}

/// A linear displacement is reproduced to rounding through the case file
/// (the patch test), on triangles, with tractions from its constant stress.
#[test]
fn elasticity_patch_test_through_a_case_file() {
    let dir = scratch("patch");
    let case = dir.join("patch.toml");
    // u = (0.1 + 0.3x − 0.2y, −0.05 + 0.1x + 0.4y): ε11 = 0.3, ε22 = 0.4,
    // ε12 = −0.05, div = 0.7; λ = 2, μ = 1: σ11 = 2.0, σ22 = 2.2, σ12 = −0.1.
    std::fs::write(
        &case,
        r#"
[mesh]
generator = "rectangle"
n = [5, 4]
cells = "simplex"
perturb = 0.2

[problem]
kind = "elasticity"
lambda = 2
mu = 1

[[boundary]]
tag = "xmin"
type = "displacement"
value = ["0.1 + 0.3*x - 0.2*y", "-0.05 + 0.1*x + 0.4*y"]

[[boundary]]
tag = "xmax"
type = "traction"
value = [2.0, -0.1]

[[boundary]]
tag = "ymin"
type = "traction"
value = [0.1, -2.2]

[[boundary]]
tag = "ymax"
type = "traction"
value = [-0.1, 2.2]

[exact]
displacement = ["0.1 + 0.3*x - 0.2*y", "-0.05 + 0.1*x + 0.4*y"]

[output]
write = false
"#,
    )
    .unwrap();
    let out = run(case.to_str().unwrap(), &[]);
    let max = reported(&out, "error", "max");
    assert!(max < 1e-13, "{out}");
}

// ---------------------------------------------------------------- coupled

#[test]
fn coupled_reaction_converges_and_the_coupling_matters() {
    let (mut u, mut v) = (vec![], vec![]);
    for n in [8, 16, 32, 64] {
        let out = run(
            "cases/coupled-reaction.toml",
            &[format!("mesh.n=[{n},{n}]")],
        );
        u.push(reported(&out, "error u", "L2"));
        v.push(reported(&out, "error v", "L2"));
    }
    println!("coupled-reaction: u {u:?}, v {v:?}");
    for (name, e) in [("u", &u), ("v", &v)] {
        let p = order(e[0], e[3], 8.0);
        assert!(
            abs_diff_eq!(p, 2.0, epsilon = 0.15),
            "{name}: order {p}, {e:?}"
        );
    }
    // The sources belong to b = 2.5. With b = 0 the u field solves
    // L w = −b v* for its error w (L = −∇·((1 + x)∇·) + 3, w = 0 on the
    // boundary); for S = sin πx sin πy, ⟨w, L S⟩ = ⟨L w, S⟩ = −b⟨v*, S⟩, so
    // ‖w‖ ≥ b ⟨v*, S⟩ / ‖L S‖ = 2.5 · 0.323157 / 16.6258 = 0.0485926
    // (⟨v*, S⟩ = 2(π² − 4)/π⁴ + 2/π², ‖L S‖ in closed form: see
    // dropped_coupling_bounds in tests/physics/coupled.rs). The error on
    // the shipped 32² mesh and on 16², extrapolated to h = 0 (Richardson,
    // order 2), is at least that.
    let uncoupled = |n: usize| {
        let out = run(
            "cases/coupled-reaction.toml",
            &["problem.b=0".into(), format!("mesh.n=[{n},{n}]")],
        );
        reported(&out, "error u", "L2")
    };
    let (coarse, fine) = (uncoupled(16), uncoupled(32));
    let limit = fine + (fine - coarse) / 3.0;
    let pi2 = PI * PI;
    let (alpha, beta) = (2.0 * pi2 + 3.0, 2.0 * pi2);
    let ls = (0.5
        * (alpha * alpha / 2.0
            + alpha * beta / 2.0
            + beta * beta * (1.0 / 6.0 - 1.0 / (4.0 * pi2))
            + beta / 2.0
            + pi2 / 2.0))
        .sqrt();
    let bound = 2.5 * (2.0 * (pi2 - 4.0) / (pi2 * pi2) + 2.0 / pi2) / ls;
    assert!(
        limit >= bound,
        "b = 0: errors {coarse}, {fine} (limit {limit}) below the bound {bound}"
    );
}

// ---------------------------------------------------------------- solver types

/// `solver.type = "multigrid" | "amg"` solve the box-3d case to 1e-8 with
/// a bounded number of CG iterations and the direct solve's error.
#[test]
fn multigrid_solver_types_match_the_direct_solution() {
    let direct = reported(&run("cases/box-3d.toml", &[]), "error", "L2");
    for kind in ["multigrid", "amg"] {
        let out = run("cases/box-3d.toml", &[format!("solver.type=\"{kind}\"")]);
        let l2 = reported(&out, "error", "L2");
        // The printed errors (7 digits) agree to their rounding, 1e-6
        // relative. That is stricter than what a relative residual of 1e-8
        // guarantees (a change of κ·1e-8·‖u‖ in the solution, κ ≈ 12/(π²h²)
        // ≈ 300 here, up to ~1e-3 of a 2e-3 error): it states what MG-CG
        // does, its error being far below the worst case, not a bound.
        assert!(
            relative_eq!(l2, direct, epsilon = 0.0, max_relative = 1e-6),
            "{kind}: {l2} vs {direct}"
        );
        let iterations = reported(&out, "iterative", "):");
        // benches/README.md's table records 7 (grid, smoothed) and 8 (constant
        // prolongation) iterations to 1e-8 for FV on the 16³ cube; 15 is
        // about twice that.
        assert!((1.0..=15.0).contains(&iterations), "{kind}: {out}");
        assert!(!out.contains("warning"), "{kind}: {out}");
    }
    // The unsmoothed cell prolongation reaches the same solution; its
    // sparser coarse levels cost more iterations (benches/README.md: 8 against 7 on
    // the 16³ cube), which shows the key reached the solver.
    let iterations = |extra: &[String]| {
        let mut args = vec!["solver.type=\"multigrid\"".to_string()];
        args.extend_from_slice(extra);
        let out = run("cases/box-3d.toml", &args);
        let l2 = reported(&out, "error", "L2");
        assert_relative_eq!(l2, direct, epsilon = 0.0, max_relative = 1e-6);
        reported(&out, "iterative", "):")
    };
    let smoothed = iterations(&[]);
    let constant = iterations(&["solver.prolongation=\"constant\"".into()]);
    assert!(
        constant > smoothed,
        "constant {constant}, smoothed {smoothed}"
    );
    assert_eq!(
        iterations(&["solver.prolongation=\"smoothed\"".into()]),
        smoothed
    );
}

/// `solver.ordering` reaches the direct solve: the summary line names the
/// ordering, and the solutions of the same system under each ordering
/// agree (all are backward-stable Cholesky factorisations of one SPD
/// matrix, so the printed 7-digit errors coincide).
#[test]
fn the_solve_line_names_the_ordering() {
    let line = |out: &str| {
        out.lines()
            .find(|l| l.starts_with("unknowns"))
            .unwrap_or_else(|| panic!("no unknowns line in\n{out}"))
            .to_string()
    };
    // A diffusion case hands the unknowns' positions to the automatic
    // rule, which orders by them.
    let auto = run("cases/poisson-square.toml", &[]);
    assert!(
        line(&auto).contains("solver sparse LLᵀ (faer), geometric nested dissection ordering"),
        "{auto}"
    );
    for (name, printed) in [
        ("nested-dissection", "nested dissection (METIS) ordering"),
        ("amd", "AMD ordering"),
        ("geometric", "geometric nested dissection ordering"),
    ] {
        let out = run(
            "cases/poisson-square.toml",
            &[format!("solver.ordering=\"{name}\"")],
        );
        assert!(
            line(&out).contains(&format!("solver sparse LLᵀ (faer), {printed}")),
            "{out}"
        );
        assert_eq!(
            reported(&out, "error", "L2"),
            reported(&auto, "error", "L2")
        );
    }
    // The transient solver analyses once per run and says which ordering.
    let heat = run(
        "cases/heat-square.toml",
        &["solver.ordering=\"nested-dissection\"".into()],
    );
    assert!(
        line(&heat).contains("nested dissection (METIS) ordering"),
        "{heat}"
    );
}

// ---------------------------------------------------------------- bad input

/// Write `text` as a case, run it, expect exit code `code` and every
/// fragment in stderr.
fn refused(name: &str, text: &str, code: i32, fragments: &[&str]) {
    let dir = scratch("bad");
    let case = dir.join(format!("{name}.toml"));
    std::fs::write(&case, text).unwrap();
    let out = hasse(&["run", case.to_str().unwrap(), "--set", "output.write=false"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "{name}:\n{stderr}");
    for f in fragments {
        assert!(stderr.contains(f), "{name}: no `{f}` in\n{stderr}");
    }
}

const HEAT: &str = r#"[mesh]
generator = "rectangle"
n = [4, 4]

[problem]
kind = "heat"
method = "fe"
initial = "x"

[time]
dt = 0.1
steps = 3
"#;

#[test]
fn bad_problem_kind_input_names_the_key() {
    refused(
        "dt",
        &HEAT.replace("dt = 0.1", "dt = -0.1"),
        2,
        &["dt.toml:11:6: `time.dt`", "positive"],
    );
    refused(
        "no-time",
        &HEAT.replace("[time]\ndt = 0.1\nsteps = 3\n", ""),
        2,
        &["`time`", "no [time] table"],
    );
    refused(
        "end",
        &HEAT.replace("steps = 3", "end = 0.25"),
        2,
        &["`time.end`", "not a whole number of steps"],
    );
    refused(
        "mimetic-heat",
        &HEAT.replace("\"fe\"", "\"fv-mimetic\""),
        2,
        &["`problem.method`", "half-face"],
    );
    refused(
        "robin-in-time",
        &format!("{HEAT}\n[[boundary]]\ntag = \"boundary\"\ntype = \"robin\"\nalpha = \"1 + t\"\nvalue = 0\n"),
        2,
        &["`boundary[0].alpha`", "may not depend on t"],
    );
    // The conductivity is refused as α is (issue 30, item 5): it used to be
    // evaluated at t = 0 and frozen, even with time.start ≠ 0. Scalar and
    // tensor forms; the error points at the key (line 9, column 16).
    refused(
        "conductivity-in-time",
        &HEAT.replace(
            "initial = \"x\"",
            "initial = \"x\"\nconductivity = \"1 + t\"",
        ),
        2,
        &[
            "conductivity-in-time.toml:9:16: `problem.conductivity`",
            "may not depend on t",
        ],
    );
    refused(
        "tensor-in-time",
        &HEAT.replace(
            "initial = \"x\"",
            "initial = \"x\"\nconductivity = [[1, 0], [0, \"exp(-t)\"]]",
        ),
        2,
        &["`problem.conductivity`", "may not depend on t"],
    );
    refused(
        "kind",
        &HEAT.replace("\"heat\"", "\"maxwel\""),
        2,
        &[
            "unknown problem kind \"maxwel\"",
            "did you mean \"maxwell\"",
        ],
    );
    refused(
        "darcy-llt",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"darcy\"\nmethod = \"mimetic\"\n[[boundary]]\ntag = \"boundary\"\ntype = \"pressure\"\nvalue = 0\n[solver]\nfactorization = \"llt\"\n",
        2,
        &["`solver.factorization`", "indefinite"],
    );
    refused(
        "darcy-dirichlet",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"darcy\"\nmethod = \"mimetic\"\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n",
        2,
        &["`boundary[0].type`", "\"pressure\""],
    );
    refused(
        "darcy-unbalanced",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"darcy\"\nmethod = \"mimetic\"\nsource = 1\n",
        2,
        &["no pressure is prescribed", "add a \"pressure\" boundary"],
    );
    let cavity = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"maxwell\"\nmethod = \"dec-barycentric\"\nmodes = 50\n";
    // 4×4: 24 interior edges, 9 interior vertices: 15 physical modes.
    refused(
        "modes",
        cavity,
        2,
        &[
            "modes.toml:7:9: `problem.modes`: 50 modes asked for",
            "only 15 physical modes",
        ],
    );
    refused(
        "cavity-boundary",
        &format!("{cavity}[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n"),
        2,
        &["`boundary`", "perfect conductors"],
    );
    refused(
        "eigen-order",
        &format!(
            "{}\n[exact]\neigenvalues = [2, 1]\n",
            cavity.replace("50", "2")
        ),
        2,
        &["`exact.eigenvalues`", "ascending"],
    );
    refused(
        "refine-heat",
        &format!("{HEAT}\n[refine]\nsteps = 1\n"),
        2,
        &["`refine`", "diffusion problems"],
    );
    refused(
        "elastic-material",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"elasticity\"\nyoung = 1\npoisson = 0.5\n[[boundary]]\ntag = \"boundary\"\ntype = \"displacement\"\nvalue = [0, 0]\n",
        2,
        &["Poisson's ratio", "(−1, 0.5)"],
    );
    refused(
        "elastic-rigid",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"elasticity\"\nlambda = 1\nmu = 1\n[[boundary]]\ntag = \"xmin\"\ntype = \"displacement\"\ncomponent = 0\nvalue = 0\n",
        2,
        &["rigid-body modes", "prescribe displacements"],
    );
    refused(
        "elastic-type",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"elasticity\"\nlambda = 1\nmu = 1\n[[boundary]]\ntag = \"xmin\"\ntype = \"dirichlet\"\nvalue = [0, 0]\n",
        2,
        &["`boundary[0].type`", "\"displacement\""],
    );
    let pair = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"coupled\"\na = 1\nb = 60\nc = 1\n[[field]]\nname = \"u\"\nmethod = \"fe\"\n[[field.boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n[[field]]\nname = \"v\"\nmethod = \"fe\"\nsource = 1\n[[field.boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n";
    // a c < b²: indefinite, and LLᵀ says so (exit 1, a solve failure).
    refused("coupled-indefinite", pair, 1, &["LLᵀ"]);
    refused(
        "coupled-fields",
        &pair.replacen("[[field]]\nname = \"v\"", "[[field]]\nname = \"u\"", 1),
        2,
        &["`field[1].name`", "differ from the other"],
    );
    refused(
        "coupled-boundary",
        &format!("{pair}[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n"),
        2,
        &["`boundary`", "per field"],
    );
    refused(
        "coupled-tag",
        &pair.replacen("tag = \"boundary\"", "tag = \"bondary\"", 1),
        2,
        &["`field[0].boundary[0].tag`", "did you mean `boundary`"],
    );
    refused(
        "multigrid-unstructured",
        "[mesh]\ngenerator = \"voronoi\"\nn = [30]\n[problem]\nmethod = \"fe\"\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n[solver]\ntype = \"multigrid\"\n",
        2,
        &["grid levels", "use \"amg\""],
    );
    refused(
        "prolongation-name",
        "[mesh]\ngenerator = \"rectangle\"\nn = [8, 8]\n[problem]\nmethod = \"fv\"\n[solver]\ntype = \"multigrid\"\nprolongation = \"linear\"\n",
        2,
        &["prolongation-name.toml:8:16: `solver.prolongation`", "unknown prolongation \"linear\"", "\"constant\""],
    );
    refused(
        "prolongation-direct",
        "[mesh]\ngenerator = \"rectangle\"\nn = [8, 8]\n[problem]\nmethod = \"fv\"\n[solver]\nprolongation = \"constant\"\n",
        2,
        &["`solver.prolongation`", "solver.type = \"multigrid\""],
    );
    refused(
        "ordering-name",
        "[mesh]\ngenerator = \"rectangle\"\nn = [8, 8]\n[problem]\nmethod = \"fv\"\n[solver]\nordering = \"metis\"\n",
        2,
        &["ordering-name.toml:7:12: `solver.ordering`", "unknown ordering \"metis\"", "\"nested-dissection\""],
    );
    refused(
        "ordering-multigrid",
        "[mesh]\ngenerator = \"rectangle\"\nn = [8, 8]\n[problem]\nmethod = \"fv\"\n[solver]\ntype = \"amg\"\nordering = \"amd\"\n",
        2,
        &["`solver.ordering`", "factorises nothing"],
    );
    refused(
        "ordering-lu",
        "[mesh]\ngenerator = \"rectangle\"\nn = [8, 8]\n[problem]\nmethod = \"fv\"\n[solver]\nfactorization = \"lu\"\nordering = \"nested-dissection\"\n",
        2,
        &["`solver.ordering`", "COLAMD"],
    );
    refused(
        "ordering-geometric-heat",
        &format!("{HEAT}\n[solver]\nordering = \"geometric\"\n"),
        2,
        &[
            "`solver.ordering`",
            "unknowns' positions",
            "kind = \"heat\"",
        ],
    );
    refused(
        "ordering-darcy",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"darcy\"\n[solver]\nordering = \"amd\"\n",
        2,
        &["`solver.ordering`", "kind = \"darcy\""],
    );
    refused(
        "multigrid-darcy",
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"darcy\"\n[solver]\ntype = \"amg\"\n",
        2,
        &["`solver.type`", "diffusion and heat problems"],
    );
    refused(
        "wrong-key",
        &HEAT.replace("initial = \"x\"", "initial = \"x\"\npermeability = 2"),
        2,
        &["`problem.permeability`", "not used by kind = \"heat\""],
    );
}
