//! An interrupted run leaves no output under its final names: `hasse run`
//! is killed (SIGKILL, then SIGINT) while it writes the HDF5 file, which it
//! writes under a temporary name and renames only when complete. After the
//! kill, no `out.h5` / `out.xdmf` exists; a new run then succeeds and
//! removes the temporaries the killed runs left.
//!
//! A transient (heat) run also writes each saved level as it completes to
//! `out.partial.xdmf` + `out.partial/`: killed after a few levels, those
//! levels stay readable and hold the right values (checked against the
//! case's formulas, not against the writer); a failed run says which levels
//! are readable and where; a re-run replaces the partial output by the
//! final one.

use approx::{abs_diff_eq, assert_abs_diff_eq};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn start(stem: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args([
            "run",
            "cases/poisson-square.toml",
            "--set",
            "mesh.n=[200,200]",
            "-q",
            "-o",
            stem.to_str().unwrap(),
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("hasse starts")
}

fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok()?.file_name().into_string().ok())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

/// Start a run, wait until its h5 temporary appears, stop it with
/// `signal`; the stopped process's id.
fn interrupt(dir: &Path, signal: &str) -> u32 {
    let mut child = start(&dir.join("out"));
    let deadline = Instant::now() + Duration::from_secs(120);
    // This child's own temporary, not one an earlier killed run left.
    let own = format!(".out.h5.tmp-{}-", child.id());
    let temporary = loop {
        if let Some(name) = names(dir).into_iter().find(|n| n.starts_with(&own)) {
            break name;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the run ended ({status}) before its h5 temporary was seen");
        }
        assert!(Instant::now() < deadline, "no temporary within 120 s");
        std::thread::sleep(Duration::from_millis(1));
    };
    let killed = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert!(!status.success(), "the run was stopped by {signal}");
    let left = names(dir);
    for final_name in ["out.h5", "out.xdmf", "out.edges.xdmf"] {
        assert!(
            !left.iter().any(|n| n == final_name),
            "{signal}: {final_name} exists after the kill: {left:?}"
        );
    }
    // Only temporaries can remain (the process had no chance to remove them).
    assert!(
        left.iter()
            .all(|n| n.starts_with('.') && n.contains(".tmp-")),
        "{signal}: unexpected files {left:?} (temporary was {temporary})"
    );
    child.id()
}

#[test]
fn a_killed_run_leaves_no_output_and_a_rerun_succeeds() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("hasse-interrupted-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let first = interrupt(&dir, "-KILL");
    let second = interrupt(&dir, "-INT");
    // Each killed run left its temporaries, but the second one, once it
    // started writing, removed the first's (its process was gone): what
    // remains is the second run's alone (its h5 temporary, and the XDMF
    // ones when the signal came after the h5 was written).
    let before = names(&dir);
    let temporaries: Vec<&String> = before.iter().filter(|n| n.contains(".tmp-")).collect();
    assert!(
        !temporaries.is_empty()
            && temporaries
                .iter()
                .all(|n| n.contains(&format!(".tmp-{second}-"))),
        "temporaries after two killed runs (pids {first}, {second}): {before:?}"
    );
    let status = start(&dir.join("out")).wait().unwrap();
    assert!(status.success());
    // The re-run also removed the temporaries of the killed runs, whose
    // processes are gone.
    assert_eq!(
        names(&dir),
        ["out.edges.xdmf", "out.h5", "out.xdmf"],
        "files after the re-run"
    );
    // The complete file opens as HDF5 (signature at offset 0).
    let h5 = std::fs::read(dir.join("out.h5")).unwrap();
    assert_eq!(&h5[..8], b"\x89HDF\r\n\x1a\n");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn hasse(args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_hasse"));
    command
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."));
    command
}

/// The `Value`s of the `<Time>` elements of an XDMF text, in order.
fn xdmf_times(xml: &str) -> Vec<f64> {
    xml.split("<Time Value=\"")
        .skip(1)
        .map(|rest| rest.split('"').next().unwrap().parse().unwrap())
        .collect()
}

/// The h5 files an XDMF text refers to (`file.h5:/path`), without repeats.
fn xdmf_files(xml: &str) -> Vec<String> {
    let mut files: Vec<String> = xml
        .split("Format=\"HDF\">")
        .skip(1)
        .map(|rest| rest.split(':').next().unwrap().to_string())
        .collect();
    files.sort();
    files.dedup();
    files
}

fn read_f64(path: &Path, dataset: &str) -> Vec<f64> {
    hdf5::File::open(path)
        .unwrap()
        .dataset(dataset)
        .unwrap()
        .read_raw::<f64>()
        .unwrap()
}

/// `cases/heat-square.toml`: dt = 0.005, save_every = 2, start 0.
const DT: f64 = 0.005;
const SAVE_EVERY: f64 = 2.0;

#[test]
fn a_killed_heat_run_keeps_its_completed_levels_and_a_rerun_replaces_them() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("hasse-interrupted-heat-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let stem = dir.join("out");
    let partial_xdmf = dir.join("out.partial.xdmf");
    // 10 000 steps: far more than the test waits for.
    let mut child = hasse(&[
        "run",
        "cases/heat-square.toml",
        "--set",
        "mesh.n=[40,40]",
        "--set",
        "time.end=50",
        "-q",
        "-o",
        stem.to_str().unwrap(),
    ])
    .stdout(Stdio::null())
    .stderr(Stdio::null())
    .spawn()
    .expect("hasse starts");
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        // The document is renamed into place, so any version read is whole.
        let listed = std::fs::read_to_string(&partial_xdmf)
            .map(|xml| xdmf_times(&xml).len())
            .unwrap_or(0);
        if listed >= 2 {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the run ended ({status}) before its partial output listed 2 levels");
        }
        assert!(Instant::now() < deadline, "no 2 levels within 120 s");
        std::thread::sleep(Duration::from_millis(1));
    }
    let killed = Command::new("kill")
        .args(["-KILL", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    assert!(!child.wait().unwrap().success());

    let left = names(&dir);
    for final_name in ["out.h5", "out.xdmf"] {
        assert!(!left.contains(&final_name.to_string()), "{left:?}");
    }
    let xml = std::fs::read_to_string(&partial_xdmf).unwrap();
    assert!(xml.trim_end().ends_with("</Xdmf>"), "{xml}");
    let times = xdmf_times(&xml);
    assert!(times.len() >= 2, "{times:?}");
    for (j, &t) in times.iter().enumerate() {
        let expected = j as f64 * SAVE_EVERY * DT;
        assert!(
            abs_diff_eq!(t, expected, epsilon = 1e-12),
            "level {j}: t = {t}, expected {expected}"
        );
    }
    let files = xdmf_files(&xml);
    let mut expected_files = vec!["out.partial/mesh.h5".to_string()];
    expected_files.extend((0..times.len()).map(|j| format!("out.partial/level-{j}.h5")));
    expected_files.sort();
    assert_eq!(files, expected_files);
    for file in &files {
        let bytes = std::fs::read(dir.join(file)).unwrap();
        assert_eq!(&bytes[..8], b"\x89HDF\r\n\x1a\n", "{file}");
    }

    // The values: u⁰ is the case's initial condition sin(πx) sin(πy) at the
    // vertices; u_exact of every level is the case's exact solution.
    let vertices = read_f64(&dir.join("out.partial/mesh.h5"), "mesh/vertices");
    assert_eq!(vertices.len(), 3 * 41 * 41);
    let pi = std::f64::consts::PI;
    let mode = |x: f64, y: f64| (pi * x).sin() * (pi * y).sin();
    let u0 = read_f64(&dir.join("out.partial/level-0.h5"), "steps/0/u");
    assert_eq!(u0.len(), 41 * 41);
    for (v, &u) in u0.iter().enumerate() {
        let (x, y) = (vertices[3 * v], vertices[3 * v + 1]);
        assert!(
            abs_diff_eq!(u, mode(x, y), epsilon = 1e-12),
            "vertex {v} ({x}, {y}): {u}"
        );
    }
    for (j, &t) in times.iter().enumerate() {
        let level = dir.join(format!("out.partial/level-{j}.h5"));
        let exact = read_f64(&level, &format!("steps/{j}/u_exact"));
        let u = read_f64(&level, &format!("steps/{j}/u"));
        let error = read_f64(&level, &format!("steps/{j}/error"));
        for v in 0..exact.len() {
            let (x, y) = (vertices[3 * v], vertices[3 * v + 1]);
            let formula = (-2.0 * pi * pi * t).exp() * mode(x, y) + t * (x + y);
            assert!(
                abs_diff_eq!(exact[v], formula, epsilon = 1e-12),
                "level {j} vertex {v}"
            );
            assert_abs_diff_eq!(error[v], u[v] - exact[v], epsilon = 1e-12);
        }
    }
    // A reader that knows nothing of hasse opens the partial series.
    if let Some(python) = crate::pyenv::python_or_skip("interrupted_output") {
        let script = r#"
import sys, meshio
with meshio.xdmf.TimeSeriesReader(sys.argv[1]) as reader:
    points, cells = reader.read_points_cells()
    t0, point_data, _ = reader.read_data(0)
    print(reader.num_steps, len(points), t0, len(point_data["u"]))
"#;
        let out = Command::new(python)
            .args(["-c", script, partial_xdmf.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = String::from_utf8(out.stdout).unwrap();
        assert_eq!(
            line.split_whitespace().collect::<Vec<_>>(),
            [times.len().to_string().as_str(), "1681", "0.0", "1681"]
        );
    }

    // A re-run under the same stem removes the stale partial output at
    // start, says so, and leaves only the final files.
    let out = hasse(&[
        "run",
        "cases/heat-square.toml",
        "--set",
        "mesh.n=[8,8]",
        "-v",
        "-o",
        stem.to_str().unwrap(),
    ])
    .output()
    .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "removed the partial output of an earlier run, {}",
            partial_xdmf.display()
        )),
        "{stderr}"
    );
    assert!(
        stderr.contains(&format!("completed levels in {}", partial_xdmf.display())),
        "{stderr}"
    );
    assert_eq!(names(&dir), ["out.h5", "out.xdmf"]);
    let final_times = hdf5::File::open(dir.join("out.h5"))
        .unwrap()
        .attr("times")
        .unwrap()
        .read_raw::<f64>()
        .unwrap();
    // 0.1 / 0.005 = 20 steps, every 2nd saved: 11 levels.
    assert_eq!(final_times.len(), 11);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_failed_heat_run_says_which_levels_are_readable() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("hasse-failed-heat-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // Forward Euler far beyond its stability limit (Δt λ_max ≈ 100 per
    // step): the temperature overflows after some 150 steps.
    let case = dir.join("blow-up.toml");
    std::fs::write(
        &case,
        r#"
[mesh]
generator = "rectangle"
n = [16, 16]

[problem]
kind = "heat"
method = "fe"
initial = "sin(pi*x) * sin(pi*y)"

[[boundary]]
tag = "boundary"
type = "dirichlet"
value = 0

[time]
dt = 0.05
end = 10
theta = 0
save_every = 20
"#,
    )
    .unwrap();
    let stem = dir.join("out");
    let out = hasse(&["run", case.to_str().unwrap(), "-o", stem.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the temperature is not finite")
            && stderr.contains("is only conditionally stable"),
        "{stderr}"
    );
    let partial_xdmf = dir.join("out.partial.xdmf");
    let xml = std::fs::read_to_string(&partial_xdmf).unwrap();
    let times = xdmf_times(&xml);
    assert!(times.len() >= 2, "{times:?}");
    assert!(
        stderr.contains(&format!(
            "completed levels 0..{} (t = 0, 1, ",
            times.len() - 1
        )) && stderr.contains(&format!("are readable in {}", partial_xdmf.display())),
        "{stderr}"
    );
    assert!(!stderr.contains("no output written"), "{stderr}");
    // Every listed level is finite; the first non-finite one is not listed.
    for (j, &t) in times.iter().enumerate() {
        let level = dir.join(format!("out.partial/level-{j}.h5"));
        let u = read_f64(&level, &format!("steps/{j}/u"));
        assert!(u.iter().all(|v| v.is_finite()), "level {j}");
        assert!(
            abs_diff_eq!(t, j as f64, epsilon = 1e-12),
            "level {j}: t = {t}"
        );
    }
    assert!(!names(&dir).contains(&"out.h5".to_string()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_file_in_the_way_of_the_partial_output_costs_a_warning_not_the_run() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("hasse-partial-blocked-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // Not ours to remove, and no directory can be made under its name.
    std::fs::write(dir.join("out.partial"), "someone's notes").unwrap();
    let out = hasse(&[
        "run",
        "cases/heat-square.toml",
        "--set",
        "mesh.n=[8,8]",
        "-o",
        dir.join("out").to_str().unwrap(),
    ])
    .output()
    .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.contains("warning    the partial output stopped early:")
            && stdout
                .contains("the output is complete, but the partial output could not be removed"),
        "{stdout}"
    );
    assert_eq!(names(&dir), ["out.h5", "out.partial", "out.xdmf"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("out.partial")).unwrap(),
        "someone's notes"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
