//! Data given per region: one value for each named tag of top cells, and
//! an optional default for the cells in none of them.
//!
//! A region is a tag of top cells (a Gmsh physical group of the mesh's
//! dimension, or a tag a case defines by a condition on the centroid). The
//! data are resolved on each complex a problem is solved on, so a SPLIT
//! refinement, which carries tags to the children of a cell, keeps every
//! child in its parent's region.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::physics::regions::{Regional, RegionError};
//! let mut mesh = rectangle(4, 1, [0.0, 4.0], [0.0, 1.0]).unwrap();
//! mesh.set_tag("steel", 2, vec![0, 1]).unwrap();
//! mesh.set_tag("copper", 2, vec![2]).unwrap();
//! let k = Regional::new(vec![("steel".into(), 1.0), ("copper".into(), 20.0)], Some(5.0));
//! let per_cell: Vec<f64> = k.per_cell(&mesh).unwrap().into_iter().copied().collect();
//! assert_eq!(per_cell, [1.0, 1.0, 20.0, 5.0]);
//! // Without the default, cell 3 has no value: refused, with the tags
//! // of top cells the mesh has.
//! let strict = Regional::new(vec![("steel".into(), 1.0), ("copper".into(), 20.0)], None);
//! let e = strict.per_cell(&mesh).unwrap_err();
//! assert!(matches!(e, RegionError::Uncovered { cell: 3, .. }));
//! assert!(e.to_string().contains("copper, steel"));
//! ```

use hasse_complex::Complex;

/// A value per region, and the value of cells in no listed region.
#[derive(Clone, Debug, PartialEq)]
pub struct Regional<T> {
    pieces: Vec<(String, T)>,
    default: Option<T>,
}

/// Why data per region do not fit a complex.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RegionError {
    /// A listed region is not a tag of the mesh.
    #[error("no tag `{name}` in the mesh; its tags of top cells: {}", list(.available))]
    UnknownTag {
        /// The region's name.
        name: String,
        /// The tags of top cells the mesh has.
        available: Vec<String>,
    },
    /// A listed region is a tag of lower-dimensional cells.
    #[error("tag `{name}` names {dim}-cells, but data per region need a tag of top cells ({top}-cells); its tags of top cells: {}", list(.available))]
    NotTopCells {
        /// The region's name.
        name: String,
        /// Dimension of the tag's cells.
        dim: usize,
        /// Dimension of the top cells.
        top: usize,
        /// The tags of top cells the mesh has.
        available: Vec<String>,
    },
    /// A top cell is in no listed region and there is no default.
    #[error("top cell {cell} (centroid {}) is in none of the regions {} and there is no `default`; the mesh's tags of top cells: {}", point_text(.point), list(.listed), list(.available))]
    Uncovered {
        /// The first such cell.
        cell: usize,
        /// Its centroid.
        point: Vec<f64>,
        /// The regions given.
        listed: Vec<String>,
        /// The tags of top cells the mesh has.
        available: Vec<String>,
    },
    /// A top cell is in two listed regions, which give it two values.
    #[error("top cell {cell} (centroid {}) is in both `{first}` and `{second}`, which give it different data; list regions that do not overlap", point_text(.point))]
    Overlap {
        /// The first such cell.
        cell: usize,
        /// Its centroid.
        point: Vec<f64>,
        /// The region listed first.
        first: String,
        /// The other one.
        second: String,
    },
}

fn list(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

fn point_text(point: &[f64]) -> String {
    let parts: Vec<String> = point.iter().map(|v| format!("{v:.6}")).collect();
    format!("({})", parts.join(", "))
}

/// The names of the tags of top cells of `complex`, sorted.
pub fn top_cell_tags(complex: &Complex) -> Vec<String> {
    let n = complex.dim();
    let mut names: Vec<String> = complex
        .tags()
        .iter()
        .filter(|(_, t)| t.dim == n)
        .map(|(name, _)| name.to_string())
        .collect();
    names.sort();
    names
}

impl<T> Regional<T> {
    /// Values per region name, and the default for every other cell.
    pub fn new(pieces: Vec<(String, T)>, default: Option<T>) -> Self {
        Self { pieces, default }
    }

    /// The regions and their values, in the order given.
    pub fn pieces(&self) -> &[(String, T)] {
        &self.pieces
    }

    /// The value of cells in no listed region.
    pub fn default(&self) -> Option<&T> {
        self.default.as_ref()
    }

    /// The same regions with every value mapped.
    pub fn map<U>(&self, mut f: impl FnMut(&T) -> U) -> Regional<U> {
        Regional {
            pieces: self.pieces.iter().map(|(n, v)| (n.clone(), f(v))).collect(),
            default: self.default.as_ref().map(f),
        }
    }

    /// The value of every top cell of `complex`, in cell order; refused
    /// when a region is not a tag of top cells, a cell is in none and
    /// there is no default, or a cell is in two regions.
    pub fn per_cell(&self, complex: &Complex) -> Result<Vec<&T>, RegionError> {
        Ok(self
            .piece_per_cell(complex)?
            .into_iter()
            .map(|i| self.piece(i))
            .collect())
    }

    /// The value of piece `i` of [`Regional::piece_per_cell`]: the i-th
    /// region's, or the default for i = the number of regions.
    pub fn piece(&self, i: usize) -> &T {
        match self.pieces.get(i) {
            Some((_, v)) => v,
            None => self
                .default
                .as_ref()
                .expect("only covered cells get the default's index"),
        }
    }

    /// For every top cell, the index of its region among
    /// [`Regional::pieces`], or the number of regions for the default;
    /// refused as [`Regional::per_cell`] says.
    pub fn piece_per_cell(&self, complex: &Complex) -> Result<Vec<usize>, RegionError> {
        let n = complex.dim();
        let cells = complex.cell_count(n);
        let available = || top_cell_tags(complex);
        let mut owner: Vec<Option<usize>> = vec![None; cells];
        for (i, (name, _)) in self.pieces.iter().enumerate() {
            let tag = complex.tag(name).ok_or_else(|| RegionError::UnknownTag {
                name: name.clone(),
                available: available(),
            })?;
            if tag.dim != n {
                return Err(RegionError::NotTopCells {
                    name: name.clone(),
                    dim: tag.dim,
                    top: n,
                    available: available(),
                });
            }
            for &c in &tag.cells {
                if let Some(j) = owner[c] {
                    return Err(RegionError::Overlap {
                        cell: c,
                        point: complex.centroid_of(n, c).to_vec(),
                        first: self.pieces[j].0.clone(),
                        second: name.clone(),
                    });
                }
                owner[c] = Some(i);
            }
        }
        owner
            .iter()
            .enumerate()
            .map(|(c, o)| match (o, &self.default) {
                (Some(i), _) => Ok(*i),
                (None, Some(_)) => Ok(self.pieces.len()),
                (None, None) => Err(RegionError::Uncovered {
                    cell: c,
                    point: complex.centroid_of(n, c).to_vec(),
                    listed: self.pieces.iter().map(|(n, _)| n.clone()).collect(),
                    available: available(),
                }),
            })
            .collect()
    }
}
