//! An interrupted run leaves no output under its final names: `hasse run`
//! is killed (SIGKILL, then SIGINT) while it writes the HDF5 file, which it
//! writes under a temporary name and renames only when complete. After the
//! kill, no `out.h5` / `out.xdmf` exists; a new run then succeeds.

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

/// Start a run, wait until its h5 temporary appears, stop it with `signal`.
fn interrupt(dir: &Path, signal: &str) {
    let mut child = start(&dir.join("out"));
    let deadline = Instant::now() + Duration::from_secs(120);
    let temporary = loop {
        if let Some(name) = names(dir)
            .into_iter()
            .find(|n| n.starts_with(".out.h5.tmp-"))
        {
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
}

#[test]
fn a_killed_run_leaves_no_output_and_a_rerun_succeeds() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("hasse-interrupted-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    interrupt(&dir, "-KILL");
    interrupt(&dir, "-INT");
    let status = start(&dir.join("out")).wait().unwrap();
    assert!(status.success());
    let left = names(&dir);
    for final_name in ["out.h5", "out.xdmf", "out.edges.xdmf"] {
        assert!(left.iter().any(|n| n == final_name), "{left:?}");
    }
    // The complete file opens as HDF5 (signature at offset 0).
    let h5 = std::fs::read(dir.join("out.h5")).unwrap();
    assert_eq!(&h5[..8], b"\x89HDF\r\n\x1a\n");
    std::fs::remove_dir_all(&dir).unwrap();
}
