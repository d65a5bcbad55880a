//! Every `hasse …` command line the documentation prints runs as printed:
//! the lines of the code blocks (but Rust's) of `README.md`,
//! `cases/README.md` and `benches/README.md` that start with `hasse` and
//! a subcommand,
//! the `hasse …` commands in the comments of `cases/*.toml`, and the
//! examples of `hasse --help` and of each subcommand's help.
//!
//! Each command runs in a scratch directory holding a link `cases` to the
//! shipped cases, so paths are the printed ones and outputs (`./NAME.h5`,
//! `-o out/fv`, `converge-…/`) land in the scratch directory. Commands are
//! split like a shell would (quotes, backslash escapes, `#` comments).
//!
//! Skipped, by the two lists below and nowhere else:
//! - `SYNOPSIS`: usage lines with placeholders (`CASE`, `N`, `[...]`), not
//!   commands (and clap's `Usage:` lines of the help);
//! - `SHRUNK`: commands whose case is too large to solve in a few seconds
//!   in a debug build; they run with `--set` overrides appended that only
//!   shrink the mesh (the printed command is still checked by `hasse
//!   check` as printed).
//!
//! No documented command needs mpirun, Python or ParaView today; a
//! command that does would be listed here with the reason.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Usage lines: placeholders, not runnable.
const SYNOPSIS: &[&str] = &[
    "hasse converge CASE --levels N [--methods fd,fe,...] [-o DIR] [--expect ORDER[:TOL]] [--set KEY=VALUE ...] [-q]",
];

/// Commands too expensive for a debug build as printed, and the
/// overrides (appended; they only make the mesh smaller) they run with.
const SHRUNK: &[(&str, &[&str])] = &[
    // 1000 × 1000 cells (10⁶), about 20 s: 64 × 64 keeps the even counts
    // the multigrid hierarchy halves.
    (
        "hasse run cases/poisson-multigrid.toml",
        &["--set", "mesh.n=[64,64]"],
    ),
    // Studies of three or four methods up to 256² or 512² cells: 9–36 s;
    // half the resolution on every level is a quarter of that.
    (
        "hasse converge cases/distorted-quads.toml --levels 5 --methods fv,fv-mimetic,fe -o out/dq",
        &["--set", "mesh.n=[8,8]"],
    ),
    (
        "hasse converge cases/distorted-quads.toml --levels 6 --set mesh.n=[8,8] --methods fv,fv-mimetic,fe",
        &["--set", "mesh.n=[4,4]"],
    ),
    (
        "hasse converge cases/poisson-square.toml --levels 4 --methods fd,fe,fv,fv-mimetic",
        &["--set", "mesh.n=[8,8]"],
    ),
    (
        "hasse converge cases/poisson-square.toml --levels 4 --set mesh.cells=simplex --methods dec,fe",
        &["--set", "mesh.n=[8,8]"],
    ),
    (
        "hasse converge cases/poisson-square.toml --levels 4 --methods dec,fe --set mesh.cells=simplex",
        &["--set", "mesh.n=[8,8]"],
    ),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Split a command line as `sh` would for these simple lines: whitespace
/// separates words, quotes group, a backslash escapes the next character,
/// an unquoted `#` starts a comment.
fn shell_words(line: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut chars = line.chars();
    let mut quote: Option<char> = None;
    while let Some(c) = chars.next() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some('"'), '\\') => {
                if let Some(next) = chars.next() {
                    word.get_or_insert_with(String::new).push(next);
                }
            }
            (Some(_), c) => word.get_or_insert_with(String::new).push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                word.get_or_insert_with(String::new);
            }
            (None, '\\') => {
                if let Some(next) = chars.next() {
                    word.get_or_insert_with(String::new).push(next);
                }
            }
            (None, '#') if word.is_none() => break,
            (None, c) if c.is_whitespace() => words.extend(word.take()),
            (None, c) => word.get_or_insert_with(String::new).push(c),
        }
    }
    words.extend(word);
    words
}

/// The `hasse` command starting at `line`'s first `hasse ` (with its
/// source for messages), if the line has one followed by a subcommand.
fn command_in(line: &str) -> Option<String> {
    let at = line.find("hasse ")?;
    let command = line[at..].trim();
    let sub = command.split_whitespace().nth(1)?;
    ["run", "check", "refine", "info", "converge", "export"]
        .contains(&sub)
        .then(|| command.to_string())
}

/// Every documented command line, with where it is printed.
fn documented() -> Vec<(String, String)> {
    let mut found = Vec::new();
    for doc in ["README.md", "cases/README.md", "benches/README.md"] {
        let text = std::fs::read_to_string(root().join(doc)).unwrap();
        // Any code block but Rust's: a line that starts with `hasse` and a
        // subcommand.
        let mut in_block = false;
        let mut rust = false;
        for (i, line) in text.lines().enumerate() {
            if let Some(fence) = line.trim_start().strip_prefix("```") {
                in_block = !in_block;
                rust = fence.trim().starts_with("rust");
                continue;
            }
            let command = line.trim_start();
            if in_block && !rust && command.starts_with("hasse ") {
                if let Some(command) = command_in(command) {
                    found.push((format!("{doc}:{}", i + 1), command));
                }
            }
        }
    }
    let mut cases: Vec<PathBuf> = std::fs::read_dir(root().join("cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    cases.sort();
    for case in cases {
        let text = std::fs::read_to_string(&case).unwrap();
        for (i, line) in text.lines().enumerate() {
            let Some(comment) = line.trim_start().strip_prefix('#') else {
                continue;
            };
            if let Some(command) = command_in(comment) {
                let name = case.file_name().unwrap().to_string_lossy();
                found.push((format!("cases/{name}:{}", i + 1), command));
            }
        }
    }
    let bin = env!("CARGO_BIN_EXE_hasse");
    for sub in ["", "run", "refine", "check", "info", "converge", "export"] {
        let mut args: Vec<&str> = Vec::new();
        if !sub.is_empty() {
            args.push(sub);
        }
        args.push("--help");
        let out = Command::new(bin).args(&args).output().unwrap();
        let help = String::from_utf8(out.stdout).unwrap();
        // `Usage: hasse run [OPTIONS] <CASE>` is clap's synopsis, not a command.
        for line in help.lines().filter(|l| !l.starts_with("Usage:")) {
            if let Some(command) = command_in(line) {
                found.push((format!("hasse {sub} --help"), command));
            }
        }
    }
    found
}

/// The printed commands, found where they are printed: if the extraction
/// broke, the test below would pass vacuously.
#[test]
fn the_documented_commands_are_found() {
    let commands = documented();
    let has = |text: &str| commands.iter().any(|(_, c)| c.contains(text));
    assert!(has(
        "hasse run cases/l-shape-adaptive.toml --set refine.strategy=uniform"
    ));
    assert!(has("hasse refine cases/l-shape-adaptive.toml --steps 4"));
    assert!(has("hasse check cases/poisson-square.toml"));
    assert!(has("hasse converge cases/box-3d.toml"));
    assert!(has("mesh.n=\\[64,64\\]"), "help examples are found");
    assert_eq!(
        shell_words("hasse run a.toml --set mesh.n=\\[64,64\\] -o 'x y'   # → out"),
        [
            "hasse",
            "run",
            "a.toml",
            "--set",
            "mesh.n=[64,64]",
            "-o",
            "x y"
        ]
    );
    for synopsis in SYNOPSIS {
        assert!(
            has(synopsis),
            "SYNOPSIS entry not printed anywhere: {synopsis}"
        );
    }
    for (command, _) in SHRUNK {
        assert!(has(command), "SHRUNK entry not printed anywhere: {command}");
    }
}

#[test]
fn every_documented_command_runs_as_printed() {
    let scratch = crate::scratch::Scratch::new("doc-commands");
    std::fs::create_dir_all(&*scratch).unwrap();
    let bin = env!("CARGO_BIN_EXE_hasse");
    let mut failures = Vec::new();
    for (index, (place, line)) in documented().iter().enumerate() {
        if SYNOPSIS.contains(&line.as_str()) {
            continue;
        }
        let words = shell_words(line);
        assert_eq!(words[0], "hasse", "{place}: {line}");
        let mut args: Vec<String> = words[1..].to_vec();
        // Each command in its own directory: outputs do not meet.
        let dir = scratch.join(format!("{index}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::os::unix::fs::symlink(root().join("cases"), dir.join("cases")).unwrap();
        let shrunk = SHRUNK.iter().find(|(c, _)| c == line);
        if let Some((_, extra)) = shrunk {
            // The command as printed is valid input.
            let mut check = vec!["check".to_string(), args[1].clone()];
            check.extend(
                args.windows(2)
                    .filter(|w| w[0] == "--set")
                    .flat_map(|w| w.to_vec()),
            );
            let out = Command::new(bin)
                .args(&check)
                .current_dir(&dir)
                .output()
                .unwrap();
            if !out.status.success() {
                failures.push(format!(
                    "{place}: `hasse {}` failed:\n{}",
                    check.join(" "),
                    String::from_utf8_lossy(&out.stderr)
                ));
            }
            args.extend(extra.iter().map(|s| s.to_string()));
        }
        let started = std::time::Instant::now();
        let out = Command::new(bin)
            .args(&args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() || stderr.contains("panicked") {
            failures.push(format!(
                "{place}: `{line}` exited with {:?}:\n{stderr}",
                out.status.code()
            ));
        }
        eprintln!(
            "{place}: {line}{} ({:.1} s)",
            if shrunk.is_some() { " (shrunk)" } else { "" },
            started.elapsed().as_secs_f64()
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
