//! The private Python environment of the tests that read output files as a
//! user would: a venv at `<target>/pyenv` with h5py and meshio, created
//! with `pip install h5py meshio` when missing.
//!
//! Declare it once in a test binary's `main.rs` with
//! `#[path = "../common/pyenv.rs"] mod pyenv;` and call
//! [`python_or_skip`] at the start of each test that needs Python.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

/// The outcome of the first attempt in this process, kept so that tests of
/// one binary (run on parallel threads) neither create the venv at the
/// same time nor retry an install that already failed. `cargo test` runs
/// test binaries one after another, so a process-wide lock is enough.
static PYTHON: Mutex<Option<Result<PathBuf, String>>> = Mutex::new(None);

/// The venv's python with h5py and meshio importable, or `None` after a
/// loud skip message on stderr naming `test_name` when it cannot be had.
/// Under `CI` (environment variable set) an unavailable environment is a
/// failure, not a skip, so CI cannot pass without running the checks.
pub fn python_or_skip(test_name: &str) -> Option<PathBuf> {
    // A test that panicked while holding the lock left a usable value (the
    // lock only guards the cached outcome), so poisoning is ignored.
    let mut cached = PYTHON
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let outcome = cached.get_or_insert_with(python).clone();
    drop(cached);
    match outcome {
        Ok(python) => Some(python),
        Err(why) => {
            if std::env::var_os("CI").is_some() {
                panic!("{test_name}: h5py/meshio environment unavailable under CI: {why}");
            }
            eprintln!("\n!!!!!!!! SKIPPED {test_name}: no h5py/meshio venv ({why}) !!!!!!!!\n");
            None
        }
    }
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../target"))
}

fn imports_work(python: &Path) -> bool {
    Command::new(python)
        .args(["-c", "import h5py, meshio"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The venv's python with h5py and meshio, or why it could not be had.
fn python() -> Result<PathBuf, String> {
    let venv = target_dir().join("pyenv");
    let python = venv.join("bin").join("python");
    if imports_work(&python) {
        return Ok(python);
    }
    let run = |cmd: &mut Command| -> Result<(), String> {
        let out = cmd.output().map_err(|e| format!("{cmd:?}: {e}"))?;
        if out.status.success() {
            Ok(())
        } else {
            Err(format!(
                "{cmd:?} failed:\n{}",
                String::from_utf8_lossy(&out.stderr)
            ))
        }
    };
    run(Command::new("python3").args(["-m", "venv"]).arg(&venv))?;
    run(Command::new(venv.join("bin").join("pip")).args(["install", "--quiet", "h5py", "meshio"]))?;
    if imports_work(&python) {
        Ok(python)
    } else {
        Err("h5py and meshio installed but do not import".into())
    }
}
