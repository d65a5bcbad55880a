//! Adaptive refinement with coarsening (`[refine] coarsen`) as a user runs
//! it: the shipped case, and `hasse check` refusing a bad fraction or the
//! key with another strategy.

use crate::hasse::{hasse, summary};

/// The rows of the refinement table: step, cells, unknowns, estimator,
/// L2, max and gradient errors, iterations, start residual, marked,
/// coarsened.
fn rows(stdout: &str) -> Vec<Vec<String>> {
    stdout
        .lines()
        .filter(|l| l.starts_with("           ") && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(str::to_string).collect())
        .filter(|r: &Vec<String>| r.len() == 11)
        .collect()
}

#[test]
fn peak_case_refines_and_coarsens() {
    let stdout = summary("cases/peak-adaptive-coarsen.toml", &[]);
    let rows = rows(&stdout);
    assert_eq!(rows.len(), 6, "{stdout}");
    let number = |r: &Vec<String>, k: usize| -> usize { r[k].parse().unwrap() };
    // Every cell is an axis-aligned rectangle (hanging vertices aside): a
    // split makes 4 of 1, a merge 1 of 4. So cells_{k+1} = cells_k
    // + 3 marked_k − 3 coarsened_k, counted independently by the table.
    let mut coarsened = 0;
    for pair in rows.windows(2) {
        let (before, after) = (&pair[0], &pair[1]);
        let merged = number(before, 10);
        coarsened += merged;
        assert_eq!(
            number(after, 1),
            number(before, 1) + 3 * number(before, 9) - 3 * merged,
            "{stdout}"
        );
    }
    // Step 0 has no earlier split to undo.
    assert_eq!(rows[0][10], "0", "{stdout}");
    assert!(coarsened > 0, "no group was merged back:\n{stdout}");
    // The final mesh is still a disk: χ = V − E + F = 1.
    let mesh = stdout.lines().find(|l| l.starts_with("mesh")).unwrap();
    let counts: Vec<i64> = mesh[mesh.find('[').unwrap() + 1..mesh.find(']').unwrap()]
        .split(", ")
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(counts[0] - counts[1] + counts[2], 1, "{mesh}");
    assert_eq!(counts[2] as usize, number(&rows[5], 1));
}

fn scratch_case(name: &str, refine: &str) -> String {
    let dir = std::env::temp_dir().join(format!(
        "hasse-refine-coarsen-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("case.toml");
    let text = format!(
        "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nmethod = \"fe\"\nsource = 1\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n[refine]\n{refine}"
    );
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn check_refuses_bad_coarsening() {
    // A fraction of 1 would merge every group, including those that hold
    // the error: outside [0, 1). Line 13 of the file.
    let file = scratch_case(
        "fraction",
        "strategy = \"adaptive\"\ncoarsen = 1.0\nsteps = 2\n",
    );
    let out = hasse(&["check", &file]);
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{text}");
    assert!(text.contains("case.toml:13:11"), "{text}");
    assert!(
        text.contains(
            "`refine.coarsen`: the coarsening fraction of Σ η² must lie in [0, 1), found 1"
        ),
        "{text}"
    );
    // With the uniform strategy nothing is marked or merged.
    let file = scratch_case(
        "uniform",
        "strategy = \"uniform\"\ncoarsen = 0.1\nsteps = 2\n",
    );
    let out = hasse(&["check", &file]);
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{text}");
    assert!(
        text.contains("`refine.coarsen`: only the adaptive strategy coarsens cells"),
        "{text}"
    );
    assert!(
        text.contains("remove `coarsen`, or set `strategy = \"adaptive\"`"),
        "{text}"
    );
    // A valid fraction passes.
    let file = scratch_case(
        "valid",
        "strategy = \"adaptive\"\ncoarsen = 0.1\nsteps = 2\n",
    );
    assert_eq!(hasse(&["check", &file]).status.code(), Some(0));
}
