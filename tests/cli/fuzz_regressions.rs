//! Inputs that once crashed a fuzz target (`scripts/fuzz`), replayed on
//! stable with the same harness code as the targets
//! (`solver/fuzz/harness.rs`). Each file of `tests/fuzz-regressions/TARGET/`
//! is one input (`tests/fuzz-regressions/README.md` says what is kept
//! there); the test fails if any still panics, and if the directory is
//! missing or holds no input, since a replay of nothing proves nothing.

#[path = "../../solver/fuzz/harness.rs"]
mod harness;

use std::cell::Cell;
use std::path::Path;
use std::sync::Once;

thread_local! {
    /// Set by the panic hook: the Gmsh reader catches panics of the mshio
    /// parser, so an input that makes mshio panic returns an error all the
    /// same; the panic still counts as the crash the fuzzer found.
    static PANICKED: Cell<bool> = const { Cell::new(false) };
}

fn watch_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            PANICKED.with(|p| p.set(true));
            default(info);
        }));
    });
}

/// Where a corpus lives (repository-relative) and how to get it back, for
/// the failure messages.
fn restore_hint(target: &str) -> String {
    format!(
        "restore tests/fuzz-regressions/{target}/ with \
         `git checkout HEAD -- tests/fuzz-regressions/{target}`, or put at least \
         one input there (a crash input from solver/fuzz/artifacts/{target}/ \
         after `scripts/fuzz`; see tests/fuzz-regressions/README.md)"
    )
}

/// Run every kept input of `target`; returns how many there were. A
/// missing or empty corpus directory is a failure, not a silent pass.
fn replay(target: &str, run: fn(&[u8])) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fuzz-regressions")
        .join(target);
    let mut count = 0;
    let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| {
        panic!(
            "the `{target}` fuzz corpus {} cannot be read ({e}): {}",
            dir.display(),
            restore_hint(target)
        )
    });
    for entry in entries {
        let path = entry.unwrap().path();
        if path.file_name().is_some_and(|n| n == "README.md") {
            continue;
        }
        let bytes = std::fs::read(&path).unwrap();
        watch_panics();
        PANICKED.with(|p| p.set(false));
        let outcome = std::panic::catch_unwind(|| run(&bytes));
        let panicked = PANICKED.with(Cell::get);
        assert!(
            outcome.is_ok() && !panicked,
            "{} still crashes",
            path.display()
        );
        count += 1;
    }
    assert!(
        count > 0,
        "the `{target}` fuzz corpus {} holds no input, so nothing was replayed: {}",
        dir.display(),
        restore_hint(target)
    );
    count
}

#[test]
fn case_file_inputs() {
    replay("case_file", harness::case_file);
}

#[test]
fn expression_inputs() {
    replay("expression", harness::expression);
}

#[test]
fn gmsh_inputs() {
    // The two committed crash inputs (inverted-node-tag-range.msh,
    // twisted-hex-dd-nonzero.msh).
    assert!(replay("gmsh", harness::gmsh) >= 2);
}

#[test]
fn complex_build_inputs() {
    replay("complex_build", harness::complex_build);
}

/// The harnesses themselves accept ordinary input (so a replay that
/// passes means something): a real case, expression, mesh and complex.
#[test]
fn harnesses_run_on_valid_input() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    harness::case_file(&std::fs::read(root.join("cases/poisson-square.toml")).unwrap());
    harness::expression(b"k * sin(pi*x) + r\nr = sqrt(x^2 + y^2)");
    harness::gmsh(&std::fs::read(root.join("cases/l-shape.msh")).unwrap());
    // Two triangles of the unit square (see harness::complex_build's decoding).
    harness::complex_build(&[1, 3, 0, 0, 4, 0, 4, 4, 0, 4, 0, 1, 3, 0, 1, 2, 3, 0, 2, 3]);
}
