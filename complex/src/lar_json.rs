//! The LAR paper's own file representation of a complex: a JSON object
//! with the vertex coordinates `"V"` and the cells of each dimension as
//! unordered vertex lists, `"EV"` (edges), `"FV"` (2-cells) and `"CV"`
//! (3-cells), exactly the rows of the characteristic matrices M_1, M_2, M_3.
//!
//! ```text
//! {"V": [[0, 0], [1, 0], [0, 1], [1, 1]],
//!  "FV": [[0, 1, 2], [1, 2, 3]]}
//! ```
//!
//! The highest key present gives the dimension n of the complex; only the
//! top cells are required. Lower cells that are not given are extracted
//! (the facets of the top cells); lower cells that are given must be
//! exactly those facets, and then keep the file's numbering. Vertex lists
//! may come in any order: a top cell with p + 1 vertices is a simplex, any
//! other 2-cell a convex polygon and any other 3-cell a convex polyhedron,
//! both ordered from the vertex positions. A non-convex 2-cell (a simple
//! polygon) cannot be ordered from its vertices alone: it is read when
//! `EV` is given and its edges there form one cycle through its vertices.
//! A 1-complex is a file with `V`
//! and `EV` only.
//!
//! Written back by [`to_lar_json`] with every dimension listed and vertex
//! lists sorted; reading that text gives the same cells, numbering and
//! coordinates (numbers are written in the shortest form that reads back to
//! the same `f64`).
//!
//! ```
//! use hasse_complex::lar_json;
//! let text = r#"{"V": [[0, 0], [1, 0], [0, 1], [1, 1]], "FV": [[2, 1, 0], [1, 2, 3]]}"#;
//! let k = lar_json::from_str(text).unwrap();
//! assert_eq!(k.cell_counts(), vec![4, 5, 2]);
//! let again = lar_json::from_str(&lar_json::to_lar_json(&k)).unwrap();
//! assert_eq!(again.lar(), k.lar());
//! ```

use crate::cells::{extract_facets, Vertices};
use crate::complex::Complex;
use crate::convex_order::{top_cells, OrderError};
use crate::error::ComplexError;
use crate::lar::Lar;
use serde_json::Value;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The cell keys, one per dimension p = 1, 2, 3.
pub const CELL_KEYS: [&str; 3] = ["EV", "FV", "CV"];

/// What is wrong with the content of a LAR file. Each variant names the key
/// and, where there is one, the cell (0-based position in its list).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LarError {
    #[error("not valid JSON: {message}")]
    Syntax {
        line: usize,
        column: usize,
        message: String,
    },
    #[error("the top level must be an object {{\"V\": [...], \"FV\": [...], ...}}")]
    NotAnObject,
    #[error("unknown key \"{0}\": the keys are V, EV, FV and CV")]
    UnknownKey(String),
    #[error("the key \"V\" (vertex coordinates) is missing")]
    MissingVertices,
    #[error("no cells: give at least one of EV, FV, CV")]
    NoCells,
    #[error("\"{key}\" must be an array of {what}")]
    NotAnArray {
        key: &'static str,
        what: &'static str,
    },
    #[error("\"V\" is empty: a complex needs at least one vertex")]
    NoVertices,
    #[error("\"V\"[{vertex}] must be an array of 1 to 3 numbers")]
    BadPoint { vertex: usize },
    #[error("\"V\"[{vertex}] has {found} coordinates but \"V\"[0] has {expected}: all points need the same dimension")]
    CoordinateDimension {
        vertex: usize,
        expected: usize,
        found: usize,
    },
    #[error("\"V\"[{vertex}][{axis}] is {value}, not a finite number")]
    NonFiniteCoordinate {
        vertex: usize,
        axis: usize,
        value: String,
    },
    #[error("\"{key}\" lists no cells")]
    EmptyCells { key: &'static str },
    #[error("\"{key}\"[{cell}] must be an array of vertex indices")]
    CellNotAnArray { key: &'static str, cell: usize },
    #[error(
        "\"{key}\"[{cell}] holds {value}, which is not a vertex index (a non-negative integer)"
    )]
    NonIntegerIndex {
        key: &'static str,
        cell: usize,
        value: String,
    },
    #[error("\"{key}\"[{cell}] refers to vertex {vertex}, but \"V\" has {vertex_count} vertices (indices start at 0)")]
    IndexOutOfRange {
        key: &'static str,
        cell: usize,
        vertex: usize,
        vertex_count: usize,
    },
    #[error("\"{key}\"[{cell}] lists vertex {vertex} more than once")]
    RepeatedVertex {
        key: &'static str,
        cell: usize,
        vertex: usize,
    },
    #[error("\"{key}\"[{cell}] has {found} vertices; a {p}-cell needs {needed}")]
    TooFewVertices {
        key: &'static str,
        cell: usize,
        p: usize,
        found: usize,
        needed: &'static str,
    },
    #[error(
        "\"{key}\" holds {p}-cells, which do not fit in R^{embedding_dim} (the points of \"V\")"
    )]
    DimensionTooHigh {
        key: &'static str,
        p: usize,
        embedding_dim: usize,
    },
    #[error("\"{key}\"[{cell}] has zero measure: its vertices span too few dimensions")]
    Degenerate { key: &'static str, cell: usize },
    #[error("\"{key}\"[{cell}] is not planar: vertex {vertex} is off the plane of the others")]
    NotPlanar {
        key: &'static str,
        cell: usize,
        vertex: usize,
    },
    #[error("\"{key}\"[{cell}] is not convex: vertex {vertex} lies inside the convex hull of the others (a cell given by its unordered vertex list must be convex, or, for a 2-cell, have its boundary cycle among the edges of a given EV)")]
    NotConvex {
        key: &'static str,
        cell: usize,
        vertex: usize,
    },
    #[error("\"{key}\"[{cell}] repeats \"{key}\"[{first}] (the same vertex set)")]
    DuplicateCell {
        key: &'static str,
        cell: usize,
        first: usize,
    },
    #[error("\"{key}\"[{cell}] (vertices {vertices:?}) is not a face of any cell of \"{upper}\": a given {key} must be exactly the facets of {upper}")]
    NotAFacet {
        key: &'static str,
        cell: usize,
        vertices: Vec<usize>,
        upper: &'static str,
    },
    #[error("\"{key}\" lacks {vertices:?}, a face of \"{upper}\"[{upper_cell}]: a given {key} must list every facet of {upper}")]
    MissingFacet {
        key: &'static str,
        vertices: Vec<usize>,
        upper: &'static str,
        upper_cell: usize,
    },
    #[error("\"{key}\" is missing: the unoriented LAR of a complex with \"{top}\" lists every lower dimension too")]
    MissingLevel {
        key: &'static str,
        top: &'static str,
    },
    #[error("{0}")]
    Complex(#[from] ComplexError),
}

/// Why a LAR file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum LarFileError {
    #[error("cannot read '{}': {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("'{}' is not valid JSON: {message} at line {line}, column {column}", path.display())]
    Syntax {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("'{}' is not a valid LAR file: {source}", path.display())]
    Invalid {
        path: PathBuf,
        #[source]
        source: LarError,
    },
}

/// The content of a LAR file, checked (indices, vertex counts,
/// coordinates) but not yet oriented: `cells[p-1]` are the given p-cells.
#[derive(Clone, Debug, PartialEq)]
pub struct LarInput {
    pub vertices: Vertices,
    pub cells: [Option<Vec<Vec<usize>>>; 3],
}

impl LarInput {
    /// Dimension of the top cells (the highest key given).
    pub fn dim(&self) -> usize {
        self.cells
            .iter()
            .rposition(Option::is_some)
            .map_or(0, |k| k + 1)
    }

    /// The given levels as a [`Lar`] (no orientation, no convexity needed:
    /// this is the paper's unoriented representation). Every level 1..n must
    /// be given; the error names the first missing key.
    pub fn to_lar(&self) -> Result<Lar, LarError> {
        let levels = (0..self.dim())
            .map(|k| {
                self.cells[k].clone().ok_or(LarError::MissingLevel {
                    key: CELL_KEYS[k],
                    top: CELL_KEYS[self.dim() - 1],
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Lar::from_vertex_sets(self.vertices.clone(), levels)?)
    }

    /// The oriented complex: top cells ordered from their vertex positions,
    /// lower cells extracted and, where given, checked against the
    /// extraction (and then numbered as given).
    pub fn to_complex(&self) -> Result<Complex, LarError> {
        let n = self.dim();
        let d = self.vertices.dim();
        if n > d {
            return Err(LarError::DimensionTooHigh {
                key: CELL_KEYS[n - 1],
                p: n,
                embedding_dim: d,
            });
        }
        let top = self.cells[n - 1].as_deref().unwrap_or_default();
        let key = CELL_KEYS[n - 1];
        let mut seen: HashMap<Vec<usize>, usize> = HashMap::new();
        for (cell, vertices) in top.iter().enumerate() {
            if let Some(&first) = seen.get(&sorted(vertices)) {
                return Err(LarError::DuplicateCell { key, cell, first });
            }
            seen.insert(sorted(vertices), cell);
        }
        let cells = top_cells(&self.vertices, n, top, self.cells[0].as_deref()).map_err(
            |(cell, e)| match e {
                OrderError::Degenerate => LarError::Degenerate { key, cell },
                OrderError::NotPlanar { vertex } => LarError::NotPlanar { key, cell, vertex },
                OrderError::NotConvex { vertex } => LarError::NotConvex { key, cell, vertex },
            },
        )?;
        // The facets of every level, as the complex will number them; each
        // given level is compared with them.
        let mut extracted: Vec<Vec<Vec<usize>>> = vec![Vec::new(); n];
        extracted[n - 1] = top.iter().map(|c| sorted(c)).collect();
        let mut current = cells.clone();
        for p in (1..n).rev() {
            let level = extract_facets(&current, p > 1);
            extracted[p - 1] = (0..level.sets.len())
                .map(|i| {
                    level.sets.vertices[level.sets.offsets[i]..level.sets.offsets[i + 1]]
                        .iter()
                        .map(|&v| v as usize)
                        .collect()
                })
                .collect();
            current = level.cells;
        }
        for p in 1..n {
            if let Some(given) = &self.cells[p - 1] {
                extracted[p - 1] = self.check_facets(p, given, &extracted[p - 1], &extracted[p])?;
            }
        }
        let lar = Lar::from_vertex_sets(self.vertices.clone(), extracted)?;
        Complex::from_lar(lar).map_err(|e| match e {
            // Named by the key of the file rather than by dimension.
            ComplexError::DegenerateCell { dim, cell, .. } if dim == n => {
                LarError::Degenerate { key, cell }
            }
            other => other.into(),
        })
    }

    /// The given p-cells, sorted, when they are exactly the `expected`
    /// facets of the `upper` (p+1)-cells.
    fn check_facets(
        &self,
        p: usize,
        given: &[Vec<usize>],
        expected: &[Vec<usize>],
        upper: &[Vec<usize>],
    ) -> Result<Vec<Vec<usize>>, LarError> {
        let (key, upper_key) = (CELL_KEYS[p - 1], CELL_KEYS[p]);
        let wanted: HashMap<&[usize], usize> = expected
            .iter()
            .enumerate()
            .map(|(i, c)| (c.as_slice(), i))
            .collect();
        let mut seen: HashMap<Vec<usize>, usize> = HashMap::new();
        let mut out = Vec::with_capacity(given.len());
        for (cell, vertices) in given.iter().enumerate() {
            let set = sorted(vertices);
            if let Some(&first) = seen.get(&set) {
                return Err(LarError::DuplicateCell { key, cell, first });
            }
            if !wanted.contains_key(set.as_slice()) {
                return Err(LarError::NotAFacet {
                    key,
                    cell,
                    vertices: vertices.clone(),
                    upper: upper_key,
                });
            }
            seen.insert(set.clone(), cell);
            out.push(set);
        }
        if let Some(missing) = expected.iter().find(|c| !seen.contains_key(*c)) {
            let upper_cell = upper
                .iter()
                .position(|u| missing.iter().all(|v| u.binary_search(v).is_ok()))
                .unwrap_or(0);
            return Err(LarError::MissingFacet {
                key,
                vertices: missing.clone(),
                upper: upper_key,
                upper_cell,
            });
        }
        Ok(out)
    }
}

fn sorted(cell: &[usize]) -> Vec<usize> {
    let mut set = cell.to_vec();
    set.sort_unstable();
    set
}

/// Check the JSON value of a LAR file.
pub fn parse_value(value: &Value) -> Result<LarInput, LarError> {
    let Value::Object(doc) = value else {
        return Err(LarError::NotAnObject);
    };
    if let Some(key) = doc
        .keys()
        .find(|k| k.as_str() != "V" && !CELL_KEYS.contains(&k.as_str()))
    {
        return Err(LarError::UnknownKey(key.clone()));
    }
    let points = doc.get("V").ok_or(LarError::MissingVertices)?;
    let Value::Array(points) = points else {
        return Err(LarError::NotAnArray {
            key: "V",
            what: "points [x, y, ...]",
        });
    };
    let first = points.first().ok_or(LarError::NoVertices)?;
    let d = match first.as_array().map(Vec::len) {
        Some(d @ 1..=3) => d,
        _ => return Err(LarError::BadPoint { vertex: 0 }),
    };
    let mut coords = Vec::with_capacity(points.len() * d);
    for (vertex, point) in points.iter().enumerate() {
        let Value::Array(xs) = point else {
            return Err(LarError::BadPoint { vertex });
        };
        if xs.len() != d {
            return Err(LarError::CoordinateDimension {
                vertex,
                expected: d,
                found: xs.len(),
            });
        }
        for (axis, x) in xs.iter().enumerate() {
            match x.as_f64() {
                Some(value) if value.is_finite() => coords.push(value),
                _ => {
                    return Err(LarError::NonFiniteCoordinate {
                        vertex,
                        axis,
                        value: x.to_string(),
                    })
                }
            }
        }
    }
    let vertex_count = points.len();
    let vertices = Vertices::new(d, coords)?;
    let mut cells: [Option<Vec<Vec<usize>>>; 3] = [None, None, None];
    for (k, key) in CELL_KEYS.iter().enumerate() {
        if let Some(list) = doc.get(*key) {
            cells[k] = Some(parse_cells(key, k + 1, list, vertex_count)?);
        }
    }
    if cells.iter().all(Option::is_none) {
        return Err(LarError::NoCells);
    }
    Ok(LarInput { vertices, cells })
}

fn parse_cells(
    key: &'static str,
    p: usize,
    list: &Value,
    vertex_count: usize,
) -> Result<Vec<Vec<usize>>, LarError> {
    let Value::Array(list) = list else {
        return Err(LarError::NotAnArray {
            key,
            what: "vertex lists [[i, j, ...], ...]",
        });
    };
    if list.is_empty() {
        return Err(LarError::EmptyCells { key });
    }
    let mut cells = Vec::with_capacity(list.len());
    for (cell, ids) in list.iter().enumerate() {
        let Value::Array(ids) = ids else {
            return Err(LarError::CellNotAnArray { key, cell });
        };
        let mut vertices = Vec::with_capacity(ids.len());
        for id in ids {
            let vertex = id
                .as_u64()
                .and_then(|v| usize::try_from(v).ok())
                .ok_or_else(|| LarError::NonIntegerIndex {
                    key,
                    cell,
                    value: id.to_string(),
                })?;
            if vertex >= vertex_count {
                return Err(LarError::IndexOutOfRange {
                    key,
                    cell,
                    vertex,
                    vertex_count,
                });
            }
            if vertices.contains(&vertex) {
                return Err(LarError::RepeatedVertex { key, cell, vertex });
            }
            vertices.push(vertex);
        }
        let (least, needed) = match p {
            1 => (2, "exactly 2"),
            2 => (3, "at least 3"),
            _ => (4, "at least 4"),
        };
        if vertices.len() < least || (p == 1 && vertices.len() != 2) {
            return Err(LarError::TooFewVertices {
                key,
                cell,
                p,
                found: vertices.len(),
                needed,
            });
        }
        cells.push(vertices);
    }
    Ok(cells)
}

/// The checked content of LAR text (see [`LarInput`]).
pub fn parse_str(text: &str) -> Result<LarInput, LarError> {
    let value: Value = serde_json::from_str(text).map_err(|e| LarError::Syntax {
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    parse_value(&value)
}

/// The complex described by LAR text.
pub fn from_str(text: &str) -> Result<Complex, LarError> {
    parse_str(text)?.to_complex()
}

/// Read the checked content of a LAR file.
pub fn read_lar_input(path: &Path) -> Result<LarInput, LarFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| LarFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let value: Value = serde_json::from_str(&text).map_err(|e| {
        let full = e.to_string();
        let suffix = format!(" at line {} column {}", e.line(), e.column());
        LarFileError::Syntax {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: full.strip_suffix(&suffix).unwrap_or(&full).to_string(),
        }
    })?;
    parse_value(&value).map_err(|source| LarFileError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// Read a LAR file (`.lar.json`) as an oriented complex.
pub fn read_lar_json(path: &Path) -> Result<Complex, LarFileError> {
    read_lar_input(path)?
        .to_complex()
        .map_err(|source| LarFileError::Invalid {
            path: path.to_path_buf(),
            source,
        })
}

/// Whether a path names a LAR file (its name ends in `.lar.json`).
pub fn is_lar_path(path: &Path) -> bool {
    path.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.to_ascii_lowercase().ends_with(".lar.json"))
}

/// A finite `f64` as its shortest JSON text that reads back to itself.
fn number(x: f64) -> String {
    // Serialising a finite f64 cannot fail.
    serde_json::to_string(&x).unwrap_or_default()
}

/// The complex in the LAR format: `V`, then `EV`, `FV`, `CV` up to its
/// dimension, one point or cell per line, vertex lists sorted.
pub fn to_lar_json(complex: &Complex) -> String {
    let mut out = String::from("{\n  \"V\": [");
    let count = complex.cell_count(0);
    for i in 0..count {
        let point: Vec<String> = complex
            .vertices()
            .point(i)
            .iter()
            .map(|&x| number(x))
            .collect();
        let _ = write!(out, "\n    [{}]", point.join(", "));
        if i + 1 < count {
            out.push(',');
        }
    }
    out.push_str("\n  ]");
    for p in 1..=complex.dim().min(3) {
        let _ = write!(out, ",\n  \"{}\": [", CELL_KEYS[p - 1]);
        let count = complex.cell_count(p);
        for i in 0..count {
            let ids: Vec<String> = complex
                .cell_vertices(p, i)
                .iter()
                .map(usize::to_string)
                .collect();
            let _ = write!(out, "\n    [{}]", ids.join(", "));
            if i + 1 < count {
                out.push(',');
            }
        }
        out.push_str("\n  ]");
    }
    out.push_str("\n}\n");
    out
}
