//! CSV and JSON files of a study, written atomically.

use super::{Norm, StudyResult};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Why a study file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error(transparent)]
    Plot(#[from] super::PlotError),
}

pub(super) fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> WriteError + '_ {
    move |source| WriteError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// A temporary name next to `path` that keeps its extension (encoders pick
/// the format from it) and is hidden from a directory listing.
pub(super) fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{}.{name}", std::process::id()))
}

/// Write `bytes` to `path` through a temporary file and a rename, so that
/// `path` is either the old file or the complete new one, never a
/// truncated mix (the design's rule for every output).
pub(super) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let temporary = temporary_path(path);
    let result = (|| {
        let mut file = std::fs::File::create(&temporary)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&temporary, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result.map_err(io_error(path))
}

fn number(x: Option<f64>) -> String {
    x.map_or_else(String::new, |v| format!("{v:e}"))
}

impl StudyResult {
    /// The rows as CSV: a header, then one line per method and level, with
    /// the pairwise order of each norm next to it (empty on level 0 and
    /// where undefined). The resolution is written `64x64` so that it
    /// stays one field.
    ///
    /// ```
    /// use hasse_solver::study::{Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fe".into(), level, resolution: vec![4 << level], h, cells: 4 << level,
    ///     unknowns: 3 << level, l2, max: l2, gradient_l2: Some(l2.sqrt()), flux: None,
    ///     mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo.toml".into(), title: None, refinement: Refinement::Uniform, levels: 2,
    ///     methods: vec!["fe".into()], rows: vec![row(0, 0.25, 1e-2), row(1, 0.125, 2.5e-3)],
    /// };
    /// let csv = result.csv();
    /// let lines: Vec<&str> = csv.lines().collect();
    /// assert_eq!(lines.len(), 3);
    /// assert!(lines[0].starts_with("method,level,resolution,h,cells,unknowns,l2,l2_order"));
    /// assert!(lines[2].starts_with("fe,1,8,1.25e-1,8,6,2.5e-3,"));
    /// let l2_order: f64 = lines[2].split(',').nth(7).unwrap().parse().unwrap();
    /// assert!((l2_order - 2.0).abs() < 1e-12);
    /// ```
    pub fn csv(&self) -> String {
        let mut out = String::from("method,level,resolution,h,cells,unknowns");
        for n in Norm::ALL {
            out.push_str(&format!(",{0},{0}_order", n.key()));
        }
        out.push_str(",mesh_seconds,solve_seconds\n");
        for method in &self.methods {
            let orders: Vec<_> = Norm::ALL.iter().map(|&n| self.orders(method, n)).collect();
            for row in self.method_rows(method) {
                let resolution: Vec<String> = row.resolution.iter().map(usize::to_string).collect();
                out.push_str(&format!(
                    "{},{},{},{:e},{},{}",
                    row.method,
                    row.level,
                    resolution.join("x"),
                    row.h,
                    row.cells,
                    row.unknowns
                ));
                for (n, o) in Norm::ALL.iter().zip(&orders) {
                    let p = row
                        .level
                        .checked_sub(1)
                        .and_then(|k| o.pairwise.get(k).copied().flatten());
                    out.push_str(&format!(",{},{}", number(row.error(*n)), number(p)));
                }
                out.push_str(&format!(
                    ",{:e},{:e}\n",
                    row.mesh_seconds, row.solve_seconds
                ));
            }
        }
        out
    }

    /// The study as JSON: the case, the refinement, every row, and per
    /// method and norm the pairwise and least-squares orders.
    pub fn json(&self) -> serde_json::Value {
        let methods: Vec<serde_json::Value> = self
            .methods
            .iter()
            .map(|m| {
                let orders: serde_json::Map<String, serde_json::Value> = self
                    .norms(m)
                    .into_iter()
                    .map(|n| {
                        let o = self.orders(m, n);
                        (
                            n.key().to_string(),
                            serde_json::json!({
                                "pairwise": o.pairwise,
                                "least_squares": o.least_squares,
                            }),
                        )
                    })
                    .collect();
                serde_json::json!({
                    "method": m,
                    "rows": self.method_rows(m).collect::<Vec<_>>(),
                    "orders": orders,
                })
            })
            .collect();
        serde_json::json!({
            "case": self.case,
            "title": self.title,
            "refinement": self.refinement,
            "levels": self.levels,
            "mesh_size": "largest diameter of a top cell",
            "methods": methods,
        })
    }

    /// Write [`StudyResult::csv`] to `path` (atomically).
    pub fn write_csv(&self, path: &Path) -> Result<(), WriteError> {
        write_atomically(path, self.csv().as_bytes())
    }

    /// Write [`StudyResult::json`] to `path` (atomically, pretty-printed).
    pub fn write_json(&self, path: &Path) -> Result<(), WriteError> {
        let mut text = serde_json::to_string_pretty(&self.json()).map_err(|e| WriteError::Io {
            path: path.display().to_string(),
            source: e.into(),
        })?;
        text.push('\n');
        write_atomically(path, text.as_bytes())
    }
}
