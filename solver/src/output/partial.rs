//! Partial output of a time series, written level by level while the run
//! goes on, so that an interrupted or failed run keeps its completed
//! levels readable. See [`PartialOutput`].

use super::topology::GridTopology;
use super::{
    check_level, create_dir, hdf5_file, is_temporary, remove_if_present, rfc3339_now, split_stem,
    write_atomically, write_run, write_text, xdmf, Cochain, Level, Levels, MeshAt, OutputError,
    OutputFiles, Provenance, RunOutput, Step,
};
use hasse_complex::Complex;
use std::path::{Path, PathBuf};

/// The file holding the mesh inside the partial directory.
const MESH_FILE: &str = "mesh.h5";

fn level_file(k: usize) -> String {
    format!("level-{k}.h5")
}

/// Whether `name` is a file a partial directory may hold: the mesh, a
/// level, or a temporary of one left by a killed run.
fn is_partial_file(name: &str) -> bool {
    let level = name
        .strip_prefix("level-")
        .and_then(|rest| rest.strip_suffix(".h5"))
        .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()));
    name == MESH_FILE || level || is_temporary(name)
}

/// Where the partial output of `stem` lives.
struct PartialPaths {
    /// `<stem>.partial.xdmf`.
    xdmf: PathBuf,
    /// `<stem>.partial/`.
    directory: PathBuf,
    /// `<name>.partial`: the directory as the XDMF document refers to it.
    directory_name: String,
}

impl PartialPaths {
    fn of(stem: &Path) -> Result<Self, OutputError> {
        let (dir, name) = split_stem(stem)?;
        let directory_name = format!("{name}.partial");
        Ok(PartialPaths {
            xdmf: dir.join(format!("{directory_name}.xdmf")),
            directory: dir.join(&directory_name),
            directory_name,
        })
    }
}

/// Removes the partial output of `stem` (`<stem>.partial.xdmf` and the
/// directory `<stem>.partial/` with the files a partial output writes
/// there), if there is one, and tells whether there was.
///
/// The XDMF document goes first, so that no document ever points at a
/// removed file. Only files a partial output writes are removed: anything
/// else in `<stem>.partial/` is left alone and makes this fail (the
/// directory is not empty), rather than deleting someone's data.
///
/// ```
/// use hasse_solver::output::remove_partial;
/// let dir = std::env::temp_dir().join(format!("hasse-doc-remove-{}", std::process::id()));
/// std::fs::create_dir_all(dir.join("run.partial")).unwrap();
/// std::fs::write(dir.join("run.partial.xdmf"), "").unwrap();
/// std::fs::write(dir.join("run.partial").join("level-0.h5"), "").unwrap();
/// assert!(remove_partial(&dir.join("run")).unwrap());
/// assert!(!dir.join("run.partial").exists() && !dir.join("run.partial.xdmf").exists());
/// assert!(!remove_partial(&dir.join("run")).unwrap()); // nothing left to remove
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn remove_partial(stem: &Path) -> Result<bool, OutputError> {
    let paths = PartialPaths::of(stem)?;
    let mut removed = remove_if_present(&paths.xdmf)?;
    // A run killed while it rewrote the document leaves its temporary.
    if let Some(dir) = paths.xdmf.parent() {
        let prefix = format!(".{}.xdmf.tmp-", paths.directory_name);
        if let Ok(entries) = std::fs::read_dir(dir) {
            for entry in entries.flatten() {
                if entry.file_name().to_string_lossy().starts_with(&prefix) {
                    removed |= remove_if_present(&entry.path())?;
                }
            }
        }
    }
    let entries = match std::fs::read_dir(&paths.directory) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(removed),
        Err(source) => {
            return Err(OutputError::Io {
                path: paths.directory,
                source,
            })
        }
    };
    for entry in entries {
        let entry = entry.map_err(|source| OutputError::Io {
            path: paths.directory.clone(),
            source,
        })?;
        if is_partial_file(&entry.file_name().to_string_lossy()) {
            remove_if_present(&entry.path())?;
        }
    }
    std::fs::remove_dir(&paths.directory).map_err(|source| OutputError::Io {
        path: paths.directory.clone(),
        source,
    })?;
    Ok(true)
}

/// A time series written level by level while it is computed, so that a
/// run that is killed, interrupted or fails keeps its completed levels.
///
/// [`create`](Self::create) removes the partial output of an earlier run
/// under the same stem and writes `<stem>.partial/mesh.h5` (a [`write_run`]
/// file without steps: the `/mesh` and `/xdmf` groups, the provenance);
/// each [`push`](Self::push) writes `<stem>.partial/level-<k>.h5` (root
/// attrs `step` and `time`, the group `/steps/<k>` of a run file) and then
/// rewrites `<stem>.partial.xdmf`, a temporal collection of exactly the
/// completed levels whose grids read geometry and topology from `mesh.h5`
/// and their cochains from `level-<k>.h5`. Every file is written under a
/// temporary name, synced and renamed into place, so a kill at any moment
/// leaves complete files only; the levels are separate files rather than
/// groups appended to one, because a kill while HDF5 writes into a file
/// can leave its metadata unreadable and so lose every level.
///
/// [`finish`](Self::finish) writes the final output with [`write_run`] and
/// only then removes the partial files. Dropping the writer without
/// finishing keeps them: that is what an interrupted run leaves.
///
/// The partial document is the top-cell grid (0-cochains as point data,
/// n-cochains as cell data), like `<stem>.xdmf`; cochains of other degrees
/// are stored in the level files but have no partial `.edges`/`.faces`
/// document (the final output has them).
///
/// ```
/// use hasse_solver::output::{Cochain, PartialOutput, Provenance, RunOutput, Step};
/// let k = hasse_complex::generate::rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let dir = std::env::temp_dir().join(format!("hasse-doc-partial-{}", std::process::id()));
/// let stem = dir.join("cooling");
/// let provenance = Provenance::new(serde_json::Value::Null);
/// let mut partial = PartialOutput::create(&stem, &k, &provenance).unwrap();
/// let level = |t: f64| Step { time: t, cochains: vec![Cochain::new("u", 0, vec![t; 9])] };
/// partial.push(&level(0.0)).unwrap();
/// partial.push(&level(0.5)).unwrap();
/// // Readable now, while the run would still be going.
/// let text = std::fs::read_to_string(partial.xdmf()).unwrap();
/// assert_eq!(text.matches("<Time ").count(), 2);
/// assert!(text.contains("cooling.partial/level-1.h5:/steps/1/u"));
/// assert!(dir.join("cooling.partial").join("mesh.h5").exists());
/// // At the end, the final output replaces the partial one.
/// let run = RunOutput { complex: &k, steps: vec![level(0.0), level(0.5)], provenance };
/// let files = partial.finish(&run).unwrap();
/// assert!(files.hdf5.exists() && !dir.join("cooling.partial.xdmf").exists());
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub struct PartialOutput<'a> {
    complex: &'a Complex,
    stem: PathBuf,
    paths: PartialPaths,
    /// The top-cell grid of the complex, computed once: `grids[0][0]`.
    grids: Vec<Vec<GridTopology>>,
    /// The completed levels with their cochains' values dropped: the
    /// document needs only names and degrees, and the values are on disk.
    levels: Vec<Step>,
    removed_stale: bool,
}

impl<'a> PartialOutput<'a> {
    /// Starts the partial output of `stem` for a series on `complex`:
    /// removes the partial output of an earlier run under this stem (see
    /// [`remove_partial`], and [`removed_stale`](Self::removed_stale)) and
    /// writes `<stem>.partial/mesh.h5` with `provenance`. There is no
    /// `<stem>.partial.xdmf` until the first level is pushed.
    pub fn create(
        stem: &Path,
        complex: &'a Complex,
        provenance: &Provenance,
    ) -> Result<Self, OutputError> {
        let paths = PartialPaths::of(stem)?;
        let removed_stale = remove_partial(stem)?;
        let mesh_only = mesh_levels(complex, provenance, Vec::new());
        let grids = xdmf::grids(&mesh_only, &[complex.dim()])?;
        create_dir(&paths.directory)?;
        write_atomically(&paths.directory.join(MESH_FILE), |path| {
            hdf5_file::write(path, &mesh_only, &grids, &rfc3339_now())
        })?;
        Ok(PartialOutput {
            complex,
            stem: stem.to_path_buf(),
            paths,
            grids,
            levels: Vec::new(),
            removed_stale,
        })
    }

    /// Writes the next level (its index is [`len`](Self::len) before the
    /// call) and then the document listing it. The checks are those of
    /// [`write_run`] for this level, times increasing over the pushes; on
    /// an error nothing of this level is written and the completed levels
    /// stay as they were.
    pub fn push(&mut self, step: &Step) -> Result<(), OutputError> {
        let k = self.levels.len();
        let provenance = Provenance::new(serde_json::Value::Null);
        let levels = mesh_levels(self.complex, &provenance, Vec::new());
        let level = Level {
            time: step.time,
            cochains: &step.cochains,
            mesh: 0,
        };
        check_level(&levels, k, &level, self.levels.last().map(|s| s.time))?;
        write_atomically(&self.paths.directory.join(level_file(k)), |path| {
            hdf5_file::write_level(path, &levels, &self.grids[0], k, &level)
        })?;
        self.levels.push(Step {
            time: step.time,
            cochains: step
                .cochains
                .iter()
                .map(|c| Cochain {
                    name: c.name.clone(),
                    dim: c.dim,
                    values: Vec::new(),
                    units: c.units.clone(),
                    method: c.method.clone(),
                    description: c.description.clone(),
                })
                .collect(),
        });
        let text = self.document();
        write_atomically(&self.paths.xdmf, |path| write_text(path, &text))
    }

    /// The document of the completed levels.
    fn document(&self) -> String {
        let provenance = Provenance::new(serde_json::Value::Null);
        let steps = self
            .levels
            .iter()
            .map(|s| Level {
                time: s.time,
                cochains: &s.cochains,
                mesh: 0,
            })
            .collect();
        let levels = mesh_levels(self.complex, &provenance, steps);
        let mesh = format!("{}/{MESH_FILE}", self.paths.directory_name);
        let level = |k: usize| format!("{}/{}", self.paths.directory_name, level_file(k));
        let files = xdmf::Files {
            mesh: &mesh,
            level: Some(&level),
        };
        xdmf::document(&levels, &self.grids, 0, &files)
    }

    /// Writes the final output with [`write_run`] and then removes the
    /// partial files. `run` must hold the pushed levels (same times, in
    /// order) on the same complex: the final output replaces the partial
    /// one and must not lose or invent a level ([`OutputError::Partial`]
    /// otherwise, before anything is written). On an error of the final
    /// write the partial output stays.
    pub fn finish(self, run: &RunOutput) -> Result<OutputFiles, OutputError> {
        let mismatch = |reason: String| OutputError::Partial {
            path: self.paths.xdmf.clone(),
            reason,
        };
        if run.complex.cell_counts() != self.complex.cell_counts() {
            return Err(mismatch(format!(
                "the run's complex has cells per dimension {:?}, the partial output's {:?}",
                run.complex.cell_counts(),
                self.complex.cell_counts()
            )));
        }
        let times: Vec<f64> = run.steps.iter().map(|s| s.time).collect();
        if times != self.times() {
            return Err(mismatch(format!(
                "the run has the times {times:?}, the partial output {:?}",
                self.times()
            )));
        }
        let files = write_run(&self.stem, run)?;
        remove_partial(&self.stem)?;
        Ok(files)
    }

    /// `<stem>.partial.xdmf`, the document of the completed levels (absent
    /// until the first push).
    pub fn xdmf(&self) -> &Path {
        &self.paths.xdmf
    }

    /// `<stem>.partial/`, the directory of `mesh.h5` and the level files.
    pub fn directory(&self) -> &Path {
        &self.paths.directory
    }

    /// The times of the completed levels.
    pub fn times(&self) -> Vec<f64> {
        self.levels.iter().map(|s| s.time).collect()
    }

    /// The number of completed levels.
    pub fn len(&self) -> usize {
        self.levels.len()
    }

    /// Whether no level is completed yet.
    pub fn is_empty(&self) -> bool {
        self.levels.is_empty()
    }

    /// Whether [`create`](Self::create) removed the partial output of an
    /// earlier run under the same stem.
    pub fn removed_stale(&self) -> bool {
        self.removed_stale
    }
}

/// The one-mesh view of `complex` with `steps`, as [`write_run`] sees it.
fn mesh_levels<'l>(
    complex: &'l Complex,
    provenance: &'l Provenance,
    steps: Vec<Level<'l>>,
) -> Levels<'l> {
    Levels {
        meshes: vec![MeshAt {
            complex,
            group: "mesh".into(),
            xdmf_group: "xdmf".into(),
            steps: (0..steps.len()).collect(),
        }],
        steps,
        provenance,
        mesh_changes: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_partial_files_are_recognised() {
        for ours in ["mesh.h5", "level-0.h5", "level-12.h5", ".level-3.h5.tmp-1-2"] {
            assert!(is_partial_file(ours), "{ours}");
        }
        for theirs in ["level-.h5", "level-1a.h5", "notes.txt", "mesh.h5.bak"] {
            assert!(!is_partial_file(theirs), "{theirs}");
        }
    }
}
