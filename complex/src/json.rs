//! A JSON file format that stores a complex exactly: reading a written file
//! gives a complex equal (`==`) to the original, with bit-identical
//! coordinates and boundary matrices.
//!
//! # Format (version 1)
//!
//! One JSON object with exactly these fields:
//!
//! | field | value |
//! |---|---|
//! | `"format"` | the string `"hasse-complex"` |
//! | `"version"` | the integer `1` |
//! | `"embedding_dim"` | d, the dimension of the space the vertices live in (1, 2 or 3) |
//! | `"vertices"` | the vertex coordinates, flat and row by row: `[x0, y0, x1, y1, …]` for d = 2 (d numbers per vertex, all finite) |
//! | `"cells"` | the cells of every dimension p = 1 … n, lowest first: `cells[p-1][i]` lists the vertex indices (0-based) of p-cell i. These are the rows of the characteristic matrices M_1 … M_n, in the complex's numbering; vertex lists are written sorted, but any order is read |
//! | `"top_orientation"` | one `1` or `-1` per n-cell: its orientation relative to the frame of its sorted vertex list. It is recomputed on reading and compared with the stored value, which catches files whose coordinates or cells were edited inconsistently |
//! | `"tags"` | an object `{name: {"dim": p, "cells": [i, …]}}` of named sets of p-cells |
//!
//! The boundary matrices are not stored: they follow from the vertices and
//! cells. A unit triangle:
//!
//! ```text
//! {
//!   "format": "hasse-complex",
//!   "version": 1,
//!   "embedding_dim": 2,
//!   "vertices": [
//!     0.0, 0.0,
//!     1.0, 0.0,
//!     0.0, 1.0
//!   ],
//!   "cells": [
//!     [[0, 1], [0, 2], [1, 2]],
//!     [[0, 1, 2]]
//!   ],
//!   "top_orientation": [1],
//!   "tags": {
//!     "bottom": {"dim": 1, "cells": [0]}
//!   }
//! }
//! ```
//!
//! Numbers are written in the shortest form that reads back to the same
//! `f64`, and read back with a correctly rounded parser (not serde_json's
//! default one, which can be one unit in the last place off).
//!
//! ```
//! use hasse_complex::{json, Complex, TopCells, Vertices};
//! let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 0.1 + 0.2]]).unwrap();
//! let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
//! let text = json::to_json(&k);
//! assert_eq!(json::from_json_str(&text, "triangle.json").unwrap(), k);
//! ```

use crate::cells::Vertices;
use crate::complex::Complex;
use crate::error::ComplexError;
use crate::lar::Lar;
use serde_json::{Map, Value};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The value of the `"format"` field.
pub const FORMAT: &str = "hasse-complex";
/// The format version written and read by this build.
pub const VERSION: u64 = 1;

const FIELDS: [&str; 7] = [
    "format",
    "version",
    "embedding_dim",
    "vertices",
    "cells",
    "top_orientation",
    "tags",
];

/// Why a complex could not be written or read as JSON.
#[derive(Debug, thiserror::Error)]
pub enum JsonError {
    #[error("cannot access '{}': {source}; check that the file and its directory exist and are readable/writable", path.display())]
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
    #[error("'{}' is not a valid hasse-complex JSON file: {message}", path.display())]
    Format { path: PathBuf, message: String },
    #[error("'{}' does not describe a valid complex: {source}", path.display())]
    Complex {
        path: PathBuf,
        #[source]
        source: ComplexError,
    },
}

impl JsonError {
    /// The file (or name) the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Io { path, .. }
            | Self::Syntax { path, .. }
            | Self::Format { path, .. }
            | Self::Complex { path, .. } => path,
        }
    }
}

/// A JSON number or string, exactly as serde_json writes it.
fn number(x: impl serde::Serialize) -> String {
    // Serialising a finite f64, an integer or a string cannot fail.
    serde_json::to_string(&x).unwrap_or_default()
}

fn int_list(out: &mut String, values: impl IntoIterator<Item = impl std::fmt::Display>) {
    out.push('[');
    for (k, v) in values.into_iter().enumerate() {
        if k > 0 {
            out.push_str(", ");
        }
        let _ = write!(out, "{v}");
    }
    out.push(']');
}

/// The complex as JSON text (format described in the module docs).
pub fn to_json(complex: &Complex) -> String {
    let d = complex.embedding_dim();
    let mut out = String::new();
    out.push_str("{\n");
    let _ = writeln!(out, "  \"format\": {},", number(FORMAT));
    let _ = writeln!(out, "  \"version\": {VERSION},");
    let _ = writeln!(out, "  \"embedding_dim\": {d},");
    out.push_str("  \"vertices\": [");
    let vertex_count = complex.cell_count(0);
    for i in 0..vertex_count {
        out.push_str("\n    ");
        let point = complex.vertices().point(i);
        for (a, x) in point.iter().enumerate() {
            if a > 0 {
                out.push_str(", ");
            }
            out.push_str(&number(x));
        }
        if i + 1 < vertex_count {
            out.push(',');
        }
    }
    out.push_str("\n  ],\n  \"cells\": [");
    let n = complex.dim();
    for p in 1..=n {
        out.push_str("\n    [");
        let count = complex.cell_count(p);
        for i in 0..count {
            out.push_str("\n      ");
            int_list(&mut out, complex.cell_vertices(p, i));
            if i + 1 < count {
                out.push(',');
            }
        }
        out.push_str("\n    ]");
        if p < n {
            out.push(',');
        }
    }
    out.push_str("\n  ],\n  \"top_orientation\": ");
    int_list(&mut out, complex.top_orientation());
    out.push_str(",\n  \"tags\": {");
    let tag_count = complex.tags().len();
    for (k, (name, tag)) in complex.tags().iter().enumerate() {
        let _ = write!(
            out,
            "\n    {}: {{\"dim\": {}, \"cells\": ",
            number(name),
            tag.dim
        );
        int_list(&mut out, &tag.cells);
        out.push('}');
        if k + 1 < tag_count {
            out.push(',');
        }
    }
    if tag_count > 0 {
        out.push_str("\n  ");
    }
    out.push_str("}\n}\n");
    out
}

/// Write the complex to `path` as JSON. The text goes to a temporary file
/// in the same directory which is then renamed over `path`, so `path` never
/// holds a half-written file; on error the temporary file is removed.
pub fn write_json(complex: &Complex, path: &Path) -> Result<(), JsonError> {
    let io = |source: std::io::Error| JsonError::Io {
        path: path.to_path_buf(),
        source,
    };
    let Some(file_name) = path.file_name() else {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the path does not name a file",
        )));
    };
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let text = to_json(complex);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |t| t.subsec_nanos());
    let temp = dir.join(format!(
        ".{}.{}-{nanos}.tmp",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(io)?;
    let written = file
        .write_all(text.as_bytes())
        .and_then(|()| file.sync_all())
        .and_then(|()| {
            drop(file);
            std::fs::rename(&temp, path)
        });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&temp);
        return Err(io(e));
    }
    Ok(())
}

/// Read a complex written by [`write_json`].
pub fn read_json(path: &Path) -> Result<Complex, JsonError> {
    let text = std::fs::read_to_string(path).map_err(|source| JsonError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Read a complex from JSON text; `name_for_errors` is the file name quoted
/// by error messages.
pub fn from_json_str(text: &str, name_for_errors: &str) -> Result<Complex, JsonError> {
    parse(text, Path::new(name_for_errors))
}

fn parse(text: &str, path: &Path) -> Result<Complex, JsonError> {
    let format_error = |message: String| JsonError::Format {
        path: path.to_path_buf(),
        message,
    };
    let value: Value = serde_json::from_str(text).map_err(|e| {
        let full = e.to_string();
        let suffix = format!(" at line {} column {}", e.line(), e.column());
        JsonError::Syntax {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: full.strip_suffix(&suffix).unwrap_or(&full).to_string(),
        }
    })?;
    let Value::Object(doc) = value else {
        return Err(format_error(
            "the top level must be an object with the fields format, version, embedding_dim, vertices, cells, top_orientation and tags".into(),
        ));
    };
    if let Some(key) = doc.keys().find(|k| !FIELDS.contains(&k.as_str())) {
        return Err(format_error(format!(
            "unknown field \"{key}\" (the fields are {})",
            FIELDS.join(", ")
        )));
    }
    let field = |name: &str| {
        doc.get(name)
            .ok_or_else(|| format_error(format!("the field \"{name}\" is missing")))
    };

    match field("format")? {
        Value::String(s) if s == FORMAT => {}
        other => {
            return Err(format_error(format!(
                "the field \"format\" is {other}, expected \"{FORMAT}\""
            )))
        }
    }
    match field("version")?.as_u64() {
        Some(VERSION) => {}
        _ => {
            return Err(format_error(format!(
                "format version {} cannot be read; this build reads version {VERSION}",
                field("version")?
            )))
        }
    }
    let d = match field("embedding_dim")?.as_u64() {
        Some(d @ 1..=3) => d as usize,
        _ => {
            return Err(format_error(format!(
                "\"embedding_dim\" is {}, expected 1, 2 or 3",
                field("embedding_dim")?
            )))
        }
    };

    let coords = exact_vertices(text, field("vertices")?).map_err(format_error)?;
    if coords.len() % d != 0 {
        return Err(format_error(format!(
            "\"vertices\" holds {} numbers, which is not a multiple of embedding_dim = {d}",
            coords.len()
        )));
    }
    let vertex_count = coords.len() / d;

    let Value::Array(levels) = field("cells")? else {
        return Err(format_error(
            "\"cells\" must be an array with one array of cells per dimension 1..n".into(),
        ));
    };
    if levels.is_empty() {
        return Err(format_error(
            "\"cells\" is empty: a complex needs cells of dimension 1 at least".into(),
        ));
    }
    let mut cells = Vec::with_capacity(levels.len());
    for (k, level) in levels.iter().enumerate() {
        let p = k + 1;
        let Value::Array(list) = level else {
            return Err(format_error(format!(
                "cells[{k}] (the {p}-cells) must be an array of vertex lists"
            )));
        };
        if list.is_empty() {
            return Err(format_error(format!("cells[{k}] lists no {p}-cells")));
        }
        let mut level_cells = Vec::with_capacity(list.len());
        for (i, cell) in list.iter().enumerate() {
            let ids = index_list(cell).ok_or_else(|| {
                format_error(format!(
                    "{p}-cell {i} must be an array of vertex indices (non-negative integers)"
                ))
            })?;
            if ids.len() < p + 1 {
                return Err(format_error(format!(
                    "{p}-cell {i} has {} vertices; a {p}-cell needs at least {}",
                    ids.len(),
                    p + 1
                )));
            }
            if let Some(&v) = ids.iter().find(|&&v| v >= vertex_count) {
                return Err(format_error(format!(
                    "{p}-cell {i} refers to vertex {v}, but there are {vertex_count} vertices"
                )));
            }
            level_cells.push(ids);
        }
        cells.push(level_cells);
    }
    let n = cells.len();
    let top_count = cells[n - 1].len();

    let stored_orientation: Vec<i8> = match field("top_orientation")? {
        Value::Array(list) => list
            .iter()
            .map(|v| match v.as_i64() {
                Some(1) => Some(1),
                Some(-1) => Some(-1),
                _ => None,
            })
            .collect::<Option<_>>()
            .ok_or_else(|| format_error("\"top_orientation\" must hold only 1 and -1".into()))?,
        _ => {
            return Err(format_error(
                "\"top_orientation\" must be an array of 1 and -1".into(),
            ))
        }
    };
    if stored_orientation.len() != top_count {
        return Err(format_error(format!(
            "\"top_orientation\" has {} entries for {top_count} top cells",
            stored_orientation.len()
        )));
    }

    let Value::Object(tag_map) = field("tags")? else {
        return Err(format_error(
            "\"tags\" must be an object {name: {\"dim\": p, \"cells\": [...]}}".into(),
        ));
    };
    let tags = read_tags(tag_map).map_err(format_error)?;

    let complex_error = |source: ComplexError| JsonError::Complex {
        path: path.to_path_buf(),
        source,
    };
    let vertices = Vertices::new(d, coords).map_err(complex_error)?;
    let lar = Lar::from_vertex_sets(vertices, cells).map_err(complex_error)?;
    let mut complex = Complex::from_lar(lar).map_err(complex_error)?;

    let inconsistent = |what: String| {
        format_error(format!(
            "the file was edited inconsistently: {what}; restore it or write it again from the program that produced it"
        ))
    };
    if let Some(i) = (0..top_count).find(|&i| complex.top_orientation()[i] != stored_orientation[i])
    {
        return Err(inconsistent(format!(
            "top cell {i} has stored orientation {} but its vertices give {}",
            stored_orientation[i],
            complex.top_orientation()[i]
        )));
    }
    for p in 2..=n {
        let dd = &**complex.boundary(p - 1) * &**complex.boundary(p);
        if dd.data().iter().any(|&x| x != 0) {
            return Err(inconsistent(format!(
                "the boundary of the boundary of the {p}-cells is not zero (a face of some {p}-cell is missing or extra)"
            )));
        }
    }
    for (name, dim, ids) in tags {
        complex.set_tag(&name, dim, ids).map_err(complex_error)?;
    }
    Ok(complex)
}

/// Non-negative integers of a JSON array.
fn index_list(value: &Value) -> Option<Vec<usize>> {
    value
        .as_array()?
        .iter()
        .map(|v| v.as_u64().and_then(|x| usize::try_from(x).ok()))
        .collect()
}

fn read_tags(map: &Map<String, Value>) -> Result<Vec<(String, usize, Vec<usize>)>, String> {
    let mut tags = Vec::with_capacity(map.len());
    for (name, tag) in map {
        let bad = || format!("tag \"{name}\" must be {{\"dim\": p, \"cells\": [i, ...]}}");
        let Value::Object(fields) = tag else {
            return Err(bad());
        };
        if fields.len() != 2 {
            return Err(bad());
        }
        let dim = fields
            .get("dim")
            .and_then(Value::as_u64)
            .and_then(|x| usize::try_from(x).ok())
            .ok_or_else(bad)?;
        let cells = fields.get("cells").and_then(index_list).ok_or_else(bad)?;
        tags.push((name.clone(), dim, cells));
    }
    Ok(tags)
}

/// The vertex coordinates, re-read from the text of the `"vertices"` array
/// with Rust's correctly rounded `f64` parser (serde_json's default parser
/// may be off by one unit in the last place). `parsed` is serde_json's value
/// of the same array, used to check the layout.
fn exact_vertices(text: &str, parsed: &Value) -> Result<Vec<f64>, String> {
    let not_numbers = || "\"vertices\" must be a flat array of finite numbers".to_string();
    let list = parsed.as_array().ok_or_else(not_numbers)?;
    if list.is_empty() {
        return Err("\"vertices\" is empty: a complex needs at least one vertex".into());
    }
    if !list.iter().all(Value::is_number) {
        return Err(not_numbers());
    }
    let raw = raw_top_level_field(text, "vertices")
        .ok_or_else(|| "\"vertices\" could not be located in the text".to_string())?;
    let inner = raw
        .trim()
        .strip_prefix('[')
        .and_then(|s| s.strip_suffix(']'))
        .ok_or_else(not_numbers)?;
    let coords = inner
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<Vec<f64>, _>>()
        .map_err(|_| not_numbers())?;
    let agrees = coords.len() == list.len()
        && coords.iter().zip(list).all(|(&x, v)| {
            v.as_f64().is_some_and(|y| {
                x == y
                    || (x - y).abs() <= 4.0 * f64::EPSILON * x.abs().max(y.abs())
                    || (x - y).abs() <= 4.0 * f64::MIN_POSITIVE
            })
        });
    if !agrees {
        return Err(not_numbers());
    }
    Ok(coords)
}

/// The raw text of the value of `key` in the top-level object of `text`
/// (already validated as JSON); the last occurrence wins, as in serde_json.
fn raw_top_level_field<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    let bytes = text.as_bytes();
    let skip_ws = |mut i: usize| {
        while i < bytes.len() && matches!(bytes[i], b' ' | b'\t' | b'\n' | b'\r') {
            i += 1;
        }
        i
    };
    // End (exclusive) of the string starting at the quote `i`.
    let string_end = |mut i: usize| {
        i += 1;
        while i < bytes.len() {
            match bytes[i] {
                b'\\' => i += 2,
                b'"' => return Some(i + 1),
                _ => i += 1,
            }
        }
        None
    };
    let value_end = |mut i: usize| -> Option<usize> {
        let mut depth = 0usize;
        loop {
            match *bytes.get(i)? {
                b'"' => i = string_end(i)?,
                b'[' | b'{' => {
                    depth += 1;
                    i += 1;
                }
                b']' | b'}' if depth > 0 => {
                    depth -= 1;
                    i += 1;
                }
                b',' | b']' | b'}' if depth == 0 => return Some(i),
                _ => i += 1,
            }
            if depth == 0 && matches!(bytes.get(i), Some(b',' | b'}')) {
                return Some(i);
            }
        }
    };
    let mut i = skip_ws(0);
    if bytes.get(i) != Some(&b'{') {
        return None;
    }
    i = skip_ws(i + 1);
    let mut found = None;
    while bytes.get(i) == Some(&b'"') {
        let end = string_end(i)?;
        let name: String = serde_json::from_str(&text[i..end]).ok()?;
        i = skip_ws(end);
        if bytes.get(i) != Some(&b':') {
            return None;
        }
        let start = skip_ws(i + 1);
        let stop = value_end(start)?;
        if name == key {
            found = Some(text[start..stop].trim_end());
        }
        i = skip_ws(stop);
        if bytes.get(i) == Some(&b',') {
            i = skip_ws(i + 1);
        }
    }
    found
}
