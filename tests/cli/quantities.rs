//! Quantities of interest and the global balance (issue 29, item 2), on
//! cases whose values are derived by hand:
//!
//! - `cases/two-materials.toml`: K = 1 on x < 1, 20 on x > 1, u(0) = 0,
//!   u(2) = 1, insulated top and bottom (height 1). The flux q = −K u′ is
//!   the same in both materials, u′ = 20/21 left and 1/21 right, so
//!   20/21 leaves through x = 0 and enters through x = 2; ∫ over the
//!   insulation of u = 20x/21 is 10/21, the mean over the copper of
//!   u = 20/21 + (x − 1)/21 is 41/42.
//! - the same plate with f = 1, heat entering at x = 0 (K∇u·n = g = 2) and
//!   a Robin exchange at x = 2: in the steady state everything that enters
//!   or is produced leaves, Σ outflow = ∫f = 2, and the flux out of xmin is
//!   −g·|xmin| = −2 whatever the method.

use crate::hasse::{hasse, summary};
use crate::scratch::Scratch;
use hdf5::types::VarLenUnicode;
use std::path::Path;

const CASE: &str = "cases/two-materials.toml";

/// `cases/two-materials.toml` with `extra` appended (more quantity
/// tables: `--set` cannot add tables), in a scratch directory.
fn case_with(test: &str, extra: &str) -> (Scratch, String) {
    let dir = Scratch::new(test);
    std::fs::create_dir_all(&*dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join(CASE)).unwrap();
    let path = dir.join("plate.toml");
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    let path = path.to_str().unwrap().to_string();
    (dir, path)
}

/// The value of the quantity named `name` in a summary.
fn quantity(stdout: &str, name: &str) -> f64 {
    let prefix = format!("{name} = ");
    stdout
        .lines()
        .filter(|l| l.starts_with("quantity"))
        .find_map(|l| {
            l.split_once(&prefix)
                .map(|(_, v)| v.trim().parse().unwrap())
        })
        .unwrap_or_else(|| panic!("no quantity `{name}` in:\n{stdout}"))
}

/// The relative imbalance of the summary's `balance` line.
fn imbalance(stdout: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("balance"))
        .unwrap_or_else(|| panic!("no balance line in:\n{stdout}"));
    let (_, after) = line.split_once(", ").expect("a relative figure");
    after.split_whitespace().next().unwrap().parse().unwrap()
}

const MORE: &str = r#"
[[output.quantity]]
type = "flux"
tag = "xmax"

[[output.quantity]]
type = "integral"
region = "insulation"

[[output.quantity]]
type = "max"
"#;

const ACROSS: &str = r#"
[[output.quantity]]
type = "flux"
tag = "interface"
"#;

#[test]
fn fluxes_and_region_statistics_are_the_analytic_ones() {
    let q = 20.0 / 21.0;
    let (_dir, case) = case_with("quantities_analytic", MORE);
    for method in ["fe", "fv", "fv-mimetic", "fd"] {
        let set = format!("problem.method=\"{method}\"");
        let s = summary(&case, &[&set]);
        // The solutions are exact to rounding (see regions.rs): so are
        // their fluxes and integrals, up to the conditioning (K jumps 20×).
        let close = |name: &str, expected: f64| {
            let value = quantity(&s, name);
            assert!(
                (value - expected).abs() < 1e-12,
                "{method}: {name} = {value:e}, expected {expected:e}"
            );
        };
        close("flux through xmin", q);
        close("flux through xmax", -q);
        close("mean of u in copper", 41.0 / 42.0);
        close("integral of u in insulation", 10.0 / 21.0);
        // The largest value of the method's field: the vertex at x = 2 for
        // fe, the centroid at x = 1.875 for the cell-centred methods.
        let top = if method == "fe" { 1.0 } else { 20.875 / 21.0 };
        close("max of u", top);
        assert!(imbalance(&s) < 1e-10, "{method}: {s}");
    }
    // Across the interior interface: every method's own flux along the
    // edges' orientation, of magnitude 20/21 (the nodal methods' from the
    // residual of one side, exact here since u is piecewise linear).
    let (_dir, across) = case_with("quantities_across", ACROSS);
    for (method, cells) in METHODS {
        let s = summary(
            &across,
            &[&set("problem.method", method), &set("mesh.cells", cells)],
        );
        let value = quantity(&s, "flux through interface");
        assert!(
            (value.abs() - q).abs() < 1e-12,
            "{method} {cells}: {value:e}"
        );
    }
}

/// Every diffusion method on the plate's mesh (nodal ones on squares and
/// on triangles).
const METHODS: [(&str, &str); 6] = [
    ("fe", "cuboid"),
    ("fe", "simplex"),
    ("dec", "simplex"),
    ("fv", "cuboid"),
    ("fv-mimetic", "cuboid"),
    ("fd", "cuboid"),
];

fn set(key: &str, value: &str) -> String {
    format!("{key}=\"{value}\"")
}

/// The flux across the interface balances each side: with f = 1 the
/// solution is no longer piecewise linear, but what crosses x = 1 from the
/// copper is what the copper produces (its area, 1) less what leaves it
/// through x = 2, and what reaches the insulation leaves through x = 0:
/// flux toward −x = 1 − outflow(xmax) = outflow(xmin) − 1, to the solver's
/// residual, for every method's own fluxes.
#[test]
fn the_flux_across_an_interface_balances_both_sides() {
    let (_dir, across) = case_with("quantities_interface_balance", &format!("{MORE}{ACROSS}"));
    // The orientation of the interface's edges, from the source-free plate
    // (flux 20/21 toward −x).
    for (method, cells) in METHODS {
        let (m, c) = (set("problem.method", method), set("mesh.cells", cells));
        let plain = summary(&across, &[&m, &c]);
        let toward_minus_x = quantity(&plain, "flux through interface") / (20.0 / 21.0);
        assert!(
            (toward_minus_x.abs() - 1.0).abs() < 1e-12,
            "{method} {cells}"
        );
        let s = summary(&across, &[&m, &c, "problem.source=1", "exact.solution=0"]);
        let value = quantity(&s, "flux through interface") * toward_minus_x;
        let (out_min, out_max) = (
            quantity(&s, "flux through xmin"),
            quantity(&s, "flux through xmax"),
        );
        assert!(
            (value - (1.0 - out_max)).abs() < 1e-10,
            "{method} {cells}: {value} vs {}",
            1.0 - out_max
        );
        assert!(
            (value - (out_min - 1.0)).abs() < 1e-10,
            "{method} {cells}: {value} vs {}",
            out_min - 1.0
        );
    }
}

/// Half the interface (y < 1/2, ending at (1, 1/2) inside the plate): a
/// nodal method's flux has no side to take at the end vertex and leaves it
/// out, with a warning. On the piecewise-linear plate each side's residual
/// at a vertex of the line is q ∫ φ_i over the line's edges at it: q h/2 at
/// the boundary vertex (1, 0), q h at (1, 1/4), shared equally by its two
/// edges; h = 1/4, so the half-line carries q (h/2 + h) = 0.375 q instead
/// of 0.5 q. The cell-centred methods' face fluxes give 0.5 q.
#[test]
fn an_open_interface_leaves_its_end_vertex_out() {
    let q = 20.0 / 21.0;
    let half = r#"
[[output.quantity]]
type = "flux"
tag = "half"
"#;
    let (_dir, case) = case_with("quantities_open_interface", half);
    let text = std::fs::read_to_string(&case).unwrap().replace(
        "[problem]",
        "[regions.half]\nfaces = \"abs(x - 1) < 1e-9 && y < 0.5\"\n\n[problem]",
    );
    std::fs::write(&case, text).unwrap();
    for (method, cells) in METHODS {
        let (m, c) = (set("problem.method", method), set("mesh.cells", cells));
        let out = hasse(&["run", &case, "--set", &m, "--set", &c]);
        let s = String::from_utf8_lossy(&out.stdout);
        let value = quantity(&s, "flux through half").abs();
        let nodal = method == "fe" || method == "dec";
        let expected = if nodal { 0.375 * q } else { 0.5 * q };
        assert!(
            (value - expected).abs() < 1e-12,
            "{method} {cells}: {value:e}"
        );
        let all = format!("{s}{}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(
            all.contains("end inside the domain"),
            nodal,
            "{method}: {all}"
        );
    }
}

/// Heat runs compute the flux across the interface at every saved level,
/// nodal methods included. Started from the plate's steady state (exact
/// for these methods, so u stays put and nothing is stored), the flux is
/// the steady 20/21 at every level.
#[test]
fn heat_runs_give_the_flux_across_an_interface_at_every_level() {
    let (dir, case) = case_with("quantities_heat_interface", ACROSS);
    // fv-mimetic's half-face unknowns carry no mass: it does not step.
    for (method, cells) in METHODS.into_iter().filter(|(m, _)| *m != "fv-mimetic") {
        let stem = dir.join(format!("heat-{method}-{cells}"));
        let out = hasse(&[
            "run",
            &case,
            "-q",
            "-o",
            stem.to_str().unwrap(),
            "--set",
            &set("problem.method", method),
            "--set",
            &set("mesh.cells", cells),
            "--set",
            "problem.kind=\"heat\"",
            "--set",
            "problem.initial=\"if(x < 1, 20*x/21, 20/21 + (x - 1)/21)\"",
            "--set",
            "time.dt=0.1",
            "--set",
            "time.steps=3",
        ]);
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let csv = std::fs::read_to_string(
            stem.with_file_name(format!("heat-{method}-{cells}.quantities.csv")),
        )
        .unwrap();
        let mut lines = csv.lines();
        let header = lines.next().unwrap();
        let column = header
            .split(',')
            .position(|h| h == "\"flux through interface\"")
            .unwrap_or_else(|| panic!("{header}"));
        let rows: Vec<f64> = lines
            .map(|l| l.split(',').nth(column).unwrap().parse().unwrap())
            .collect();
        assert_eq!(rows.len(), 4, "{method}: t = 0 and 3 steps");
        for value in rows {
            assert!(
                (value.abs() - 20.0 / 21.0).abs() < 1e-12,
                "{method} {cells}: {value:e}"
            );
        }
    }
}

#[test]
fn neumann_in_and_robin_out_balances_the_source() {
    let robin_plate = [
        "problem.source=1",
        "problem.conductivity=1",
        "boundary.0.type=\"neumann\"",
        "boundary.0.value=2",
        "boundary.1.type=\"robin\"",
        "boundary.1.alpha=3",
        "boundary.1.value=0.5",
        "exact.solution=0",
    ];
    let (_dir, case) = case_with("quantities_robin", MORE);
    for (method, cells) in [
        ("fe", "cuboid"),
        ("fe", "simplex"),
        ("fv", "cuboid"),
        ("fd", "cuboid"),
        ("fv-mimetic", "cuboid"),
        ("dec", "simplex"),
    ] {
        let m = format!("problem.method=\"{method}\"");
        let c = format!("mesh.cells=\"{cells}\"");
        let mut sets = vec![m.as_str(), c.as_str()];
        sets.extend(robin_plate);
        let s = summary(&case, &sets);
        let relative = imbalance(&s);
        assert!(
            relative < 1e-10,
            "{method} on {cells}: imbalance {relative:e}\n{s}"
        );
        // What enters through xmin is the Neumann datum; the source and the
        // inflow leave through the Robin side: 2 + 2 = 4.
        let inflow = quantity(&s, "flux through xmin");
        assert!(
            (inflow + 2.0).abs() < 1e-10,
            "{method} on {cells}: xmin {inflow:e}"
        );
        let outflow = quantity(&s, "flux through xmax");
        assert!(
            (outflow - 4.0).abs() < 1e-10,
            "{method} on {cells}: xmax {outflow:e}"
        );
    }
}

#[test]
fn quantities_are_stored_in_the_run_report() {
    let dir = Scratch::new("quantities_report");
    let stem = dir.join("plate");
    let out = hasse(&["run", CASE, "-o", stem.to_str().unwrap(), "-q"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = hdf5::File::open(stem.with_extension("h5")).unwrap();
    let report = file
        .dataset("provenance/report")
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap();
    let report: serde_json::Value = serde_json::from_str(report.as_str()).unwrap();
    let quantities = report["quantities"].as_array().expect("a quantities array");
    assert_eq!(quantities.len(), 2);
    assert_eq!(quantities[0]["name"], "flux through xmin");
    assert_eq!(quantities[0]["type"], "flux");
    assert_eq!(quantities[0]["tag"], "xmin");
    let flux = quantities[0]["value"].as_f64().unwrap();
    assert!((flux - 20.0 / 21.0).abs() < 1e-12, "{flux:e}");
    assert_eq!(quantities[1]["region"], "copper");
    let balance = report["balance"]["relative"].as_f64().unwrap();
    assert!(balance < 1e-10, "{balance:e}");
}

#[test]
fn quantities_that_do_not_fit_are_refused_before_solving() {
    for (sets, words) in [
        (
            vec!["output.quantity.0.tag=\"nowhere\""],
            "no tag `nowhere` in the mesh",
        ),
        (
            vec!["output.quantity.0.tag=\"copper\""],
            "tag `copper` names 2-cells; a flux needs 1-cells",
        ),
        (
            vec!["output.quantity.1.region=\"xmin\""],
            "tag `xmin` names 1-cells; a mean needs 2-cells",
        ),
        (
            vec!["output.quantity.1.type=\"average\""],
            "unknown quantity type \"average\"",
        ),
        (
            vec!["output.quantity.0.type=\"mean\""],
            "a mean is over a region of top cells, not through a tag",
        ),
        (vec!["output.quantity.1.field=\"v\""], "no field \"v\""),
    ] {
        let mut args = vec!["check", CASE];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let out = hasse(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{sets:?} should be refused");
        assert!(stderr.contains(words), "{sets:?}: {stderr}");
    }
    // Other kinds compute no quantities.
    let dir = Scratch::new("quantities_maxwell");
    std::fs::create_dir_all(&*dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("cases/maxwell-square.toml")).unwrap();
    let case = dir.join("maxwell.toml");
    std::fs::write(
        &case,
        format!("{text}\n[[output.quantity]]\ntype = \"max\"\n"),
    )
    .unwrap();
    let out = hasse(&["check", case.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success()
            && stderr.contains("quantities are computed for diffusion and heat problems"),
        "{stderr}"
    );
}

#[test]
fn heat_quantities_follow_every_saved_level() {
    // Insulated plate, u(0) = 0, f = 1: nothing leaves, so ∫u = ∫f t = 2t
    // exactly for a conservative scheme (backward Euler with the
    // method's mass: Σ M (u¹ − u⁰) = Δt Σ f), at every level.
    let extra = r#"
[[output.quantity]]
type = "integral"
name = "heat content"
"#;
    let (dir, case) = case_with("quantities_heat", extra);
    let text = std::fs::read_to_string(&case).unwrap();
    // Only the stored heat is checked here: drop the case's flux quantity
    // (heat fluxes are checked in heat_solvers.rs).
    let text = text.replace("[[output.quantity]]\ntype = \"flux\"\ntag = \"xmin\"\n", "");
    std::fs::write(&case, text).unwrap();
    for method in ["fv", "fe"] {
        let stem = dir.join(format!("heat-{method}"));
        let m = format!("problem.method=\"{method}\"");
        let out = hasse(&[
            "run",
            &case,
            "-q",
            "-o",
            stem.to_str().unwrap(),
            "--set",
            &m,
            "--set",
            "problem.kind=\"heat\"",
            "--set",
            "problem.initial=0",
            "--set",
            "problem.source=1",
            "--set",
            "time.dt=0.125",
            "--set",
            "time.steps=8",
            "--set",
            "boundary.0.type=\"neumann\"",
            "--set",
            "boundary.0.value=0",
            "--set",
            "boundary.1.type=\"neumann\"",
            "--set",
            "boundary.1.value=0",
            "--set",
            "exact.solution=\"t\"",
        ]);
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let csv =
            std::fs::read_to_string(stem.with_file_name(format!("heat-{method}.quantities.csv")))
                .unwrap();
        let mut lines = csv.lines();
        assert_eq!(
            lines.next(),
            Some("t,\"mean of u in copper\",\"heat content\"")
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 9, "{method}: t = 0 and 8 steps");
        for row in rows {
            let (t, mean, content) = (row[0], row[1], row[2]);
            assert!(
                (content - 2.0 * t).abs() < 1e-12,
                "{method}: ∫u = {content} at t = {t}"
            );
            // The plate heats uniformly: u = t everywhere.
            assert!((mean - t).abs() < 1e-12, "{method}: mean {mean} at t = {t}");
        }
    }
}
