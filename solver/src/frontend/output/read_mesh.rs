//! Reading a run's mesh back from its output file: the vertex coordinates
//! and the cells by their vertices (`/mesh/vertices`, `/mesh/cells/<p>`,
//! cases/OUTPUT.md) rebuilt into a [`Complex`] the way the LAR reader
//! builds one ([`hasse_complex::lar_json::LarInput::to_complex`]): top
//! cells ordered from their vertex positions, lower cells extracted, or
//! taken with the file's numbering where the file has them (the full
//! layout, or the degrees of its cochains). Vertex and top-cell ids are
//! the file's, so the saved cochains index the rebuilt complex directly.

use hasse_complex::lar_json::{LarError, LarInput};
use hasse_complex::{Complex, Vertices};
use std::path::{Path, PathBuf};

/// Why a mesh could not be read back from an output file; every variant
/// names the file and the dataset.
#[derive(Debug, thiserror::Error)]
pub enum ReadMeshError {
    /// The file or one of its datasets or attributes could not be read
    /// (missing, or of another type).
    #[error("{}: cannot read {dataset}: {message}", path.display())]
    Hdf5 {
        /// The h5 file.
        path: PathBuf,
        /// The dataset or attribute, as an HDF5 path.
        dataset: String,
        /// The library's message.
        message: String,
    },
    /// A dataset holds something the layout does not allow.
    #[error("{}: {dataset} {message}", path.display())]
    Layout {
        /// The h5 file.
        path: PathBuf,
        /// The dataset.
        dataset: String,
        /// What is wrong with it.
        message: String,
    },
    /// The cells do not make a complex.
    #[error("{}: the cells of {dataset} do not make a complex: {source}", path.display())]
    Complex {
        /// The h5 file.
        path: PathBuf,
        /// The top cells' dataset.
        dataset: String,
        /// Why.
        #[source]
        source: LarError,
    },
}

/// The complex stored in the mesh group `mesh` (`"mesh"` for a run on one
/// mesh, `"steps/<k>/mesh"` for level k of a series whose mesh changes)
/// of the output file `h5`.
///
/// ```
/// use hasse_solver::frontend::output::read_mesh::read_mesh;
/// use hasse_solver::frontend::output::{write_run, Provenance, RunOutput};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let k = hasse_complex::generate::rectangle(2, 1, [0.0, 2.0], [0.0, 1.0])?;
/// let run = RunOutput { complex: &k, steps: vec![], provenance: Provenance::new(serde_json::Value::Null) };
/// let dir = std::env::temp_dir().join(format!("hasse-doc-read-mesh-{}", std::process::id()));
/// let files = write_run(&dir.join("run"), &run)?;
/// let back = read_mesh(&files.hdf5, "mesh")?;
/// assert_eq!(back.cell_counts(), vec![6, 7, 2]);
/// assert_eq!(back.cell_vertices(2, 1), k.cell_vertices(2, 1));
/// // A run on one mesh has no mesh per level: the error names the group.
/// let Err(missing) = read_mesh(&files.hdf5, "steps/0/mesh") else { panic!("read a missing mesh") };
/// assert!(missing.to_string().contains("/steps/0/mesh"));
/// std::fs::remove_dir_all(&dir)?;
/// # Ok(())
/// # }
/// ```
pub fn read_mesh(h5: &Path, mesh: &str) -> Result<Complex, ReadMeshError> {
    let hdf5_error = |dataset: &str| {
        let dataset = format!("/{mesh}{dataset}");
        move |e: hdf5::Error| ReadMeshError::Hdf5 {
            path: h5.to_path_buf(),
            dataset,
            message: e.to_string(),
        }
    };
    let layout = |dataset: String, message: String| ReadMeshError::Layout {
        path: h5.to_path_buf(),
        dataset,
        message,
    };
    let file = hdf5::File::open(h5).map_err(hdf5_error(""))?;
    let group = file.group(mesh).map_err(hdf5_error(""))?;
    let attr = |name: &str| -> Result<usize, ReadMeshError> {
        let value: u64 = group
            .attr(name)
            .and_then(|a| a.read_scalar())
            .map_err(hdf5_error(&format!(" attribute {name}")))?;
        Ok(value as usize)
    };
    let (n, d) = (attr("dim")?, attr("embedding_dim")?);
    let dataset = format!("/{mesh}/vertices");
    let padded = group.dataset("vertices").map_err(hdf5_error("/vertices"))?;
    let shape = padded.shape();
    if shape.len() != 2 || shape[1] != 3 || !(1..=3).contains(&d) || n > d || n == 0 {
        return Err(layout(
            dataset,
            format!("has the shape {shape:?} in a mesh of dimension {n} in R^{d}; the layout is (vertices, 3) with 1 ≤ n ≤ d ≤ 3"),
        ));
    }
    let padded: Vec<f64> = padded.read_raw().map_err(hdf5_error("/vertices"))?;
    // Stored zero-padded to three coordinates.
    let coords: Vec<f64> = padded.chunks(3).flat_map(|p| p[..d].to_vec()).collect();
    let vertex_count = coords.len() / d;
    let vertices = Vertices::new(d, coords).map_err(|e| layout(dataset, e.to_string()))?;
    let mut cells: [Option<Vec<Vec<usize>>>; 3] = [None, None, None];
    for p in 1..=n {
        let name = format!("cells/{p}");
        // Lower degrees are in the file only for the full layout or a
        // cochain on them; the top cells always are.
        if p < n && !group.link_exists(&name) {
            continue;
        }
        cells[p - 1] = Some(
            read_cells(&group, &name, vertex_count).map_err(|e| match e {
                CellsError::Hdf5(e) => hdf5_error(&format!("/{name}"))(e),
                CellsError::Layout(message) => layout(format!("/{mesh}/{name}"), message),
            })?,
        );
    }
    LarInput { vertices, cells }
        .to_complex()
        .map_err(|source| ReadMeshError::Complex {
            path: h5.to_path_buf(),
            dataset: format!("/{mesh}/cells/{n}"),
            source,
        })
}

enum CellsError {
    Hdf5(hdf5::Error),
    Layout(String),
}

/// The rows of a CSR characteristic matrix `name` (`indptr`, `indices`):
/// each cell's vertex list.
fn read_cells(
    group: &hdf5::Group,
    name: &str,
    vertex_count: usize,
) -> Result<Vec<Vec<usize>>, CellsError> {
    let g = group.group(name).map_err(CellsError::Hdf5)?;
    let read = |part: &str| -> Result<Vec<u64>, CellsError> {
        g.dataset(part)
            .and_then(|d| d.read_raw())
            .map_err(CellsError::Hdf5)
    };
    let indptr = read("indptr")?;
    let indices = read("indices")?;
    if indptr.first() != Some(&0)
        || indptr.last().map(|&e| e as usize) != Some(indices.len())
        || indptr.windows(2).any(|w| w[0] >= w[1])
    {
        return Err(CellsError::Layout(format!(
            "has an indptr that does not rise from 0 to the {} indices in steps of at least 1",
            indices.len()
        )));
    }
    if let Some(&v) = indices.iter().find(|&&v| v as usize >= vertex_count) {
        return Err(CellsError::Layout(format!(
            "names vertex {v}, the mesh has {vertex_count}"
        )));
    }
    Ok(indptr
        .windows(2)
        .map(|w| {
            indices[w[0] as usize..w[1] as usize]
                .iter()
                .map(|&v| v as usize)
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontend::output::{write_run_with, ComplexLayout, Provenance, RunOutput};
    use hasse_complex::generate;

    type Outcome = Result<(), Box<dyn std::error::Error>>;

    /// Every p-cell of `back` (top cells, and every degree with the full
    /// layout: the minimal one numbers the lower cells by extraction) has
    /// the vertex list of `k`'s p-cell of the same id, and the coordinates
    /// are the same bits: the round trip keeps the numbering the saved
    /// cochains index.
    fn same_complex(k: &Complex, back: &Complex, layout: ComplexLayout) {
        assert_eq!(back.cell_counts(), k.cell_counts());
        assert_eq!(back.vertices().as_slice(), k.vertices().as_slice());
        let lowest = match layout {
            ComplexLayout::Full => 1,
            ComplexLayout::Minimal => k.dim(),
        };
        for p in lowest..=k.dim() {
            for c in 0..k.cell_count(p) {
                assert_eq!(
                    back.cell_vertices(p, c),
                    k.cell_vertices(p, c),
                    "{p}-cell {c}"
                );
            }
        }
    }

    fn round_trip(
        k: &Complex,
        layout: ComplexLayout,
        name: &str,
    ) -> Result<Complex, Box<dyn std::error::Error>> {
        let dir =
            std::env::temp_dir().join(format!("hasse-read-mesh-{}-{name}", std::process::id()));
        let run = RunOutput {
            complex: k,
            steps: vec![],
            provenance: Provenance::new(serde_json::Value::Null),
        };
        let files = write_run_with(&dir.join("run"), &run, layout)?;
        let back = read_mesh(&files.hdf5, "mesh");
        std::fs::remove_dir_all(&dir)?;
        Ok(back?)
    }

    #[test]
    fn meshes_come_back_with_their_numbering() -> Outcome {
        // Quads (polygons ordered from positions), Kuhn triangles,
        // hexahedra (polyhedra from positions) and tetrahedra, in both
        // layouts (the full one also gives every lower degree's ids).
        let axis = generate::uniform_axis;
        let (quads, _) =
            hasse_complex::refine::uniform(&generate::rectangle(3, 2, [0.0, 3.0], [0.0, 1.0])?)?;
        let meshes = [
            generate::interval(4, 0.0, 1.0)?,
            quads,
            generate::kuhn(&[axis(3, 0.0, 1.0)?, axis(2, 0.0, 1.0)?])?,
            generate::voronoi(12, [0.0, 1.0], [0.0, 1.0], 3, 0)?,
            generate::grid(&[axis(2, 0.0, 1.0)?, axis(2, 0.0, 1.0)?, axis(1, 0.0, 0.5)?])?,
            generate::kuhn(&[axis(2, 0.0, 1.0)?, axis(1, 0.0, 1.0)?, axis(1, 0.0, 1.0)?])?,
        ];
        for (i, k) in meshes.iter().enumerate() {
            for layout in ComplexLayout::ALL {
                let back = round_trip(k, layout, &format!("{i}-{}", layout.name()))?;
                same_complex(k, &back, layout);
            }
        }
        Ok(())
    }

    #[test]
    fn a_file_without_a_mesh_is_named_with_its_dataset() -> Outcome {
        let path =
            std::env::temp_dir().join(format!("hasse-read-mesh-none-{}.h5", std::process::id()));
        hdf5::File::create(&path)?.create_group("mesh")?;
        let error = read_mesh(&path, "mesh");
        std::fs::remove_file(&path)?;
        let Err(e) = error else {
            return Err("a mesh group without attributes was read".into());
        };
        let text = e.to_string();
        assert!(
            text.contains(&path.display().to_string()) && text.contains("/mesh attribute dim"),
            "{text}"
        );
        Ok(())
    }
}
