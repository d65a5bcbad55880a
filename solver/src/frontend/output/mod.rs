//! Output of a run: one HDF5 file holding the complex, every cochain of
//! every time level and the provenance, plus XDMF 3 files beside it (one
//! per cochain degree grid) so ParaView, VisIt and meshio open the same data.
//!
//! # HDF5 layout (`<stem>.h5`)
//!
//! Everything is readable with h5py alone; `cases/OUTPUT.md` has examples.
//!
//! | path | content |
//! | --- | --- |
//! | `/` attrs `step_count` (u64), `times` (f64 array), `format` = `"hasse-output"`, `format_version` (u64: 1, or 2 for a mesh series), `mesh_changes` (u64: 0, or 1 for a mesh series) | |
//! | `/mesh` attrs `dim` (n), `embedding_dim` (d), `complex` (`"minimal"` or `"full"`, see [`ComplexLayout`]) | |
//! | `/mesh/vertices` | (N, 3) f64, zero-padded when d < 3; attr `embedding_dim` |
//! | `/mesh/cells/<p>/indptr`, `indices` | CSR characteristic matrix M_p (u64) for p = n and the degrees of the cochains (every p = 0..=n in the full layout); attr `shape` = (rows, cols). Row i lists the sorted vertex ids of p-cell i; p-cell ids everywhere else are these row numbers |
//! | `/mesh/boundary/<p>/indptr`, `indices` (u64), `data` (i8) | full layout only: signed ∂_p in CSR, rows (p-1)-cells, columns p-cells, p = 1..=n; attr `shape` |
//! | `/mesh/tags/<name>` | u64 ids of the tagged cells; attr `dim` |
//! | `/steps/<k>` attr `time` | one group per time level k = 0, 1, … |
//! | `/steps/<k>/<name>` | f64 cochain, one value per p-cell; attrs `dim`, and `units`, `method`, `description` when given |
//! | `/provenance` attrs `hasse_version`, `written_at` (RFC 3339 UTC), `case_path` (if known) | |
//! | `/provenance/case_text`, `/provenance/report` | scalar UTF-8 string datasets (the case file, the run report as JSON) |
//! | `/xdmf/<p>/topology` | connectivity of the XDMF grid of the p-cells (i64), see below |
//! | `/xdmf/<p>/cell_ids` | only when the grid's elements are not the p-cells one to one: the p-cell of each element |
//! | `/xdmf/<p>/steps/<k>/<name>` | only with `cell_ids`: the cochain expanded to the elements |
//!
//! The integer arrays of `cells`, `boundary` and `xdmf` of 1 MiB or more
//! are chunked and shuffle + deflate compressed (when the HDF5 library has
//! zlib); readers see ordinary datasets.
//!
//! Strings are variable-length UTF-8, so h5py returns attributes as `str`
//! (string datasets need `.asstr()[()]`).
//!
//! # Series whose mesh changes ([`write_mesh_series`])
//!
//! Root attr `mesh_changes` = 1, `format_version` = 2; there is no `/mesh`
//! and no `/xdmf`. Instead each level k has its own mesh inside its step:
//! `/steps/<k>/mesh` holds what `/mesh` holds above (attrs, `vertices`,
//! `cells/<p>`, `boundary/<p>` in the full layout, `tags/<name>`, with that step's cell ids),
//! and `/steps/<k>/mesh/xdmf` what `/xdmf` holds, for level k only
//! (`<p>/topology`, `<p>/cell_ids`, `<p>/steps/<k>/<name>`). The cochains
//! stay in `/steps/<k>/<name>`, so no cochain of a series may be named
//! `mesh`. In the XDMF files, the k-th grid of the temporal collection
//! reads its geometry and topology from `/steps/<k>/mesh` (and leaves
//! `GridType` at its default, so that meshio's `TimeSeriesReader`, which
//! takes one mesh for all grids, refuses the file). Each level also gets
//! files of its own, `<stem>.level-<k>.xdmf` (and
//! `<stem>.level-<k>.<grid>.xdmf`), one plain uniform grid each, which
//! `meshio.read` opens; for meshio too, polygons of five or more vertices
//! are written as triangles (with `cell_ids`, as split polyhedra).
//!
//! # Partial output of a running series ([`PartialOutput`])
//!
//! A time series can also be written level by level while it is computed:
//! `<stem>.partial/mesh.h5` (a run file without steps), one
//! `<stem>.partial/level-<k>.h5` per completed level (`/steps/<k>` as
//! above, plus root attrs `step` and `time`), and `<stem>.partial.xdmf`,
//! rewritten after each level, whose k-th grid reads the mesh file and
//! level k's file. Each file is renamed into place complete, so a killed
//! run leaves every listed level readable; [`PartialOutput::finish`]
//! writes the final output with [`write_run`] and then removes them.
//!
//! # XDMF (`<stem>.xdmf`, `<stem>.edges.xdmf`, `<stem>.faces.xdmf`)
//!
//! ParaView and VisIt ignore `Center="Edge"`/`"Face"`, so each cochain
//! degree gets its own grid with ordinary cell data: the top cells
//! (carrying the top-degree cochains as cell data and the 0-cochains as
//! point data), the edges as 2-node polylines when n ≥ 2 and there are
//! 1-cochains, and the faces as polygons when n = 3 and there are
//! 2-cochains. Cells are written with VTK vertex order (cyclic polygons,
//! VTK hexahedra, positive tetrahedra), rebuilt from ∂ since hasse keeps
//! only sorted vertex sets. Triangles, quadrilaterals, tetrahedra and
//! hexahedra keep their own types (uniform topology when all cells agree,
//! `Mixed` otherwise); polygons with five or more vertices are XDMF
//! `Polygon` cells; other convex polyhedra are split into tetrahedra from
//! their lowest vertex (XDMF `Polyhedron` is read by neither meshio nor
//! reliably by ParaView), with `cell_ids` mapping elements back.
//!
//! Each grid is a document of its own: the top grid is `<stem>.xdmf`
//! (written even when no cochain lives on it, as the mesh), the edges
//! `<stem>.edges.xdmf`, the faces `<stem>.faces.xdmf`, all pointing into
//! the one `<stem>.h5`. `meshio.read` accepts only a domain with a single
//! uniform grid (a spatial collection fails with "Unknown section
//! 'Grid'") and `meshio.xdmf.TimeSeriesReader` only one temporal
//! collection, so one grid per file lets meshio read every file, while
//! ParaView opens each. One time level gives a plain uniform grid,
//! several give a temporal collection. `TimeSeriesReader` takes the mesh of the
//! first grid only, so it cannot read a series whose mesh changes; the
//! level files and h5py can (`cases/OUTPUT.md`).

pub(crate) mod atomic;
mod hdf5_file;
mod layout;
mod levels;
mod partial;
pub mod read_mesh;
pub mod study;
#[cfg(test)]
mod tests;
mod topology;
mod xdmf;

pub use layout::{read_boundary, ComplexLayout};
pub use partial::{remove_partial, PartialOutput};

use levels::write_levels;
pub(crate) use levels::{Level, Levels, MeshAt};

use hasse_complex::Complex;

/// Write a text file under a temporary name in its directory and rename
/// it into place: `path` holds the old file or the complete new one, never
/// a part (used by `hasse export`).
pub fn write_text_file(path: &Path, text: &str) -> Result<(), OutputError> {
    atomic::write_atomically(path, |temporary| atomic::write_text(temporary, text))
}

use std::collections::HashSet;

use std::path::{Path, PathBuf};

/// One cochain: values on the p-cells of the complex (`values.len() == complex.cell_count(dim)`).
///
/// ```
/// use hasse_solver::frontend::output::Cochain;
/// let u = Cochain::new("u", 0, vec![0.0, 1.0, 2.0]).with_units("K");
/// assert_eq!(u.units.as_deref(), Some("K"));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Cochain {
    /// Name of the field; unique within a step, used as HDF5 and XDMF name.
    pub name: String,
    /// Degree p: the values live on the p-cells.
    pub dim: usize,
    /// One value per p-cell, in cell-id order.
    pub values: Vec<f64>,
    /// Physical units, e.g. `"K"`.
    pub units: Option<String>,
    /// Discretisation that produced the values, e.g. `"fe"`.
    pub method: Option<String>,
    /// Free text.
    pub description: Option<String>,
}

impl Cochain {
    /// A cochain without metadata.
    pub fn new(name: impl Into<String>, dim: usize, values: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            dim,
            values,
            units: None,
            method: None,
            description: None,
        }
    }

    /// The same cochain with its units set.
    pub fn with_units(mut self, units: impl Into<String>) -> Self {
        self.units = Some(units.into());
        self
    }

    /// The same cochain with the method that produced it.
    pub fn with_method(mut self, method: impl Into<String>) -> Self {
        self.method = Some(method.into());
        self
    }

    /// The same cochain with a description.
    pub fn with_description(mut self, description: impl Into<String>) -> Self {
        self.description = Some(description.into());
        self
    }
}

/// One time level (a steady run has exactly one step with time 0.0).
///
/// ```
/// use hasse_solver::frontend::output::{Cochain, Step};
/// let step = Step { time: 0.5, cochains: vec![Cochain::new("u", 0, vec![1.0])] };
/// assert_eq!(step.cochains.len(), 1);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// Time of the level; times must be finite and strictly increasing.
    pub time: f64,
    /// The fields at this time.
    pub cochains: Vec<Cochain>,
}

/// Where a run came from, stored under `/provenance`.
///
/// ```
/// use hasse_solver::frontend::output::Provenance;
/// let p = Provenance::new(serde_json::json!({"iterations": 3}));
/// assert_eq!(p.hasse_version, env!("CARGO_PKG_VERSION"));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    /// Full text of the case file.
    pub case_text: Option<String>,
    /// Path of the case file as given.
    pub case_path: Option<String>,
    /// Version of hasse that wrote the file.
    pub hasse_version: String,
    /// The run report (errors, iterations, timings…), stored as JSON text.
    pub report: serde_json::Value,
}

impl Provenance {
    /// Provenance of this build of hasse with the given report and no case file.
    pub fn new(report: serde_json::Value) -> Self {
        Self {
            case_text: None,
            case_path: None,
            hasse_version: env!("CARGO_PKG_VERSION").to_string(),
            report,
        }
    }
}

/// Everything [`write_run`] stores: the complex, the time levels and the provenance.
///
/// ```
/// use hasse_solver::frontend::output::{Provenance, RunOutput};
/// let k = hasse_complex::generate::interval(2, 0.0, 1.0).unwrap();
/// let run = RunOutput { complex: &k, steps: vec![], provenance: Provenance::new(serde_json::Value::Null) };
/// assert!(run.steps.is_empty());
/// ```
#[derive(Clone, Debug)]
pub struct RunOutput<'a> {
    /// The complex every cochain lives on.
    pub complex: &'a Complex,
    /// Time levels in increasing time (may be empty: mesh only).
    pub steps: Vec<Step>,
    /// Where the run came from.
    pub provenance: Provenance,
}

/// One time level with its own complex, for [`write_mesh_series`].
///
/// ```
/// use hasse_solver::frontend::output::{Cochain, MeshStep};
/// let k = hasse_complex::generate::interval(3, 0.0, 1.0).unwrap();
/// let step = MeshStep { time: 0.5, complex: &k, cochains: vec![Cochain::new("q", 1, vec![1.0; 3])] };
/// assert_eq!(step.cochains[0].values.len(), step.complex.cell_count(1));
/// ```
#[derive(Clone, Debug)]
pub struct MeshStep<'a> {
    /// Time of the level; times must be finite and strictly increasing.
    pub time: f64,
    /// The complex of this level; the cochains live on it.
    pub complex: &'a Complex,
    /// The fields at this time, on `complex`.
    pub cochains: Vec<Cochain>,
}

/// Everything [`write_mesh_series`] stores: time levels, each with its own
/// complex, and the provenance.
///
/// ```
/// use hasse_solver::frontend::output::{MeshStep, Provenance, SeriesOutput};
/// let coarse = hasse_complex::generate::interval(2, 0.0, 1.0).unwrap();
/// let fine = hasse_complex::generate::interval(4, 0.0, 1.0).unwrap();
/// let series = SeriesOutput {
///     steps: vec![
///         MeshStep { time: 0.0, complex: &coarse, cochains: vec![] },
///         MeshStep { time: 1.0, complex: &fine, cochains: vec![] },
///     ],
///     provenance: Provenance::new(serde_json::Value::Null),
/// };
/// assert_eq!(series.steps[1].complex.cell_count(1), 4);
/// ```
#[derive(Clone, Debug)]
pub struct SeriesOutput<'a> {
    /// Time levels in increasing time; at least one.
    pub steps: Vec<MeshStep<'a>>,
    /// Where the run came from.
    pub provenance: Provenance,
}

/// The files [`write_run`] or [`write_mesh_series`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputFiles {
    /// `<stem>.h5`.
    pub hdf5: PathBuf,
    /// `<stem>.xdmf`: the top-cell grid (0-cochains as point data,
    /// n-cochains as cell data), referring to the h5 file by its bare name.
    pub xdmf: PathBuf,
    /// `<stem>.edges.xdmf` and `<stem>.faces.xdmf`, in increasing degree:
    /// one per lower degree that carries cochains (empty when none does).
    pub extra_xdmf: Vec<PathBuf>,
    /// Only for a series whose mesh changes ([`write_mesh_series`]; empty
    /// otherwise): `levels[k]` are the files of level k alone, each one
    /// plain uniform grid: `<stem>.level-<k>.xdmf` (top cells), then
    /// `<stem>.level-<k>.<grid>.xdmf` for the degrees of `extra_xdmf`.
    pub levels: Vec<Vec<PathBuf>>,
}

impl OutputFiles {
    /// A refinement also writes each level alone (for readers that take
    /// one mesh per file): the summary names the first and the last.
    pub fn levels_line(&self) -> Option<String> {
        let first_file = |files: Option<&Vec<PathBuf>>| {
            files
                .and_then(|f| f.first())
                .map(|p| p.display().to_string())
        };
        match (
            first_file(self.levels.first()),
            first_file(self.levels.last()),
        ) {
            (Some(first), Some(last)) if self.levels.len() > 1 => Some(format!(
                "{first} … {last} (each level alone, {} files)",
                self.levels.iter().map(Vec::len).sum::<usize>()
            )),
            (Some(only), _) => Some(format!("{only} (the level alone)")),
            _ => None,
        }
    }
}

/// Why an output could not be written. Nothing is left under the final
/// file names when any of these is returned, except for an [`Io`] error on
/// removing a stale degree file of an older output, or the partial output
/// ([`PartialOutput::finish`], [`remove_partial`]), which happens only
/// after the new output is complete and in place.
///
/// [`Io`]: OutputError::Io
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A directory or file could not be created, written or renamed.
    #[error("{path}: {source}")]
    Io {
        /// The directory or file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The HDF5 library refused an operation on the (temporary) h5 file.
    #[error("{path}: HDF5 error: {message}")]
    Hdf5 {
        /// The h5 file.
        path: PathBuf,
        /// The library's message.
        message: String,
    },
    /// A cochain's length is not the number of cells of its degree (in
    /// the complex of its step).
    #[error(
        "cochain '{name}' (step {step}) of degree {dim} has {got} values, the complex has {expected} {dim}-cells"
    )]
    Shape {
        /// The step, counted from 0.
        step: usize,
        /// The cochain's name.
        name: String,
        /// Its degree p.
        dim: usize,
        /// The number of p-cells.
        expected: usize,
        /// The number of values.
        got: usize,
    },
    /// A cochain's degree exceeds the dimension of the complex.
    #[error(
        "cochain '{name}' (step {step}) has degree {dim}, the complex has dimension {complex_dim}"
    )]
    Degree {
        /// The step, counted from 0.
        step: usize,
        /// The cochain's name.
        name: String,
        /// Its degree.
        dim: usize,
        /// The dimension of the complex.
        complex_dim: usize,
    },
    /// NaN or ±∞ in a cochain; `cell` is the first bad cell id.
    #[error(
        "cochain '{name}' (step {step}) has the non-finite value {value} on {dim}-cell {cell}"
    )]
    NonFinite {
        /// The step, counted from 0.
        step: usize,
        /// The cochain's name.
        name: String,
        /// Its degree p.
        dim: usize,
        /// The first p-cell with a non-finite value.
        cell: usize,
        /// That value.
        value: f64,
    },
    /// Two cochains of one step share a name.
    #[error("step {step} has two cochains named '{name}'")]
    DuplicateName {
        /// The step, counted from 0.
        step: usize,
        /// The shared name.
        name: String,
    },
    /// A cochain name that cannot be an HDF5 link name or an XDMF reference.
    #[error("cochain name '{name}' cannot be stored: {reason}")]
    InvalidName {
        /// The name.
        name: String,
        /// Why it cannot be stored.
        reason: &'static str,
    },
    /// Times must be finite and strictly increasing.
    #[error("step {step} has time {time}: times must be finite and strictly increasing")]
    Time {
        /// The first step out of order, counted from 0.
        step: usize,
        /// Its time.
        time: f64,
    },
    /// A series whose mesh changes needs at least one time level: the
    /// complexes come with the levels.
    #[error("a series whose mesh changes needs at least one step")]
    EmptySeries,
    /// The complexes of a series must all have the same dimension (the
    /// XDMF files are one per cell degree).
    #[error("step {step} has a complex of dimension {dim}, step 0 one of dimension {expected}")]
    MeshDimension {
        /// The step, counted from 0.
        step: usize,
        /// The dimension of its complex.
        dim: usize,
        /// The dimension of step 0's complex.
        expected: usize,
    },
    /// An output file's place is taken by something that is not a file
    /// (a directory), or the output directory's place by a file.
    #[error("{}: {reason}", path.display())]
    Place {
        /// The path that is taken.
        path: PathBuf,
        /// What is there instead, and what to do.
        reason: String,
    },
    /// The output stem cannot name the output files.
    #[error("output stem '{path}': {reason}")]
    Stem {
        /// The stem as given.
        path: PathBuf,
        /// Why it cannot be used.
        reason: &'static str,
    },
    /// A provenance or metadata string cannot be stored (e.g. it contains NUL).
    #[error("{field} cannot be stored as an HDF5 string: {reason}")]
    Text {
        /// Which string: its attribute or dataset name (e.g.
        /// `case_text`, `units`).
        field: String,
        /// Why.
        reason: String,
    },
    /// [`PartialOutput::finish`] was given a run that is not the series it
    /// streamed (other times or another complex); nothing was written.
    #[error("{path}: {reason}")]
    Partial {
        /// The partial output.
        path: PathBuf,
        /// How the run differs from it.
        reason: String,
    },
    /// An output file does not hold what a reader asked of it: the
    /// boundary matrices of a file written with the minimal layout.
    #[error("{path}: {message}")]
    Layout {
        /// The h5 file.
        path: PathBuf,
        /// What is missing, and how to get it.
        message: String,
    },
    /// The reader-order connectivity of some cell could not be rebuilt.
    #[error("cannot write the XDMF cells: {message}")]
    Topology {
        /// Which cell, and why.
        message: String,
    },
}

/// Writes `<stem>.h5`, `<stem>.xdmf` and one `<stem>.<grid>.xdmf` per
/// lower cochain degree (stem may include a directory, created if missing)
/// and returns their paths.
///
/// Inputs are checked before anything is written. All files are first
/// written under temporary names in the target directory and renamed into
/// place only when all are complete (the h5 first, then the degree files,
/// `<stem>.xdmf` last), so an error never leaves a truncated file and
/// never replaces an older output. Once the new output is in place, degree
/// files of an older output that this run does not have are removed.
///
/// ```
/// use hasse_solver::frontend::output::{write_run, Cochain, Provenance, RunOutput, Step};
/// let k = hasse_complex::generate::rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let x: Vec<f64> = (0..k.cell_count(0)).map(|v| k.vertices().point(v)[0]).collect();
/// let run = RunOutput {
///     complex: &k,
///     steps: vec![Step { time: 0.0, cochains: vec![Cochain::new("x", 0, x)] }],
///     provenance: Provenance::new(serde_json::json!({"note": "doctest"})),
/// };
/// let dir = std::env::temp_dir().join(format!("hasse-doc-{}", std::process::id()));
/// let files = write_run(&dir.join("run"), &run).unwrap();
/// assert!(files.hdf5.ends_with("run.h5") && files.xdmf.exists());
/// assert!(files.extra_xdmf.is_empty()); // no edge cochain, no run.edges.xdmf
/// let xdmf = std::fs::read_to_string(&files.xdmf).unwrap();
/// assert!(xdmf.contains("run.h5:/steps/0/x"));
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_run(stem: &Path, run: &RunOutput) -> Result<OutputFiles, OutputError> {
    write_run_with(stem, run, ComplexLayout::default())
}

/// [`write_run`] with the complex stored in `layout`: the default
/// [`ComplexLayout::Minimal`] (what `write_run` writes), or
/// [`ComplexLayout::Full`], which adds every M_p and every ∂_p.
pub fn write_run_with(
    stem: &Path,
    run: &RunOutput,
    layout: ComplexLayout,
) -> Result<OutputFiles, OutputError> {
    write_levels(stem, &Levels::of_run(run, layout))
}

/// Writes `<stem>.h5`, `<stem>.xdmf` and one `<stem>.<grid>.xdmf` per
/// lower cochain degree for a time series whose complex changes from one
/// level to the next (refinement studies, growing tissues), plus the same
/// documents for each level k alone, `<stem>.level-<k>[.<grid>].xdmf`
/// (for readers of one mesh per file, such as `meshio.read`), and returns
/// their paths.
///
/// Each level k stores its own complex under `/steps/<k>/mesh` (the layout
/// of `/mesh` in a [`write_run`] file, plus the XDMF arrays under
/// `/steps/<k>/mesh/xdmf`) next to its cochains `/steps/<k>/<name>`; the
/// root attribute `mesh_changes` is 1 (0 in [`write_run`] files). In every
/// XDMF file the k-th grid of the temporal collection has its own geometry
/// and topology pointing into `/steps/<k>/mesh`; the level files hold
/// grid k alone, without `<Time>`. Polygons of five or more vertices are
/// written as triangles (meshio reads no polygon).
///
/// Checks, temporary files and renames are those of [`write_run`]. Besides
/// its checks, the series must have at least one level
/// ([`OutputError::EmptySeries`]), all complexes the same dimension
/// ([`OutputError::MeshDimension`]), and no cochain may be named `mesh`.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::frontend::output::{write_mesh_series, Cochain, MeshStep, Provenance, SeriesOutput};
/// let coarse = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let fine = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let x = |k: &hasse_complex::Complex| -> Vec<f64> {
///     (0..k.cell_count(0)).map(|v| k.vertices().point(v)[0]).collect()
/// };
/// let series = SeriesOutput {
///     steps: vec![
///         MeshStep { time: 0.0, complex: &coarse, cochains: vec![Cochain::new("x", 0, x(&coarse))] },
///         MeshStep { time: 1.0, complex: &fine, cochains: vec![Cochain::new("x", 0, x(&fine))] },
///     ],
///     provenance: Provenance::new(serde_json::json!({"note": "doctest"})),
/// };
/// let dir = std::env::temp_dir().join(format!("hasse-doc-series-{}", std::process::id()));
/// let files = write_mesh_series(&dir.join("grow"), &series).unwrap();
/// let xdmf = std::fs::read_to_string(&files.xdmf).unwrap();
/// assert!(xdmf.contains("grow.h5:/steps/1/mesh/vertices"));
/// assert!(xdmf.contains("grow.h5:/steps/1/x"));
/// assert_eq!(files.levels[1], [dir.join("grow.level-1.xdmf")]);
/// let level = std::fs::read_to_string(&files.levels[1][0]).unwrap();
/// assert!(level.contains("grow.h5:/steps/1/x") && !level.contains("/steps/0/"));
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn write_mesh_series(stem: &Path, series: &SeriesOutput) -> Result<OutputFiles, OutputError> {
    write_mesh_series_with(stem, series, ComplexLayout::default())
}

/// [`write_mesh_series`] with each step's complex stored in `layout`.
pub fn write_mesh_series_with(
    stem: &Path,
    series: &SeriesOutput,
    layout: ComplexLayout,
) -> Result<OutputFiles, OutputError> {
    write_levels(stem, &Levels::of_series(series, layout))
}

/// Check, before any long computation, that output can be written under
/// `stem`: the directory is created if missing and a probe file is created
/// and removed in it. An unwritable place is then reported at once instead
/// of after the solve.
///
/// ```
/// use hasse_solver::frontend::output::check_writable;
/// let dir = std::env::temp_dir().join(format!("hasse-doc-probe-{}", std::process::id()));
/// assert!(check_writable(&dir.join("run")).is_ok());
/// std::fs::remove_dir_all(&dir).unwrap();
/// // Under a regular file nothing can be created.
/// let file = std::env::temp_dir().join(format!("hasse-doc-file-{}", std::process::id()));
/// std::fs::write(&file, "").unwrap();
/// assert!(check_writable(&file.join("run")).is_err());
/// std::fs::remove_file(&file).unwrap();
/// ```
pub fn check_writable(stem: &Path) -> Result<(), OutputError> {
    let dir = match stem.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| OutputError::Io { path, source }
    };
    std::fs::create_dir_all(&dir).map_err(io(&dir))?;
    let probe = dir.join(format!(".hasse-probe.tmp-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(io(&dir))?;
    std::fs::remove_file(&probe).map_err(io(&probe))
}

/// Where the output of `stem` would go, found without writing anything:
/// the directories that do not exist yet (the writer creates them, the
/// nearest existing one first).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OutputPlace {
    /// The first directory on the way to the stem's that does not exist
    /// (creating it creates the ones below too); `None` when the stem's
    /// directory exists.
    pub missing: Option<PathBuf>,
}

/// Check every path the output under `stem` can take, before anything is
/// solved and without creating anything: the stem must name files
/// (UTF-8, no `:`), the nearest existing directory on its way must be a
/// directory, `<stem>.h5` and every `<stem>[.<grid>].xdmf` must not be
/// directories (they are written to a temporary name and renamed over).
/// Whether a directory is writable is found by
/// [`check_writable`], which creates it.
///
/// ```
/// use hasse_solver::frontend::output::check_place;
/// let dir = std::env::temp_dir().join(format!("hasse-doc-place-{}", std::process::id()));
/// std::fs::create_dir_all(dir.join("run.h5")).unwrap();
/// // `run.h5` is a directory: the output could not be renamed into place.
/// let error = check_place(&dir.join("run")).unwrap_err();
/// assert!(error.to_string().contains("run.h5: a directory is in the way"));
/// // A stem under directories that do not exist names the first of them.
/// let place = check_place(&dir.join("a/b/run")).unwrap();
/// assert_eq!(place.missing, Some(dir.join("a")));
/// assert!(!dir.join("a").exists());
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn check_place(stem: &Path) -> Result<OutputPlace, OutputError> {
    let (dir, file_name) = split_stem(stem)?;
    let mut missing = None;
    let mut existing = dir.as_path();
    loop {
        match std::fs::metadata(existing) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) => {
                return Err(OutputError::Place {
                    path: existing.to_path_buf(),
                    reason: "a file is in the way of the output directory: Not a directory".into(),
                })
            }
            Err(_) => {
                missing = Some(existing.to_path_buf());
                match existing.parent() {
                    Some(parent) if !parent.as_os_str().is_empty() => existing = parent,
                    _ => break,
                }
            }
        }
    }
    if missing.is_some() {
        return Ok(OutputPlace { missing });
    }
    let mut files = vec![
        dir.join(format!("{file_name}.h5")),
        dir.join(format!("{file_name}.xdmf")),
    ];
    files.extend(
        levels::LOWER_GRID_NAMES
            .iter()
            .map(|grid| dir.join(format!("{file_name}.{grid}.xdmf"))),
    );
    for file in files {
        if file.is_dir() {
            return Err(OutputError::Place {
                path: file,
                reason: "a directory is in the way of this output file".into(),
            });
        }
    }
    // A file in the way of `<stem>.partial` only costs the partial output
    // of a transient run (a warning), not the run.
    Ok(OutputPlace { missing })
}

/// The directory of `stem` (`.` when it has none) and its file name, which
/// every output file name starts with.
fn split_stem(stem: &Path) -> Result<(PathBuf, String), OutputError> {
    let stem_error = |reason| OutputError::Stem {
        path: stem.to_path_buf(),
        reason,
    };
    let file_name = stem
        .file_name()
        .ok_or_else(|| stem_error("it has no file name"))?
        .to_str()
        .ok_or_else(|| stem_error("the file name is not UTF-8"))?
        .to_string();
    if file_name.contains(':') {
        // XDMF readers split "file.h5:/path" at the first ':'.
        return Err(stem_error(
            "':' in the file name breaks XDMF data references",
        ));
    }
    let dir = match stem.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((dir, file_name))
}
