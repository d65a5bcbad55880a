//! A run's output: the final HDF5/XDMF files, the time series of a
//! refinement study, and the partial output of a transient run written
//! level by level while it goes on.

use super::*;

/// The run's cochains, each marked with the method that computed it.
/// The fields of a level as written: those `[output] fields` selects (all
/// by default), each with the method that made it.
fn cochains(case: &Case, fields: &[Cochain], method: Option<&str>) -> Vec<Cochain> {
    fields
        .iter()
        .filter(|c| case.output.keeps(&c.name))
        .map(|c| match method {
            Some(m) => c.clone().with_method(m),
            None => c.clone(),
        })
        .collect()
}

/// A warning for each name of `[output] fields` that the run does not
/// produce (a misspelt name would otherwise drop a field silently).
pub fn unwritten_fields(case: &Case, result: &RunResult) -> Vec<String> {
    let Some(wanted) = &case.output.fields else {
        return Vec::new();
    };
    let mut produced: Vec<&str> = result
        .fields
        .iter()
        .chain(result.series.iter().flat_map(|(_, f)| f))
        .map(|c| c.name.as_str())
        .collect();
    produced.sort_unstable();
    produced.dedup();
    wanted
        .iter()
        .filter(|w| !produced.contains(&w.as_str()))
        .map(|w| {
            format!(
                "output.fields names `{w}`, which this run does not produce (it produces {})",
                produced.join(", ")
            )
        })
        .collect()
}

/// The provenance of a run of `case` with `report`.
fn provenance(case: &Case, report: serde_json::Value) -> crate::frontend::output::Provenance {
    let mut provenance = crate::frontend::output::Provenance::new(report);
    provenance.case_text = Some(case.text.clone());
    provenance.case_path = Some(case.path.display().to_string());
    provenance
}

/// What [`write_output`] writes for `result`.
fn run_output<'c>(
    case: &Case,
    complex: &'c Complex,
    result: &RunResult,
) -> crate::frontend::output::RunOutput<'c> {
    use crate::frontend::output::Step;
    let method = result.method.as_deref();
    let steps = if result.series.is_empty() {
        vec![Step {
            time: 0.0,
            cochains: cochains(case, &result.fields, method),
        }]
    } else {
        result
            .series
            .iter()
            .map(|(time, fields)| Step {
                time: *time,
                cochains: cochains(case, fields, method),
            })
            .collect()
    };
    crate::frontend::output::RunOutput {
        complex,
        steps,
        provenance: provenance(case, result.report_json(complex)),
    }
}

/// Write the run's fields, mesh and provenance to `<stem>.h5`,
/// `<stem>.xdmf` and, for edge or face fields, `<stem>.edges.xdmf` /
/// `<stem>.faces.xdmf` (atomically: nothing appears under those names
/// unless all were written completely).
pub fn write_output(
    case: &Case,
    complex: &Complex,
    result: &RunResult,
    stem: &std::path::Path,
) -> Result<crate::frontend::output::OutputFiles, crate::frontend::output::OutputError> {
    crate::frontend::output::write_run_with(
        stem,
        &run_output(case, complex, result),
        case.output.complex,
    )
}

/// Write a refinement study as a time series whose mesh changes: level k
/// at "time" k, each with its own complex (see `cases/OUTPUT.md`).
pub fn write_levels(
    case: &Case,
    levels: &[(Complex, Vec<Cochain>)],
    report: serde_json::Value,
    stem: &std::path::Path,
) -> Result<crate::frontend::output::OutputFiles, crate::frontend::output::OutputError> {
    use crate::frontend::output::{MeshStep, SeriesOutput};
    let method = case.method().map(|m| m.name());
    let steps = levels
        .iter()
        .enumerate()
        .map(|(k, (complex, fields))| MeshStep {
            time: k as f64,
            complex,
            cochains: cochains(case, fields, method),
        })
        .collect();
    crate::frontend::output::write_mesh_series_with(
        stem,
        &SeriesOutput {
            steps,
            provenance: provenance(case, report),
        },
        case.output.complex,
    )
}

/// Solve as [`solve`]; a transient (heat) run also hands each saved level,
/// as soon as it is computed, to `stream`, which writes it to the partial
/// output of its stem (see [`crate::frontend::output::PartialOutput`]), so that an
/// interrupted or failed run keeps its completed levels. Other problems
/// ignore `stream`.
pub fn solve_streaming<'a>(
    case: &'a Case,
    complex: &'a Complex,
    stream: Option<&mut LevelStream<'a>>,
    phase: &mut dyn FnMut(&str),
) -> Result<RunResult, RunError> {
    match (&case.problem, stream) {
        (Problem::Heat(spec), Some(stream)) => {
            heat::solve_streaming(case, spec, complex, phase, Some(stream))
        }
        _ => solve(case, complex, phase),
    }
}

/// The output of one `hasse run` under one stem: the partial output of a
/// transient run while it goes on, then the final output.
///
/// The partial output is started by the first level (so steady runs write
/// none) and stops for good at the first level it cannot write: a level
/// with a non-finite value (the run fails anyway and says why) or an I/O
/// error ([`stopped`](Self::stopped); the run goes on, since the final
/// output may still succeed).
///
/// ```
/// use hasse_solver::frontend::{case::Case, run};
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [4, 4]
/// [problem]
/// kind = "heat"
/// method = "fe"
/// initial = "x"
/// [time]
/// dt = 0.01
/// end = 0.04
/// "#;
/// let case = Case::from_text("cool.toml", text, &[]).unwrap();
/// let complex = case.build_mesh().unwrap();
/// let dir = std::env::temp_dir().join(format!("hasse-doc-stream-{}", std::process::id()));
/// let mut stream = run::LevelStream::new(&case, &dir.join("cool"));
/// let mut result = run::solve_streaming(&case, &complex, Some(&mut stream), &mut |_| {}).unwrap();
/// // Every saved level is in the partial output until the final one is written.
/// assert_eq!(stream.partial().unwrap().len(), result.series.len());
/// assert!(dir.join("cool.partial.xdmf").exists());
/// let files = stream.finish(&complex, &mut result).unwrap();
/// assert!(files.xdmf.exists() && !dir.join("cool.partial.xdmf").exists());
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub struct LevelStream<'a> {
    case: &'a Case,
    stem: PathBuf,
    partial: Option<crate::frontend::output::PartialOutput<'a>>,
    /// Levels are no longer written (see the type's documentation).
    closed: bool,
    stopped: Option<crate::frontend::output::OutputError>,
}

impl<'a> LevelStream<'a> {
    /// A stream to the output of `case` under `stem`; nothing is written
    /// before the first level.
    pub fn new(case: &'a Case, stem: &std::path::Path) -> Self {
        Self {
            case,
            stem: stem.to_path_buf(),
            partial: None,
            closed: false,
            stopped: None,
        }
    }

    /// Write saved level `time` with `fields` (on `complex`), starting the
    /// partial output at the first one; `phase` is told when it starts.
    pub(crate) fn level(
        &mut self,
        complex: &'a Complex,
        time: f64,
        fields: &[Cochain],
        method: Option<&str>,
        phase: &mut dyn FnMut(&str),
    ) {
        use crate::frontend::output::{OutputError, PartialOutput, Step};
        if self.closed {
            return;
        }
        if self.partial.is_none() {
            let report = serde_json::json!({ "partial": "written level by level during the run" });
            match PartialOutput::create(&self.stem, complex, &provenance(self.case, report)) {
                Ok(partial) => {
                    if partial.removed_stale() {
                        phase(&format!(
                            "removed the partial output of an earlier run, {}",
                            partial.xdmf().display()
                        ));
                    }
                    self.partial = Some(partial);
                }
                Err(e) => {
                    self.closed = true;
                    self.stopped = Some(e);
                    return;
                }
            }
        }
        let Some(partial) = self.partial.as_mut() else {
            return;
        };
        let step = Step {
            time,
            cochains: cochains(self.case, fields, method),
        };
        match partial.push(&step) {
            Ok(()) => {}
            Err(OutputError::NonFinite { .. }) => self.closed = true,
            Err(e) => {
                self.closed = true;
                self.stopped = Some(e);
            }
        }
    }

    /// The partial output, once started.
    pub fn partial(&self) -> Option<&crate::frontend::output::PartialOutput<'a>> {
        self.partial.as_ref()
    }

    /// Why the partial output stopped before the run ended, if an error
    /// stopped it.
    pub fn stopped(&self) -> Option<&crate::frontend::output::OutputError> {
        self.stopped.as_ref()
    }

    /// Which levels an interrupted or failed run left readable, and where,
    /// e.g. `completed levels 0..2 (t = 0, 0.01, 0.02) are readable in
    /// out/heat.partial.xdmf`; `None` when there are none.
    pub fn readable(&self) -> Option<String> {
        let partial = self.partial.as_ref().filter(|p| !p.is_empty())?;
        let times = partial.times();
        // Long runs save hundreds of levels: the first two and the last tell
        // the spacing and how far the run came.
        let shown: Vec<String> = if times.len() <= 5 {
            times.iter().map(|t| format!("{t}")).collect()
        } else {
            vec![
                format!("{}", times[0]),
                format!("{}", times[1]),
                "…".into(),
                format!("{}", times[times.len() - 1]),
            ]
        };
        Some(format!(
            "completed levels 0..{} (t = {}) are readable in {}",
            times.len() - 1,
            shown.join(", "),
            partial.xdmf().display()
        ))
    }

    /// Write the final output of `result` (as [`write_output`]) and then
    /// remove the partial output of the stem, this run's or an earlier
    /// one's. On an error the partial output stays. Once the final output
    /// is in place, a failure to remove the partial output does not undo
    /// it: it becomes a warning of `result`.
    pub fn finish(
        self,
        complex: &Complex,
        result: &mut RunResult,
    ) -> Result<crate::frontend::output::OutputFiles, crate::frontend::output::OutputError> {
        let run = run_output(self.case, complex, result);
        if let (Some(partial), false) = (&self.partial, self.closed) {
            // The partial output holds every level: the final one must
            // have the same.
            partial.check_run(&run)?;
        }
        let files =
            crate::frontend::output::write_run_with(&self.stem, &run, self.case.output.complex)?;
        if let Err(e) = crate::frontend::output::remove_partial(&self.stem) {
            result.warnings.push(format!(
                "the output is complete, but the partial output could not be removed: {e}"
            ));
        }
        Ok(files)
    }
}
