//! Partial output of a time series, written level by level while the run
//! goes on, so that an interrupted or failed run keeps its completed
//! levels readable. See [`PartialOutput`].

use super::atomic::{create_dir, is_temporary, remove_if_present, write_atomically, write_text};
use super::levels::{check_level, rfc3339_now};
use super::topology::GridTopology;
use super::{
    hdf5_file, split_stem, write_run_with, xdmf, Cochain, ComplexLayout, Level, Levels, MeshAt,
    OutputError, OutputFiles, Provenance, RunOutput, Step,
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
/// use hasse_solver::frontend::output::remove_partial;
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
/// under the same stem and writes `<stem>.partial/mesh.h5` (a [`write_run`](super::write_run)
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
/// [`finish`](Self::finish) writes the final output with [`write_run`](super::write_run) and
/// only then removes the partial files. Dropping the writer without
/// finishing keeps them: that is what an interrupted run leaves.
///
/// The partial document is the top-cell grid (0-cochains as point data,
/// n-cochains as cell data), like `<stem>.xdmf`; cochains of other degrees
/// are stored in the level files but have no partial `.edges`/`.faces`
/// document (the final output has them).
///
/// ```
/// use hasse_solver::frontend::output::{Cochain, PartialOutput, Provenance, RunOutput, Step};
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
    /// [`write_run`](super::write_run) for this level, times increasing over the pushes; on
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

    /// Writes the final output with [`write_run`](super::write_run) and then removes the
    /// partial files. `run` must hold the pushed levels (same times, in
    /// order) on the same complex: the final output replaces the partial
    /// one and must not lose or invent a level ([`OutputError::Partial`]
    /// otherwise, before anything is written). On an error of the final
    /// write the partial output stays.
    pub fn finish(self, run: &RunOutput) -> Result<OutputFiles, OutputError> {
        self.finish_with(run, ComplexLayout::default())
    }

    /// [`finish`](Self::finish) with the final output's complex stored in
    /// `layout` (see [`write_run_with`](super::write_run_with)).
    pub fn finish_with(
        self,
        run: &RunOutput,
        layout: ComplexLayout,
    ) -> Result<OutputFiles, OutputError> {
        self.check_run(run)?;
        let files = write_run_with(&self.stem, run, layout)?;
        remove_partial(&self.stem)?;
        Ok(files)
    }

    /// The check of [`finish`](Self::finish): `run` has the pushed levels
    /// on a complex like this one.
    pub fn check_run(&self, run: &RunOutput) -> Result<(), OutputError> {
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
        Ok(())
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

/// The one-mesh view of `complex` with `steps`, as [`write_run`](super::write_run) sees it.
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
        // The partial mesh file is for viewing the levels while the run
        // goes on; the final output has the layout the run asked for.
        layout: ComplexLayout::Minimal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontend::output::write_run;
    use hasse_complex::generate::rectangle;
    use hasse_complex::{TopCells, Vertices};
    use hdf5::types::{TypeDescriptor, VarLenUnicode};

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hasse-partial-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        names
    }

    /// Level j of the test series: u = x + 10 t at the vertices, q = edge
    /// id + t on the edges (a degree the partial document does not show).
    fn level(k: &Complex, t: f64) -> Step {
        let u = (0..k.cell_count(0))
            .map(|v| k.vertices().point(v)[0] + 10.0 * t)
            .collect();
        let q = (0..k.cell_count(1)).map(|e| e as f64 + t).collect();
        Step {
            time: t,
            cochains: vec![
                Cochain::new("u", 0, u).with_units("K").with_method("fe"),
                Cochain::new("q", 1, q).with_description("edge values"),
            ],
        }
    }

    const TIMES: [f64; 3] = [0.0, 0.25, 0.5];

    fn read_f64(path: &Path, dataset: &str) -> Vec<f64> {
        let f = hdf5::File::open(path).unwrap();
        f.dataset(dataset).unwrap().read_raw::<f64>().unwrap()
    }

    #[test]
    fn a_dropped_writer_leaves_every_completed_level_readable() {
        let k = rectangle(3, 2, [0.0, 3.0], [0.0, 2.0]).unwrap();
        let dir = scratch("dropped");
        let stem = dir.join("heat");
        {
            let provenance = Provenance::new(serde_json::json!({"case": "test"}));
            let mut partial = PartialOutput::create(&stem, &k, &provenance).unwrap();
            assert!(!partial.removed_stale());
            for t in TIMES {
                partial.push(&level(&k, t)).unwrap();
            }
            assert_eq!(partial.times(), TIMES);
            // Times must increase over the pushes; nothing is written then.
            assert!(matches!(
                partial.push(&level(&k, 0.5)),
                Err(OutputError::Time { step: 3, .. })
            ));
        }
        assert_eq!(names(&dir), ["heat.partial", "heat.partial.xdmf"]);
        assert_eq!(
            names(&dir.join("heat.partial")),
            ["level-0.h5", "level-1.h5", "level-2.h5", "mesh.h5"]
        );
        let xml = std::fs::read_to_string(dir.join("heat.partial.xdmf")).unwrap();
        assert_eq!(xml.matches("CollectionType=\"Temporal\"").count(), 1);
        for (j, t) in TIMES.iter().enumerate() {
            assert_eq!(xml.matches(&format!("<Time Value=\"{t:?}\"/>")).count(), 1);
            assert!(xml.contains(&format!(
                "Format=\"HDF\">heat.partial/level-{j}.h5:/steps/{j}/u</DataItem>"
            )));
        }
        assert_eq!(
            xml.matches(">heat.partial/mesh.h5:/mesh/vertices<").count(),
            3
        );
        assert_eq!(
            xml.matches(">heat.partial/mesh.h5:/xdmf/2/topology<")
                .count(),
            3
        );
        assert!(!xml.contains("Name=\"q\""));

        // The level files hold the values pushed, the mesh file the mesh.
        let partial_dir = dir.join("heat.partial");
        for (j, &t) in TIMES.iter().enumerate() {
            let file = partial_dir.join(format!("level-{j}.h5"));
            let expected = level(&k, t);
            for c in &expected.cochains {
                assert_eq!(read_f64(&file, &format!("steps/{j}/{}", c.name)), c.values);
            }
            let f = hdf5::File::open(&file).unwrap();
            let time: f64 = f.attr("time").unwrap().read_scalar().unwrap();
            assert_eq!(time, t);
            let units: VarLenUnicode = f
                .dataset(&format!("steps/{j}/u"))
                .unwrap()
                .attr("units")
                .unwrap()
                .read_scalar()
                .unwrap();
            assert_eq!(units.as_str(), "K");
        }
        let vertices = read_f64(&partial_dir.join("mesh.h5"), "mesh/vertices");
        assert_eq!(vertices.len(), 3 * 12);
        assert_eq!(
            &vertices[3 * 5..3 * 6],
            k.vertices()
                .point(5)
                .iter()
                .chain(&[0.0])
                .copied()
                .collect::<Vec<_>>()
                .as_slice()
        );

        // The next run under this stem starts by removing them.
        let provenance = Provenance::new(serde_json::Value::Null);
        let next = PartialOutput::create(&stem, &k, &provenance).unwrap();
        assert!(next.removed_stale());
        assert!(next.is_empty());
        assert_eq!(names(&dir), ["heat.partial"]);
        assert_eq!(names(&partial_dir), ["mesh.h5"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Every dataset under `a` equals the one under `b` at the same path.
    fn assert_same_datasets(a: &hdf5::Group, b: &hdf5::Group) {
        let (mut na, mut nb) = (a.member_names().unwrap(), b.member_names().unwrap());
        na.sort();
        nb.sort();
        assert_eq!(na, nb, "members of {}", a.name());
        for name in na {
            if let Ok(ga) = a.group(&name) {
                assert_same_datasets(&ga, &b.group(&name).unwrap());
                continue;
            }
            let (da, db) = (a.dataset(&name).unwrap(), b.dataset(&name).unwrap());
            let what = da.name();
            match da.dtype().unwrap().to_descriptor().unwrap() {
                TypeDescriptor::Float(_) => assert_eq!(
                    da.read_raw::<f64>().unwrap(),
                    db.read_raw::<f64>().unwrap(),
                    "{what}"
                ),
                TypeDescriptor::Unsigned(_) => assert_eq!(
                    da.read_raw::<u64>().unwrap(),
                    db.read_raw::<u64>().unwrap(),
                    "{what}"
                ),
                TypeDescriptor::Integer(_) => assert_eq!(
                    da.read_raw::<i64>().unwrap(),
                    db.read_raw::<i64>().unwrap(),
                    "{what}"
                ),
                TypeDescriptor::VarLenUnicode => assert_eq!(
                    da.read_scalar::<VarLenUnicode>().unwrap(),
                    db.read_scalar::<VarLenUnicode>().unwrap(),
                    "{what}"
                ),
                other => panic!("{what}: unexpected type {other:?}"),
            }
        }
    }

    #[test]
    fn finishing_writes_what_write_run_writes_and_removes_the_partial_files() {
        let k = rectangle(3, 2, [0.0, 3.0], [0.0, 2.0]).unwrap();
        let dir = scratch("finished");
        let run = RunOutput {
            complex: &k,
            steps: TIMES.iter().map(|&t| level(&k, t)).collect(),
            provenance: Provenance::new(serde_json::json!({"case": "test"})),
        };
        let reference = write_run(&dir.join("reference"), &run).unwrap();

        // A run with other levels than the streamed ones is refused, and
        // the partial output stays.
        let mut partial = PartialOutput::create(&dir.join("other"), &k, &run.provenance).unwrap();
        for step in &run.steps {
            partial.push(step).unwrap();
        }
        let short = RunOutput {
            complex: &k,
            steps: run.steps[..2].to_vec(),
            provenance: run.provenance.clone(),
        };
        assert!(matches!(
            partial.finish(&short),
            Err(OutputError::Partial { .. })
        ));
        assert!(!dir.join("other.h5").exists());
        assert!(remove_partial(&dir.join("other")).unwrap());

        let mut partial =
            PartialOutput::create(&dir.join("streamed"), &k, &run.provenance).unwrap();
        for step in &run.steps {
            partial.push(step).unwrap();
        }
        let files = partial.finish(&run).unwrap();

        assert_eq!(
            names(&dir),
            [
                "reference.edges.xdmf",
                "reference.h5",
                "reference.xdmf",
                "streamed.edges.xdmf",
                "streamed.h5",
                "streamed.xdmf"
            ]
        );
        let (a, b) = (
            hdf5::File::open(&files.hdf5).unwrap(),
            hdf5::File::open(&reference.hdf5).unwrap(),
        );
        assert_same_datasets(&a, &b);
        let times = |f: &hdf5::File| f.attr("times").unwrap().read_raw::<f64>().unwrap();
        assert_eq!(times(&a), TIMES);
        assert_eq!(times(&b), TIMES);
        let xdmf =
            |path: &Path, stem: &str| std::fs::read_to_string(path).unwrap().replace(stem, "STEM");
        assert_eq!(
            xdmf(&files.xdmf, "streamed"),
            xdmf(&reference.xdmf, "reference")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn split_polyhedra_keep_their_expanded_values_in_the_level_files() {
        // A cube cut into two triangular prisms, which XDMF gets as tetrahedra.
        let v = Vertices::from_points(&[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ])
        .unwrap();
        let prism = |a: usize, b: usize, c: usize| {
            vec![
                vec![a, b, c],
                vec![a + 4, b + 4, c + 4],
                vec![a, b, b + 4, a + 4],
                vec![b, c, c + 4, b + 4],
                vec![c, a, a + 4, c + 4],
            ]
        };
        let k = Complex::build(v, TopCells::polyhedra([prism(0, 1, 2), prism(0, 2, 3)])).unwrap();
        let dir = scratch("prisms");
        let provenance = Provenance::new(serde_json::Value::Null);
        let mut partial = PartialOutput::create(&dir.join("p"), &k, &provenance).unwrap();
        for (j, t) in [1.0, 2.0].into_iter().enumerate() {
            let values = vec![10.0 * t, 20.0 * t];
            partial
                .push(&Step {
                    time: t,
                    cochains: vec![Cochain::new("c", 3, values.clone())],
                })
                .unwrap();
            let file = dir.join("p.partial").join(format!("level-{j}.h5"));
            let ids = hdf5::File::open(dir.join("p.partial").join("mesh.h5"))
                .unwrap()
                .dataset("xdmf/3/cell_ids")
                .unwrap()
                .read_raw::<u64>()
                .unwrap();
            let expected: Vec<f64> = ids.iter().map(|&c| values[c as usize]).collect();
            assert_eq!(read_f64(&file, &format!("xdmf/3/steps/{j}/c")), expected);
        }
        let xml = std::fs::read_to_string(partial.xdmf()).unwrap();
        assert!(xml.contains(">p.partial/level-1.h5:/xdmf/3/steps/1/c<"));
        assert!(xml.contains(">p.partial/mesh.h5:/xdmf/3/topology<"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn foreign_files_in_the_partial_directory_are_kept() {
        let dir = scratch("foreign");
        std::fs::create_dir_all(dir.join("run.partial")).unwrap();
        std::fs::write(dir.join("run.partial").join("level-0.h5"), "").unwrap();
        std::fs::write(dir.join("run.partial").join("notes.txt"), "mine").unwrap();
        assert!(matches!(
            remove_partial(&dir.join("run")),
            Err(OutputError::Io { .. })
        ));
        assert_eq!(names(&dir.join("run.partial")), ["notes.txt"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn only_partial_files_are_recognised() {
        for ours in [
            "mesh.h5",
            "level-0.h5",
            "level-12.h5",
            ".level-3.h5.tmp-1-2",
        ] {
            assert!(is_partial_file(ours), "{ours}");
        }
        for theirs in ["level-.h5", "level-1a.h5", "notes.txt", "mesh.h5.bak"] {
            assert!(!is_partial_file(theirs), "{theirs}");
        }
    }
}
