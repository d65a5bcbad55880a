//! `[output] fields` and `partial` (issue 29, item 5): what a run writes.

use crate::scratch::Scratch;
use std::process::Command;

fn run(args: &[&str]) -> std::process::Output {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(root)
        .output()
        .unwrap()
}

#[test]
fn output_fields_selects_what_is_written() {
    let dir = Scratch::new("output_fields");
    let stem = dir.join("plate");
    let out = run(&[
        "run",
        "cases/two-materials.toml",
        "-o",
        stem.to_str().unwrap(),
        "--set",
        "output.fields=[\"u\", \"flux\", \"fluxx\"]",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = hdf5::File::open(stem.with_extension("h5")).unwrap();
    let mut written = file.group("steps/0").unwrap().member_names().unwrap();
    written.sort();
    assert_eq!(written, ["flux", "u"]);
    // A name the run does not produce is said, with the names it does.
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("output.fields names `fluxx`, which this run does not produce (it produces conductivity, edge_flux, error, flux,"),
        "{stdout}"
    );
    let bad = run(&[
        "check",
        "cases/two-materials.toml",
        "--set",
        "output.fields=[]",
    ]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("a non-empty array of field names"));
}

#[test]
fn partial_false_writes_the_transient_output_once_at_the_end() {
    let dir = Scratch::new("output_partial");
    for partial in ["true", "false"] {
        let stem = dir.join(format!("heat-{partial}"));
        let set = format!("output.partial={partial}");
        let out = run(&[
            "run",
            "cases/heat-square.toml",
            "-o",
            stem.to_str().unwrap(),
            "--set",
            &set,
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        // The partial output is timed when it is written, and only then.
        assert_eq!(
            stdout.contains("partial output"),
            partial == "true",
            "{stdout}"
        );
        // Either way the final output holds every saved level.
        let file = hdf5::File::open(stem.with_extension("h5")).unwrap();
        assert_eq!(
            file.group("steps").unwrap().member_names().unwrap().len(),
            11,
            "{partial}"
        );
    }
}

#[test]
fn an_output_larger_than_the_free_space_is_refused_before_solving() {
    // heat-square: 21 levels of 33² vertices with u, u_exact and error, and
    // its mesh, twice over with the partial output: well above 100 kB.
    let dir = Scratch::new("output_disk");
    let stem = dir.join("heat");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args([
            "run",
            "cases/heat-square.toml",
            "-o",
            stem.to_str().unwrap(),
        ])
        .env("HASSE_DISK_LIMIT", "100000")
        .current_dir(&root)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("the output would take at least")
            && stderr.contains("97.7 KiB free (HASSE_DISK_LIMIT)"),
        "{stderr}"
    );
    // Refused before solving: no time step was taken, nothing is written.
    assert!(!String::from_utf8_lossy(&out.stdout).contains("time "));
    assert!(!stem.with_extension("h5").exists());
}
