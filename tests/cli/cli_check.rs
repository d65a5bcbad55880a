//! `hasse check` on the broken case files of `tests/bad-input/` reports
//! each expected problem at the right line, all at once; `hasse run` on them
//! exits with code 2 and writes no output.

use crate::hasse::hasse;
use std::path::PathBuf;

/// File, then the (line, text) pairs `hasse check` must print, in order.
const EXPECTED: &[(&str, &[(usize, &str)])] = &[
    (
        "unknown-key",
        &[
            (
                7,
                "`problem.methdo`: unknown key\n    help: did you mean `method`?",
            ),
            (6, "`problem.method`: missing: which discretisation to use"),
        ],
    ),
    (
        "wrong-type",
        &[(
            8,
            "`problem.conductivity`: expected a number or an expression string, found a boolean",
        )],
    ),
    (
        "bad-expression",
        &[(8, "`problem.source`: cannot parse `sin(pi*x`")],
    ),
    (
        "unknown-variable",
        &[(
            11,
            "`problem.source`: unknown variable `kapa` in `kapa * x` (did you mean `kappa`?)",
        )],
    ),
    (
        "missing-mesh-file",
        &[(3, "`mesh.file`: cannot read Gmsh mesh")],
    ),
    (
        "unknown-tag",
        &[(
            10,
            "`boundary[0].tag`: no tag `bondary` in the mesh\n    help: did you mean `boundary`?",
        )],
    ),
    ("malformed", &[(3, "not valid TOML")]),
    (
        "several-problems",
        &[
            (
                5,
                "`mesh.perturbation`: unknown key\n    help: did you mean `perturb`?",
            ),
            (
                8,
                "`problem.method`: unknown method \"fem\"\n    help: did you mean \"fe\"?",
            ),
            (
                9,
                "`problem.source`: unknown variable `pie` in `2 * pie` (did you mean `pi`?)",
            ),
            (11, "`boundary[0].value`: missing: the boundary value"),
            (
                16,
                "`solver.residual_limit`: must be a positive number, found -1",
            ),
        ],
    ),
];

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hasse-cli-check-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn check_reports_every_problem_with_its_line() {
    for (name, expected) in EXPECTED {
        let file = format!("tests/bad-input/{name}.toml");
        let out = hasse(&["check", &file]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{file}: {stderr}");
        let errors: Vec<&str> = stderr.split("error: ").skip(1).collect();
        assert_eq!(
            errors.len(),
            expected.len(),
            "{file}: expected {} problems:\n{stderr}",
            expected.len()
        );
        for (error, (line, text)) in errors.iter().zip(expected.iter()) {
            let prefix = format!("{file}:{line}:");
            assert!(
                error.starts_with(&prefix),
                "{file}: expected line {line}, got:\n{error}"
            );
            assert!(
                error.contains(text),
                "{file}: expected `{text}` in:\n{error}"
            );
        }
    }
}

#[test]
fn run_on_bad_input_exits_2_and_writes_nothing() {
    for (name, _) in EXPECTED {
        let dir = scratch(name);
        let stem = dir.join("out");
        let file = format!("tests/bad-input/{name}.toml");
        let out = hasse(&["run", &file, "-o", stem.to_str().unwrap()]);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{file}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "{file} left files in {}",
            dir.display()
        );
    }
}

#[test]
fn problems_found_only_while_solving_also_exit_2() {
    // Incompatible pure-Neumann data show only in the assembled system:
    // check passes, run refuses.
    let file = "tests/bad-input/incompatible-neumann.toml";
    assert_eq!(hasse(&["check", file]).status.code(), Some(0));
    let dir = scratch("incompatible");
    let stem = dir.join("out");
    let out = hasse(&["run", file, "-o", stem.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("incompatible data"), "{stderr}");
    assert!(stderr.contains("no output written"), "{stderr}");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

#[test]
fn data_that_are_not_finite_are_refused_by_check_before_any_solve() {
    // 1/(…) singular at the centroids (0.125, ·): evaluation alone shows
    // it, so check refuses it with the key's line and the point, as run.
    let file = "tests/bad-input/singular-source.toml";
    let out = hasse(&["check", file]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.starts_with(&format!(
            "error: {file}:11:10: `problem.source`: the source is not finite (NaN) at (0.125, "
        )),
        "{stderr}"
    );
}

#[test]
fn set_overrides_are_checked_and_applied() {
    // A bad override is reported like a bad key.
    let out = hasse(&[
        "check",
        "cases/poisson-square.toml",
        "--set",
        "problem.method=fvm",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr.contains("unknown method \"fvm\""), "{stderr}");
    let out = hasse(&["check", "cases/poisson-square.toml", "--set", "nonsense"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected KEY=VALUE"));
    // A good one changes the mesh that check builds: 8 × 8 quads.
    let out = hasse(&[
        "check",
        "cases/poisson-square.toml",
        "--set",
        "mesh.n=[8,8]",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(stdout.contains("[81, 144, 64]"), "{stdout}");
}

/// A build without the cargo feature `mpi` refuses `solver.type = "petsc"`
/// at `check`, with the command that builds a hasse that has it.
#[cfg(not(feature = "mpi"))]
#[test]
fn petsc_without_the_mpi_feature_is_refused_with_the_build_command() {
    let out = hasse(&[
        "check",
        "cases/poisson-square.toml",
        "--set",
        "solver.type=\"petsc\"",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("`solver.type`"), "{stderr}");
    assert!(
        stderr.contains("cargo build --release --features mpi"),
        "{stderr}"
    );
}
