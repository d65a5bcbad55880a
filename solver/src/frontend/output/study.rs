//! The files of a convergence study: CSV, JSON and the log–log plot (PNG
//! or SVG), each written under a temporary name and renamed into place,
//! so that a failed write leaves no truncated file.

use super::atomic::write_atomically;
use super::OutputError;
use crate::study::{PlotError, PlotFormat, PlotOptions, StudyResult};
use std::path::Path;

/// Why a study file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The file could not be created, written or renamed into place.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// serde_json refused the study (a non-finite number, say).
    #[error("{path}: the study could not be written as JSON: {message}")]
    Json {
        /// The JSON file.
        path: String,
        /// serde_json's message.
        message: String,
    },
}

/// Write [`StudyResult::csv`] to `path`.
pub fn write_csv(result: &StudyResult, path: &Path) -> Result<(), WriteError> {
    Ok(write_atomically(path, |temporary| {
        super::atomic::write_bytes(temporary, result.csv().as_bytes())
    })?)
}

/// Write [`StudyResult::json`] to `path`, pretty-printed.
pub fn write_json(result: &StudyResult, path: &Path) -> Result<(), WriteError> {
    let mut text = serde_json::to_string_pretty(&result.json()).map_err(|e| WriteError::Json {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    text.push('\n');
    Ok(write_atomically(path, |temporary| {
        super::atomic::write_bytes(temporary, text.as_bytes())
    })?)
}

/// Write the study's plot to `path` as PNG or SVG.
///
/// ```
/// use hasse_solver::frontend::output::study::write_plot;
/// use hasse_solver::study::{PlotFormat, PlotOptions, Refinement, StudyResult, StudyRow};
/// let row = |level: usize, h: f64, l2: f64| StudyRow {
///     method: "fe".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
///     l2, max: l2, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
/// };
/// let result = StudyResult {
///     case: "demo.toml".into(), title: Some("demo".into()), refinement: Refinement::Uniform,
///     levels: 2, methods: vec!["fe".into()], rows: vec![row(0, 0.2, 4e-2), row(1, 0.1, 1e-2)],
/// };
/// let path = std::env::temp_dir().join(format!("hasse-doc-plot-{}.png", std::process::id()));
/// write_plot(&result, &path, PlotFormat::Png, PlotOptions { width: 320, height: 200 }).unwrap();
/// let png = std::fs::read(&path).unwrap();
/// assert_eq!(&png[1..4], b"PNG");
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_plot(
    result: &StudyResult,
    path: &Path,
    format: PlotFormat,
    options: PlotOptions,
) -> Result<(), WriteError> {
    let bytes = match format {
        PlotFormat::Svg => result.svg(options)?.into_bytes(),
        PlotFormat::Png => result.png(options)?,
    };
    Ok(write_atomically(path, |temporary| {
        super::atomic::write_bytes(temporary, &bytes)
    })?)
}
