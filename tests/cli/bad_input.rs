//! The bad-input catalogue: every case file in `tests/bad-input/` is run
//! with `hasse run`, and the table below says what must happen: the exit
//! code (2 for bad input, 1 for a solve that fails), where the message
//! points (file and line, or the cell / point it names), the words of the
//! message and its hint. No run may panic or leave output behind. A file
//! added to the directory without a row here fails the test, so the table
//! stays the complete list (`tests/bad-input/README.md` explains it).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

struct Bad {
    /// File stem in tests/bad-input/.
    file: &'static str,
    /// `--set` overrides the file is run with (the bad value comes from the
    /// command line: the error must name the `--set` text, not a line).
    set: &'static [&'static str],
    exit: i32,
    /// Line the first error names (`file:line:`), when the problem has one.
    line: Option<usize>,
    /// Fragments the error output must contain.
    says: &'static [&'static str],
}

const CATALOGUE: &[Bad] = &[
    // ---- the case file itself
    Bad {
        set: &[],
        file: "malformed",
        exit: 2,
        line: Some(3),
        says: &["not valid TOML", "help: see https://toml.io"],
    },
    Bad {
        set: &[],
        file: "unknown-key",
        exit: 2,
        line: Some(7),
        says: &["`problem.methdo`: unknown key", "did you mean `method`?"],
    },
    Bad {
        set: &[],
        file: "wrong-type",
        exit: 2,
        line: Some(8),
        says: &["`problem.conductivity`: expected a number or an expression string, found a boolean"],
    },
    Bad {
        set: &[],
        file: "several-problems",
        exit: 2,
        line: Some(5),
        says: &["unknown method \"fem\"", "unknown variable `pie`", "residual_limit"],
    },
    // ---- expressions
    Bad {
        set: &[],
        file: "bad-expression",
        exit: 2,
        line: Some(8),
        says: &["cannot parse `sin(pi*x`", "help: operators"],
    },
    Bad {
        set: &[],
        file: "unknown-variable",
        exit: 2,
        line: Some(11),
        says: &["unknown variable `kapa`", "did you mean `kappa`?"],
    },
    Bad {
        set: &[],
        file: "nonfinite-constant",
        exit: 2,
        line: Some(12),
        says: &["`boundary[0].value`: `sqrt(-1)` evaluates to NaN", "help: give a finite value"],
    },
    Bad {
        set: &[],
        file: "division-by-zero",
        exit: 2,
        line: Some(9),
        says: &[
            "`problem.source`: the source is not finite (∞) at (0.375, 0.125)",
            "check divisions",
            "no output written",
        ],
    },
    Bad {
        set: &[],
        file: "singular-source",
        exit: 2,
        line: Some(11),
        says: &[
            "`problem.source`: the source is not finite (NaN) at (0.125, 0.125)",
            "no output written",
        ],
    },
    Bad {
        set: &[],
        file: "nan-source",
        exit: 2,
        line: Some(10),
        // The first Gauss point of cell 0 = [−1, −½] × [0, ¼]: x = −¾ − ¼/√3.
        says: &[
            "`problem.source`: the source is not finite (NaN) at (-0.8943375672974064, ",
            "no output written",
        ],
    },
    Bad {
        set: &["problem.source=ln(x)"],
        file: "nan-source-set",
        exit: 2,
        line: None,
        says: &[
            "`problem.source`: the source is not finite (NaN) at (-0.8943375672974064, ",
            "no output written",
        ],
    },
    // ---- coefficients
    Bad {
        set: &[],
        file: "negative-conductivity",
        exit: 2,
        line: Some(8),
        says: &[
            "`problem.conductivity`: the conductivity at (0.125, 0.125) (top cell 0) is not symmetric positive definite",
            "help: the conductivity must be finite and positive",
        ],
    },
    Bad {
        set: &["problem.conductivity=x - 0.5"],
        file: "negative-conductivity-set",
        exit: 2,
        line: None,
        says: &[
            "`problem.conductivity`: the conductivity at (0.125, 0.125) (top cell 0) is not symmetric positive definite",
        ],
    },
    Bad {
        set: &[],
        file: "nan-conductivity",
        exit: 2,
        line: Some(9),
        says: &["`problem.conductivity`: the conductivity at (0.125, 0.125) (top cell 0) is not finite"],
    },
    Bad {
        set: &[],
        file: "tensor-size",
        exit: 2,
        line: Some(8),
        says: &[
            "`problem.conductivity`: a 3×3 tensor, but the mesh lives in 2 dimensions",
            "help: give 2 rows of 2 entries",
        ],
    },
    Bad {
        set: &["problem.conductivity=[[1,0,0],[0,1,0],[0,0,1]]"],
        file: "tensor-size-set",
        exit: 2,
        line: None,
        says: &["`problem.conductivity`: a 3×3 tensor, but the mesh lives in 2 dimensions"],
    },
    // ---- mesh files
    Bad {
        set: &[],
        file: "missing-mesh-file",
        exit: 2,
        line: Some(3),
        says: &["`mesh.file`: cannot read Gmsh mesh", "No such file", "relative to the case file"],
    },
    Bad {
        set: &[],
        file: "unreadable-mesh",
        exit: 2,
        line: Some(3),
        says: &["`mesh.file`: cannot read Gmsh mesh", "directory.msh", "check the path"],
    },
    Bad {
        set: &[],
        file: "mesh-truncated",
        exit: 2,
        line: Some(3),
        says: &["truncated.msh' is not a valid Gmsh .msh 4.1 file", "probably truncated", "re-export it"],
    },
    Bad {
        set: &[],
        file: "mesh-version-2",
        exit: 2,
        line: Some(3),
        says: &["format version 2.2, but only version 4.1 can be read", "-format msh4"],
    },
    Bad {
        set: &[],
        file: "mesh-missing-node",
        exit: 2,
        line: Some(3),
        says: &["element 4 refers to node 9, which is not listed in the $Nodes section"],
    },
    Bad {
        set: &[],
        file: "mesh-duplicate-vertices",
        exit: 2,
        line: Some(3),
        says: &["vertices 2 and 4 coincide at [1.0, 1.0]", "merge duplicate nodes"],
    },
    Bad {
        set: &[],
        file: "mesh-degenerate",
        exit: 2,
        line: Some(3),
        says: &["2-cell 1 (vertices [0, 1, 3]) has zero 2-measure", "Gmsh element 2"],
    },
    Bad {
        set: &[],
        file: "mesh-inverted",
        exit: 2,
        line: Some(4),
        says: &["top cells 0 and 1 lie on the same side of their shared face 0", "inverted"],
    },
    Bad {
        set: &[],
        file: "mesh-overlap",
        exit: 2,
        line: Some(4),
        says: &["face 0 bounds 3 top cells ([0, 1, 2])", "the cells overlap"],
    },
    Bad {
        set: &[],
        file: "mesh-non-manifold",
        exit: 2,
        line: Some(3),
        says: &["1-cell 0 (vertices [0, 1]) bounds 3 top cells", "not a manifold"],
    },
    Bad {
        set: &[],
        file: "mesh-mobius",
        exit: 2,
        line: Some(3),
        says: &["not orientable: top cell 4", "Gmsh element 5"],
    },
    Bad {
        set: &[],
        file: "too-big",
        exit: 2,
        line: Some(5),
        says: &[
            "`mesh.n`: this mesh would have 4.000e10 top cells (1.600e11 cells of all dimensions, at least 2.000e11 nonzeros in the system)",
            "TiB of memory",
            "use a smaller mesh.n",
        ],
    },
    // ---- boundary conditions and the system
    Bad {
        set: &[],
        file: "unknown-tag",
        exit: 2,
        line: Some(10),
        says: &["no tag `bondary` in the mesh", "did you mean `boundary`?"],
    },
    Bad {
        set: &[],
        file: "disconnected",
        exit: 2,
        line: None,
        says: &[
            "2 disconnected parts",
            "vertex 4 (at [2.0, 0.0]) has no Dirichlet or Robin boundary",
            "put a Dirichlet or Robin condition",
        ],
    },
    Bad {
        set: &[],
        file: "incompatible-neumann",
        exit: 2,
        line: None,
        says: &["pure Neumann problem with incompatible data", "∫f + ∮g = 0"],
    },
    Bad {
        set: &[],
        file: "singular-system",
        exit: 1,
        line: None,
        says: &["the matrix is singular (a zero pivot)", "Check the boundary conditions and coefficients"],
    },
    // ---- messages of issue 30, item 13
    // (a) TOML's nan is a float: not "unknown variable `NaN`".
    Bad {
        set: &[],
        file: "nan-conductivity-literal",
        exit: 2,
        line: Some(9),
        says: &["`problem.conductivity`: `nan` is not a finite number", "help: give a finite value"],
    },
    // (b) A bad coordinate names its node, and no cells.
    Bad {
        set: &[],
        file: "mesh-nonfinite-vertex",
        exit: 2,
        line: Some(4),
        says: &["vertex 2 has a non-finite coordinate NaN on axis 0", "(vertex 2 is Gmsh node 3)"],
    },
    // (c) A repeated element is a duplicate, named by its element tags.
    Bad {
        set: &[],
        file: "mesh-duplicate-element",
        exit: 2,
        line: Some(4),
        says: &["element 3 duplicates element 1"],
    },
    // (d) A 198 002-character source: about 80 characters around the
    // unclosed `(` (character 198 001, the file's last but one), with a caret.
    Bad {
        set: &[],
        file: "long-expression",
        exit: 2,
        line: Some(10),
        says: &[
            "cannot parse the expression of 198002 characters: 1 `(` never closed",
            ", at character 198001:\n    …",
            " + x*y + (x\n",
        ],
    },
    // (e) The case keys, not the library's value names.
    Bad {
        set: &[],
        file: "maxwell-zero-star",
        exit: 2,
        line: Some(11),
        says: &["⋆1 of 1-cell 2 is 0e0 ≤ 0", "`mass = \"whitney\"`", "`method = \"dec-barycentric\"`"],
    },
    // A Hodge Laplacian's degree above the mesh's dimension.
    Bad {
        set: &[],
        file: "hodge-degree",
        exit: 2,
        line: Some(11),
        says: &["`problem.degree`: degree 3 is out of range: the mesh is 2-dimensional, so 0 ≤ degree ≤ 2"],
    },
    // (f) A negative constant permeability.
    Bad {
        set: &[],
        file: "negative-permeability",
        exit: 2,
        line: Some(13),
        says: &["`problem.permeability`: coefficient in top cell 0 is not symmetric positive definite"],
    },
    // ---- time
    Bad {
        set: &[],
        file: "time-cannot-advance",
        exit: 2,
        line: Some(19),
        says: &["`time.dt`: time.start + time.dt = time.start in floating point (start = 1e0, dt = 1e-300)"],
    },
    Bad {
        set: &[],
        file: "time-levels-repeat",
        exit: 2,
        line: Some(21),
        says: &["`time.dt`: the saved levels after step 1 and step 2 both have time 1.0000000000000002e0"],
    },
    // ---- output
    Bad {
        set: &[],
        file: "output-not-writable",
        exit: 2,
        line: None,
        says: &["output-not-writable.toml/out", "Not a directory", "help: choose a writable place"],
    },
];

/// Words some messages must not contain: a hint about cells when the
/// fault is a node, the library's value names instead of the case keys,
/// the whole of a 200 kB expression.
const NEVER: &[(&str, &[&str])] = &[
    ("mesh-nonfinite-vertex", &["inverted", "overlapping"]),
    ("mesh-duplicate-element", &["overlap"]),
    ("nan-conductivity-literal", &["unknown variable"]),
    ("maxwell-zero-star", &["Mass::"]),
    (
        "long-expression",
        &["x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y + x*y"],
    ),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn hasse(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the hasse binary runs")
}

#[test]
fn every_bad_input_is_in_the_catalogue() {
    let mut files: Vec<String> = std::fs::read_dir(root().join("tests/bad-input"))
        .unwrap()
        .filter_map(|e| {
            let path = e.unwrap().path();
            (path.extension()? == "toml").then(|| path.file_stem()?.to_str().map(String::from))?
        })
        .collect();
    files.sort();
    let mut listed: Vec<String> = CATALOGUE.iter().map(|b| b.file.to_string()).collect();
    listed.sort();
    assert_eq!(files, listed, "tests/bad-input/*.toml and CATALOGUE differ");
}

#[test]
fn every_bad_input_is_refused_clearly_and_writes_nothing() {
    let scratch = std::env::temp_dir().join(format!("hasse-bad-input-{}", std::process::id()));
    let mut failures = Vec::new();
    for bad in CATALOGUE {
        let dir = scratch.join(bad.file);
        std::fs::create_dir_all(&dir).unwrap();
        let file = format!("tests/bad-input/{}.toml", bad.file);
        let stem = dir.join("out");
        let mut args = vec!["run", file.as_str()];
        for set in bad.set {
            args.extend(["--set", set]);
        }
        // This file is about its own [output] directory.
        if bad.file != "output-not-writable" {
            args.extend(["-o", stem.to_str().unwrap()]);
        }
        let out = hasse(&args, &root());
        let stderr = String::from_utf8_lossy(&out.stderr);
        let mut wrong = Vec::new();
        if out.status.code() != Some(bad.exit) {
            wrong.push(format!(
                "exit {:?}, expected {}",
                out.status.code(),
                bad.exit
            ));
        }
        if stderr.contains("panicked") {
            wrong.push("it panicked".into());
        }
        let at = match (bad.line, bad.set) {
            (Some(line), _) => format!("error: {file}:{line}:"),
            (None, []) => format!("error: {file}: "),
            (None, [set, ..]) => format!("error: {file}: --set {set}: "),
        };
        if !stderr.starts_with(&at) {
            wrong.push(format!("the first error does not start with `{at}`"));
        }
        for fragment in bad.says {
            if !stderr.contains(fragment) {
                wrong.push(format!("no `{fragment}`"));
            }
        }
        let never = NEVER.iter().filter(|(f, _)| *f == bad.file);
        for fragment in never.flat_map(|(_, words)| words.iter()) {
            if stderr.contains(fragment) {
                wrong.push(format!("it says `{fragment}`"));
            }
        }
        // The excerpt of the 200 kB expression: no line much longer than
        // its 80 characters (plus the position and the message).
        let excerpt = bad.file == "long-expression";
        if let Some(long) = stderr.lines().find(|l| excerpt && l.chars().count() > 200) {
            wrong.push(format!("a line of {} characters", long.chars().count()));
        }
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        if !left.is_empty() {
            wrong.push(format!("{} files left in {}", left.len(), dir.display()));
        }
        if !wrong.is_empty() {
            failures.push(format!("{file}: {}\n{stderr}", wrong.join("; ")));
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// `hasse check` reads the same files without solving: problems of the file,
/// of the mesh and of the data where the solve evaluates them (sources and
/// coefficients) are found (exit 2), with the same first message as `hasse
/// run`; problems that only the assembled system or the output reveal are
/// not, and check says the case is fine (exit 0).
#[test]
fn check_finds_what_needs_no_solve() {
    let solve_only = [
        "disconnected",
        "incompatible-neumann",
        "singular-system",
        "maxwell-zero-star",
    ];
    for bad in CATALOGUE {
        let file = format!("tests/bad-input/{}.toml", bad.file);
        let mut args = vec!["check", file.as_str()];
        for set in bad.set {
            args.extend(["--set", set]);
        }
        let out = hasse(&args, &root());
        let stderr = String::from_utf8_lossy(&out.stderr);
        let expected = if solve_only.contains(&bad.file) { 0 } else { 2 };
        assert_eq!(out.status.code(), Some(expected), "{file}:\n{stderr}");
        assert!(!stderr.contains("panicked"), "{file}:\n{stderr}");
        if expected == 2 {
            assert!(stderr.contains(bad.says[0]), "{file}:\n{stderr}");
        }
    }
}

/// The memory estimate follows HASSE_MEMORY_LIMIT, so the refusal can be
/// shown on a mesh that would fit on any machine.
#[test]
fn the_memory_limit_is_the_one_in_force() {
    let args = [
        "check",
        "cases/poisson-square.toml",
        "--set",
        "mesh.n=[100,100]",
    ];
    let run = |limit: &str| {
        Command::new(env!("CARGO_BIN_EXE_hasse"))
            .args(args)
            .current_dir(root())
            .env("HASSE_MEMORY_LIMIT", limit)
            .output()
            .unwrap()
    };
    // 10⁴ quads: 4·10⁴ cells and 5·10⁴ nonzeros, at least 4.8 MB.
    let refused = run("1000000");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("1.000e4 top cells"), "{stderr}");
    assert!(
        stderr.contains("976.6 KiB is available (HASSE_MEMORY_LIMIT)"),
        "{stderr}"
    );
    assert!(run("100000000").status.success());
}

/// A coefficient spanning 17 orders of magnitude solves, but the run warns
/// that the system is ill-conditioned (κ ≥ max M_ii / min M_ii); a modest
/// one does not.
#[test]
fn ill_conditioned_systems_are_reported() {
    let run = |conductivity: &str| {
        let set = format!("problem.conductivity=\"{conductivity}\"");
        let out = hasse(
            &[
                "run",
                "cases/poisson-square.toml",
                "--set",
                &set,
                "--set",
                "output.write=false",
            ],
            &root(),
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let stiff = run("exp(40*x)");
    assert!(
        stiff.contains("condition number is at least 1.9e16"),
        "{stiff}"
    );
    let mild = run("1 + x");
    assert!(!mild.contains("condition number"), "{mild}");
}
