//! The layering of `solver/src` (see the crate documentation, `lib.rs`):
//! dependencies point one way,
//!
//! ```text
//! la ← {multigrid, operator} ← metric ← physics ← {refine, study, distributed} ← frontend
//! ```
//!
//! This test reads every source file of the crate and fails when a module
//! names (`crate::…`) a module of its own layer's rank or higher, other
//! than itself, or when the complex is named where it must not be: `la`
//! knows no complex, and in `multigrid` only the transfers do. Comments
//! and test code (`tests.rs` files, `tests/` directories, and everything after `#[cfg(test)]`)
//! do not count: a test may build realistic input with a higher layer (an
//! FE metric to exercise the operator) without making the library depend
//! on it.

use std::path::{Path, PathBuf};

/// Each top-level module of the library and its rank: a module may name
/// only modules of lower rank (and itself).
const LAYERS: [(&str, usize); 9] = [
    ("la", 0),
    ("multigrid", 1),
    ("operator", 1),
    ("metric", 2),
    ("physics", 3),
    ("refine", 4),
    ("study", 4),
    ("distributed", 4),
    ("frontend", 5),
];

fn rank(module: &str) -> Option<usize> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, r)| r)
}

fn source_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            source_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The line without its comment: everything from a `//` that is not
/// inside a string literal.
fn code(line: &str) -> &str {
    let mut in_string = false;
    let mut previous = ' ';
    for (i, c) in line.char_indices() {
        match c {
            '"' if previous != '\\' => in_string = !in_string,
            '/' if !in_string && previous == '/' => return &line[..i - 1],
            _ => {}
        }
        previous = c;
    }
    line
}

/// Every `crate::<module>` a line of code names.
fn named_modules(line: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = code(line);
    while let Some(i) = rest.find("crate::") {
        let before = rest[..i].chars().last();
        rest = &rest[i + "crate::".len()..];
        // `hasse_complex::` and the like end in "crate::" too.
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        out.push(&rest[..end]);
    }
    out
}

#[test]
fn lower_layers_never_name_higher_ones() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    source_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut checked = 0;
    for file in &files {
        let relative = file.strip_prefix(&src).unwrap();
        let Some(layer) = relative
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .filter(|c| !c.ends_with(".rs"))
        else {
            // lib.rs declares the layers; main.rs may use all of them.
            continue;
        };
        let own = rank(layer)
            .unwrap_or_else(|| panic!("{}: `{layer}` is not in LAYERS", relative.display()));
        // Test code: `tests.rs` files and `tests/` directories of a layer.
        if relative.ends_with("tests.rs") || relative.components().any(|c| c.as_os_str() == "tests")
        {
            continue;
        }
        let text = std::fs::read_to_string(file).unwrap();
        let library = text.split("#[cfg(test)]").next().unwrap_or("");
        for (number, line) in library.lines().enumerate() {
            checked += 1;
            let at = format!("{}:{}", relative.display(), number + 1);
            for module in named_modules(line) {
                if module == layer {
                    continue;
                }
                match rank(module) {
                    Some(r) if r < own => {}
                    Some(r) => violations.push(format!(
                        "{at}: `{layer}` (rank {own}) names `crate::{module}` (rank {r})"
                    )),
                    None => violations.push(format!("{at}: `crate::{module}` is no layer")),
                }
            }
            let names_complex = code(line).contains("hasse_complex");
            let transfers = relative.ends_with("multigrid/transfer.rs");
            if names_complex && (layer == "la" || (layer == "multigrid" && !transfers)) {
                violations.push(format!("{at}: `{layer}` names the complex"));
            }
        }
    }
    assert!(
        checked > 10_000,
        "read only {checked} lines of {}",
        src.display()
    );
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

#[test]
fn the_check_sees_what_it_looks_for() {
    // The parser of the test itself, on lines with a known answer.
    assert_eq!(named_modules("use crate::la::fixed::FixedSplit;"), ["la"]);
    assert_eq!(
        named_modules("let x = crate::physics::point_text(&y); // crate::frontend"),
        ["physics"]
    );
    assert!(named_modules("use hasse_complex::Complex;").is_empty());
    assert!(named_modules("/// [`crate::frontend::run`]").is_empty());
    assert_eq!(
        code(r#"let url = "https://toml.io"; // a comment"#),
        r#"let url = "https://toml.io"; "#
    );
    assert_eq!(rank("metric"), Some(2));
}
