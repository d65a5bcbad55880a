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

/// A heat case whose state is the linear field 1 + 2x − y: no source and
/// the field's own Dirichlet data on every side make it the steady state,
/// so every saved level is that field (to the rounding of the solves).
fn linear_case(mesh: &str, method: &str, initial: &str) -> String {
    format!(
        "{mesh}\n\n[problem]\nkind = \"heat\"\nmethod = \"{method}\"\nconductivity = 1\nsource = 0\ninitial = {initial}\n\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = \"1 + 2*x - y\"\n\n[time]\ndt = 0.01\nsteps = 2\n"
    )
}

const COARSE: &str = "[mesh]\ngenerator = \"rectangle\"\nn = [8, 8]";
const RESTART: &str = "{ from = \"coarse.h5\", level = \"last\" }";

/// An output's vertices (x, y) and top cells (vertex lists), read from
/// `/mesh` as cases/OUTPUT.md lays it out.
fn mesh_of(path: &Path) -> (Vec<[f64; 2]>, Vec<Vec<usize>>) {
    let file = hdf5::File::open(path).expect("an output file");
    let xyz: Vec<f64> = file
        .dataset("mesh/vertices")
        .and_then(|d| d.read_raw())
        .expect("vertices");
    let indptr: Vec<u64> = file
        .dataset("mesh/cells/2/indptr")
        .and_then(|d| d.read_raw())
        .expect("indptr");
    let indices: Vec<u64> = file
        .dataset("mesh/cells/2/indices")
        .and_then(|d| d.read_raw())
        .expect("indices");
    let vertices = xyz.chunks(3).map(|p| [p[0], p[1]]).collect();
    let cells = indptr
        .windows(2)
        .map(|w| {
            indices[w[0] as usize..w[1] as usize]
                .iter()
                .map(|&v| v as usize)
                .collect()
        })
        .collect();
    (vertices, cells)
}

fn level(path: &Path, k: usize) -> (f64, Vec<f64>) {
    let file = hdf5::File::open(path).expect("an output file");
    let step = file.group(&format!("steps/{k}")).expect("the level");
    (
        step.attr("time")
            .and_then(|a| a.read_scalar())
            .expect("time"),
        step.dataset("u").and_then(|d| d.read_raw()).expect("u"),
    )
}

/// Run the linear case on the coarse 8 × 8 grid with `method`, from the
/// linear field: coarse.h5, levels at t = 0, 0.01, 0.02.
fn save_coarse(dir: &Path, method: &str) {
    std::fs::write(
        dir.join("coarse.toml"),
        linear_case(COARSE, method, "\"1 + 2*x - y\""),
    )
    .expect("case");
    run_ok(dir, &["run", "coarse.toml", "-q", "-o", "coarse"]);
}

fn run_ok(dir: &Path, args: &[&str]) -> String {
    let out = hasse(dir, args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn a_linear_steady_state_restarts_exactly_on_refinements() {
    let dir = Scratch::new("heat_restart_refined");
    std::fs::create_dir_all(&*dir).expect("scratch directory");
    // SPLIT's uniform refinement of the coarse grid, as a mesh file: the
    // same squares as the 16 × 16 grid, numbered otherwise.
    let coarse = hasse_complex::generate::rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).expect("grid");
    let (split, _) = hasse_complex::refine::uniform(&coarse).expect("SPLIT");
    hasse_complex::json::write_json(&split, &dir.join("split.json")).expect("mesh file");
    let fine_meshes = [
        ("grid", "[mesh]\ngenerator = \"rectangle\"\nn = [16, 16]"),
        ("split", "[mesh]\nfile = \"split.json\""),
    ];
    let linear = |p: [f64; 2]| 1.0 + 2.0 * p[0] - p[1];
    for method in ["fe", "fv"] {
        save_coarse(&dir, method);
        let (t_saved, u_saved) = level(&dir.join("coarse.h5"), 2);
        let (coarse_vertices, coarse_cells) = mesh_of(&dir.join("coarse.h5"));
        for (name, mesh) in fine_meshes {
            std::fs::write(dir.join("fine.toml"), linear_case(mesh, method, RESTART))
                .expect("case");
            let summary = run_ok(&dir, &["run", "fine.toml", "-o", "fine"]);
            let (t0, u0) = level(&dir.join("fine.h5"), 0);
            let (vertices, cells) = mesh_of(&dir.join("fine.h5"));
            // The restart starts at the saved level's time, 2 steps of 0.01.
            assert_eq!((t_saved, t0), (0.02, 0.02), "{method} on {name}");
            if method == "fe" {
                // Q1 reproduces a linear field: every new vertex takes
                // 1 + 2x − y. Values are at most 3 (ulp 4.4e-16); the saved
                // state and the interpolation each add a few ulps (3.3e-15
                // measured on both meshes).
                assert_eq!(u0.len(), 17 * 17);
                for (&u, &p) in u0.iter().zip(&vertices) {
                    approx::assert_abs_diff_eq!(u, linear(p), epsilon = 1e-14);
                }
                // 9 × 9 of the 17 × 17 vertices are coarse vertices; the
                // stored report says so too.
                let report: serde_json::Value = serde_json::from_str(
                    hdf5::File::open(dir.join("fine.h5"))
                        .and_then(|f| f.dataset("provenance/report"))
                        .and_then(|d| d.read_scalar::<hdf5::types::VarLenUnicode>())
                        .expect("the report")
                        .as_str(),
                )
                .expect("JSON");
                assert_eq!(report["restart"]["mesh"], "refinement");
                assert_eq!(report["restart"]["interpolated"], 208);
                assert_eq!(report["restart"]["unknowns"], 289);
                assert!(
                    summary.contains(
                        "on a refinement: 208 of 289 values interpolated (P1/Q1 in the saved cell), 81 at saved vertices"
                    ),
                    "{summary}"
                );
            } else {
                // Each fine square lies in one coarse square (its parent,
                // found here by the coarse squares' bounding boxes) and
                // starts from the parent's saved value, bit for bit.
                assert_eq!(u0.len(), 16 * 16);
                let mut children = vec![0; coarse_cells.len()];
                for (c, cell) in cells.iter().enumerate() {
                    let k = cell.len() as f64;
                    let centre =
                        [0, 1].map(|a| cell.iter().map(|&v| vertices[v][a]).sum::<f64>() / k);
                    let parents: Vec<usize> = (0..coarse_cells.len())
                        .filter(|&p| {
                            (0..2).all(|a| {
                                let side = coarse_cells[p].iter().map(|&v| coarse_vertices[v][a]);
                                let lo = side.clone().fold(f64::INFINITY, f64::min);
                                let hi = side.fold(f64::NEG_INFINITY, f64::max);
                                lo < centre[a] && centre[a] < hi
                            })
                        })
                        .collect();
                    assert_eq!(parents.len(), 1, "fine cell {c} at {centre:?}");
                    children[parents[0]] += 1;
                    assert_eq!(u0[c], u_saved[parents[0]], "{name}: fine cell {c}");
                }
                assert!(children.iter().all(|&k| k == 4), "{children:?}");
                assert!(
                    summary.contains(
                        "on a refinement: 256 cell values from their parents (64 saved cells)"
                    ),
                    "{summary}"
                );
            }
        }
    }
}

#[test]
fn a_restart_on_another_domain_or_mesh_is_refused_before_solving() {
    let dir = Scratch::new("heat_restart_elsewhere");
    std::fs::create_dir_all(&*dir).expect("scratch directory");
    let wide = "[mesh]\ngenerator = \"rectangle\"\nn = [16, 8]\nx = [0.0, 2.0]";
    let mesh = hasse_complex::generate::rectangle(16, 8, [0.0, 2.0], [0.0, 1.0]).expect("grid");
    for method in ["fe", "fv"] {
        save_coarse(&dir, method);
        // The first unknown's point beyond x = 1, in the wide mesh's own
        // numbering: a vertex (fe) or a cell centroid (fv).
        let (what, points): (&str, Vec<Vec<f64>>) = if method == "fe" {
            (
                "vertex",
                (0..mesh.cell_count(0))
                    .map(|v| mesh.vertices().point(v).to_vec())
                    .collect(),
            )
        } else {
            (
                "the centroid of cell",
                mesh.centroid(2).chunks(2).map(<[f64]>::to_vec).collect(),
            )
        };
        let first = points
            .iter()
            .position(|p| p[0] > 1.0)
            .expect("a point beyond x = 1");
        let expected = format!(
            "{what} {first} of this mesh, at {:?}, lies outside the saved mesh (/mesh/cells/2 of coarse.h5), where /steps/2/u has no value",
            points[first]
        );
        std::fs::write(dir.join("wide.toml"), linear_case(wide, method, RESTART)).expect("case");
        for args in [
            &["check", "wide.toml"][..],
            &["run", "wide.toml", "-o", "wide"],
        ] {
            let out = hasse(&dir, args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                !out.status.success()
                    && stderr.contains("coarse.h5 was computed on another mesh")
                    && stderr.contains(&expected),
                "{method} {args:?}: {stderr}\nexpected: {expected}"
            );
        }
        assert!(!dir.join("wide.h5").exists(), "refused before any output");
        // Same domain, not nested: 12 × 12 squares straddle the 8 × 8 ones.
        assert_check_refuses(
            &dir,
            "[mesh]\ngenerator = \"rectangle\"\nn = [12, 12]",
            method,
            &["is not a refinement", "saved cell 0"],
        );
    }
    // The method of the saved run (fv, the last above) is the restart's.
    assert_check_refuses(
        &dir,
        "[mesh]\ngenerator = \"rectangle\"\nn = [16, 16]",
        "fe",
        &[
            "coarse.h5 was computed with method \"fv\"",
            "this case uses \"fe\"",
        ],
    );
}

/// `hasse check` of a linear case on `mesh` restarted from coarse.h5
/// fails, and its message holds each of `words`.
fn assert_check_refuses(dir: &Path, mesh: &str, method: &str, words: &[&str]) {
    std::fs::write(dir.join("refused.toml"), linear_case(mesh, method, RESTART)).expect("case");
    let out = hasse(dir, &["check", "refused.toml"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && words.iter().all(|w| stderr.contains(w)),
        "{method} on {mesh}: {stderr}"
    );
}
