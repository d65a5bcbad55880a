//! Refinement series through the `hasse` binary, read back level by level
//! with meshio (`tests/python/read_levels.py`): every level's own file
//! `<stem>.level-<k>.xdmf` must give that level's mesh, with the point and
//! cell counts that something other than the XDMF writer reports for it —
//! `hasse info` of the case (level 0: counts and the domain's area), the
//! refinement table of the run's report (every level's cell counts, taken
//! from the refined complexes by the refinement study) and the printed
//! summary — and `<stem>.xdmf` must list every level in order, each grid
//! with its own mesh.
//!
//! Python runs in the private venv of `tests/common/pyenv.rs`; without it
//! the tests are skipped loudly (and fail under `CI`).

use crate::pyenv::python_or_skip;
use crate::scratch::Scratch;
use hdf5::types::VarLenUnicode;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// Open an h5 file without HDF5's file locking: a child process that this
/// test binary spawns (Python, hasse) while another test writes an h5 file
/// inherits that writer's descriptor and lock (see `open` in
/// output_files.rs), and reading needs no lock, nothing else writing these.
fn open(path: &Path) -> hdf5::File {
    hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn hasse(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_hasse"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("the hasse binary runs");
    assert!(
        out.status.success(),
        "hasse {args:?} failed ({:?}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The run's stdout.
fn run(args: &[&str]) -> String {
    String::from_utf8_lossy(&hasse(args).stdout).into_owned()
}

/// What `hasse info CASE` reports: the cell counts K0, K1, … and the total
/// measure of the top cells.
fn info(case: &str) -> (Vec<usize>, f64) {
    let stdout = run(&["info", case]);
    let line = |key: &str| {
        stdout
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .unwrap_or_else(|| panic!("no '{key}' line in:\n{stdout}"))
            .trim()
            .to_string()
    };
    let counts = line("cells")
        .split_whitespace()
        .filter_map(|word| word.parse().ok())
        .collect();
    let measure = line("measure")
        .split_whitespace()
        .last()
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no total measure in:\n{stdout}"));
    (counts, measure)
}

/// Cell counts per dimension of every level, from the refinement table
/// the run stores in its report (`/provenance/report`, key `refinement`).
fn reported_counts(h5: &Path) -> Vec<Vec<usize>> {
    let f = open(h5);
    let report = f
        .dataset("provenance/report")
        .unwrap()
        .read_scalar::<VarLenUnicode>()
        .unwrap();
    let report: Value = serde_json::from_str(report.as_str()).unwrap();
    report["refinement"]
        .as_array()
        .unwrap_or_else(|| panic!("no refinement table in the report: {report}"))
        .iter()
        .map(|step| {
            step["cells"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_u64().unwrap() as usize)
                .collect()
        })
        .collect()
}

/// The top-cell counts of the printed refinement table, level by level.
fn printed_top_counts(stdout: &str) -> Vec<usize> {
    let mut lines = stdout.lines().skip_while(|l| !l.starts_with("refinement "));
    lines
        .next()
        .unwrap_or_else(|| panic!("no table in:\n{stdout}"));
    lines
        .map_while(|l| {
            let mut words = l.split_whitespace();
            let step: usize = words.next()?.parse().ok()?;
            Some((step, words.next()?.parse().ok()?))
        })
        .enumerate()
        .map(|(k, (step, cells))| {
            assert_eq!(step, k, "table rows in level order");
            cells
        })
        .collect()
}

/// Vertex count of each top cell of level k, from the h5 file's own
/// characteristic matrix `/steps/<k>/mesh/cells/2` (the complex as
/// stored, not the XDMF arrays).
fn top_cell_sizes(h5: &Path, k: usize) -> Vec<usize> {
    let f = open(h5);
    let indptr = f
        .dataset(&format!("steps/{k}/mesh/cells/2/indptr"))
        .unwrap()
        .read_raw::<u64>()
        .unwrap();
    indptr.windows(2).map(|w| (w[1] - w[0]) as usize).collect()
}

/// `read_levels.py` on `stem` with `levels` level files.
fn read_levels(python: &Path, stem: &Path, levels: usize) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/python/read_levels.py");
    let out = Command::new(python)
        .arg(script)
        .arg(stem)
        .arg(levels.to_string())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "read_levels.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn as_usize(v: &Value) -> usize {
    v.as_u64().unwrap_or_else(|| panic!("not a count: {v}")) as usize
}

/// `<stem>.xdmf` lists every level once, in order: grid k at time k, with
/// level k's vertices (as many rows as the report gives it points) and
/// topology, and no grid names its type, so that meshio's
/// `TimeSeriesReader` refuses the file instead of giving level 0's mesh
/// with every level's fields.
fn check_series_file(found: &Value, stem: &Path, counts: &[Vec<usize>]) {
    let h5 = format!("{}.h5", stem.file_name().unwrap().to_str().unwrap());
    let series = &found["series"];
    assert_eq!(series["collection"], "Temporal", "{series}");
    let grids = series["grids"].as_array().unwrap();
    assert_eq!(grids.len(), counts.len(), "one grid per level");
    for (k, grid) in grids.iter().enumerate() {
        assert_eq!(grid["time"], k as f64, "grid {k}: {grid}");
        assert_eq!(grid["grid_type"], Value::Null, "grid {k}: {grid}");
        assert_eq!(
            grid["geometry"],
            format!("{h5}:/steps/{k}/mesh/vertices"),
            "grid {k}"
        );
        assert_eq!(
            grid["topology"],
            format!("{h5}:/steps/{k}/mesh/xdmf/2/topology"),
            "grid {k}"
        );
        assert_eq!(as_usize(&grid["geometry_rows"]), counts[k][0], "grid {k}");
    }
    let refused = found["time_series_reader"]["error"]
        .as_str()
        .unwrap_or_else(|| panic!("TimeSeriesReader read the series: {found}"));
    assert!(refused.contains("Couldn't find the mesh grid"), "{refused}");
}

/// `cases/poisson-square.toml` on a 4 × 4 grid with `method`, written to
/// `dir` so that `hasse info` (which takes no `--set`) sees the same mesh.
fn small_square(dir: &Path, method: &str) -> String {
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/poisson-square.toml"),
    )
    .unwrap();
    assert!(shipped.contains("n = [32, 32]") && shipped.contains("method = \"fe\""));
    let text = shipped
        .replace("n = [32, 32]", "n = [4, 4]")
        .replace("method = \"fe\"", &format!("method = \"{method}\""));
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("square.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

/// The level files of `name` in `dir`, sorted.
fn level_files(dir: &Path, name: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&format!("{name}.level-")))
        .collect();
    names.sort();
    names
}

#[test]
fn each_level_of_an_adaptive_series_opens_in_meshio_with_its_own_counts() {
    let Some(python) = python_or_skip("adaptive refinement levels in meshio") else {
        return;
    };
    let dir = Scratch::new("adaptive-levels");
    // The command of cases/OUTPUT.md, whose snippet reads the result below.
    let stem = dir.join("out/adaptive");
    let case = "cases/l-shape-adaptive.toml";
    let steps = 3;
    let stdout = run(&[
        "refine",
        case,
        "--steps",
        &steps.to_string(),
        "-o",
        stem.to_str().unwrap(),
    ]);
    let levels = steps + 1;
    let h5 = stem.with_extension("h5");
    let counts = reported_counts(&h5);
    assert_eq!(counts.len(), levels);
    // The report's counts are those of the meshes the run printed and,
    // for the mesh it started from, those of `hasse info`.
    assert_eq!(
        printed_top_counts(&stdout),
        counts.iter().map(|c| c[2]).collect::<Vec<_>>()
    );
    let (initial, area) = info(case);
    assert_eq!(counts[0], initial);
    // Adaptive refinement changes the mesh at every step.
    assert!(counts.windows(2).all(|w| w[1][0] > w[0][0]), "{counts:?}");
    assert!(
        stdout.contains(&format!("{}.level-0.xdmf", stem.display()))
            && stdout.contains(&format!("{}.level-{steps}.xdmf", stem.display())),
        "{stdout}"
    );

    let found = read_levels(&python, &stem, levels);
    let mut polygons = 0;
    for (k, level) in found["levels"].as_array().unwrap().iter().enumerate() {
        // Every vertex of level k is a point, and the nodal fields have one
        // value per point.
        assert_eq!(
            as_usize(&level["points"]),
            counts[k][0],
            "level {k}: {level}"
        );
        assert_eq!(as_usize(&level["unused_points"]), 0, "level {k}");
        for field in ["u", "u_exact", "error"] {
            assert_eq!(
                as_usize(&level["point_data"][field]),
                counts[k][0],
                "level {k} {field}"
            );
        }
        // Cut cells' neighbours are polygons with hanging vertices; meshio
        // reads no polygon, so each one with v ≥ 5 vertices is v − 2
        // triangles, none flat, and the cells still cover the domain.
        let sizes = top_cell_sizes(&h5, k);
        assert_eq!(sizes.len(), counts[k][2], "level {k}");
        polygons += sizes.iter().filter(|&&v| v > 4).count();
        let elements: usize = sizes.iter().map(|&v| if v > 4 { v - 2 } else { 1 }).sum();
        assert_eq!(as_usize(&level["elements"]), elements, "level {k}: {level}");
        assert!(
            level["min_area"].as_f64().unwrap() > 0.0,
            "level {k}: {level}"
        );
        // (`hasse info` prints the area to 7 significant digits.)
        let covered = level["area"].as_f64().unwrap();
        assert!(
            (covered - area).abs() < 1e-6 * area,
            "level {k}: area {covered}, not {area}"
        );
    }
    assert!(polygons > 0, "the series has no polygon to triangulate");
    check_series_file(&found, &stem, &counts);

    // The snippet of cases/OUTPUT.md that reads the levels with meshio runs
    // as printed and prints level k's time and point count.
    let snippet = doc_snippet("meshio.read(f\"out/adaptive.level-{k}.xdmf\")");
    let out = Command::new(&python)
        .args(["-c", &snippet])
        .current_dir(&*dir)
        .output()
        .unwrap();
    let printed = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "the OUTPUT.md snippet failed:\n{snippet}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<Vec<&str>> = printed.lines().map(|l| l.split(' ').collect()).collect();
    assert_eq!(rows.len(), levels, "{printed}");
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0], k.to_string(), "{printed}");
        assert_eq!(row[1].parse::<f64>().unwrap(), k as f64, "{printed}");
        assert_eq!(row[2], counts[k][0].to_string(), "{printed}");
    }
}

/// The ```python block of cases/OUTPUT.md that contains `marker`.
fn doc_snippet(marker: &str) -> String {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../cases/OUTPUT.md"))
            .unwrap();
    doc.split("```python\n")
        .skip(1)
        .filter_map(|rest| rest.split_once("```").map(|(block, _)| block))
        .find(|block| block.contains(marker))
        .unwrap_or_else(|| panic!("no python block with {marker} in cases/OUTPUT.md"))
        .to_string()
}

#[test]
fn each_level_of_a_uniform_series_opens_in_meshio_with_its_cell_values() {
    let Some(python) = python_or_skip("uniform refinement levels in meshio") else {
        return;
    };
    let dir = Scratch::new("uniform-levels");
    let stem = dir.join("uniform");
    // Cell-centred unknowns, so every level also has cell data to compare.
    let case = small_square(&dir, "fv");
    let stdout = run(&[
        "refine",
        &case,
        "--strategy",
        "uniform",
        "--steps",
        "2",
        "-o",
        stem.to_str().unwrap(),
    ]);
    let h5 = stem.with_extension("h5");
    let counts = reported_counts(&h5);
    // Uniform SPLIT of a 4 × 4 grid of squares: on level k, n = 4·2ᵏ
    // squares a side, (n + 1)² vertices and 2n(n + 1) edges.
    let expected: Vec<Vec<usize>> = (0..3u32)
        .map(|k| {
            let n = 4 * 2usize.pow(k);
            vec![(n + 1) * (n + 1), 2 * n * (n + 1), n * n]
        })
        .collect();
    assert_eq!(counts, expected);
    assert_eq!(
        printed_top_counts(&stdout),
        counts.iter().map(|c| c[2]).collect::<Vec<_>>()
    );
    let (initial, area) = info(&case);
    assert_eq!(counts[0], initial);

    let found = read_levels(&python, &stem, 3);
    let f = open(&h5);
    for (k, level) in found["levels"].as_array().unwrap().iter().enumerate() {
        assert_eq!(
            as_usize(&level["points"]),
            counts[k][0],
            "level {k}: {level}"
        );
        assert_eq!(
            as_usize(&level["elements"]),
            counts[k][2],
            "level {k}: {level}"
        );
        assert_eq!(level["types"], serde_json::json!(["quad"]), "level {k}");
        let side = 1.0 / (4 * 2usize.pow(k as u32)) as f64;
        assert!((level["min_area"].as_f64().unwrap() - side * side).abs() < 1e-12);
        assert!((level["area"].as_f64().unwrap() - area).abs() < 1e-6 * area);
        // The cell values are level k's solution, cell by cell.
        let u = f
            .dataset(&format!("steps/{k}/u"))
            .unwrap()
            .read_raw::<f64>()
            .unwrap();
        let shown: Vec<f64> = level["cell_data"]["u"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(shown, u, "level {k}");
    }
    check_series_file(&found, &stem, &counts);
    assert_eq!(
        level_files(&dir, "uniform"),
        [
            "uniform.level-0.xdmf",
            "uniform.level-1.xdmf",
            "uniform.level-2.xdmf"
        ]
    );
}

/// A run on one mesh writes what it always wrote: `<stem>.xdmf` is one
/// uniform grid on `/mesh` that `meshio.read` opens, with no level files;
/// and when it replaces a refinement series under the same stem, the
/// series' level files go (they would point at datasets the new h5 lacks).
/// A shorter series replacing a longer one likewise leaves no level beyond
/// its own.
#[test]
fn a_plain_run_opens_in_meshio_as_before_and_removes_stale_levels() {
    let Some(python) = python_or_skip("plain run in meshio") else {
        return;
    };
    let dir = Scratch::new("plain-levels");
    let stem = dir.join("square");
    let out = stem.to_str().unwrap();
    let case = small_square(&dir, "fe");
    let refine = |steps: &str| {
        run(&[
            "refine",
            &case,
            "--strategy",
            "uniform",
            "--steps",
            steps,
            "-o",
            out,
        ]);
    };
    refine("2");
    assert_eq!(level_files(&dir, "square").len(), 3);
    refine("1");
    assert_eq!(
        level_files(&dir, "square"),
        ["square.level-0.xdmf", "square.level-1.xdmf"]
    );

    let stdout = run(&["run", &case, "-o", out]);
    assert!(!stdout.contains("levels "), "{stdout}");
    assert_eq!(level_files(&dir, "square"), Vec::<String>::new());
    let xdmf = std::fs::read_to_string(stem.with_extension("xdmf")).unwrap();
    assert_eq!(xdmf.matches("<Grid ").count(), 1, "{xdmf}");
    assert!(
        xdmf.contains("<Grid Name=\"cells\" GridType=\"Uniform\">"),
        "{xdmf}"
    );
    assert!(xdmf.contains(">square.h5:/xdmf/2/topology<"), "{xdmf}");
    assert!(xdmf.contains(">square.h5:/mesh/vertices<"), "{xdmf}");

    let found = read_levels(&python, &stem, 0);
    assert_eq!(found["series"]["collection"], Value::Null, "{found}");
    let (counts, area) = info(&case);
    let main = &found["main"];
    assert_eq!(as_usize(&main["points"]), counts[0], "{main}");
    assert_eq!(as_usize(&main["elements"]), counts[2], "{main}");
    assert_eq!(main["types"], serde_json::json!(["quad"]), "{main}");
    assert!((main["area"].as_f64().unwrap() - area).abs() < 1e-6 * area);
    assert_eq!(as_usize(&main["point_data"]["u"]), counts[0], "{main}");
}
