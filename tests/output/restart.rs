//! Restarting a heat run from a saved level (issue 29, item 5): the
//! restarted run equals the uninterrupted one to rounding, since the
//! θ-scheme's step from t_k needs only u_k and the data at t_k and t_k+1.

use crate::scratch::Scratch;
use std::path::Path;
use std::process::{Command, Output};

fn hasse(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn last_level(path: &Path) -> (f64, Vec<f64>) {
    let file = hdf5::File::open(path).unwrap();
    let levels = file.group("steps").unwrap().member_names().unwrap().len();
    let step = file.group(&format!("steps/{}", levels - 1)).unwrap();
    (
        step.attr("time").unwrap().read_scalar().unwrap(),
        step.dataset("u").unwrap().read_raw().unwrap(),
    )
}

#[test]
fn a_restarted_heat_run_equals_the_uninterrupted_one() {
    let dir = Scratch::new("heat_restart");
    std::fs::create_dir_all(&*dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let text = std::fs::read_to_string(root.join("cases/heat-square.toml")).unwrap();
    std::fs::write(dir.join("full.toml"), &text).unwrap();
    let initial = text.lines().find(|l| l.starts_with("initial = ")).unwrap();
    let restarted = text.replace(initial, "initial = { from = \"full.h5\", level = 8 }");
    std::fs::write(dir.join("restart.toml"), restarted).unwrap();
    for scheme in ["backward-euler", "crank-nicolson"] {
        let set = format!("time.scheme=\"{scheme}\"");
        let full = hasse(
            &dir,
            &[
                "run",
                "full.toml",
                "-q",
                "-o",
                "full",
                "--set",
                &set,
                "--set",
                "time.save_every=1",
            ],
        );
        assert!(
            full.status.success(),
            "{}",
            String::from_utf8_lossy(&full.stderr)
        );
        let again = hasse(
            &dir,
            &["run", "restart.toml", "-q", "-o", "again", "--set", &set],
        );
        assert!(
            again.status.success(),
            "{}",
            String::from_utf8_lossy(&again.stderr)
        );
        let (t_full, u_full) = last_level(&dir.join("full.h5"));
        let (t_again, u_again) = last_level(&dir.join("again.h5"));
        // Both end at the case's end, t = 0.1, after 20 and 12 steps.
        assert!((t_full - 0.1).abs() < 1e-15 && (t_again - 0.1).abs() < 1e-15);
        let worst = u_full
            .iter()
            .zip(&u_again)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        // |u| ≤ 1.3 here; 12 steps of a well-conditioned solve keep the two
        // within a few ulps of each other.
        assert!(worst < 1e-13, "{scheme}: {worst:e}");
    }
    // What does not fit is refused by `hasse check`, before solving.
    for (sets, words) in [
        (
            vec!["problem.initial.level=99"],
            "has 21 saved levels (0 to 20)",
        ),
        (vec!["problem.initial.from=\"nowhere.h5\""], "cannot open"),
        (vec!["mesh.n=[8, 8]"], "was computed on another mesh"),
    ] {
        let mut args = vec!["check", "restart.toml"];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let out = hasse(&dir, &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(words),
            "{sets:?}: {stderr}"
        );
    }
}
