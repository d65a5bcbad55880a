//! Convergence studies: solve one case on successively refined meshes with
//! one or several methods, measure the errors against the case's `[exact]`
//! solution and the observed orders of convergence.
//!
//! A [`Study`] says how many levels and which methods; [`Study::run`] (or
//! [`Study::run_text`]) returns a [`StudyResult`] with one [`StudyRow`]
//! per method and level. The result prints as a table (`Display`), and
//! writes itself as CSV ([`StudyResult::write_csv`]), JSON
//! ([`StudyResult::write_json`]) and a log–log plot of error against mesh
//! size ([`StudyResult::write_plot`], PNG or SVG). Orders come from
//! [`pairwise_orders`] and [`least_squares_order`].
//!
//! ```
//! use hasse_solver::study::{Refinement, Study};
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
//! let fe = result.orders("fe", hasse_solver::study::Norm::L2);
//! assert!((fe.least_squares.unwrap() - 2.0).abs() < 0.2);  // P1/Q1: second order
//! ```

mod orders;
mod plot;
mod write;

pub use orders::{least_squares_order, pairwise_orders, OrderError};
pub use plot::{PlotError, PlotFormat, PlotOptions};
pub use write::WriteError;

use crate::frontend::case::{Case, CaseError, Diagnostics, Problem};
use crate::frontend::mesh_spec::MeshSpec;
use crate::frontend::run::{self, RunError};
use crate::metric::Method;
use hasse_complex::dual::DualKind;
use serde::Serialize;
use std::path::Path;
use std::str::FromStr;
use std::time::Instant;

/// Every method a study can name, in the order `--help` lists them.
pub const METHODS: [Method; 6] = [
    Method::Fd,
    Method::Fe,
    Method::Fv,
    Method::FvMimetic,
    Method::Dec(DualKind::Circumcentric),
    Method::Dec(DualKind::Barycentric),
];

/// The method with this case-file name (`fd`, `fe`, `fv`, `fv-mimetic`,
/// `dec`, `dec-barycentric`).
///
/// ```
/// use hasse_solver::study::parse_method;
/// use hasse_solver::metric::Method;
/// assert_eq!(parse_method("fv-mimetic").unwrap(), Method::FvMimetic);
/// assert!(parse_method("fvm").unwrap_err().to_string().contains("fv-mimetic"));
/// ```
pub fn parse_method(name: &str) -> Result<Method, StudyError> {
    METHODS
        .iter()
        .find(|m| m.name() == name.trim())
        .copied()
        .ok_or_else(|| StudyError::UnknownMethod(name.trim().to_string()))
}

/// How each level's mesh is made from the previous one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Refinement {
    /// Re-generate the case's mesh at a finer resolution: level k has
    /// 2ᵏ times the case's `mesh.n` per axis (4ᵏ times the sites of a
    /// `voronoi` mesh, whose n is a site count in 2D; 2ᵏ times a
    /// `hollow-box`'s cells and cavity indices; k more `sphere`
    /// subdivisions). A `grading` ratio r becomes r^(1/2ᵏ) so that the
    /// stretching stays that of the coarse mesh. Mesh files cannot be
    /// refined this way.
    Uniform,
}

impl Refinement {
    /// The name used on the command line and in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Refinement::Uniform => "uniform",
        }
    }
}

/// A convergence study: the number of levels, the refinement and the
/// methods (empty: the case's own method).
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// Number of meshes, the case's own resolution being level 0.
    pub levels: usize,
    pub refinement: Refinement,
    /// Methods solved side by side on the same meshes.
    pub methods: Vec<Method>,
}

/// The error norms a study reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Norm {
    /// Discrete L² error of the primary field.
    L2,
    /// Largest pointwise error of the primary field.
    Max,
    /// L² error of the cell-wise reconstructed gradient (an energy-norm
    /// error), where the case gives `[exact].gradient`.
    GradientL2,
    /// L² error of the face fluxes (cell-centred and hybrid methods).
    Flux,
}

impl Norm {
    /// All norms, in table order.
    pub const ALL: [Norm; 4] = [Norm::L2, Norm::Max, Norm::GradientL2, Norm::Flux];

    /// Column name in CSV and JSON.
    pub fn key(&self) -> &'static str {
        match self {
            Norm::L2 => "l2",
            Norm::Max => "max",
            Norm::GradientL2 => "gradient_l2",
            Norm::Flux => "flux",
        }
    }

    /// Human label, as in the table and the plot legend.
    pub fn label(&self) -> &'static str {
        match self {
            Norm::L2 => "L²",
            Norm::Max => "max",
            Norm::GradientL2 => "gradient L²",
            Norm::Flux => "flux",
        }
    }
}

/// One method on one level.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyRow {
    /// Method name as in case files.
    pub method: String,
    /// 0 = the case's own mesh.
    pub level: usize,
    /// The generator's resolution on this level (`mesh.n`, or the
    /// subdivisions of a sphere).
    pub resolution: Vec<usize>,
    /// Mesh size: the largest diameter of a top cell
    /// ([`hasse_complex::Complex::mesh_size`]).
    pub h: f64,
    /// Number of top cells.
    pub cells: usize,
    pub unknowns: usize,
    pub l2: f64,
    pub max: f64,
    /// Gradient L² error, when the case gives the exact gradient.
    pub gradient_l2: Option<f64>,
    /// Face-flux L² error, where the method defines it.
    pub flux: Option<f64>,
    /// Seconds to build the mesh (shared by the methods of a level).
    pub mesh_seconds: f64,
    /// Seconds of assembly, factorisation, solve and error evaluation.
    pub solve_seconds: f64,
}

impl StudyRow {
    /// The error in `norm`, if this row has it.
    pub fn error(&self, norm: Norm) -> Option<f64> {
        match norm {
            Norm::L2 => Some(self.l2),
            Norm::Max => Some(self.max),
            Norm::GradientL2 => self.gradient_l2,
            Norm::Flux => self.flux,
        }
    }
}

/// Observed orders of one method in one norm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Orders {
    pub method: String,
    pub norm: Norm,
    /// Between level k and k + 1 (None where undefined, e.g. a zero error).
    pub pairwise: Vec<Option<f64>>,
    /// Least-squares slope over all levels.
    pub least_squares: Option<f64>,
}

/// The rows of a study, method by method, each method's levels in order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyResult {
    /// The case file as named.
    pub case: String,
    pub title: Option<String>,
    pub refinement: Refinement,
    pub levels: usize,
    /// Method names in the order studied.
    pub methods: Vec<String>,
    pub rows: Vec<StudyRow>,
}

/// A minimum order that a study must reach: `ORDER[:TOL]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expectation {
    pub order: f64,
    /// Slack below `order` (default 0.15, the design's tolerance).
    pub tolerance: f64,
}

impl Expectation {
    /// The default tolerance.
    pub const DEFAULT_TOLERANCE: f64 = 0.15;
}

impl FromStr for Expectation {
    type Err = StudyError;

    /// ```
    /// use hasse_solver::study::Expectation;
    /// let e: Expectation = "2".parse().unwrap();
    /// assert_eq!((e.order, e.tolerance), (2.0, 0.15));
    /// let e: Expectation = "1:0.3".parse().unwrap();
    /// assert_eq!((e.order, e.tolerance), (1.0, 0.3));
    /// assert!("two".parse::<Expectation>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || StudyError::BadExpectation(s.to_string());
        let (order, tolerance) = match s.split_once(':') {
            Some((o, t)) => (o, Some(t)),
            None => (s, None),
        };
        let order: f64 = order.trim().parse().map_err(|_| bad())?;
        let tolerance: f64 = match tolerance {
            Some(t) => t.trim().parse().map_err(|_| bad())?,
            None => Self::DEFAULT_TOLERANCE,
        };
        if !order.is_finite() || !tolerance.is_finite() || tolerance < 0.0 {
            return Err(bad());
        }
        Ok(Self { order, tolerance })
    }
}

/// A method whose least-squares L² order missed an [`Expectation`].
#[derive(Clone, Debug, PartialEq)]
pub struct Shortfall {
    pub method: String,
    /// None when the order could not be computed (e.g. a zero error).
    pub observed: Option<f64>,
}

/// Why a study could not run.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error(transparent)]
    Case(#[from] CaseError),
    /// The case (with a level's overrides) or its mesh is invalid.
    #[error("{0}")]
    Invalid(Diagnostics),
    #[error("unknown method `{0}`; known: fd, fe, fv, fv-mimetic, dec, dec-barycentric")]
    UnknownMethod(String),
    #[error("`{0}` is not ORDER or ORDER:TOLERANCE with numbers (tolerance ≥ 0), e.g. 2 or 2:0.1")]
    BadExpectation(String),
    #[error("a study needs at least 1 level")]
    NoLevels,
    #[error("{case}: a convergence study compares methods on a diffusion problem; this case is kind = \"{kind}\"")]
    NotDiffusion { case: String, kind: &'static str },
    #[error("{case}: a convergence study needs the exact solution: add an [exact] table with `solution` (and `gradient` for gradient and flux errors)")]
    NoExact { case: String },
    /// The case's mesh cannot be refined as asked.
    #[error("{case}: {message}")]
    Refinement { case: String, message: String },
    /// A level failed to solve.
    #[error("{case}: level {level}, method {method}: {source}")]
    Run {
        case: String,
        level: usize,
        method: String,
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
    // A voronoi n counts sites in the plane: 4× the sites halve h.
    let factor = if generator == "voronoi" { 4 } else { 2 };
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
    /// use hasse_solver::study::{Norm, Refinement, Study};
    /// use hasse_solver::metric::Method;
    /// let case = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../cases/box-3d.toml"));
    /// let study = Study { levels: 2, refinement: Refinement::Uniform, methods: vec![Method::Fv] };
    /// let mut lines = Vec::new();
    /// let result = study
    ///     .run(case, &["mesh.n=[4,4,4]".into()], &mut |level, rows| lines.push((level, rows[0].unknowns)))
    ///     .unwrap();
    /// assert_eq!(lines, [(0, 64), (1, 512)]);                 // one call per level
    /// let p = result.orders("fv", Norm::L2).pairwise[0].unwrap();
    /// assert!((p - 2.0).abs() < 0.1);                          // TPFA on a uniform grid
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
            title: base.title.clone(),
            refinement: self.refinement,
            levels: self.levels,
            methods: methods.iter().map(|m| m.name().to_string()).collect(),
            rows: ordered,
        })
    }
}

impl StudyResult {
    /// The rows of one method, by level.
    pub fn method_rows<'a>(&'a self, method: &'a str) -> impl Iterator<Item = &'a StudyRow> + 'a {
        self.rows.iter().filter(move |r| r.method == method)
    }

    /// Observed orders of `method` in `norm`. Where some level lacks the
    /// norm (no exact gradient, no flux for this method), every order is
    /// None.
    pub fn orders(&self, method: &str, norm: Norm) -> Orders {
        let rows: Vec<&StudyRow> = self.method_rows(method).collect();
        let h: Vec<f64> = rows.iter().map(|r| r.h).collect();
        let e: Option<Vec<f64>> = rows.iter().map(|r| r.error(norm)).collect();
        let (pairwise, least_squares) = match e {
            Some(e) if rows.len() >= 2 => {
                let pairwise = (0..rows.len() - 1)
                    .map(|k| {
                        pairwise_orders(&h[k..k + 2], &e[k..k + 2])
                            .ok()
                            .map(|p| p[0])
                    })
                    .collect();
                (pairwise, least_squares_order(&h, &e).ok())
            }
            _ => (vec![None; rows.len().saturating_sub(1)], None),
        };
        Orders {
            method: method.to_string(),
            norm,
            pairwise,
            least_squares,
        }
    }

    /// The norms that every level of `method` has.
    pub fn norms(&self, method: &str) -> Vec<Norm> {
        Norm::ALL
            .into_iter()
            .filter(|&n| {
                let mut rows = self.method_rows(method).peekable();
                rows.peek().is_some() && rows.all(|r| r.error(n).is_some())
            })
            .collect()
    }

    /// The methods whose least-squares L² order is below
    /// `expect.order − expect.tolerance` (or cannot be computed).
    ///
    /// ```
    /// use hasse_solver::study::{Expectation, Refinement, StudyResult, StudyRow};
    /// let row = |level: usize, h: f64, l2: f64| StudyRow {
    ///     method: "fv".into(), level, resolution: vec![], h, cells: 0, unknowns: 0,
    ///     l2, max: l2, gradient_l2: None, flux: None, mesh_seconds: 0.0, solve_seconds: 0.0,
    /// };
    /// let result = StudyResult {
    ///     case: "demo".into(), title: None, refinement: Refinement::Uniform, levels: 2,
    ///     methods: vec!["fv".into()], rows: vec![row(0, 0.1, 1e-2), row(1, 0.05, 2.5e-3)],
    /// };
    /// assert!(result.shortfalls(Expectation { order: 2.0, tolerance: 0.15 }).is_empty());
    /// assert_eq!(result.shortfalls("3".parse().unwrap())[0].method, "fv");
    /// ```
    pub fn shortfalls(&self, expect: Expectation) -> Vec<Shortfall> {
        self.methods
            .iter()
            .filter_map(|m| {
                let observed = self.orders(m, Norm::L2).least_squares;
                match observed {
                    Some(p) if p >= expect.order - expect.tolerance => None,
                    _ => Some(Shortfall {
                        method: m.clone(),
                        observed,
                    }),
                }
            })
            .collect()
    }
}

mod table;
