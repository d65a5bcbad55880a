//! Case files: a TOML description of a problem that `hasse run` solves.
//!
//! Every key is documented in `cases/README.md`. A minimal case:
//!
//! ```toml
//! [mesh]
//! generator = "rectangle"
//! n = [16, 16]
//!
//! [problem]
//! method = "fe"
//! source = "2 * pi^2 * sin(pi*x) * sin(pi*y)"
//!
//! [[boundary]]
//! tag = "boundary"
//! type = "dirichlet"
//! value = 0
//! ```
//!
//! Reading checks the whole file and reports every problem at once, each
//! with its line, column and key ([`Diagnostics`]); building the mesh and
//! checking the boundary tags against it is a second step
//! ([`Case::build_mesh`]) because it can be expensive.
//!
//! ```
//! use hasse_solver::frontend::case::Case;
//! let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n\n[problem]\nmethod = \"fv\"\nsource = 1\n\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = \"x*y\"\n";
//! let case = Case::from_text("demo.toml", text, &[]).unwrap();
//! let complex = case.build_mesh().unwrap();
//! assert_eq!(complex.cell_count(2), 16);
//! let bad = Case::from_text("demo.toml", &text.replace("method", "methdo"), &[]).unwrap_err();
//! assert!(bad.to_string().contains("demo.toml:6:1: `problem.methdo`: unknown key"));
//! ```

pub mod diagnostic;
pub mod expr;
mod reader;

pub use diagnostic::{Diagnostic, Diagnostics};

use crate::frontend::mesh_spec::{MeshError, MeshSpec};
use crate::la::direct::Factorization;
use crate::la::ordering::Ordering;
use crate::metric::Method;
use crate::multigrid::CellProlongation;
use diagnostic::Collector;
use expr::{Expression, Scope};
use hasse_complex::Complex;
use reader::Reader;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A diffusion coefficient: scalar or a full symmetric tensor, each entry
/// an expression.
#[derive(Clone, Debug)]
pub enum Coefficient {
    Scalar(Expression),
    /// Rows of the tensor (d × d, d the embedding dimension).
    Tensor(Vec<Vec<Expression>>),
}

/// A boundary condition of the case.
#[derive(Clone, Debug)]
pub struct BoundarySpec {
    /// Tag of (n−1)-cells in the mesh.
    pub tag: String,
    pub kind: BoundaryKindSpec,
    /// Where the `tag` key is, for messages about the mesh.
    pub(crate) tag_span: Option<Range<usize>>,
    pub(crate) key: String,
}

/// Kind and data of a boundary condition.
#[derive(Clone, Debug)]
pub enum BoundaryKindSpec {
    Dirichlet(Expression),
    Neumann(Expression),
    Robin {
        alpha: Expression,
        value: Expression,
    },
}

/// The metric of a gradient problem (the face-to-face Ω of the thesis's
/// Ch. 6).
#[derive(Clone, Debug, PartialEq)]
pub enum GradientMetric {
    /// Ω = σ I.
    Diagonal(f64),
    /// Ω read from a file of `row column value` triplets (face ids of the
    /// mesh, 0-based), times `scale`.
    File { path: PathBuf, scale: f64 },
    /// The two-point metric σ_F = |F| / d_F of the mesh geometry.
    TwoPoint,
}

/// −∇·(K∇u) = f with boundary conditions.
#[derive(Clone, Debug)]
pub struct DiffusionSpec {
    pub method: Method,
    pub conductivity: Coefficient,
    pub source: Expression,
    pub boundary: Vec<BoundarySpec>,
    /// Two-point flux with unknowns at circumcentres instead of centroids.
    pub circumcentres: bool,
}

/// g = Ω δ f: a cell field's "normal gradient" as a face cochain.
#[derive(Clone, Debug)]
pub struct GradientSpec {
    /// The field sampled at top-cell centroids.
    pub field: Expression,
    pub metric: GradientMetric,
}

/// The time stepping of a transient problem (`[time]`).
#[derive(Clone, Debug, PartialEq)]
pub struct TimeSpec {
    /// Constant step Δt > 0.
    pub dt: f64,
    /// Number of steps taken from t₀.
    pub steps: usize,
    /// Start time t₀.
    pub start: f64,
    /// θ of the θ-scheme: 1 backward Euler, ½ Crank–Nicolson.
    pub theta: f64,
    /// Every how many steps a level is written (t₀ and the last always are).
    pub save_every: usize,
}

/// ∂u/∂t − ∇·(K∇u) = f(x, t) from u(x, t₀) = `initial`.
#[derive(Clone, Debug)]
pub struct HeatSpec {
    pub method: Method,
    pub conductivity: Coefficient,
    /// f(x, t).
    pub source: Expression,
    /// u(x, t₀).
    pub initial: Expression,
    /// Values may depend on t; a Robin α may not.
    pub boundary: Vec<BoundarySpec>,
    pub time: TimeSpec,
}

/// Mixed Darcy: u = −K∇p, ∇·u = f, flux on faces and pressure on cells.
///
/// Boundary conditions reuse [`BoundarySpec`]: `type = "pressure"` is read
/// as [`BoundaryKindSpec::Dirichlet`] (p given), `type = "flux"` as
/// [`BoundaryKindSpec::Neumann`] with the value the outward normal velocity
/// u·n. Boundary faces in no tag are no-flow.
#[derive(Clone, Debug)]
pub struct DarcySpec {
    pub mass: crate::metric::fv::FluxMass,
    pub permeability: Coefficient,
    pub source: Expression,
    pub boundary: Vec<BoundarySpec>,
}

/// Resonant modes of a cavity with perfectly conducting walls.
#[derive(Clone, Debug, PartialEq)]
pub struct MaxwellSpec {
    /// The dual whose Hodge stars ⋆₁, ⋆₂ are used.
    pub dual: hasse_complex::DualKind,
    pub mass: crate::physics::maxwell::Mass,
    /// How many of the smallest nonzero ω² to compute.
    pub modes: usize,
}

/// The material of an elasticity problem.
#[derive(Clone, Debug)]
pub enum MaterialSpec {
    Lame {
        lambda: Expression,
        mu: Expression,
    },
    Young {
        young: Expression,
        poisson: Expression,
    },
}

/// A boundary condition of an elasticity problem.
#[derive(Clone, Debug)]
pub enum ElasticBoundaryKind {
    /// u = g (all components), or u_a = g for one component a.
    Displacement {
        component: Option<usize>,
        value: Vec<Expression>,
    },
    /// σ n = t.
    Traction(Vec<Expression>),
}

/// A tagged elasticity boundary condition.
#[derive(Clone, Debug)]
pub struct ElasticBoundarySpec {
    pub tag: String,
    pub kind: ElasticBoundaryKind,
    pub(crate) tag_span: Option<Range<usize>>,
    pub(crate) key: String,
}

/// Linear elasticity −∇·σ(u) = f, displacement on vertices.
#[derive(Clone, Debug)]
pub struct ElasticitySpec {
    pub material: MaterialSpec,
    /// f, one expression per coordinate.
    pub body_force: Vec<Expression>,
    pub plane: crate::physics::elasticity::PlaneModel,
    pub boundary: Vec<ElasticBoundarySpec>,
}

/// One field of a coupled problem: its own diffusion operator and data.
#[derive(Clone, Debug)]
pub struct CoupledFieldSpec {
    pub name: String,
    pub diffusion: DiffusionSpec,
    /// The exact field, when known.
    pub exact: Option<Expression>,
}

/// Two diffusion fields coupled by linear reaction terms:
/// −∇·(D₁∇u) + a u − b v = f, −∇·(D₂∇v) − b u + c v = g.
#[derive(Clone, Debug)]
pub struct CoupledSpec {
    pub fields: [CoupledFieldSpec; 2],
    pub a: Expression,
    pub b: Expression,
    pub c: Expression,
}

/// What the case solves.
#[derive(Clone, Debug)]
pub enum Problem {
    Diffusion(DiffusionSpec),
    Gradient(GradientSpec),
    Heat(HeatSpec),
    Darcy(DarcySpec),
    Maxwell(MaxwellSpec),
    Elasticity(ElasticitySpec),
    Coupled(Box<CoupledSpec>),
}

impl Problem {
    /// The `problem.kind` that names this problem.
    pub fn kind(&self) -> &'static str {
        match self {
            Problem::Diffusion(_) => "diffusion",
            Problem::Gradient(_) => "gradient",
            Problem::Heat(_) => "heat",
            Problem::Darcy(_) => "darcy",
            Problem::Maxwell(_) => "maxwell",
            Problem::Elasticity(_) => "elasticity",
            Problem::Coupled(_) => "coupled",
        }
    }

    /// The scalar boundary conditions (diffusion, heat, Darcy).
    pub fn boundary(&self) -> &[BoundarySpec] {
        match self {
            Problem::Diffusion(d) => &d.boundary,
            Problem::Heat(h) => &h.boundary,
            Problem::Darcy(d) => &d.boundary,
            Problem::Gradient(_)
            | Problem::Maxwell(_)
            | Problem::Elasticity(_)
            | Problem::Coupled(_) => &[],
        }
    }

    /// (tag, where the tag is written, `boundary[i]`) of every boundary
    /// condition, whatever the kind.
    fn boundary_tags(&self) -> Vec<(&str, Option<Range<usize>>, &str)> {
        match self {
            Problem::Elasticity(e) => e
                .boundary
                .iter()
                .map(|b| (b.tag.as_str(), b.tag_span.clone(), b.key.as_str()))
                .collect(),
            Problem::Coupled(c) => c
                .fields
                .iter()
                .flat_map(|f| &f.diffusion.boundary)
                .map(|b| (b.tag.as_str(), b.tag_span.clone(), b.key.as_str()))
                .collect(),
            other => other
                .boundary()
                .iter()
                .map(|b| (b.tag.as_str(), b.tag_span.clone(), b.key.as_str()))
                .collect(),
        }
    }

    /// The diffusion coefficient or permeability, if the problem has one.
    pub fn coefficient(&self) -> Option<&Coefficient> {
        match self {
            Problem::Diffusion(d) => Some(&d.conductivity),
            Problem::Heat(h) => Some(&h.conductivity),
            Problem::Darcy(d) => Some(&d.permeability),
            Problem::Gradient(_)
            | Problem::Maxwell(_)
            | Problem::Elasticity(_)
            | Problem::Coupled(_) => None,
        }
    }

    /// Every coefficient K of the problem with its key: the conductivity
    /// or permeability, or each field's conductivity.
    pub fn coefficients(&self) -> Vec<(String, &Coefficient)> {
        match self {
            Problem::Diffusion(d) => vec![("problem.conductivity".into(), &d.conductivity)],
            Problem::Heat(h) => vec![("problem.conductivity".into(), &h.conductivity)],
            Problem::Darcy(d) => vec![("problem.permeability".into(), &d.permeability)],
            Problem::Coupled(c) => c
                .fields
                .iter()
                .enumerate()
                .map(|(i, f)| {
                    (
                        format!("field[{i}].conductivity"),
                        &f.diffusion.conductivity,
                    )
                })
                .collect(),
            Problem::Gradient(_) | Problem::Maxwell(_) | Problem::Elasticity(_) => Vec::new(),
        }
    }
}

/// The exact solution, when known.
#[derive(Clone, Debug)]
pub struct ExactSpec {
    /// u(x, y, z) (and t for heat; the pressure for Darcy). Absent for
    /// eigenproblems.
    pub solution: Option<Expression>,
    /// ∇u, one expression per coordinate (enables flux errors).
    pub gradient: Option<Vec<Expression>>,
    /// Exact eigenvalues, ascending (Maxwell: ω²).
    pub eigenvalues: Vec<f64>,
    /// The exact displacement of an elasticity problem, per coordinate.
    pub displacement: Option<Vec<Expression>>,
}

/// Which linear solver a diffusion case uses (`solver.type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SolverKind {
    /// Sparse direct factorisation (faer).
    #[default]
    Direct,
    /// CG preconditioned by a geometric multigrid V-cycle on the
    /// generator's grid levels.
    Multigrid,
    /// CG preconditioned by smoothed-aggregation algebraic multigrid.
    Amg,
    /// [`crate::multigrid::automatic`] decides.
    Auto,
}

/// Linear solver settings.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSpec {
    pub kind: SolverKind,
    /// Relative residual the multigrid-preconditioned CG stops at.
    pub tolerance: f64,
    pub factorization: Option<Factorization>,
    /// A relative residual above this is reported as a warning.
    pub residual_warning: f64,
    /// A relative residual above this fails the run (exit code 1).
    pub residual_limit: f64,
    /// How a grid hierarchy prolongs cell-centred unknowns.
    pub cell_prolongation: CellProlongation,
    /// Fill-reducing ordering of the direct factorisation
    /// (`solver.ordering`).
    pub ordering: Ordering,
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            kind: SolverKind::Direct,
            tolerance: 1e-8,
            factorization: None,
            residual_warning: 1e-10,
            residual_limit: 1e-6,
            cell_prolongation: CellProlongation::Smoothed,
            ordering: Ordering::Automatic,
        }
    }
}

/// Where results go.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSpec {
    /// Directory (relative to the working directory).
    pub directory: PathBuf,
    /// File stem: `<directory>/<name>.h5` and `.xdmf`.
    pub name: String,
    /// Whether to write files at all.
    pub write: bool,
}

/// A case file, read and checked.
#[derive(Clone, Debug)]
pub struct Case {
    /// The case file's path as given.
    pub path: PathBuf,
    /// The text after `--set` overrides (stored with the results).
    pub text: String,
    pub title: Option<String>,
    pub constants: BTreeMap<String, f64>,
    pub scope: Scope,
    pub mesh: MeshSpec,
    pub problem: Problem,
    pub exact: Option<ExactSpec>,
    pub solver: SolverSpec,
    pub output: OutputSpec,
    /// SPLIT refinement steps after the first solve, if any.
    pub refine: Option<crate::refine::RefineSpec>,
    /// Keeps spans for messages found after reading (mesh problems).
    collector: Collector,
    mesh_spans: BTreeMap<String, Range<usize>>,
}

/// Why a case could not be loaded or its mesh built.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("{path}: cannot read the case file: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{0}")]
    Invalid(Diagnostics),
}

impl Case {
    /// Read a case file, apply `key=value` overrides, check everything.
    pub fn read(path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let mut case = Case::from_text(&path.display().to_string(), &text, overrides)
            .map_err(CaseError::Invalid)?;
        case.path = path.to_path_buf();
        Ok(case)
    }

    /// Read a case from text; `file` names it in messages and anchors
    /// relative paths (mesh files, metric files).
    pub fn from_text(file: &str, text: &str, overrides: &[String]) -> Result<Case, Diagnostics> {
        let (text, overridden) = reader::apply_overrides(file, text, overrides)?;
        Reader::read(file, &text, overridden)
    }

    /// Build the mesh and check the boundary tags against it; problems are
    /// reported with the case file's line numbers.
    pub fn build_mesh(&self) -> Result<Complex, Diagnostics> {
        let mut collector = self.collector.clone();
        collector.diagnostics.clear();
        let complex = match self.mesh.build(&self.path) {
            Ok(complex) => complex,
            Err(e) => {
                let (key, message) = match &e {
                    MeshError::Key { key, message, .. } => (key.to_string(), message.clone()),
                    other => ("file".to_string(), other.to_string()),
                };
                let span = self
                    .mesh_spans
                    .get(&key)
                    .or_else(|| self.mesh_spans.get(""))
                    .cloned();
                let help = (key == "file")
                    .then(|| "mesh paths are relative to the case file's directory".to_string());
                collector.error(span, &format!("mesh.{key}"), message, help);
                return Err(Diagnostics(collector.diagnostics));
            }
        };
        {
            let n = complex.dim();
            let available: Vec<String> = complex
                .tags()
                .iter()
                .filter(|(_, t)| n > 0 && t.dim == n - 1)
                .map(|(name, _)| name.to_string())
                .collect();
            for (tag, tag_span, key) in self.problem.boundary_tags() {
                match complex.tag(tag) {
                    None => {
                        let help = match expr::closest(tag, &available) {
                            Some(s) => format!(
                                "did you mean `{s}`? the mesh has: {}",
                                available.join(", ")
                            ),
                            None if available.is_empty() => {
                                "the mesh has no boundary tags (a closed surface has no boundary)"
                                    .into()
                            }
                            None => format!("the mesh has: {}", available.join(", ")),
                        };
                        collector.error(
                            tag_span.clone(),
                            &format!("{}.tag", key),
                            format!("no tag `{}` in the mesh", tag),
                            Some(help),
                        );
                    }
                    Some(t) if t.dim + 1 != n => collector.error(
                        tag_span.clone(),
                        &format!("{}.tag", key),
                        format!(
                            "tag `{}` names {}-cells; boundary conditions need {}-cells",
                            tag,
                            t.dim,
                            n.saturating_sub(1)
                        ),
                        None,
                    ),
                    Some(_) => {}
                }
            }
            for (key, coefficient) in self.problem.coefficients() {
                let Coefficient::Tensor(rows) = coefficient else {
                    continue;
                };
                let d = complex.embedding_dim();
                if rows.len() != d {
                    collector.error(
                        None,
                        &key,
                        format!(
                            "a {}×{} tensor, but the mesh lives in {d} dimensions",
                            rows.len(),
                            rows.len()
                        ),
                        Some(format!("give {d} rows of {d} entries")),
                    );
                }
            }
        }
        if collector.diagnostics.is_empty() {
            Ok(complex)
        } else {
            Err(Diagnostics(collector.diagnostics))
        }
    }

    /// A diagnostic about key `key` (e.g. `problem.source`,
    /// `boundary[1].value`) of this case: at the line and column where the
    /// key is written, or at the `--set` text that gave it, or at the file
    /// when the case does not write the key (a default).
    pub fn diagnostic(
        &self,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) -> Diagnostic {
        self.collector.diagnostic(None, key, message, help)
    }

    /// The method of a diffusion or heat problem.
    pub fn method(&self) -> Option<Method> {
        match &self.problem {
            Problem::Diffusion(d) => Some(d.method),
            Problem::Heat(h) => Some(h.method),
            Problem::Gradient(_)
            | Problem::Darcy(_)
            | Problem::Maxwell(_)
            | Problem::Elasticity(_)
            | Problem::Coupled(_) => None,
        }
    }
}
