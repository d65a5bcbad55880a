//! `hasse converge`: a convergence study of a case file. Each level
//! re-generates the case's mesh at a finer resolution, every method is
//! solved on it, and the rows go to a [`StudyResult`] of the study layer,
//! which computes the observed orders and prints the table.
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

use super::case::{Case, CaseError, Diagnostics, Problem};
use super::mesh_spec::MeshSpec;
use super::run::{self, RunError};
use crate::metric::Method;
use crate::study::{BadExpectation, Refinement, StudyResult, StudyRow};
use std::path::Path;
use std::time::Instant;

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
    /// The case is not a diffusion problem, whose methods a study compares.
    #[error("{case}: a convergence study compares methods on a diffusion problem; this case is kind = \"{kind}\"")]
    NotDiffusion {
        /// The case file.
        case: String,
        /// Its `problem.kind`.
        kind: &'static str,
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

/// The `--set` overrides that make level `level` of a uniform refinement
/// of `mesh`, and the resolution they give.
fn uniform_overrides(
    case: &str,
    mesh: &MeshSpec,
    level: usize,
) -> Result<(Vec<String>, Vec<usize>), StudyError> {
    let refuse = |message: String| StudyError::Refinement {
        case: case.to_string(),
        message,
    };
    let generator = match (&mesh.generator, &mesh.file) {
        (Some(g), _) => g.as_str(),
        (None, Some(file)) => {
            return Err(refuse(format!(
                "the mesh is read from `{}`: a mesh file cannot be refined uniformly (there is no generator resolution to raise); use a generator case, or SPLIT refinement once it is available",
                file.display()
            )))
        }
        (None, None) => return Err(refuse("the case has no mesh generator".into())),
    };
    let scale = |n: usize, factor: usize| -> Result<usize, StudyError> {
        factor
            .checked_pow(level as u32)
            .and_then(|f| n.checked_mul(f))
            .ok_or_else(|| refuse(format!("level {level}: the resolution overflows")))
    };
    let list = |v: &[usize]| {
        format!(
            "[{}]",
            v.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    if generator == "sphere" {
        let s = mesh.subdivisions.unwrap_or(2) as usize + level;
        return Ok((vec![format!("mesh.subdivisions={s}")], vec![s]));
    }
    let n = mesh.n.as_ref().ok_or_else(|| {
        refuse("mesh.n is missing: uniform refinement multiplies the case's n".into())
    })?;
    // A voronoi or delaunay n counts points in the plane: 4× the points
    // halve h.
    let factor = if matches!(generator, "voronoi" | "delaunay") {
        4
    } else {
        2
    };
    let refined = n
        .iter()
        .map(|&c| scale(c, factor))
        .collect::<Result<Vec<_>, _>>()?;
    let mut overrides = vec![format!("mesh.n={}", list(&refined))];
    if generator == "hollow-box" {
        if let Some([a, b]) = mesh.cavity {
            overrides.push(format!("mesh.cavity=[{}, {}]", scale(a, 2)?, scale(b, 2)?));
        }
    }
    if let Some(grading) = &mesh.grading {
        let refined: Vec<String> = grading
            .iter()
            .map(|r| format!("{:?}", r.powf(0.5f64.powi(level as i32))))
            .collect();
        overrides.push(format!("mesh.grading=[{}]", refined.join(", ")));
    }
    Ok((overrides, refined))
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
    /// and anchors relative paths.
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
        let own = match &base.problem {
            Problem::Diffusion(d) => d.method,
            other => {
                return Err(StudyError::NotDiffusion {
                    case: file.to_string(),
                    kind: other.kind(),
                })
            }
        };
        if base.exact.is_none() {
            return Err(StudyError::NoExact {
                case: file.to_string(),
            });
        }
        let methods = if self.methods.is_empty() {
            vec![own]
        } else {
            self.methods.clone()
        };
        let mut rows = Vec::with_capacity(methods.len() * self.levels);
        for level in 0..self.levels {
            let (level_overrides, resolution) = match self.refinement {
                Refinement::Uniform => uniform_overrides(file, &base.mesh, level)?,
            };
            let mut all: Vec<String> = overrides.to_vec();
            all.extend(level_overrides);
            let cases = methods
                .iter()
                .map(|m| {
                    let mut with_method = all.clone();
                    with_method.push(format!("problem.method={}", m.name()));
                    Case::from_text(file, text, &with_method).map_err(StudyError::Invalid)
                })
                .collect::<Result<Vec<Case>, _>>()?;
            // Only the method differs between these cases: one mesh serves all.
            let started = Instant::now();
            let complex = cases[0].build_mesh().map_err(StudyError::Invalid)?;
            let mesh_seconds = started.elapsed().as_secs_f64();
            let h = complex.mesh_size();
            let cells = complex.cell_count(complex.dim());
            let first = rows.len();
            for (method, case) in methods.iter().zip(&cases) {
                let started = Instant::now();
                let result =
                    run::solve(case, &complex, &mut |_| {}).map_err(|source| StudyError::Run {
                        case: file.to_string(),
                        level,
                        method: method.name().to_string(),
                        source,
                    })?;
                let solve_seconds = started.elapsed().as_secs_f64();
                let errors = result.errors.ok_or_else(|| StudyError::NoExact {
                    case: file.to_string(),
                })?;
                rows.push(StudyRow {
                    method: method.name().to_string(),
                    level,
                    resolution: resolution.clone(),
                    h,
                    cells,
                    unknowns: result.unknowns,
                    l2: errors.l2,
                    max: errors.max,
                    gradient_l2: errors.gradient_l2.is_finite().then_some(errors.gradient_l2),
                    flux: result.flux_error.filter(|f| f.is_finite()),
                    mesh_seconds,
                    solve_seconds,
                });
            }
            progress(level, &rows[first..]);
        }
        // Method-major order: each method's levels together, as tables read.
        let mut ordered = Vec::with_capacity(rows.len());
        for m in &methods {
            ordered.extend(rows.iter().filter(|r| r.method == m.name()).cloned());
        }
        Ok(StudyResult {
            case: file.to_string(),
            // A case's title describes its own method; a study that swaps
            // the methods must not carry it onto tables and plots.
            title: if methods == [own] {
                base.title.clone()
            } else {
                None
            },
            refinement: self.refinement,
            levels: self.levels,
            methods: methods.iter().map(|m| m.name().to_string()).collect(),
            rows: ordered,
        })
    }
}
