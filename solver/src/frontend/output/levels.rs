//! The writer behind [`super::write_run`] and [`super::write_mesh_series`]:
//! the output as a list of levels on one or several meshes, checked, then
//! written as one h5 file and its XDMF documents.

use super::atomic::{
    create_dir, remove_if_present, remove_orphaned_temporaries, rename, sync, temporary,
    temporary_tag, write_text, Temporaries,
};
use super::*;

/// The shared body of [`write_run`] and [`write_mesh_series`].
pub(super) fn write_levels(stem: &Path, levels: &Levels) -> Result<OutputFiles, OutputError> {
    validate(levels)?;
    let (dir, file_name) = split_stem(stem)?;
    let degrees = xdmf::degrees(levels);

    create_dir(&dir)?;
    let h5_name = format!("{file_name}.h5");
    let files = xdmf::Files::one(&h5_name);
    let n = levels.dim();
    let final_h5 = dir.join(&h5_name);
    let final_xdmf = dir.join(format!("{file_name}.xdmf"));
    // A series whose mesh changes also gets one document per level and
    // degree, `<stem>.level-<k>[.<grid>].xdmf`: readers that take one mesh
    // per file (meshio) open those, while `<stem>.xdmf` is the series.
    let mut level_files: Vec<Vec<PathBuf>> = Vec::new();
    let mut documents = Vec::new();
    if levels.mesh_changes {
        for k in 0..levels.steps.len() {
            let mut of_level = Vec::new();
            for (i, &p) in degrees.iter().enumerate() {
                let grid = (i > 0).then(|| xdmf::grid_name(p, n));
                let path = dir.join(level_file_name(&file_name, k, grid));
                of_level.push(path.clone());
                documents.push((path, Document::Level { grid: i, level: k }));
            }
            level_files.push(of_level);
        }
    }
    // One XDMF document per degree: the top grid (first in `degrees`) under
    // `<stem>.xdmf`, each lower degree under `<stem>.<grid>.xdmf`.
    let mut extra_xdmf = Vec::new();
    for (i, &p) in degrees.iter().enumerate().skip(1) {
        let path = dir.join(format!("{file_name}.{}.xdmf", xdmf::grid_name(p, n)));
        extra_xdmf.push(path.clone());
        documents.push((path, Document::Series { grid: i }));
    }
    // Rename order: the h5 first, because no xdmf may point at a file that
    // is not there; the main xdmf last, because it is the one users open,
    // so once it appears the whole output is in place.
    documents.push((final_xdmf.clone(), Document::Series { grid: 0 }));

    let tag = temporary_tag();
    let mut finals = vec![final_h5.clone()];
    finals.extend(documents.iter().map(|(path, _)| path.clone()));
    let mut temps = Temporaries(finals.iter().map(|path| temporary(path, &tag)).collect());
    // Level documents of an earlier output under this stem, and the
    // temporaries of killed writers of any of them.
    let earlier_levels = level_files_in(&dir, &file_name);
    let mut known = finals.clone();
    known.extend(
        LOWER_GRID_NAMES
            .iter()
            .map(|grid| dir.join(format!("{file_name}.{grid}.xdmf"))),
    );
    known.extend(earlier_levels.iter().cloned());
    remove_orphaned_temporaries(&dir, &known);

    // The grids' reader vertex orders (at 10⁶ cells, the output's largest
    // computation) are built on the other cores while this thread writes
    // the fields and the complex, which do not need them, to the h5 file.
    let grids = std::thread::scope(|scope| {
        let builder = scope.spawn(|| xdmf::grids(levels, &degrees));
        let built = || {
            builder
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        };
        hdf5_file::write_while(&temps.0[0], levels, &degrees, built, &rfc3339_now())
    })?;
    for (path, (_, document)) in temps.0[1..].iter().zip(&documents) {
        let text = match *document {
            Document::Level { grid, level } => {
                xdmf::level_document(levels, &grids, grid, level, &files)
            }
            Document::Series { grid } => xdmf::document(levels, &grids, grid, &files),
        };
        write_text(path, &text)?;
    }

    // Contents reach the disk before the names do, so a crash right after
    // the renames cannot leave an empty file under a final name.
    for path in &temps.0 {
        sync(path)?;
    }
    for target in &finals {
        rename(&temps.0[0], target)?;
        temps.0.remove(0);
    }
    // Degree and level files of an earlier output under this stem that this
    // run does not have would point at datasets the new h5 may lack (a
    // level it has fewer of, a degree without cochains): remove them.
    let stale_degrees = LOWER_GRID_NAMES
        .iter()
        .map(|grid_name| dir.join(format!("{file_name}.{grid_name}.xdmf")));
    for path in stale_degrees.chain(earlier_levels) {
        if finals.contains(&path) {
            continue;
        }
        remove_if_present(&path)?;
    }
    Ok(OutputFiles {
        hdf5: final_h5,
        xdmf: final_xdmf,
        extra_xdmf,
        levels: level_files,
    })
}

/// Which XDMF document a file holds: that of the grid of degree
/// `degrees[grid]` over the whole series, or for one level alone.
enum Document {
    Series { grid: usize },
    Level { grid: usize, level: usize },
}

/// `<stem>.level-<k>.xdmf`, or `<stem>.level-<k>.<grid>.xdmf` for a lower
/// degree's grid.
fn level_file_name(file_name: &str, k: usize, grid: Option<&str>) -> String {
    match grid {
        None => format!("{file_name}.level-{k}.xdmf"),
        Some(grid) => format!("{file_name}.level-{k}.{grid}.xdmf"),
    }
}

/// The level documents of `file_name` in `dir`: those there under their
/// final names, and the final names of temporaries of them. Names that
/// only look alike (another stem, `level-x`) are not theirs.
fn level_files_in(dir: &Path, file_name: &str) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut found = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        // A temporary is `.<final>.tmp-<tag>[.<ext>]` (see `atomic::temporary`).
        let name = match name.strip_prefix('.').and_then(|n| n.split_once(".tmp-")) {
            Some((final_name, _)) => final_name.to_string(),
            None => name,
        };
        if is_level_file_name(&name, file_name) && !found.contains(&dir.join(&name)) {
            found.push(dir.join(&name));
        }
    }
    found
}

/// Whether `name` is `<file_name>.level-<k>[.<grid>].xdmf`.
fn is_level_file_name(name: &str, file_name: &str) -> bool {
    let Some(rest) = name
        .strip_prefix(file_name)
        .and_then(|r| r.strip_prefix(".level-"))
        .and_then(|r| r.strip_suffix(".xdmf"))
    else {
        return false;
    };
    let (k, grid) = match rest.split_once('.') {
        Some((k, grid)) => (k, Some(grid)),
        None => (rest, None),
    };
    !k.is_empty()
        && k.bytes().all(|b| b.is_ascii_digit())
        && grid.is_none_or(|g| LOWER_GRID_NAMES.contains(&g))
}

/// An output as the writers see it, whichever entry point built it: the
/// meshes with the h5 groups they go to, and the time levels on them.
pub(crate) struct Levels<'a> {
    /// One mesh shared by every level ([`write_run`]) or one per level.
    pub meshes: Vec<MeshAt<'a>>,
    pub steps: Vec<Level<'a>>,
    pub provenance: &'a Provenance,
    /// Each level has its own mesh under `/steps/<k>/mesh`.
    pub mesh_changes: bool,
    /// How much of each complex is stored.
    pub layout: ComplexLayout,
}

/// A complex and where it goes in the h5 file.
pub(crate) struct MeshAt<'a> {
    pub complex: &'a Complex,
    /// Group of the mesh, from the root without a leading `/`: `mesh`, or
    /// `steps/<k>/mesh` in a series.
    pub group: String,
    /// Group of its XDMF arrays: `xdmf`, or `steps/<k>/mesh/xdmf`.
    pub xdmf_group: String,
    /// The levels whose cochains live on it, in increasing order.
    pub steps: Vec<usize>,
}

/// One time level: its cochains live on `meshes[mesh]`.
pub(crate) struct Level<'a> {
    pub time: f64,
    pub cochains: &'a [Cochain],
    pub mesh: usize,
}

impl<'a> Levels<'a> {
    pub(super) fn of_run(run: &'a RunOutput, layout: ComplexLayout) -> Self {
        Levels {
            meshes: vec![MeshAt {
                complex: run.complex,
                group: "mesh".into(),
                xdmf_group: "xdmf".into(),
                steps: (0..run.steps.len()).collect(),
            }],
            steps: run
                .steps
                .iter()
                .map(|s| Level {
                    time: s.time,
                    cochains: &s.cochains,
                    mesh: 0,
                })
                .collect(),
            provenance: &run.provenance,
            mesh_changes: false,
            layout,
        }
    }

    pub(super) fn of_series(series: &'a SeriesOutput, layout: ComplexLayout) -> Self {
        let meshes = series
            .steps
            .iter()
            .enumerate()
            .map(|(k, s)| MeshAt {
                complex: s.complex,
                group: format!("steps/{k}/mesh"),
                xdmf_group: format!("steps/{k}/mesh/xdmf"),
                steps: vec![k],
            })
            .collect();
        Levels {
            meshes,
            steps: series
                .steps
                .iter()
                .enumerate()
                .map(|(k, s)| Level {
                    time: s.time,
                    cochains: &s.cochains,
                    mesh: k,
                })
                .collect(),
            provenance: &series.provenance,
            mesh_changes: true,
            layout,
        }
    }

    /// Dimension n of the top cells (the same on every mesh, see `validate`).
    pub fn dim(&self) -> usize {
        self.meshes.first().map_or(0, |m| m.complex.dim())
    }
}

/// Every name a lower-degree grid file can have (see `xdmf::grid_name`).
pub(super) const LOWER_GRID_NAMES: [&str; 2] = ["edges", "faces"];

pub(super) fn validate(levels: &Levels) -> Result<(), OutputError> {
    if levels.meshes.is_empty() {
        return Err(OutputError::EmptySeries);
    }
    let mut previous: Option<f64> = None;
    for (k, step) in levels.steps.iter().enumerate() {
        check_level(levels, k, step, previous)?;
        previous = Some(step.time);
    }
    Ok(())
}

/// The checks of one level `k` of `levels` (`step`, which need not be in
/// `levels.steps`), whose predecessor has time `previous`.
pub(super) fn check_level(
    levels: &Levels,
    k: usize,
    step: &Level,
    previous: Option<f64>,
) -> Result<(), OutputError> {
    if !step.time.is_finite() || previous.is_some_and(|t| step.time <= t) {
        return Err(OutputError::Time {
            step: k,
            time: step.time,
        });
    }
    let complex = levels.meshes[step.mesh].complex;
    let n = levels.dim();
    if complex.dim() != n {
        return Err(OutputError::MeshDimension {
            step: k,
            dim: complex.dim(),
            expected: n,
        });
    }
    let mut names = HashSet::new();
    for c in step.cochains {
        check_name(&c.name)?;
        if levels.mesh_changes && c.name == "mesh" {
            return Err(OutputError::InvalidName {
                name: c.name.clone(),
                reason: "'mesh' is the group of the step's own mesh in a series",
            });
        }
        if !names.insert(c.name.as_str()) {
            return Err(OutputError::DuplicateName {
                step: k,
                name: c.name.clone(),
            });
        }
        if c.dim > complex.dim() {
            return Err(OutputError::Degree {
                step: k,
                name: c.name.clone(),
                dim: c.dim,
                complex_dim: complex.dim(),
            });
        }
        let expected = complex.cell_count(c.dim);
        if c.values.len() != expected {
            return Err(OutputError::Shape {
                step: k,
                name: c.name.clone(),
                dim: c.dim,
                expected,
                got: c.values.len(),
            });
        }
        if let Some(cell) = c.values.iter().position(|v| !v.is_finite()) {
            return Err(OutputError::NonFinite {
                step: k,
                name: c.name.clone(),
                dim: c.dim,
                cell,
                value: c.values[cell],
            });
        }
    }
    Ok(())
}

/// Names become HDF5 link names and XML attribute values.
pub(super) fn check_name(name: &str) -> Result<(), OutputError> {
    let reason = if name.is_empty() {
        Some("it is empty")
    } else if name == "." || name == ".." {
        Some("'.' and '..' are HDF5 path components")
    } else if name.contains('/') {
        Some("'/' separates HDF5 groups")
    } else if name.contains(':') {
        Some("':' separates file and path in XDMF data references")
    } else if name.chars().any(char::is_control) {
        Some("it contains a control character")
    } else {
        None
    };
    match reason {
        Some(reason) => Err(OutputError::InvalidName {
            name: name.to_string(),
            reason,
        }),
        None => Ok(()),
    }
}

/// The current time as RFC 3339 UTC (`YYYY-MM-DDTHH:MM:SSZ`).
pub(super) fn rfc3339_now() -> String {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    rfc3339(seconds)
}

/// Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
pub(super) fn rfc3339(seconds: u64) -> String {
    let days = (seconds / 86_400) as i64;
    let rem = seconds % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_file_names_are_recognised_only_for_their_stem() {
        assert_eq!(level_file_name("run", 3, None), "run.level-3.xdmf");
        assert_eq!(
            level_file_name("run", 0, Some("edges")),
            "run.level-0.edges.xdmf"
        );
        for name in [
            "run.level-0.xdmf",
            "run.level-12.xdmf",
            "run.level-2.edges.xdmf",
            "run.level-2.faces.xdmf",
        ] {
            assert!(is_level_file_name(name, "run"), "{name}");
        }
        for name in [
            "run.xdmf",
            "run.edges.xdmf",
            "run.level-.xdmf",
            "run.level-x.xdmf",
            "run.level-1.cells.xdmf",
            "run.level-1.h5",
            "other.level-1.xdmf",
            "runs.level-1.xdmf",
        ] {
            assert!(!is_level_file_name(name, "run"), "{name}");
        }
    }
}
