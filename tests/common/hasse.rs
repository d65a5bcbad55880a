//! The `hasse` binary run as a user runs it: from the repository root,
//! its output captured. Declare it in a binary's `main.rs` with
//! `#[path = "../common/hasse.rs"] mod hasse;`.

use std::path::Path;
use std::process::{Command, Output};

/// `hasse ARGS…` in the repository root.
pub fn hasse(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("the hasse binary runs")
}

/// `hasse run CASE --set output.write=false --set …`, which must succeed:
/// its summary (stdout).
pub fn summary(case: &str, sets: &[&str]) -> String {
    let mut args = vec!["run", case, "--set", "output.write=false"];
    for s in sets {
        args.extend(["--set", s]);
    }
    let out = hasse(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "hasse {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}
