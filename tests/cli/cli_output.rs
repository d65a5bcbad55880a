//! A real client reads what `hasse run` wrote: h5py recomputes the printed
//! errors from the stored arrays (its own cell areas and exact values), and
//! meshio opens the XDMF and finds the cells and the field.

use std::path::Path;
use std::process::Command;

#[test]
fn h5py_and_meshio_read_a_run() {
    let Some(python) = crate::pyenv::python_or_skip("cli_output") else {
        return;
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = crate::scratch::Scratch::new("cli_output");
    let stem = dir.join("fv");
    let out = Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args([
            "run",
            "cases/poisson-square.toml",
            "--set",
            "problem.method=fv",
            "-o",
        ])
        .arg(&stem)
        .current_dir(&root)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The sampled L² (at the cell points) is what the script recomputes;
    // the max is also a sampled figure, on the `error` line.
    let number = |prefix: &str, label: &str| -> String {
        let line = stdout.lines().find(|l| l.starts_with(prefix)).unwrap();
        let rest = &line[line.find(label).unwrap() + label.len()..];
        rest.trim_start()
            .split([',', ' '])
            .next()
            .unwrap()
            .to_string()
    };
    let check = Command::new(python)
        .arg(root.join("tests/python/check_run.py"))
        .arg(&stem)
        .arg(number("sampled", "L2"))
        .arg(number("error", "max"))
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "check_run.py failed:\n{}{}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );
}
