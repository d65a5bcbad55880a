//! Per-test scratch directories under cargo's `CARGO_TARGET_TMPDIR`.
//!
//! The tests of one binary run on parallel threads of one process, and two
//! `cargo test` runs may share a target directory, so a fixed path is not
//! safe: a scratch directory is named after the test and the process id.
//! It is removed when the guard is dropped after the test passed, and kept
//! (for inspection) when the test panicked.
//!
//! Declare it in a binary's `main.rs` with
//! `#[path = "../common/scratch.rs"] mod scratch;`.

use std::ops::Deref;
use std::path::{Path, PathBuf};

/// A scratch directory that does not exist yet (the code under test may
/// create it); derefs to its path.
pub struct Scratch(PathBuf);

impl Scratch {
    /// `<CARGO_TARGET_TMPDIR>/<name>-<process id>`, emptied: any leftover of
    /// an earlier process with the same id is removed, and nothing is created.
    pub fn new(name: &str) -> Scratch {
        let dir =
            Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Scratch(dir)
    }
}

impl Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
