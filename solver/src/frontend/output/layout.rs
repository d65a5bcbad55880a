//! How much of the complex an output file stores (`[output] complex`),
//! and the reader of the boundary matrices that only the full layout has.

use super::OutputError;
use hdf5::types::VarLenUnicode;
use sprs::CsMat;
use std::path::Path;

/// How much of the complex goes into the h5 file, recorded in the mesh
/// group's attribute `complex` (`/mesh`, or `/steps/<k>/mesh`).
///
/// The boundary matrices are the largest part of a big output (at 10⁶
/// hexahedra ∂₁, ∂₂, ∂₃ hold 24·10⁶ entries) and any reader that has the
/// case file can rebuild them, so they are written only when asked for.
///
/// ```
/// use hasse_solver::frontend::output::ComplexLayout;
/// assert_eq!(ComplexLayout::default(), ComplexLayout::Minimal);
/// assert_eq!(ComplexLayout::parse("full"), Some(ComplexLayout::Full));
/// assert_eq!(ComplexLayout::Full.name(), "full");
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ComplexLayout {
    /// The vertices, the characteristic matrices M_p of the top cells and
    /// of every degree that carries a cochain (the cells the fields and
    /// the XDMF grids live on), the tags.
    #[default]
    Minimal,
    /// Besides: M_p of every dimension p = 0..=n and every signed ∂_p,
    /// p = 1..=n (`/mesh/boundary/<p>`).
    Full,
}

impl ComplexLayout {
    /// Every layout, in the order the case-file reader lists them.
    pub const ALL: [ComplexLayout; 2] = [ComplexLayout::Minimal, ComplexLayout::Full];

    /// The name in the case file and in the `complex` attribute.
    pub fn name(&self) -> &'static str {
        match self {
            ComplexLayout::Minimal => "minimal",
            ComplexLayout::Full => "full",
        }
    }

    /// The layout called `name`, if any.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|l| l.name() == name)
    }
}

/// Read the signed boundary matrix ∂_p (rows (p−1)-cells, columns p-cells)
/// of the mesh group `mesh` (`"mesh"`, or `"steps/<k>/mesh"` in a series)
/// of the output file `h5`.
///
/// A file written with the minimal layout has no boundary matrices: it is
/// refused with [`OutputError::Layout`], whose message says to rerun with
/// `[output] complex = "full"`, rather than read as if empty.
///
/// ```
/// use hasse_solver::frontend::output::{read_boundary, write_run_with, ComplexLayout, Provenance, RunOutput};
/// let k = hasse_complex::generate::rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let run = RunOutput { complex: &k, steps: vec![], provenance: Provenance::new(serde_json::Value::Null) };
/// let dir = std::env::temp_dir().join(format!("hasse-doc-boundary-{}", std::process::id()));
/// let files = write_run_with(&dir.join("full"), &run, ComplexLayout::Full).unwrap();
/// let d2 = read_boundary(&files.hdf5, "mesh", 2).unwrap();
/// assert_eq!(d2.shape(), (7, 2)); // 7 edges, 2 squares
/// let files = write_run_with(&dir.join("small"), &run, ComplexLayout::Minimal).unwrap();
/// let refused = read_boundary(&files.hdf5, "mesh", 2).unwrap_err().to_string();
/// assert!(refused.contains("complex = \"full\""));
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn read_boundary(h5: &Path, mesh: &str, p: usize) -> Result<CsMat<i8>, OutputError> {
    let hdf5_error = |e: hdf5::Error| OutputError::Hdf5 {
        path: h5.to_path_buf(),
        message: e.to_string(),
    };
    let file = hdf5::File::open(h5).map_err(hdf5_error)?;
    let group = file.group(mesh).map_err(hdf5_error)?;
    let layout = match group.attr("complex") {
        Ok(attr) => {
            let name: VarLenUnicode = attr.read_scalar().map_err(hdf5_error)?;
            ComplexLayout::parse(name.as_str()).ok_or_else(|| OutputError::Layout {
                path: h5.to_path_buf(),
                message: format!("/{mesh} has the unknown layout \"{name}\""),
            })?
        }
        // Files written before the attribute existed always held every ∂_p.
        Err(_) => ComplexLayout::Full,
    };
    if layout != ComplexLayout::Full {
        return Err(OutputError::Layout {
            path: h5.to_path_buf(),
            message: format!(
                "/{mesh} holds the {} layout, without the boundary matrices ∂_p; rerun with `[output] complex = \"full\"` to write them",
                layout.name()
            ),
        });
    }
    let g = group.group(&format!("boundary/{p}")).map_err(hdf5_error)?;
    let shape: Vec<u64> = g
        .attr("shape")
        .and_then(|a| a.read_raw())
        .map_err(hdf5_error)?;
    let read_u64 = |name: &str| -> Result<Vec<usize>, OutputError> {
        let v: Vec<u64> = g
            .dataset(name)
            .and_then(|d| d.read_raw())
            .map_err(hdf5_error)?;
        Ok(v.into_iter().map(|x| x as usize).collect())
    };
    let indptr = read_u64("indptr")?;
    let indices = read_u64("indices")?;
    let data: Vec<i8> = g
        .dataset("data")
        .and_then(|d| d.read_raw())
        .map_err(hdf5_error)?;
    let [rows, cols] = shape[..] else {
        return Err(OutputError::Layout {
            path: h5.to_path_buf(),
            message: format!("/{mesh}/boundary/{p} has the shape {shape:?}, not (rows, cols)"),
        });
    };
    CsMat::try_new((rows as usize, cols as usize), indptr, indices, data).map_err(|(_, _, _, e)| {
        OutputError::Layout {
            path: h5.to_path_buf(),
            message: format!("/{mesh}/boundary/{p} is not a CSR matrix: {e}"),
        }
    })
}
