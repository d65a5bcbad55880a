//! `hasse converge`: a convergence study of a case file. Each level
//! re-generates the case's mesh at a finer resolution
//! ([`Refinement::Uniform`]), splits every cell of the previous level's
//! mesh ([`Refinement::Split`], any mesh, files included), or halves the
//! time step of a transient case on the same mesh ([`Refinement::Time`]);
//! every method is solved on it, and the rows go to a [`StudyResult`] of
//! the study layer, which computes the observed orders and prints the
//! table.
//!
//! Diffusion, heat, Darcy and coupled cases are measured, each by the
//! errors its run reports: diffusion by quadrature (L², H¹) and at the
//! unknowns (max); heat at the last step, at the unknowns' points; Darcy
//! the pressure at the cell points and the flux; a coupled case one row
//! per field that has an exact solution, named `FIELD (METHOD)`.
//!
//! A spatial study of a heat case keeps the case's Δt: the time error
//! (O(Δt) backward Euler, O(Δt²) Crank–Nicolson) is the same on every
//! level and floors the spatial error, so the observed order falls once
//! the spatial error reaches it. Choose Δt small enough that the time
//! error stays well below the finest level's spatial error (a time study
//! on the finest mesh measures it), and the same for a time study: its
//! mesh must be fine enough that the spatial error stays below the
//! smallest Δt's time error.
//!
//! ```
//! use hasse_solver::frontend::converge::Study;
//! use hasse_solver::study::{Norm, Refinement};
//! use hasse_solver::metric::Method;
//! let text = r#"
//! [mesh]
//! generator = "rectangle"
//! n = [4, 4]
//! [problem]
//! method = "fe"
//! source = "2*pi^2*sin(pi*x)*sin(pi*y)"
//! [[boundary]]
//! tag = "boundary"
//! type = "dirichlet"
//! value = 0
//! [exact]
//! solution = "sin(pi*x)*sin(pi*y)"
//! "#;
//! let study = Study {
//!     levels: 3,
//!     refinement: Refinement::Uniform,
//!     methods: vec![Method::Fe, Method::Fv],
//! };
//! let result = study.run_text("demo.toml", text, &[], &mut |_, _| {}).unwrap();
//! assert_eq!(result.rows.len(), 6);                       // 2 methods × 3 levels
//! assert_eq!(result.rows[2].resolution, vec![16, 16]);    // n = 4 · 2²
//! let fe = result.orders("fe", Norm::L2);
//! assert!((fe.least_squares.unwrap() - 2.0).abs() < 0.2);  // P1/Q1: second order
//! ```

mod levels;
mod subject;

use super::case::{Case, CaseError, Diagnostics, Problem};
use super::run::{self, RunError};
use crate::metric::Method;
use crate::study::{BadExpectation, Refinement, StudyResult, StudyRow};
use hasse_complex::Complex;
use std::path::Path;
use std::time::Instant;
use subject::Subject;

/// A convergence study: the number of levels, the refinement and the
/// methods (empty: the case's own method).
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// Number of meshes, the case's own resolution being level 0.
    pub levels: usize,
    /// How each level's mesh is made.
    pub refinement: Refinement,
    /// Methods solved side by side on the same meshes.
    pub methods: Vec<Method>,
}

/// Why a study could not run.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The case file could not be read.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// The case (with a level's overrides) or its mesh is invalid.
    #[error("{0}")]
    Invalid(Diagnostics),
    /// A method name (`--methods`) names no method.
    #[error(transparent)]
    UnknownMethod(#[from] crate::metric::UnknownMethod),
    /// An `--expect` text is not `ORDER` or `ORDER:TOL`.
    #[error(transparent)]
    BadExpectation(#[from] BadExpectation),
    /// [`Study::levels`] is 0.
    #[error("a study needs at least 1 level")]
    NoLevels,
    /// The case's kind is not one a study measures.
    #[error("{case}: a convergence study measures diffusion (of functions or k-forms), heat, darcy and coupled cases; this case is kind = \"{kind}\"")]
    Unsupported {
        /// The case file.
        case: String,
        /// Its `problem.kind`.
        kind: &'static str,
    },
    /// `--methods` on a case whose methods are not diffusion methods.
    #[error("{case}: --methods names diffusion methods; a {kind} case's method is its own (darcy: problem.method = mimetic, dec or dec-barycentric; coupled: each [[field]]'s method): change it with --set and study one method at a time")]
    MethodsNotApplicable {
        /// The case file.
        case: String,
        /// Its `problem.kind`.
        kind: &'static str,
    },
    /// A time refinement of a steady case.
    #[error("{case}: --refine time halves the time step of a transient case; this case is kind = \"{kind}\", which does not step in time: use --refine uniform (generated mesh) or --refine split")]
    NotTransient {
        /// The case file.
        case: String,
        /// Its `problem.kind`.
        kind: &'static str,
    },
    /// A coupled case none of whose fields has an exact solution.
    #[error("{case}: a convergence study needs an exact solution: give `exact` in at least one [[field]]")]
    NoFieldExact {
        /// The case file.
        case: String,
    },
    /// The case has no `[exact]` solution to measure errors against.
    #[error("{case}: a convergence study needs the exact solution: add an [exact] table with `solution` (and `gradient` for gradient and flux errors)")]
    NoExact {
        /// The case file.
        case: String,
    },
    /// The case's mesh cannot be refined as asked.
    #[error("{case}: {message}")]
    Refinement {
        /// The case file.
        case: String,
        /// Why (a mesh file, a missing `mesh.n`, an overflowing
        /// resolution).
        message: String,
    },
    /// A level failed to solve.
    #[error("level {level}, method {method}: {source}")]
    Run {
        /// The case file.
        case: String,
        /// The level that failed.
        level: usize,
        /// The method that failed on it.
        method: String,
        /// Why.
        source: RunError,
    },
}

impl StudyError {
    /// Whether the user's input is at fault (exit code 2) rather than a
    /// solve (exit code 1).
    pub fn is_input(&self) -> bool {
        match self {
            StudyError::Run { source, .. } => source.is_input(),
            _ => true,
        }
    }
}

impl Study {
    /// Run the study on a case file; `overrides` are `KEY=VALUE` strings
    /// as for `hasse run --set`, applied before the level's refinement.
    /// `progress` is called once per level with the rows just solved.
    ///
    /// ```
    /// use hasse_solver::frontend::converge::Study;
    /// use hasse_solver::study::{Norm, Refinement};
    /// use hasse_solver::metric::Method;
    /// let case = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../cases/box-3d.toml"));
    /// let study = Study { levels: 2, refinement: Refinement::Uniform, methods: vec![Method::Fv] };
    /// let mut lines = Vec::new();
    /// let result = study
    ///     .run(case, &["mesh.n=[8,8,8]".into()], &mut |level, rows| lines.push((level, rows[0].unknowns)))
    ///     .unwrap();
    /// assert_eq!(lines, [(0, 512), (1, 4096)]);               // one call per level
    /// // TPFA on a uniform grid: second order (4³ → 8³ is still
    /// // pre-asymptotic, 2.20; 8³ → 16³ gives 2.08).
    /// let p = result.orders("fv", Norm::L2).pairwise[0].unwrap();
    /// assert!((p - 2.0).abs() < 0.1);
    /// ```
    pub fn run(
        &self,
        path: &Path,
        overrides: &[String],
        progress: &mut dyn FnMut(usize, &[StudyRow]),
    ) -> Result<StudyResult, StudyError> {
        let text = std::fs::read_to_string(path).map_err(|source| {
            StudyError::Case(CaseError::Io {
                path: path.display().to_string(),
                source,
            })
        })?;
        self.run_text(&path.display().to_string(), &text, overrides, progress)
    }

    /// Run the study on a case given as text; `file` names it in messages
    /// and anchors relative paths. Every refusal (the problem kind, a
    /// refinement the case cannot take, a missing exact solution) comes
    /// before the first solve.
    pub fn run_text(
        &self,
        file: &str,
        text: &str,
        overrides: &[String],
        progress: &mut dyn FnMut(usize, &[StudyRow]),
    ) -> Result<StudyResult, StudyError> {
        if self.levels == 0 {
            return Err(StudyError::NoLevels);
        }
        let base = Case::from_text(file, text, overrides).map_err(StudyError::Invalid)?;
        let subject = Subject::of(file, &base, self.refinement, self.levels, &self.methods)?;
        let methods = subject.methods(&self.methods);
        let mut rows = Vec::with_capacity(methods.len() * self.levels);
        // The previous level's complex, which a SPLIT level refines and a
        // time level reuses.
        let mut previous: Option<Complex> = None;
        for level in 0..self.levels {
            let source = Source {
                file,
                text,
                overrides,
            };
            let (cases, resolution) =
                self.level_cases(&source, &base, &subject, &methods, level)?;
            let started = Instant::now();
            let complex = match (self.refinement, previous.take()) {
                (Refinement::Uniform, _) | (_, None) => {
                    let complex = cases[0].build_mesh().map_err(StudyError::Invalid)?;
                    if self.refinement == Refinement::Split {
                        levels::check_splittable(file, &complex)?;
                    }
                    complex
                }
                (Refinement::Split, Some(coarse)) => hasse_complex::refine::uniform(&coarse)
                    .map(|(fine, _)| fine)
                    .map_err(|e| StudyError::Refinement {
                        case: file.to_string(),
                        message: format!("level {level}: SPLIT refinement failed: {e}"),
                    })?,
                (Refinement::Time, Some(same)) => same,
            };
            let mesh_seconds = started.elapsed().as_secs_f64();
            let h = match self.refinement {
                Refinement::Time => time_step(&cases[0]).unwrap_or(f64::NAN),
                Refinement::Uniform | Refinement::Split => complex.mesh_size(),
            };
            let cells = complex.cell_count(complex.dim());
            let resolution = resolution.unwrap_or_else(|| vec![cells]);
            let first = rows.len();
            for (method, case) in methods.iter().zip(&cases) {
                let started = Instant::now();
                let result =
                    run::solve(case, &complex, &mut |_| {}).map_err(|source| StudyError::Run {
                        case: file.to_string(),
                        level,
                        method: method.clone(),
                        source,
                    })?;
                let solve_seconds = started.elapsed().as_secs_f64();
                for (name, errors) in subject.errors(file, method, &result)? {
                    rows.push(StudyRow {
                        method: name,
                        level,
                        resolution: resolution.clone(),
                        h,
                        cells,
                        unknowns: result.unknowns,
                        l2: errors.l2,
                        max: errors.max,
                        gradient_l2: errors.gradient_l2,
                        flux: result.flux_error.filter(|f| f.is_finite()),
                        mesh_seconds,
                        solve_seconds,
                    });
                }
            }
            progress(level, &rows[first..]);
            previous = Some(complex);
        }
        // Method-major order: each method's levels together, as tables read.
        let mut names: Vec<String> = Vec::new();
        for r in &rows {
            if !names.contains(&r.method) {
                names.push(r.method.clone());
            }
        }
        let mut ordered = Vec::with_capacity(rows.len());
        for m in &names {
            ordered.extend(rows.iter().filter(|r| &r.method == m).cloned());
        }
        Ok(StudyResult {
            case: file.to_string(),
            // A case's title describes its own method; a study that swaps
            // the methods must not carry it onto tables and plots.
            title: if methods == [subject.own.clone()] {
                base.title.clone()
            } else {
                None
            },
            refinement: self.refinement,
            levels: self.levels,
            methods: names,
            rows: ordered,
        })
    }

    /// The cases of one level, one per method, and the resolution the
    /// level's overrides give (None: the level's cell count, known once
    /// its mesh is built).
    fn level_cases(
        &self,
        source: &Source,
        base: &Case,
        subject: &Subject,
        methods: &[String],
        level: usize,
    ) -> Result<(Vec<Case>, Option<Vec<usize>>), StudyError> {
        let Source {
            file,
            text,
            overrides,
        } = *source;
        let mut all: Vec<String> = overrides.to_vec();
        let resolution = match self.refinement {
            Refinement::Uniform => {
                let (o, resolution) = levels::uniform_overrides(file, &base.mesh, level)?;
                all.extend(o);
                Some(resolution)
            }
            Refinement::Split => None,
            Refinement::Time => {
                let Problem::Heat(heat) = &base.problem else {
                    // Subject::of refuses this before any level.
                    return Err(StudyError::NotTransient {
                        case: file.to_string(),
                        kind: base.problem.kind(),
                    });
                };
                let (dt, steps, count) = levels::time_overrides(file, &heat.time, level)?;
                all.push(dt);
                // A case with `time.end` derives the count from Δt and
                // refuses `time.steps` beside it; one with `time.steps`
                // needs the count given.
                let derived = Case::from_text(file, text, &all).map_err(StudyError::Invalid)?;
                if time_steps(&derived) != Some(count) {
                    all.push(steps);
                }
                Some(vec![count])
            }
        };
        let cases = methods
            .iter()
            .map(|m| {
                let mut with_method = all.clone();
                if subject.sets_method() {
                    with_method.push(format!("problem.method={m}"));
                }
                Case::from_text(file, text, &with_method).map_err(StudyError::Invalid)
            })
            .collect::<Result<Vec<Case>, _>>()?;
        Ok((cases, resolution))
    }
}

/// The case a study reads: its name, its text and the user's overrides.
#[derive(Clone, Copy)]
struct Source<'a> {
    file: &'a str,
    text: &'a str,
    overrides: &'a [String],
}

/// The time step of a transient case.
fn time_step(case: &Case) -> Option<f64> {
    match &case.problem {
        Problem::Heat(h) => Some(h.time.dt),
        _ => None,
    }
}

/// The number of time steps of a transient case.
fn time_steps(case: &Case) -> Option<usize> {
    match &case.problem {
        Problem::Heat(h) => Some(h.time.steps),
        _ => None,
    }
}
