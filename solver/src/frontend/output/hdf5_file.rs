//! The HDF5 file of a run; the layout is documented on the `output` module.

use super::topology::GridTopology;
use super::xdmf::{center, Center};
use super::{ComplexLayout, Level, Levels, MeshAt, OutputError};
use hdf5::types::VarLenUnicode;
use hdf5::{Group, H5Type, Location};
use ndarray::ArrayView2;
use sprs::CsMat;
use std::borrow::Cow;
use std::path::Path;

/// Version of the layout below `/`; bumped when a reader would need to change.
/// Version 1 is the one-mesh layout of `write_run` (with `mesh_changes` = 0).
pub(crate) const FORMAT_VERSION: u64 = 1;
/// Version 2: `write_mesh_series`, one mesh per step under `/steps/<k>/mesh`
/// (`mesh_changes` = 1), no `/mesh` and no `/xdmf`.
pub(crate) const FORMAT_VERSION_MESH_SERIES: u64 = 2;

/// Whether every large dataset is compressed (fields and coordinates
/// too), or only the integer arrays of the grid (see `write_mesh`).
const COMPRESSION: Compression = Compression::None;

/// Attach the file path to an HDF5 error.
trait At<T> {
    fn at(self, path: &Path) -> Result<T, OutputError>;
}

impl<T> At<T> for hdf5::Result<T> {
    fn at(self, path: &Path) -> Result<T, OutputError> {
        self.map_err(|e| OutputError::Hdf5 {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    }
}

/// Datasets of at least this many bytes are compressed by a writer that
/// compresses at all: below it the chunk index and filter headers cost
/// more than they save.
const DEFLATE_MIN_BYTES: usize = 1 << 20;
/// Elements per chunk of a compressed dataset (rows for a matrix are this
/// over its width): 2 MiB of u64, big enough for deflate to find the
/// repetitions of an index array, small enough to stay in HDF5's cache.
const CHUNK_ELEMENTS: usize = 1 << 18;
/// zlib level of the deflate filter: level 1 already takes the shuffled
/// index arrays to a fraction of their size; higher levels cost several
/// times the time for a few per cent more.
const DEFLATE_LEVEL: u8 = 1;

/// Whether large datasets of a writer go through shuffle + deflate.
#[derive(Clone, Copy, PartialEq)]
enum Compression {
    None,
    Large,
}

struct Writer<'p> {
    path: &'p Path,
    compression: Compression,
}

impl<'p> Writer<'p> {
    /// A writer of `path` that compresses large datasets when `compression`
    /// asks for it and the HDF5 library in use has the deflate filter (a
    /// build without zlib writes them uncompressed: same contents, no error).
    fn new(path: &'p Path, compression: Compression) -> Self {
        let compression = match compression {
            Compression::Large if hdf5::filters::deflate_available() => Compression::Large,
            _ => Compression::None,
        };
        Writer { path, compression }
    }

    /// The same file, with large datasets compressed (if the library can).
    fn compressing(&self) -> Self {
        Writer::new(self.path, Compression::Large)
    }

    fn group(&self, parent: &Group, name: &str) -> Result<Group, OutputError> {
        parent.create_group(name).at(self.path)
    }

    /// Rows per chunk for a `rows` × `columns` dataset of `T`, when it is
    /// to be compressed.
    fn chunk_rows<T>(&self, rows: usize, columns: usize) -> Option<usize> {
        let bytes = rows * columns * std::mem::size_of::<T>();
        (self.compression == Compression::Large && bytes >= DEFLATE_MIN_BYTES)
            .then(|| (CHUNK_ELEMENTS / columns.max(1)).clamp(1, rows))
    }

    fn vector<T: H5Type>(&self, g: &Group, name: &str, data: &[T]) -> Result<(), OutputError> {
        let builder = g.new_dataset_builder();
        let builder = match self.chunk_rows::<T>(data.len(), 1) {
            Some(rows) => builder.chunk(rows).shuffle().deflate(DEFLATE_LEVEL),
            None => builder,
        };
        builder
            .with_data(data)
            .create(name)
            .at(self.path)
            .map(|_| ())
    }

    fn matrix<T: H5Type>(
        &self,
        g: &Group,
        name: &str,
        data: &[T],
        columns: usize,
    ) -> Result<(), OutputError> {
        let rows = data.len().checked_div(columns).unwrap_or(0);
        let view =
            ArrayView2::from_shape((rows, columns), data).map_err(|e| OutputError::Hdf5 {
                path: self.path.to_path_buf(),
                message: format!("dataset {name}: {e}"),
            })?;
        let builder = g.new_dataset_builder();
        let builder = match self.chunk_rows::<T>(rows, columns) {
            Some(chunk) => builder
                .chunk((chunk, columns))
                .shuffle()
                .deflate(DEFLATE_LEVEL),
            None => builder,
        };
        builder
            .with_data(view)
            .create(name)
            .at(self.path)
            .map(|_| ())
    }

    fn scalar_attr<T: H5Type>(
        &self,
        loc: &Location,
        name: &str,
        value: T,
    ) -> Result<(), OutputError> {
        loc.new_attr::<T>()
            .shape(())
            .create(name)
            .and_then(|a| a.write_scalar(&value))
            .at(self.path)
    }

    fn array_attr<T: H5Type>(
        &self,
        loc: &Location,
        name: &str,
        data: &[T],
    ) -> Result<(), OutputError> {
        loc.new_attr_builder()
            .with_data(data)
            .create(name)
            .at(self.path)
            .map(|_| ())
    }

    fn text(field: &str, value: &str) -> Result<VarLenUnicode, OutputError> {
        value
            .parse::<VarLenUnicode>()
            .map_err(|e| OutputError::Text {
                field: field.to_string(),
                reason: e.to_string(),
            })
    }

    fn string_attr(&self, loc: &Location, name: &str, value: &str) -> Result<(), OutputError> {
        let s = Self::text(name, value)?;
        self.scalar_attr(loc, name, s)
    }

    /// Long text goes in datasets: attributes are limited to 64 KiB.
    fn string_dataset(&self, g: &Group, name: &str, value: &str) -> Result<(), OutputError> {
        let s = Self::text(name, value)?;
        g.new_dataset::<VarLenUnicode>()
            .shape(())
            .create(name)
            .and_then(|d| d.write_scalar(&s))
            .at(self.path)
    }

    /// A sparse matrix as CSR datasets `indptr`, `indices` (and `data`).
    fn csr<T: Copy + Default + H5Type>(
        &self,
        g: &Group,
        m: &CsMat<T>,
        with_data: bool,
    ) -> Result<(), OutputError> {
        let m: Cow<CsMat<T>> = if m.is_csr() {
            Cow::Borrowed(m)
        } else {
            Cow::Owned(m.to_csr())
        };
        let indptr: Vec<u64> = m.indptr().to_proper().iter().map(|&x| x as u64).collect();
        let indices: Vec<u64> = m.indices().iter().map(|&x| x as u64).collect();
        self.vector(g, "indptr", &indptr)?;
        self.vector(g, "indices", &indices)?;
        if with_data {
            self.vector(g, "data", m.data())?;
        }
        self.array_attr(g, "shape", &[m.rows() as u64, m.cols() as u64])
    }
}

/// Write the whole h5 file at `path` (a temporary name) and close it;
/// `grids[m]` are the XDMF grids of `levels.meshes[m]`.
pub(crate) fn write(
    path: &Path,
    levels: &Levels,
    grids: &[Vec<GridTopology>],
    written_at: &str,
) -> Result<(), OutputError> {
    let degrees: Vec<usize> = grids
        .first()
        .map(|g| g.iter().map(|grid| grid.degree).collect())
        .unwrap_or_default();
    write_while(path, levels, &degrees, || Ok(grids), written_at).map(|_| ())
}

/// [`write`], with the grids (of the cells of `degrees` on every mesh)
/// given by `grids`, called only once everything else but the provenance
/// is written: the caller builds them meanwhile. Returns them.
pub(crate) fn write_while<G: AsRef<[Vec<GridTopology>]>>(
    path: &Path,
    levels: &Levels,
    degrees: &[usize],
    grids: impl FnOnce() -> Result<G, OutputError>,
    written_at: &str,
) -> Result<G, OutputError> {
    let file = hdf5::File::create(path).at(path)?;
    let w = Writer::new(path, COMPRESSION);
    let grids = write_contents(&w, &file, levels, degrees, grids, written_at)?;
    file.flush().at(path)?;
    file.close().at(path)?;
    Ok(grids)
}

fn write_contents<G: AsRef<[Vec<GridTopology>]>>(
    w: &Writer,
    root: &Group,
    levels: &Levels,
    degrees: &[usize],
    grids: impl FnOnce() -> Result<G, OutputError>,
    written_at: &str,
) -> Result<G, OutputError> {
    let times: Vec<f64> = levels.steps.iter().map(|s| s.time).collect();
    w.string_attr(root, "format", "hasse-output")?;
    let version = if levels.mesh_changes {
        FORMAT_VERSION_MESH_SERIES
    } else {
        FORMAT_VERSION
    };
    w.scalar_attr(root, "format_version", version)?;
    w.scalar_attr(root, "step_count", levels.steps.len() as u64)?;
    w.array_attr(root, "times", &times)?;
    w.scalar_attr(root, "mesh_changes", u64::from(levels.mesh_changes))?;

    // The steps first: in a series each mesh lives inside its step's group.
    let steps = w.group(root, "steps")?;
    for (k, step) in levels.steps.iter().enumerate() {
        write_step(w, &steps, k, step)?;
    }

    for mesh in &levels.meshes {
        write_mesh(w, &w.group(root, &mesh.group)?, levels, mesh, degrees)?;
    }
    let grids = grids()?;
    for (mesh, grids) in levels.meshes.iter().zip(grids.as_ref()) {
        write_xdmf_arrays(w, &w.group(root, &mesh.xdmf_group)?, levels, mesh, grids)?;
    }

    let prov = w.group(root, "provenance")?;
    let p = levels.provenance;
    w.string_attr(&prov, "hasse_version", &p.hasse_version)?;
    w.string_attr(&prov, "written_at", written_at)?;
    if let Some(path) = &p.case_path {
        w.string_attr(&prov, "case_path", path)?;
    }
    if let Some(text) = &p.case_text {
        w.string_dataset(&prov, "case_text", text)?;
    }
    w.string_dataset(&prov, "report", &p.report.to_string())?;
    Ok(grids)
}

/// Level `k` into group `steps/<k>`: attr `time`, one dataset per cochain.
fn write_step(w: &Writer, steps: &Group, k: usize, step: &Level) -> Result<(), OutputError> {
    let g = w.group(steps, &k.to_string())?;
    w.scalar_attr(&g, "time", step.time)?;
    for c in step.cochains {
        w.vector(&g, &c.name, &c.values)?;
        let ds = g.dataset(&c.name).at(w.path)?;
        w.scalar_attr(&ds, "dim", c.dim as u64)?;
        for (key, value) in [
            ("units", &c.units),
            ("method", &c.method),
            ("description", &c.description),
        ] {
            if let Some(value) = value {
                w.string_attr(&ds, key, value)?;
            }
        }
    }
    Ok(())
}

/// Write the h5 file of one level of a partial output at `path` (a
/// temporary name): root attrs `format` = `"hasse-output-level"`,
/// `format_version`, `step` (k) and `time`, the group `/steps/<k>` as in a
/// run file, and for split cells the expanded cochains
/// `/<xdmf_group>/<p>/steps/<k>/<name>`, so the XDMF paths of a run file
/// stay valid, only the file changes. `grids` are the XDMF grids of the
/// level's mesh.
pub(crate) fn write_level(
    path: &Path,
    levels: &Levels,
    grids: &[GridTopology],
    k: usize,
    step: &Level,
) -> Result<(), OutputError> {
    let file = hdf5::File::create(path).at(path)?;
    let w = Writer::new(path, COMPRESSION);
    w.string_attr(&file, "format", "hasse-output-level")?;
    w.scalar_attr(&file, "format_version", FORMAT_VERSION)?;
    w.scalar_attr(&file, "step", k as u64)?;
    w.scalar_attr(&file, "time", step.time)?;
    write_step(&w, &w.group(&file, "steps")?, k, step)?;
    let split: Vec<(&GridTopology, &Vec<u64>)> = grids
        .iter()
        .filter_map(|g| Some((g, g.cell_ids.as_ref()?)))
        .collect();
    if !split.is_empty() {
        let xdmf = w.group(&file, &levels.meshes[step.mesh].xdmf_group)?;
        for (grid, cell_ids) in split {
            let g = w.group(&xdmf, &grid.degree.to_string())?;
            let g = w.group(&w.group(&g, "steps")?, &k.to_string())?;
            write_expanded(&w, &g, grid, cell_ids, levels.dim(), step)?;
        }
    }
    file.flush().at(path)?;
    file.close().at(path)
}

/// The cell cochains of `step` on a grid whose elements are pieces of
/// cells (`cell_ids`), one value per element, into group `g`.
fn write_expanded(
    w: &Writer,
    g: &Group,
    grid: &GridTopology,
    cell_ids: &[u64],
    n: usize,
    step: &Level,
) -> Result<(), OutputError> {
    for c in step.cochains {
        if center(grid, n, c) != Some(Center::Cell) {
            continue;
        }
        let values: Vec<f64> = cell_ids.iter().map(|&i| c.values[i as usize]).collect();
        w.vector(g, &c.name, &values)?;
    }
    Ok(())
}

/// One complex into group `mesh` (`/mesh`, or `/steps/<k>/mesh`): attrs
/// `dim`, `embedding_dim` and `complex` (the layout's name), `vertices`,
/// `cells/<p>`, `tags/<name>`; with [`ComplexLayout::Full`] `cells/<p>`
/// for every p and `boundary/<p>`, otherwise `cells/<p>` only for the top
/// cells and the degrees of the cochains and XDMF grids (`degrees`) on
/// this mesh.
fn write_mesh(
    w: &Writer,
    group: &Group,
    levels: &Levels,
    mesh: &MeshAt,
    degrees: &[usize],
) -> Result<(), OutputError> {
    let complex = mesh.complex;
    let n = complex.dim();
    let d = complex.embedding_dim();
    w.scalar_attr(group, "dim", n as u64)?;
    w.scalar_attr(group, "embedding_dim", d as u64)?;
    w.string_attr(group, "complex", levels.layout.name())?;
    let nv = complex.cell_count(0);
    let mut xyz = vec![0.0; nv * 3];
    for v in 0..nv {
        xyz[3 * v..3 * v + d].copy_from_slice(complex.vertices().point(v));
    }
    w.matrix(group, "vertices", &xyz, 3)?;
    let vertices = group.dataset("vertices").at(w.path)?;
    w.scalar_attr(&vertices, "embedding_dim", d as u64)?;

    let full = levels.layout == ComplexLayout::Full;
    let mut needed = vec![false; n + 1];
    needed[n] = true;
    for &p in degrees {
        needed[p] = true;
    }
    for &k in &mesh.steps {
        for c in levels.steps[k].cochains {
            needed[c.dim] = true;
        }
    }
    // Integer arrays of a grid (cell vertex lists, ∂_p) are compressed
    // when large: shuffled, their high bytes are runs of zeros and their
    // index pointers near-arithmetic, so deflate takes them to about 1/70
    // at 100³ hexahedra for 0.3 s (cases/OUTPUT.md). Fields and
    // coordinates are not: f64 values deflate poorly for the same time.
    let extra = w.compressing();
    let cells = w.group(group, "cells")?;
    for (p, &needed) in needed.iter().enumerate() {
        if !needed && !full {
            continue;
        }
        let w = &extra;
        let g = w.group(&cells, &p.to_string())?;
        if p == 0 {
            let identity = CsMat::new(
                (nv, nv),
                (0..=nv).collect(),
                (0..nv).collect(),
                vec![1u8; nv],
            );
            w.csr(&g, &identity, false)?;
            continue;
        }
        let m = complex
            .lar()
            .characteristic(p)
            .map_err(|e| OutputError::Topology {
                message: e.to_string(),
            })?;
        w.csr(&g, m, false)?;
    }
    if full {
        let boundary = w.group(group, "boundary")?;
        for p in 1..=n {
            extra.csr(
                &w.group(&boundary, &p.to_string())?,
                complex.boundary(p),
                true,
            )?;
        }
    }
    let tags = w.group(group, "tags")?;
    for (name, tag) in complex.tags().iter() {
        let ids: Vec<u64> = tag.cells.iter().map(|&c| c as u64).collect();
        w.vector(&tags, name, &ids)?;
        let ds = tags.dataset(name).at(w.path)?;
        w.scalar_attr(&ds, "dim", tag.dim as u64)?;
    }
    Ok(())
}

/// The XDMF arrays of one mesh into group `xdmf` (`/xdmf`, or
/// `/steps/<k>/mesh/xdmf`): `<p>/topology`, and for split cells
/// `<p>/cell_ids` with the expanded cochains `<p>/steps/<k>/<name>` of the
/// levels on this mesh.
fn write_xdmf_arrays(
    w: &Writer,
    xdmf: &Group,
    levels: &Levels,
    mesh: &MeshAt,
    grids: &[GridTopology],
) -> Result<(), OutputError> {
    let n = levels.dim();
    // Connectivity compresses as the vertex lists of `cells` do.
    let ints = w.compressing();
    for grid in grids {
        let g = w.group(xdmf, &grid.degree.to_string())?;
        match grid.uniform {
            Some((_, nodes)) => ints.matrix(&g, "topology", &grid.connectivity, nodes)?,
            None => ints.vector(&g, "topology", &grid.connectivity)?,
        }
        let Some(cell_ids) = &grid.cell_ids else {
            continue;
        };
        ints.vector(&g, "cell_ids", cell_ids)?;
        let expanded = w.group(&g, "steps")?;
        for &k in &mesh.steps {
            let sg = w.group(&expanded, &k.to_string())?;
            write_expanded(w, &sg, grid, cell_ids, n, &levels.steps[k])?;
        }
    }
    Ok(())
}
