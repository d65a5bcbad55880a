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

mod dec_spec;
pub mod diagnostic;
mod elasticity_spec;
pub mod expr;
mod growth_spec;
mod hodge_spec;
mod mesh_checks;
mod problem;
mod quantity;
mod reader;
mod transport_spec;

pub use dec_spec::{CohomologySpec, DecompositionSpec, FormDiffusionSpec};
pub use diagnostic::{Diagnostic, Diagnostics};
pub use elasticity_spec::{ElasticBoundaryKind, ElasticBoundarySpec, ElasticitySpec, MaterialSpec};
pub use growth_spec::GrowthSpec;
pub use hodge_spec::{HodgeMethod, HodgeSpec};
pub use problem::*;
pub use quantity::{ProbeSpec, QuantityKind, QuantitySpec};
pub use transport_spec::TransportSpec;

use crate::frontend::mesh_spec::{MeshError, MeshSpec};
use crate::la::direct::Factorization;
use crate::la::ordering::Ordering;
use crate::metric::Method;
use crate::multigrid::CellProlongation;
use crate::physics::nonlinear::Iteration;
use diagnostic::Collector;
use expr::{Expression, Scope};
use hasse_complex::Complex;
use reader::Reader;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The exact solution, when known (`[exact]`).
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// let text = r#"
/// [mesh]
/// generator = "rectangle"
/// n = [2, 2]
/// [problem]
/// method = "fe"
/// [exact]
/// solution = "x * y"
/// gradient = ["y", "x"]
/// "#;
/// let case = Case::from_text("x.toml", text, &[]).unwrap();
/// let exact = case.exact.unwrap();
/// assert_eq!(exact.solution.unwrap().eval(&[2.0, 3.0], 0.0), 6.0);
/// let gradient = exact.gradient.unwrap();
/// assert_eq!((gradient[0].eval(&[2.0, 3.0], 0.0), gradient[1].eval(&[2.0, 3.0], 0.0)), (3.0, 2.0));
/// assert!(exact.eigenvalues.is_empty() && exact.displacement.is_none());
/// ```
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
    /// The exact k-form of a Poisson problem for k-forms: its proxy field,
    /// one expression per coordinate (vector) or one (scalar).
    pub form: Option<Vec<Expression>>,
}

/// Which linear solver a diffusion case uses (`solver.type`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, SolverKind};
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fv\"\n";
/// assert_eq!(Case::from_text("s.toml", text, &[]).unwrap().solver.kind, SolverKind::Direct);
/// let amg = ["solver.type=\"amg\"".to_string()];
/// assert_eq!(Case::from_text("s.toml", text, &amg).unwrap().solver.kind, SolverKind::Amg);
/// ```
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
    /// PETSc over MPI (`mpirun -np N hasse run …`; the cargo feature
    /// `mpi`): CG + GAMG by default, MUMPS when a factorisation is asked
    /// for, and `[solver.petsc] options` on top.
    Petsc,
    /// Restarted GMRES(30) with ILU(0), for the nonsymmetric systems of
    /// `kind = "transport"` ([`crate::la::krylov`]).
    Gmres,
    /// BiCGStab with ILU(0), for `kind = "transport"`.
    Bicgstab,
}

/// Linear solver settings (`[solver]`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, SolverSpec};
/// use hasse_solver::la::direct::Factorization;
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fv\"\n[solver]\nfactorization = \"ldlt\"\n";
/// let solver = Case::from_text("s.toml", text, &[]).unwrap().solver;
/// assert_eq!(solver, SolverSpec { factorization: Some(Factorization::Ldlt), ..SolverSpec::default() });
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSpec {
    /// `solver.type` (default direct).
    pub kind: SolverKind,
    /// Relative residual the multigrid-preconditioned CG stops at.
    pub tolerance: f64,
    /// `solver.factorization`; `None` leaves the choice to the problem
    /// (LLᵀ, or the constrained LDLᵀ of Darcy).
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
    /// `[solver.petsc] options`: PETSc's own command-line options
    /// (`"-ksp_type cg -pc_type hypre"`), applied after hasse's defaults.
    pub petsc_options: String,
    /// `solver.preconditioner = "multigrid"` (default `"ilu0"`): GMRES and
    /// BiCGStab of a transport case preconditioned by a multigrid V-cycle
    /// of the diffusion part instead of ILU(0).
    pub multigrid_preconditioner: bool,
    /// Newton/Picard settings of a nonlinear problem (`[solver.nonlinear]`).
    pub nonlinear: NonlinearSolverSpec,
}

/// `[solver.nonlinear]`: how a nonlinear diffusion problem iterates.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// use hasse_solver::physics::nonlinear::Iteration;
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fv\"\nreaction = \"u^3\"\n[solver.nonlinear]\nmethod = \"picard\"\nmax_iterations = 80\nmonitor = true\n";
/// let nonlinear = Case::from_text("n.toml", text, &[]).unwrap().solver.nonlinear;
/// assert_eq!((nonlinear.iteration, nonlinear.max_iterations, nonlinear.monitor), (Iteration::Picard, 80, true));
/// assert_eq!(nonlinear.tolerance, 1e-10);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct NonlinearSolverSpec {
    /// `method`: "newton" (default) or "picard".
    pub iteration: Iteration,
    /// `tolerance`: the residual relative to the size of its terms
    /// (default 1e-10).
    pub tolerance: f64,
    /// `max_iterations` (default 50).
    pub max_iterations: usize,
    /// `monitor`: one line per iteration on stderr (default false).
    pub monitor: bool,
    /// `linear = "krylov"`: Newton–Krylov steps (GMRES preconditioned by
    /// an LLᵀ of the Jacobian's symmetric part) instead of an LU per step
    /// (`"direct"`, the default); `"krylov-multigrid"` preconditions by an
    /// algebraic multigrid V-cycle of that part instead.
    pub krylov: bool,
    /// The preconditioner of Newton–Krylov steps.
    pub preconditioner: crate::physics::nonlinear::KrylovPreconditioner,
}

impl Default for NonlinearSolverSpec {
    fn default() -> Self {
        Self {
            iteration: Iteration::Newton,
            tolerance: 1e-10,
            max_iterations: 50,
            monitor: false,
            krylov: false,
            preconditioner: crate::physics::nonlinear::KrylovPreconditioner::Factor,
        }
    }
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
            petsc_options: String::new(),
            multigrid_preconditioner: false,
            nonlinear: NonlinearSolverSpec::default(),
        }
    }
}

/// Where results go (`[output]`).
///
/// ```
/// use hasse_solver::frontend::case::{Case, OutputSpec};
/// use std::path::PathBuf;
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [2, 2]\n[problem]\nmethod = \"fv\"\n";
/// // By default the stem is the case file's, in the working directory.
/// let output = Case::from_text("cases/plate.toml", text, &[]).unwrap().output;
/// assert_eq!(output, OutputSpec { directory: PathBuf::from("."), name: "plate".into(), write: true, quantities: vec![], probes: vec![], fields: None, partial: true, complex: Default::default() });
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSpec {
    /// Directory (relative to the working directory).
    pub directory: PathBuf,
    /// File stem: `<directory>/<name>.h5` and `.xdmf`.
    pub name: String,
    /// Whether to write files at all.
    pub write: bool,
    /// `[[output.quantity]]` tables, in order.
    pub quantities: Vec<QuantitySpec>,
    /// `[[output.probe]]` tables, in order.
    pub probes: Vec<ProbeSpec>,
    /// `fields`: the names of the fields to write (`None`: all).
    pub fields: Option<Vec<String>>,
    /// `partial`: whether a transient run writes each level as it
    /// completes to a partial output (default true).
    pub partial: bool,
    /// `complex`: how much of the complex the h5 file stores, `"minimal"`
    /// (default: vertices, the cells the fields and grids live on, tags)
    /// or `"full"` (besides, every M_p and every ∂_p).
    pub complex: crate::frontend::output::ComplexLayout,
}

impl OutputSpec {
    /// Whether the field called `name` is written.
    pub fn keeps(&self, name: &str) -> bool {
        self.fields
            .as_ref()
            .is_none_or(|fields| fields.iter().any(|f| f == name))
    }
}

/// One `[regions]` entry: `name = "condition"` tags the top cells whose
/// centroid satisfies the condition; `name = { faces = "condition" }` the
/// (n−1)-cells (an interface to measure a flux across).
#[derive(Clone, Debug)]
pub struct RegionSpec {
    /// The tag's name.
    pub name: String,
    /// The condition on the centroid (nonzero where it holds).
    pub condition: Expression,
    /// Whether it tags (n−1)-cells instead of top cells.
    pub faces: bool,
}

/// A case file, read and checked.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// let text = r#"
/// title = "Ramp"
/// [constants]
/// slope = 2
/// [definitions]
/// u = "slope * x"
/// [mesh]
/// generator = "interval"
/// n = [4]
/// [problem]
/// method = "fe"
/// [[boundary]]
/// tag = "boundary"
/// type = "dirichlet"
/// value = "u"
/// "#;
/// let case = Case::from_text("ramp.toml", text, &[]).unwrap();
/// assert_eq!(case.title.as_deref(), Some("Ramp"));
/// assert_eq!(case.constants["slope"], 2.0);
/// // Definitions are names every expression of the case may use.
/// assert_eq!(case.scope.parse("u + 1").unwrap().eval(&[0.5], 0.0), 2.0);
/// assert_eq!(case.build_mesh().unwrap().cell_count(1), 4);
/// ```
#[derive(Clone, Debug)]
pub struct Case {
    /// The case file's path as given.
    pub path: PathBuf,
    /// The text after `--set` overrides (stored with the results).
    pub text: String,
    /// `title`, if given.
    pub title: Option<String>,
    /// `[constants]`, evaluated.
    pub constants: BTreeMap<String, f64>,
    /// The names expressions of the case may use: coordinates, `pi`, the
    /// constants and the `[definitions]`.
    pub scope: Scope,
    /// `[mesh]`: how to build the complex ([`Case::build_mesh`]).
    pub mesh: MeshSpec,
    /// `[regions]`: tags defined by a condition on the centroids of top
    /// cells (or of (n−1)-cells), added to the mesh when it is built.
    pub regions: Vec<RegionSpec>,
    /// `[problem]` and its boundary conditions.
    pub problem: Problem,
    /// `[exact]`, if given.
    pub exact: Option<ExactSpec>,
    /// `[solver]`, defaults where absent.
    pub solver: SolverSpec,
    /// `[output]`, defaults where absent.
    pub output: OutputSpec,
    /// SPLIT refinement steps after the first solve, if any.
    pub refine: Option<crate::refine::RefineSpec>,
    /// What reading found worth saying that does not stop the case (a
    /// key left unused by a `--set` override), each with its position;
    /// `hasse check`, `run` and `refine` print them as `warning: …`.
    pub warnings: Vec<Diagnostic>,
    /// Keeps spans for messages found after reading (mesh problems).
    collector: Collector,
    mesh_spans: BTreeMap<String, Range<usize>>,
}

/// Why a case could not be loaded or its mesh built.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// The file could not be read (missing, unreadable, not UTF-8).
    #[error("{path}: cannot read the case file: {source}")]
    Io {
        /// The path as given.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The case has problems: every one found, with its position.
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
    /// relative paths (mesh files, metric files). `overrides` are
    /// `--set` assignments, `key.path=value`.
    ///
    /// ```
    /// use hasse_solver::frontend::case::Case;
    /// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nmethod = \"fe\"\n";
    /// let set = ["problem.method=fv".to_string(), "problem.sorce=1".to_string()];
    /// let errors = Case::from_text("demo.toml", text, &set).unwrap_err();
    /// // A misspelt key is reported at the --set text that wrote it.
    /// assert_eq!(errors.len(), 1);
    /// assert!(errors.to_string().contains("--set problem.sorce=1"));
    /// ```
    pub fn from_text(file: &str, text: &str, overrides: &[String]) -> Result<Case, Diagnostics> {
        let (text, overridden) = reader::apply_overrides(file, text, overrides)?;
        Reader::read(file, &text, overridden)
    }

    /// Build the mesh and check the boundary tags against it; problems are
    /// reported with the case file's line numbers.
    pub fn build_mesh(&self) -> Result<Complex, Diagnostics> {
        let mut collector = self.collector.clone();
        collector.diagnostics.clear();
        let mut complex = match self.mesh.build(&self.path) {
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
        self.apply_regions(&mut complex, &mut collector);
        self.check_regional_data(&complex, &mut collector);
        self.check_quantities(&complex, &mut collector);
        self.check_probes(&complex, &mut collector);
        self.check_hodge(&complex, &mut collector);
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
            Problem::Transport(t) => Some(t.method),
            Problem::Growth(g) => Some(g.method),
            Problem::Gradient(_)
            | Problem::Darcy(_)
            | Problem::Maxwell(_)
            | Problem::Hodge(_)
            | Problem::Cohomology(_)
            | Problem::Decomposition(_)
            | Problem::FormDiffusion(_)
            | Problem::Elasticity(_)
            | Problem::Coupled(_) => None,
        }
    }
}
