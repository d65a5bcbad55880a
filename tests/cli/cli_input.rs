//! Input that the command line must read as documented (issue 30): the
//! annulus's `n`, the Delaunay generator, a `boundary` tag on every mesh,
//! a file's `refine.theta` under a strategy from the command line, and
//! output places checked before solving.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn hasse_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the hasse binary runs")
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

const POISSON: &str = r#"[problem]
method = "fe"
source = 1

[[boundary]]
tag = "boundary"
type = "dirichlet"
value = 0
"#;

/// `n = [angular, radial]` (cases/README.md): 16 sectors of 4 rings have
/// 16·5 = 80 vertices, 16·4 radial + 16·5 circular = 144 edges and 64
/// quads (read the other way round: 68, 132, 64).
#[test]
fn annulus_n_is_angular_then_radial() {
    let dir = crate::scratch::Scratch::new("annulus-n");
    std::fs::create_dir_all(&*dir).unwrap();
    let case = format!(
        "[mesh]\ngenerator = \"annulus\"\nn = [16, 4]\ninner_radius = 0.5\nouter_radius = 1.0\n\n{POISSON}"
    );
    std::fs::write(dir.join("annulus.toml"), case).unwrap();
    let out = hasse_in(&dir, &["check", "annulus.toml"]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("[80, 144, 64]"), "{}", text(&out));
    // Two rings: 16·3 = 48 vertices, 16·2 + 16·3 = 80 edges, 32 quads.
    let out = hasse_in(&dir, &["check", "annulus.toml", "--set", "mesh.n=[16,2]"]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("[48, 80, 32]"), "{}", text(&out));
}

/// The documented comparison of cases/l-shape-adaptive.toml: the file's
/// `theta` is for its adaptive strategy; with the strategy switched on the
/// command line it is unused (a warning), not an error. A `theta` with a
/// non-adaptive strategy from one source is still refused.
#[test]
fn a_files_theta_under_a_strategy_from_the_command_line_warns() {
    let dir = crate::scratch::Scratch::new("theta-uniform");
    std::fs::create_dir_all(&*dir).unwrap();
    std::os::unix::fs::symlink(root().join("cases"), dir.join("cases")).unwrap();
    let case = "cases/l-shape-adaptive.toml";
    for args in [
        vec!["check", case, "--set", "refine.strategy=uniform"],
        vec![
            "run",
            case,
            "--set",
            "refine.strategy=uniform",
            "--set",
            "refine.steps=1",
        ],
        vec!["refine", case, "--strategy", "uniform", "--steps", "1"],
    ] {
        let out = hasse_in(&dir, &args);
        let all = text(&out);
        assert!(out.status.success(), "{args:?}: {all}");
        assert_eq!(
            all.matches("warning: cases/l-shape-adaptive.toml:35:1: `refine.theta`: unused")
                .count(),
            1,
            "{args:?}: {all}"
        );
    }
    // Both from the command line: a contradiction.
    let out = hasse_in(
        &dir,
        &[
            "check",
            case,
            "--set",
            "refine.strategy=uniform",
            "--set",
            "refine.theta=0.3",
        ],
    );
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(text(&out).contains("only the adaptive strategy marks cells"));
    // Both in the file: the same.
    let file = dir.join("both.toml");
    let adaptive = std::fs::read_to_string(root().join(case)).unwrap();
    let both = adaptive
        .replace("strategy = \"adaptive\"", "strategy = \"uniform\"")
        .replace("l-shape.msh", "cases/l-shape.msh");
    std::fs::write(&file, both).unwrap();
    let out = hasse_in(&dir, &["check", "both.toml"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
    assert!(text(&out).contains("both.toml:35:1: `refine.theta`: only the adaptive strategy"));
}
