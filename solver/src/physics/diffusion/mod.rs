//! Scalar diffusion −∇·(K ∇u) = f in canonical form, with boundary
//! conditions on tagged boundary regions.
//!
//! Every method is the same assembly M = Aᵀ Ω A with a different Ω and,
//! for the hybrid mimetic method, a different A. Boundary conditions are
//! written in the same language:
//!
//! - Dirichlet on a cell-centred method keeps the boundary face as a row of
//!   A (a "ghost" at the face) and moves the known value to the right-hand
//!   side, b += Aᵀ Ω w with w the signed boundary values; on nodal and
//!   hybrid unknowns the fixed values are eliminated symmetrically (the
//!   system on the free unknowns stays symmetric positive definite).
//! - Neumann, K∇u·n = g with n the outward normal, adds ∫_F g to the
//!   equation of the unknown(s) at the face and removes the face's ghost.
//! - Robin, K∇u·n + α u = g, adds a row to A with one entry at the boundary
//!   unknown (a ghost with value g/α), weighted by α|F| in Ω (lumped on
//!   vertices for nodal methods); for cell-centred methods the ghost sits
//!   behind the cell-to-face transmissibility σ, giving σα|F|/(σ + α|F|).
//!
//! Unlisted boundary faces are homogeneous Neumann (no flux). A problem
//! without any Dirichlet or Robin boundary is singular: it is detected,
//! the data are checked for compatibility (Σ sources + Σ boundary fluxes
//! = 0 up to quadrature error), and the solution with zero mean is returned.

use crate::la::direct::{self, DirectSolver, Factorization, SolveError, SolveReport};
use crate::la::iterative::{conjugate_gradient, CgError, CgOptions, CgReport, RowMatrix};
use crate::la::ordering::Ordering;
use crate::la::ordering::UnknownPoints;
use crate::metric::{self, dec, fd, fe, fv, CellTensors, MetricError, Tensor};
use crate::multigrid::{
    self, CellProlongation, Hierarchy, Multigrid, MultigridError, MultigridOptions, SolverChoice,
};
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use hasse_complex::dual::DualKind;
use hasse_complex::Complex;
use rayon::prelude::*;
use sprs::TriMat;
use std::sync::Arc;
use std::time::Instant;

/// A scalar function of position.
pub type ScalarFn = Arc<dyn Fn(&[f64]) -> f64 + Send + Sync>;
/// A tensor-valued function of position.
pub type TensorFn = Arc<dyn Fn(&[f64]) -> Tensor + Send + Sync>;
/// A vector-valued function of position (gradients of exact solutions).
pub type VectorFn = Arc<dyn Fn(&[f64]) -> [f64; 3] + Send + Sync>;

/// The diffusion coefficient K.
#[derive(Clone)]
pub enum Conductivity {
    /// K = λ(x) I.
    Scalar(ScalarFn),
    /// A symmetric positive definite tensor field.
    Tensor(TensorFn),
}

/// The discretisation: which Ω (and A) to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Five/seven-point finite differences on cell centres of an axis-aligned grid.
    Fd,
    /// Nodal finite elements: P1 on simplices, Q1 on quads/hexes, lowest-order
    /// virtual elements on other polytopes.
    Fe,
    /// Cell-centred finite volumes with the two-point flux.
    Fv,
    /// Hybrid mimetic finite differences (cell and face unknowns).
    FvMimetic,
    /// Discrete exterior calculus on vertices with the given dual.
    Dec(DualKind),
}

impl Method {
    /// The name used in case files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Fd => "fd",
            Method::Fe => "fe",
            Method::Fv => "fv",
            Method::FvMimetic => "fv-mimetic",
            Method::Dec(DualKind::Circumcentric) => "dec",
            Method::Dec(DualKind::Barycentric) => "dec-barycentric",
        }
    }
}

/// Where the cell values of the two-point finite-volume method ([`Method::Fv`])
/// are located. The two-point flux is consistent only when the line between
/// two neighbouring cell points is orthogonal to their common face; on
/// meshes that are orthogonal for other points than the centroids, put the
/// unknowns there.
///
/// ```
/// use hasse_complex::generate::voronoi_with_sites;
/// use hasse_solver::physics::diffusion::{CellPoints, Conductivity, Diffusion, Method, BoundaryKind};
/// use std::sync::Arc;
/// let (mesh, sites) = voronoi_with_sites(100, [0.0, 1.0], [0.0, 1.0], 1, 0).unwrap();
/// let u = |x: &[f64]| 1.0 + 2.0 * x[0] - x[1];
/// let mut problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 0.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(u)));
/// problem.cell_points = CellPoints::Given(sites.iter().flatten().copied().collect());
/// let solution = problem.solve(&mesh).unwrap();
/// // Linear solutions are reproduced exactly at the sites.
/// for (c, s) in sites.iter().enumerate() {
///     assert!((solution.values[c] - u(s)).abs() < 1e-11);
/// }
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CellPoints {
    /// Cell centroids: consistent on K-orthogonal grids (boxes).
    #[default]
    Centroids,
    /// Circumcentres of simplices: consistent on Delaunay triangulations
    /// and well-centred simplicial meshes.
    Circumcentres,
    /// One point per top cell (stride d), e.g. the sites of a Voronoi mesh.
    Given(Arc<[f64]>),
}

/// Where the unknowns of a method live.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// On vertices (0-cells).
    Nodal,
    /// On top cells.
    CellCentred,
    /// On top cells, then on (n−1)-cells.
    Hybrid,
}

/// A boundary condition's kind and data.
#[derive(Clone)]
pub enum BoundaryKind {
    /// u = g.
    Dirichlet(ScalarFn),
    /// K∇u·n = g (n outward).
    Neumann(ScalarFn),
    /// K∇u·n + α u = g, α > 0.
    Robin { alpha: ScalarFn, value: ScalarFn },
}

/// A condition on the boundary faces carrying a tag.
#[derive(Clone)]
pub struct BoundaryCondition {
    pub tag: String,
    pub kind: BoundaryKind,
}

/// The problem −∇·(K ∇u) = f with boundary conditions.
#[derive(Clone)]
pub struct Diffusion {
    pub method: Method,
    pub conductivity: Conductivity,
    pub source: ScalarFn,
    /// Applied in order; a later condition on the same face replaces an earlier one.
    pub boundary: Vec<BoundaryCondition>,
    /// Direct factorisation (default: LLᵀ, the systems are SPD).
    pub factorization: Factorization,
    /// Fill-reducing ordering of the direct factorisation (default:
    /// automatic).
    pub ordering: Ordering,
    /// Where the cell values of [`Method::Fv`] live (default: centroids).
    pub cell_points: CellPoints,
    /// Largest relative imbalance Σ b / Σ |b| accepted for pure-Neumann data
    /// (quadrature makes consistent data slightly incompatible).
    pub neumann_tolerance: f64,
    /// Solve by preconditioned conjugate gradients instead of a
    /// factorisation (SPD systems), optionally from an initial guess.
    pub iterative: Option<Iterative>,
}

/// Settings of an iterative solve.
#[derive(Clone, Debug, Default)]
pub struct Iterative {
    pub options: CgOptions,
    /// A guess for every unknown (fixed ones are ignored), e.g. a coarse
    /// solution transferred to a refined mesh.
    pub initial: Option<Vec<f64>>,
    /// The preconditioner of conjugate gradients (default: Jacobi).
    pub preconditioner: Preconditioning,
}

/// The preconditioner of an iterative solve.
#[derive(Clone, Debug, Default)]
pub enum Preconditioning {
    /// diag(M)⁻¹: cheap, iteration counts grow like 1/h.
    #[default]
    Jacobi,
    /// One multigrid V-cycle per iteration ([`crate::multigrid`]): counts
    /// independent of h. The hierarchy is for all unknowns of the mesh;
    /// Dirichlet unknowns are removed from it at solve time.
    Multigrid {
        hierarchy: Hierarchy,
        options: MultigridOptions,
    },
}

/// Why a problem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiffusionError {
    #[error("boundary condition on tag '{tag}': no such tag in the mesh (tags: {available})")]
    UnknownTag { tag: String, available: String },
    #[error("boundary condition on tag '{tag}': it tags {dim}-cells, but boundary conditions need (n−1)-cells (n = {n})")]
    TagDimension { tag: String, dim: usize, n: usize },
    #[error("boundary condition on tag '{tag}': face {face} is not on the boundary")]
    InteriorFace { tag: String, face: usize },
    #[error("Robin coefficient α = {alpha} at face {face} (tag '{tag}') must be positive")]
    RobinAlpha {
        tag: String,
        face: usize,
        alpha: f64,
    },
    #[error("{what} is not finite at {location:?}")]
    NonFinite {
        what: &'static str,
        location: Vec<f64>,
    },
    #[error("pure Neumann problem with incompatible data: sources plus boundary fluxes sum to {imbalance:e} (relative {relative:e}); they must balance (∫f + ∮g = 0)")]
    IncompatibleNeumann { imbalance: f64, relative: f64 },
    #[error("pure Neumann problem on a disconnected domain ({components} parts): give every part a Dirichlet or Robin boundary")]
    Disconnected { components: usize },
    #[error("the domain has {parts} disconnected parts and the part holding {what} {unknown} (at {point:?}) has no Dirichlet or Robin boundary: its solution is fixed only up to a constant and the system is singular; put a Dirichlet or Robin condition on a boundary tag of every part, or mesh the parts separately")]
    FloatingPart {
        parts: usize,
        what: &'static str,
        unknown: usize,
        point: Vec<f64>,
    },
    #[error("conductivity at {point:?}: {source}; check the conductivity expression there")]
    Coefficient {
        point: Vec<f64>,
        source: MetricError,
    },
    #[error("the {method} metric is not symmetric, but {factorization} needs a symmetric positive definite system; use Factorization::Lu for a non-symmetric Ω")]
    NotSymmetric {
        method: &'static str,
        factorization: Factorization,
    },
    #[error("the {method} method cannot impose {what}")]
    Unsupported {
        method: &'static str,
        what: &'static str,
    },
    #[error(transparent)]
    Metric(#[from] MetricError),
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Iterative(#[from] CgError),
    #[error(transparent)]
    Multigrid(#[from] MultigridError),
}

/// The discrete solution and how it was obtained.
#[derive(Clone, Debug)]
pub struct Solution {
    pub method: Method,
    pub location: Location,
    /// All unknowns (fixed ones included), in the layout of `location`.
    pub values: Vec<f64>,
    /// The flux cochain Ω A u on the rows of A (edges for nodal methods,
    /// (n−1)-cells for cell-centred ones, half-faces for the hybrid one).
    pub flux: Vec<f64>,
    pub report: SolveReport,
    pub assembly_seconds: f64,
    /// Whether the direct solve's symbolic analysis ran beside the assembly
    /// (from the solved matrix's pattern known from topology: two-point
    /// FV/FD, nodal FE), so that its seconds overlap `assembly_seconds`
    /// instead of adding to them.
    pub analysed_during_assembly: bool,
    /// Whether the problem was pure Neumann (solution normalised to zero mean).
    pub pure_neumann: bool,
    /// Relative imbalance of pure-Neumann data removed before solving.
    pub neumann_imbalance: f64,
    /// The points whose exact values the cell values approximate (stride d),
    /// when they are not the centroids (see [`CellPoints`]).
    pub cell_points: Option<Vec<f64>>,
    /// Iterations and residuals when solved iteratively.
    pub iterations: Option<CgReport>,
    /// A lower bound on the condition number of the solved (reduced)
    /// system: for a symmetric positive definite M, λ_max ≥ max M_ii and
    /// λ_min ≤ min M_ii, so κ(M) ≥ max M_ii / min M_ii. Free to compute,
    /// and large when coefficients or cell sizes span many orders.
    pub condition_bound: f64,
}

/// max M_ii / min M_ii over the unknowns not held fixed (see
/// [`Solution::condition_bound`]); infinite when a diagonal entry is zero.
pub fn diagonal_condition_bound(matrix: &SparseColMat<usize, f64>, fixed: &[Option<f64>]) -> f64 {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for c in 0..matrix.ncols() {
        if fixed.get(c).is_some_and(Option::is_some) {
            continue;
        }
        let range = matrix.col_range(c);
        let diagonal = matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
            .find(|(&r, _)| r == c)
            .map_or(0.0, |(_, &v)| v.abs());
        lo = lo.min(diagonal);
        hi = hi.max(diagonal);
    }
    if hi == 0.0 {
        1.0
    } else {
        hi / lo
    }
}

impl Solution {
    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.values.len()
    }

    /// The primary field on its cells (top cells for hybrid).
    pub fn field(&self, complex: &Complex) -> &[f64] {
        match self.location {
            Location::Hybrid => &self.values[..complex.cell_count(complex.dim())],
            _ => &self.values,
        }
    }
}

/// Error figures against an exact solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// Discrete L² error of the primary field (lumped-mass weights on
    /// vertices, cell volumes on cells): sqrt(Σ w_i (u_i − u(x_i))²) with
    /// x_i the vertices, or the cell points (centroids unless
    /// [`Solution::cell_points`] says otherwise).
    pub l2: f64,
    /// Largest pointwise error of the primary field.
    pub max: f64,
    /// Discrete L² error of the cell-wise reconstructed gradient.
    pub gradient_l2: f64,
}

/// The assembled system of a diffusion problem (see [`Diffusion::assemble`]).
#[derive(Clone, Debug)]
pub struct Assembled {
    pub location: Location,
    /// The canonical operator, with boundary and ghost rows.
    pub canonical: Canonical,
    /// M = Aᵀ Ω A over all unknowns (full symmetric storage for symmetric Ω).
    pub matrix: SparseColMat<usize, f64>,
    /// Sources, Neumann data and lifted Dirichlet/Robin ghost values.
    pub rhs: Vec<f64>,
    /// Unknowns held at a Dirichlet value (nodal and hybrid methods).
    pub fixed: Vec<Option<f64>>,
    /// No Dirichlet or Robin boundary: M is singular (constants).
    pub pure_neumann: bool,
    /// Rows of A before the ghost rows.
    pub flux_rows: usize,
    /// Ghost values w on the rows of A (b contains Aᵀ Ω w).
    pub ghost_values: Vec<f64>,
    /// The data's flux on cell-centred Neumann faces.
    pub neumann_flux: Vec<f64>,
    /// Cell points of [`Method::Fv`] when they are not the centroids.
    pub cell_points: Option<Vec<f64>>,
    pub assembly_seconds: f64,
    /// What [`Diffusion::data`] needs to redo only the data part.
    layout: DataLayout,
}

/// The parts of an assembly that the data (source, boundary values) do
/// not change.
#[derive(Clone, Debug)]
struct DataLayout {
    faces: Faces,
    /// Ω's diagonal on each conditioned face's row, in the order of
    /// `faces.condition` (cell-centred methods).
    cell_diagonal: Vec<Option<f64>>,
}

/// The boundary's contribution to an assembly.
struct BoundaryData {
    fixed: Vec<Option<f64>>,
    /// Ghost rows: (unknown, weight, ghost value) appended to A and Ω.
    ghosts: Vec<(usize, f64, f64)>,
    /// Cell-centred boundary faces whose own row changes weight: (row,
    /// weight), by row.
    face_weight: Vec<(usize, f64)>,
    /// Ghost value of every flux row (non-zero on Dirichlet and Robin faces).
    face_value: Vec<f64>,
    /// Cell-centred Neumann faces carry no row weight; their flux (along
    /// the face's orientation) is the data's, −s g |F|.
    neumann_flux: Vec<f64>,
}

#[derive(Clone, Debug)]
struct Faces {
    /// (face, condition index) of every conditioned boundary (n−1)-cell,
    /// by face.
    condition: Vec<(usize, usize)>,
}

/// (face, k) for every (n−1)-cell a tag names, in face order, with k the
/// index of the last such tag (in `tags` order), so later conditions
/// override earlier ones. Only boundary faces appear, so the list is short
/// next to the face count. Errors: a tag missing from the mesh, a tag of
/// cells of another dimension, a tagged interior face.
pub(crate) fn tagged_boundary_faces<'a>(
    complex: &Complex,
    tags: impl Iterator<Item = &'a str>,
) -> Result<Vec<(usize, usize)>, DiffusionError> {
    let n = complex.dim();
    let top = complex.boundary(n);
    let mut condition: Vec<(usize, usize)> = Vec::new();
    for (k, name) in tags.enumerate() {
        let tag = complex
            .tag(name)
            .ok_or_else(|| DiffusionError::UnknownTag {
                tag: name.to_string(),
                available: {
                    let names: Vec<&str> = complex.tags().names().collect();
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                },
            })?;
        if tag.dim != n - 1 {
            return Err(DiffusionError::TagDimension {
                tag: name.to_string(),
                dim: tag.dim,
                n,
            });
        }
        for &f in &tag.cells {
            if top.outer_view(f).map_or(0, |r| r.nnz()) != 1 {
                return Err(DiffusionError::InteriorFace {
                    tag: name.to_string(),
                    face: f,
                });
            }
            condition.push((f, k));
        }
    }
    // Stable: a face's entries stay in tag order, and the last one wins.
    condition.sort_by_key(|&(f, _)| f);
    let mut last: Vec<(usize, usize)> = Vec::with_capacity(condition.len());
    for (f, k) in condition {
        match last.last_mut() {
            Some(previous) if previous.0 == f => previous.1 = k,
            _ => last.push((f, k)),
        }
    }
    Ok(last)
}

/// A conductivity evaluated at the cells, owned.
enum CellConductivity {
    Scalar(Vec<f64>),
    Full(Vec<Tensor>),
}

impl CellConductivity {
    fn cells(&self) -> CellTensors<'_> {
        match self {
            Self::Scalar(values) => CellTensors::Scalar(values),
            Self::Full(tensors) => CellTensors::Full(tensors),
        }
    }
}

/// Ω's diagonal entry (summed over its 1×1 blocks) on each of the sorted
/// `rows`, or `None` where a row has none.
fn diagonal_on(metric: &BlockMetric, rows: &[usize]) -> Vec<Option<f64>> {
    if let Some(weights) = metric.diagonal_weights() {
        return rows.iter().map(|&r| weights.get(r).copied()).collect();
    }
    let mut diag = vec![None; rows.len()];
    for b in 0..metric.block_count() {
        let (r, s, w) = metric.block(b);
        if let ([r], [s]) = (r, s) {
            if r == s {
                if let Ok(k) = rows.binary_search(r) {
                    diag[k] = Some(diag[k].unwrap_or(0.0) + w[0]);
                }
            }
        }
    }
    diag
}

/// Set the diagonal weight of each listed row (sorted, distinct) of Ω: the
/// row's first 1×1 block takes the weight and its other 1×1 blocks zero.
fn replace_row_weights(metric: &mut BlockMetric, rows: &[(usize, f64)]) {
    if metric.diagonal_weights().is_some() {
        // Block r is row r's only block.
        for &(r, weight) in rows {
            if r < metric.block_count() {
                metric.block_values_mut(r)[0] = weight;
            }
        }
        return;
    }
    let mut replaced = vec![false; rows.len()];
    for b in 0..metric.block_count() {
        let (r, s, _) = metric.block(b);
        if let ([r], [s]) = (r, s) {
            if r == s {
                if let Ok(k) = rows.binary_search_by_key(r, |&(row, _)| row) {
                    let first = !replaced[k];
                    replaced[k] = true;
                    metric.block_values_mut(b)[0] = if first { rows[k].1 } else { 0.0 };
                }
            }
        }
    }
}

/// A load whose every entry is finite (finite values can still overflow
/// when summed).
fn finite_load(rhs: Vec<f64>) -> Result<Vec<f64>, DiffusionError> {
    if rhs.iter().any(|v| !v.is_finite()) {
        return Err(DiffusionError::NonFinite {
            what: "source",
            location: vec![],
        });
    }
    Ok(rhs)
}

fn evaluate(f: &ScalarFn, x: &[f64], what: &'static str) -> Result<f64, DiffusionError> {
    let v = f(x);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(DiffusionError::NonFinite {
            what,
            location: x.to_vec(),
        })
    }
}

impl Diffusion {
    /// A problem with default solver settings.
    pub fn new(method: Method, conductivity: Conductivity, source: ScalarFn) -> Self {
        Self {
            method,
            conductivity,
            source,
            boundary: Vec::new(),
            factorization: Factorization::Llt,
            ordering: Ordering::Automatic,
            cell_points: CellPoints::Centroids,
            neumann_tolerance: 1e-2,
            iterative: None,
        }
    }

    /// Add a boundary condition on a tag.
    pub fn with_boundary(mut self, tag: &str, kind: BoundaryKind) -> Self {
        self.boundary.push(BoundaryCondition {
            tag: tag.to_string(),
            kind,
        });
        self
    }

    /// Choose the linear solver: [`SolverChoice::Direct`] factorises,
    /// [`SolverChoice::Multigrid`] runs multigrid-preconditioned CG to
    /// `tolerance`, [`SolverChoice::Auto`] applies [`multigrid::automatic`]
    /// to this method's unknowns on `complex`. A case file's
    /// `[solver] kind = "direct" | "multigrid" | "amg" | "auto"` maps onto
    /// Direct, Multigrid(Grid or Refinements), Multigrid(Algebraic), Auto.
    ///
    /// ```
    /// use hasse_complex::generate::box3;
    /// use hasse_solver::physics::diffusion::{BoundaryKind, Conductivity, Diffusion, Method};
    /// use hasse_solver::multigrid::{Hierarchy, SolverChoice};
    /// use std::sync::Arc;
    /// let mesh = box3(16, 16, 16, [0.0, 1.0], [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let grid = Hierarchy::Grid { cells: vec![16, 16, 16] };
    /// let problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    ///     .with_solver(SolverChoice::Multigrid(grid), 1e-8, &mesh);
    /// let solution = problem.solve(&mesh).unwrap();
    /// let report = solution.iterations.unwrap();
    /// assert!(report.relative_residual <= 1e-8 && report.iterations < 15);
    /// ```
    pub fn with_solver(mut self, choice: SolverChoice, tolerance: f64, complex: &Complex) -> Self {
        let choice = match choice {
            SolverChoice::Auto(hierarchy) => {
                let n = complex.dim();
                let unknowns = match self.location() {
                    Location::Nodal => complex.cell_count(0),
                    Location::CellCentred => complex.cell_count(n),
                    Location::Hybrid => complex.cell_count(n) + complex.cell_count(n - 1),
                };
                multigrid::automatic(n, unknowns, hierarchy)
            }
            other => other,
        };
        self.iterative = match choice {
            SolverChoice::Multigrid(hierarchy) => Some(Iterative {
                options: CgOptions {
                    tolerance,
                    ..CgOptions::default()
                },
                initial: None,
                preconditioner: Preconditioning::Multigrid {
                    hierarchy,
                    options: MultigridOptions::default(),
                },
            }),
            _ => None,
        };
        self
    }

    /// How the multigrid chosen by [`Diffusion::with_solver`] prolongs
    /// cell-centred unknowns on grid levels (no effect on a direct solve or
    /// on nodal unknowns).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::diffusion::{BoundaryKind, Conductivity, Diffusion, Method};
    /// use hasse_solver::multigrid::{CellProlongation, Hierarchy, SolverChoice};
    /// use std::sync::Arc;
    /// let mesh = rectangle(32, 32, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let problem = Diffusion::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)))
    ///     .with_solver(SolverChoice::Multigrid(Hierarchy::Grid { cells: vec![32, 32] }), 1e-8, &mesh)
    ///     .with_cell_prolongation(CellProlongation::Constant { correction: 2.0 });
    /// let report = problem.solve(&mesh).unwrap().iterations.unwrap();
    /// assert!(report.relative_residual <= 1e-8);
    /// ```
    pub fn with_cell_prolongation(mut self, prolongation: CellProlongation) -> Self {
        if let Some(Iterative {
            preconditioner: Preconditioning::Multigrid { options, .. },
            ..
        }) = &mut self.iterative
        {
            options.cell_prolongation = prolongation;
        }
        self
    }

    /// Where this method's unknowns live.
    pub fn location(&self) -> Location {
        match self.method {
            Method::Fe | Method::Dec(_) => Location::Nodal,
            Method::Fd | Method::Fv => Location::CellCentred,
            Method::FvMimetic => Location::Hybrid,
        }
    }

    /// The conductivity at every cell centroid: scalars stay scalars (8
    /// bytes a cell instead of a 72-byte tensor).
    fn cell_conductivity(&self, complex: &Complex) -> Result<CellConductivity, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let centroids = complex.centroid(n);
        let at = |c: usize| &centroids[c * d..(c + 1) * d];
        let cells = 0..complex.cell_count(n);
        let conductivity = match &self.conductivity {
            Conductivity::Scalar(f) => {
                CellConductivity::Scalar(cells.into_par_iter().map(|c| f(at(c))).collect())
            }
            Conductivity::Tensor(f) => {
                CellConductivity::Full(cells.into_par_iter().map(|c| f(at(c))).collect())
            }
        };
        metric::check_tensors(conductivity.cells(), complex.cell_count(n), d).map_err(
            |e| match e {
                MetricError::NotPositive { cell, .. } | MetricError::NonFinite { cell } => {
                    DiffusionError::Coefficient {
                        point: at(cell).to_vec(),
                        source: e,
                    }
                }
                other => other.into(),
            },
        )?;
        Ok(conductivity)
    }

    fn boundary_faces(&self, complex: &Complex) -> Result<Faces, DiffusionError> {
        let condition =
            tagged_boundary_faces(complex, self.boundary.iter().map(|b| b.tag.as_str()))?;
        Ok(Faces { condition })
    }

    /// Assemble the system on `complex` without solving it: the operator
    /// M = Aᵀ Ω A (boundary rows and ghosts included), the right-hand side
    /// and the unknowns held fixed by Dirichlet conditions. [`Diffusion::solve`]
    /// is this followed by [`solve_with_fixed`]; transient problems reuse M
    /// as their stiffness.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::diffusion::{BoundaryKind, Conductivity, Diffusion, Method};
    /// use std::sync::Arc;
    /// let mesh = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
    ///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
    /// let system = problem.assemble(&mesh).unwrap();
    /// // 3×3 vertices, only the centre is free.
    /// assert_eq!(system.fixed.iter().filter(|g| g.is_none()).count(), 1);
    /// assert_eq!(system.matrix.nrows(), 9);
    /// ```
    pub fn assemble(&self, complex: &Complex) -> Result<Assembled, DiffusionError> {
        let started = Instant::now();
        let n = complex.dim();
        if self.location() == Location::Nodal && n >= 2 {
            // A nodal assembly needs ∂ₙ by cells (for the centroids and the
            // elements' edges), the vertex star (for the pattern) and δ⁰
            // (its A). Each is built when first asked for, mostly serially
            // (two transposes, a copy and sprs's check) and bound by page
            // faults: side by side they took 0.13-0.15 s on the 2D 1000²
            // grid, one after the other about 0.17 s.
            rayon::join(
                || complex.boundary_csc(n),
                || {
                    rayon::join(
                        || complex.shared_vertex_star(n),
                        || complex.shared_coboundary(0),
                    )
                },
            );
        }
        let conductivity = self.cell_conductivity(complex)?;
        let tensors = conductivity.cells();
        let faces = self.boundary_faces(complex)?;
        let location = self.location();
        let cells = complex.cell_count(n);
        let face_count = complex.cell_count(n - 1);
        let cell_points = self.cell_points(complex)?;

        // Nodal FE finds each cell's element once for Ω and the load.
        let mut fe_load = None;
        let (incidence, metric, unknowns) = match self.method {
            Method::Fe => {
                let (metric, load) =
                    fe::stiffness_and_load(complex, tensors, &|x| (self.source)(x))?;
                fe_load = Some(load);
                (complex.shared_coboundary(0), metric, complex.cell_count(0))
            }
            Method::Dec(kind) => (
                complex.shared_coboundary(0),
                dec::hodge_metric(complex, kind, tensors)?,
                complex.cell_count(0),
            ),
            Method::Fv => (
                complex.shared_boundary(n),
                match &cell_points {
                    None => fv::two_point(complex, tensors)?,
                    Some(points) => fv::two_point_at(complex, tensors, points)?,
                },
                cells,
            ),
            Method::Fd => (
                complex.shared_boundary(n),
                fd::five_point(complex, tensors)?,
                cells,
            ),
            Method::FvMimetic => {
                let (a, omega, layout) = fv::mimetic_hybrid(complex, tensors)?;
                (Arc::new(a), omega, layout.cells + layout.faces)
            }
        };
        let flux_rows = incidence.rows();
        if self.factorization != Factorization::Lu && !metric.is_symmetric(1e-12) {
            return Err(DiffusionError::NotSymmetric {
                method: self.method.name(),
                factorization: self.factorization,
            });
        }

        let top = complex.boundary(n);
        let cell_diagonal = match location {
            Location::CellCentred => {
                let rows: Vec<usize> = faces.condition.iter().map(|&(f, _)| f).collect();
                diagonal_on(&metric, &rows)
            }
            _ => Vec::new(),
        };
        let layout = DataLayout {
            faces,
            cell_diagonal,
        };
        let mut rhs = match fe_load {
            Some(load) => finite_load(load)?,
            None => self.source_load(complex, unknowns)?,
        };
        let BoundaryData {
            fixed,
            ghosts,
            mut face_weight,
            face_value,
            neumann_flux,
        } = self.boundary_data(
            complex,
            location,
            &layout,
            &cell_points,
            flux_rows,
            &mut rhs,
        )?;
        let faces = &layout.faces;
        let indptr = top.indptr();
        let on_boundary = |f: usize| indptr.outer_inds_sz(f).len() == 1;
        let conditioned = |f: usize| faces.condition.binary_search_by_key(&f, |c| c.0).is_ok();
        if location == Location::CellCentred {
            // Boundary faces without a condition are homogeneous Neumann.
            let untagged: Vec<(usize, f64)> = (0..face_count)
                .filter(|&f| on_boundary(f) && !conditioned(f))
                .map(|f| (f, 0.0))
                .collect();
            if !untagged.is_empty() {
                face_weight.extend(untagged);
                face_weight.sort_by_key(|&(f, _)| f);
            }
        }

        // A and Ω with the boundary changes and the ghost rows.
        let mut metric_final = metric;
        replace_row_weights(&mut metric_final, &face_weight);
        metric_final.add_rows(ghosts.len());
        let mut ghost_values = face_value;
        let incidence = if ghosts.is_empty() {
            incidence
        } else {
            let mut tri = TriMat::new((flux_rows + ghosts.len(), unknowns));
            for (v, (i, j)) in incidence.iter() {
                tri.add_triplet(i, j, *v);
            }
            for (k, &(u, weight, value)) in ghosts.iter().enumerate() {
                tri.add_triplet(flux_rows + k, u, 1i8);
                metric_final.push_block(&[flux_rows + k], &[flux_rows + k], &[weight]);
                ghost_values.push(value);
            }
            Arc::new(tri.to_csr())
        };
        // The cell-centred methods' A is ∂ₙ itself, which the complex also
        // keeps by columns; a nodal element metric's blocks are the top
        // cells, whose vertex lists the complex keeps.
        let mut canonical = if ghosts.is_empty() && matches!(self.method, Method::Fv | Method::Fd) {
            Canonical::with_columns(incidence, complex.shared_boundary_csc(n), metric_final)?
        } else if location == Location::Nodal {
            Canonical::with_cell_blocks(incidence, metric_final, complex)?
        } else {
            Canonical::new(incidence, metric_final)?
        };
        // b += Aᵀ Ω w for ghost values w (Dirichlet faces, Robin ghosts).
        if ghost_values.iter().any(|&v| v != 0.0) {
            let lifted = canonical.sum_transpose(&canonical.metric().apply(&ghost_values));
            for (b, l) in rhs.iter_mut().zip(lifted) {
                *b += l;
            }
        }
        let matrix = canonical.assemble_owned();
        let pure_neumann = fixed.iter().all(Option::is_none)
            && ghosts.is_empty()
            && (location != Location::CellCentred
                || (0..face_count).filter(|&f| on_boundary(f)).all(|f| {
                    face_weight
                        .binary_search_by_key(&f, |w| w.0)
                        .is_ok_and(|k| face_weight[k].1 == 0.0)
                }));
        let assembly_seconds = started.elapsed().as_secs_f64();
        Ok(Assembled {
            location,
            canonical,
            matrix,
            rhs,
            fixed,
            pure_neumann,
            flux_rows,
            ghost_values,
            neumann_flux,
            cell_points,
            assembly_seconds,
            layout,
        })
    }

    /// The source's load on the unknowns.
    fn source_load(&self, complex: &Complex, unknowns: usize) -> Result<Vec<f64>, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let cells = complex.cell_count(n);
        let mut rhs = crate::la::parallel::zeroed(unknowns);
        match self.method {
            Method::Fe => rhs = fe::load(complex, &|x| (self.source)(x))?,
            Method::Dec(kind) => rhs = dec::load(complex, kind, &|x| (self.source)(x))?,
            _ => {
                let volume = complex.measure(n);
                let centre = complex.centroid(n);
                let at = |c: usize| &centre[c * d..(c + 1) * d];
                let values: Vec<f64> = (0..cells)
                    .into_par_iter()
                    .map(|c| (self.source)(at(c)))
                    .collect();
                // The first bad cell in cell order, whatever the threads did.
                for (c, &v) in values.iter().enumerate() {
                    let v = if v.is_finite() {
                        v
                    } else {
                        evaluate(&self.source, at(c), "source")?
                    };
                    rhs[c] += v * volume[c];
                }
            }
        }
        finite_load(rhs)
    }

    /// Boundary values and data on the faces of `layout`: Dirichlet values
    /// of fixed unknowns, ghost rows, and the Neumann and Robin data added
    /// to `rhs`.
    fn boundary_data(
        &self,
        complex: &Complex,
        location: Location,
        layout: &DataLayout,
        cell_points: &Option<Vec<f64>>,
        flux_rows: usize,
        rhs: &mut [f64],
    ) -> Result<BoundaryData, DiffusionError> {
        let n = complex.dim();
        let d = complex.embedding_dim();
        let cells = complex.cell_count(n);
        let unknowns = rhs.len();
        let (faces, cell_diagonal) = (&layout.faces, &layout.cell_diagonal);
        // Only the conditioned faces' geometry, by slot: computing that of
        // every face would cost a nodal problem, which needs nothing else
        // of it, a pass over all (n−1)-cells.
        let conditioned: Vec<usize> = faces.condition.iter().map(|&(f, _)| f).collect();
        let (face_area, face_centre) = complex
            .geometry_of(n - 1, &conditioned)
            .map_err(MetricError::from)?;
        let x_face = |slot: usize| &face_centre[slot * d..(slot + 1) * d];
        let top = complex.boundary(n);
        let mut fixed: Vec<Option<f64>> = vec![None; unknowns];
        let mut ghosts: Vec<(usize, f64, f64)> = Vec::new();
        let mut face_weight: Vec<(usize, f64)> = Vec::new();
        let mut face_value = vec![0.0; flux_rows];
        let mut neumann_flux = vec![0.0; flux_rows];
        for (slot, &(f, k)) in faces.condition.iter().enumerate() {
            let bc = &self.boundary[k];
            let area = face_area[slot];
            let xf = x_face(slot);
            match location {
                Location::Nodal => {
                    let verts = complex.cell_vertices(n - 1, f);
                    let share = area / verts.len() as f64;
                    for &v in verts {
                        let xv = complex.vertices().point(v);
                        apply_at_unknown(bc, f, v, xv, share, &mut fixed, rhs, &mut ghosts)?;
                    }
                }
                Location::Hybrid => {
                    apply_at_unknown(bc, f, cells + f, xf, area, &mut fixed, rhs, &mut ghosts)?;
                }
                Location::CellCentred => {
                    let (cell, sign) = top
                        .outer_view(f)
                        .and_then(|r| r.iter().next().map(|(c, &s)| (c, f64::from(s))))
                        .ok_or(DiffusionError::InteriorFace {
                            tag: bc.tag.clone(),
                            face: f,
                        })?;
                    let sigma = cell_diagonal[slot].ok_or(DiffusionError::Unsupported {
                        method: self.method.name(),
                        what: "boundary conditions with a non-diagonal boundary metric",
                    })?;
                    // The ghost value sits where the two-point flux measures
                    // the gradient: the foot of the perpendicular from the
                    // cell point to the face (the centroid's foot is taken
                    // as the face centroid, as on a box).
                    let foot: Vec<f64> = match &cell_points {
                        None => xf.to_vec(),
                        Some(points) => {
                            let p = &points[cell * d..(cell + 1) * d];
                            let normal = &complex.normal()[f * d..(f + 1) * d];
                            let s = fv::signed_distance(xf, p, normal, sign as i8);
                            (0..d).map(|a| p[a] + s * sign * normal[a]).collect()
                        }
                    };
                    let xg = foot.as_slice();
                    match &bc.kind {
                        BoundaryKind::Dirichlet(g) => {
                            face_value[f] = sign * evaluate(g, xg, "Dirichlet value")?
                        }
                        BoundaryKind::Neumann(g) => {
                            face_weight.push((f, 0.0));
                            let outward = evaluate(g, xf, "Neumann value")? * area;
                            rhs[cell] += outward;
                            neumann_flux[f] = -sign * outward;
                        }
                        BoundaryKind::Robin { alpha, value } => {
                            let a = robin_alpha(bc, f, alpha, xg)?;
                            face_weight.push((f, sigma * a * area / (sigma + a * area)));
                            face_value[f] = sign * evaluate(value, xg, "Robin value")? / a;
                        }
                    }
                }
            }
        }
        Ok(BoundaryData {
            fixed,
            ghosts,
            face_weight,
            face_value,
            neumann_flux,
        })
    }

    /// The right-hand side and fixed values of this problem on the
    /// operator of `assembled`, without rebuilding Ω or M: for data that
    /// change (a time-dependent source or boundary value) on a problem
    /// whose method, conductivity, boundary tags and kinds and Robin α are
    /// those `assembled` was made with.
    pub fn data(
        &self,
        complex: &Complex,
        assembled: &Assembled,
    ) -> Result<(Vec<f64>, Vec<Option<f64>>), DiffusionError> {
        let unknowns = assembled.rhs.len();
        let mut rhs = self.source_load(complex, unknowns)?;
        let boundary = self.boundary_data(
            complex,
            assembled.location,
            &assembled.layout,
            &assembled.cell_points,
            assembled.flux_rows,
            &mut rhs,
        )?;
        let mut ghost_values = boundary.face_value;
        ghost_values.extend(boundary.ghosts.iter().map(|g| g.2));
        if ghost_values.len() != assembled.ghost_values.len() {
            return Err(DiffusionError::Unsupported {
                method: self.method.name(),
                what: "new data with other boundary kinds than the assembled operator's",
            });
        }
        if ghost_values.iter().any(|&v| v != 0.0) {
            let canonical = &assembled.canonical;
            let lifted = canonical.sum_transpose(&canonical.metric().apply(&ghost_values));
            for (b, l) in rhs.iter_mut().zip(lifted) {
                *b += l;
            }
        }
        Ok((rhs, boundary.fixed))
    }

    /// Assemble and solve on `complex`.
    pub fn solve(&self, complex: &Complex) -> Result<Solution, DiffusionError> {
        // Assembly and the checks before a solve; only their result is
        // needed by the factorisation.
        let prepare = || -> Result<(Assembled, f64, f64), DiffusionError> {
            let mut system = self.assemble(complex)?;
            let neumann_imbalance = self.make_compatible(complex, &mut system)?;
            if !system.pure_neumann {
                check_anchored(complex, system.location, &system.matrix, &system.fixed)?;
            }
            let condition_bound = diagonal_condition_bound(&system.matrix, &system.fixed);
            Ok((system, neumann_imbalance, condition_bound))
        };
        // The analysis reads only M's pattern; when topology alone fixes it,
        // it runs on one thread while the geometry, Ω, the values and the
        // checks are computed on the other.
        // Only a direct solve orders its unknowns.
        let coordinates = self
            .iterative
            .is_none()
            .then(|| unknown_points(complex, self.location()));
        let points = coordinates.as_deref().map(|coordinates| UnknownPoints {
            coordinates,
            dimension: complex.embedding_dim(),
        });
        let (prepared, analysis) = if self.pattern_from_topology(complex) {
            rayon::join(prepare, || self.analyse_topology(complex, points?))
        } else {
            (prepare(), None)
        };
        let (system, neumann_imbalance, condition_bound) = prepared?;
        let Assembled {
            location,
            canonical,
            matrix,
            rhs,
            fixed,
            pure_neumann,
            flux_rows,
            ghost_values,
            neumann_flux,
            cell_points,
            assembly_seconds,
            ..
        } = system;
        let unknowns = rhs.len();
        let (mut values, report, iterations, analysed_during_assembly) = solve_fixed(
            &matrix,
            &rhs,
            &fixed,
            self.factorization,
            self.ordering,
            self.iterative.as_ref(),
            analysis,
            points,
        )?;
        if pure_neumann {
            let weights = self.mean_weights(complex, location, unknowns);
            let wsum: f64 = weights.iter().sum();
            let mean: f64 = values.iter().zip(&weights).map(|(u, w)| u * w).sum::<f64>() / wsum;
            for u in &mut values {
                *u -= mean;
            }
        }
        let flux_all = canonical.flux(&values);
        let mut flux = flux_all[..flux_rows].to_vec();
        // The ghost part of boundary fluxes: Ω(Au − w) on Dirichlet/Robin faces.
        if location == Location::CellCentred {
            let lifted = canonical.metric().apply(&ghost_values);
            for ((q, l), g) in flux.iter_mut().zip(lifted).zip(&neumann_flux) {
                *q += g - l;
            }
        }
        Ok(Solution {
            method: self.method,
            location,
            values,
            flux,
            report,
            iterations,
            assembly_seconds,
            analysed_during_assembly,
            pure_neumann,
            neumann_imbalance,
            cell_points,
            condition_bound,
        })
    }

    /// A pure-Neumann system made solvable: a connected complex is
    /// required, the data's imbalance Σb must be within the tolerance and is
    /// removed in proportion to each unknown's weight, and unknown 0 is
    /// pinned (the zero-mean shift follows the solve). Returns the relative
    /// imbalance removed (0 when the system is not pure Neumann).
    fn make_compatible(
        &self,
        complex: &Complex,
        system: &mut Assembled,
    ) -> Result<f64, DiffusionError> {
        if !system.pure_neumann {
            return Ok(0.0);
        }
        let components = complex.betti_numbers_over(hasse_complex::Field::Z2)[0];
        if components != 1 {
            return Err(DiffusionError::Disconnected { components });
        }
        let rhs = &mut system.rhs;
        let total: f64 = rhs.iter().sum();
        let scale: f64 = rhs.iter().map(|b| b.abs()).sum();
        let relative = if scale > 0.0 {
            total.abs() / scale
        } else {
            0.0
        };
        if relative > self.neumann_tolerance {
            return Err(DiffusionError::IncompatibleNeumann {
                imbalance: total,
                relative,
            });
        }
        let weights = self.mean_weights(complex, system.location, rhs.len());
        let wsum: f64 = weights.iter().sum();
        for (b, w) in rhs.iter_mut().zip(&weights) {
            *b -= total * w / wsum;
        }
        system.fixed[0] = Some(0.0);
        Ok(relative)
    }

    /// Whether the solved matrix's pattern is known before assembly. For
    /// the cell-centred two-point methods it is that of ∂ₙᵀ∂ₙ (cells
    /// coupled through their faces), whatever the conductivity and the
    /// boundary conditions, whose ghost rows touch one cell each and so add
    /// only to the diagonal. For nodal FE every top cell couples all its
    /// vertices (Q1 and virtual-element blocks over the cell, P1 weights
    /// on every edge of a simplex), and the Dirichlet vertices, which the
    /// solve drops, are those of the Dirichlet faces. So does DEC on a
    /// simplicial complex, whose edges join every two vertices of a cell.
    fn pattern_from_topology(&self, complex: &Complex) -> bool {
        let n = complex.dim();
        self.iterative.is_none()
            && match self.method {
                Method::Fv | Method::Fd | Method::Fe => true,
                Method::Dec(_) => {
                    (0..complex.cell_count(n)).all(|c| complex.cell_vertices(n, c).len() == n + 1)
                }
                Method::FvMimetic => false,
            }
    }

    /// The pattern the solve will factorise, predicted from topology (see
    /// [`Diffusion::pattern_from_topology`]: ∂ₙᵀ∂ₙ cell-centred, the free
    /// vertices' cell cliques nodal), and its symbolic analysis for this
    /// problem's factorisation and ordering. The nodal prediction restates
    /// which vertices the boundary data and `make_compatible` hold; the
    /// solve uses it only where it matches entry for entry. `None` when the
    /// analysis fails: the solve then analyses the assembled matrix and
    /// reports the failure itself.
    fn analyse_topology(
        &self,
        complex: &Complex,
        points: UnknownPoints<'_>,
    ) -> Option<TopologyAnalysis> {
        let n = complex.dim();
        let mut free_points = Vec::new();
        let pattern = if self.location() == Location::Nodal {
            // A boundary tag that names nothing is reported by the assembly.
            let faces = self.boundary_faces(complex).ok()?;
            let mut free = vec![true; complex.cell_count(0)];
            let mut anchored = false;
            for &(f, k) in &faces.condition {
                match self.boundary[k].kind {
                    BoundaryKind::Dirichlet(_) => {
                        anchored = true;
                        for &v in complex.cell_vertices(n - 1, f) {
                            free[v] = false;
                        }
                    }
                    BoundaryKind::Robin { .. } => anchored = true,
                    BoundaryKind::Neumann(_) => {}
                }
            }
            // Without Dirichlet or Robin faces the problem is pure Neumann,
            // and the solve pins vertex 0 (`make_compatible`).
            if !anchored {
                if let Some(first) = free.first_mut() {
                    *first = false;
                }
            }
            free_points = points_of(points, (0..free.len()).filter(|&v| free[v]));
            crate::operator::clique_pattern(
                complex.vertex_star(n),
                |c| complex.cell_vertices(n, c),
                &free,
            )
        } else {
            crate::operator::diagonal_pattern(
                &complex.shared_boundary(n),
                &complex.shared_boundary_csc(n),
            )
        };
        let points = if self.location() == Location::Nodal {
            UnknownPoints {
                coordinates: &free_points,
                ..points
            }
        } else {
            points
        };
        let solver = DirectSolver::analyse_pattern_at(
            pattern.as_ref(),
            self.factorization,
            self.ordering,
            Some(points),
        )
        .ok()?;
        Some(TopologyAnalysis { pattern, solver })
    }

    /// The cell points of [`Method::Fv`] when they are not the centroids.
    fn cell_points(&self, complex: &Complex) -> Result<Option<Vec<f64>>, DiffusionError> {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        if self.cell_points != CellPoints::Centroids && self.method != Method::Fv {
            return Err(DiffusionError::Unsupported {
                method: self.method.name(),
                what: "cell points other than centroids (only the two-point method \"fv\" moves its unknowns)",
            });
        }
        Ok(match &self.cell_points {
            CellPoints::Centroids => None,
            CellPoints::Circumcentres => {
                Some(complex.circumcentre(n).map_err(MetricError::from)?.to_vec())
            }
            CellPoints::Given(points) => {
                let cells = complex.cell_count(n);
                if points.len() != cells * d {
                    return Err(DiffusionError::Metric(MetricError::UnsupportedMesh {
                        method: self.method.name(),
                        needs: "one given cell point per top cell",
                        detail: format!(
                            "{} coordinates given for {cells} top cells in R^{d}",
                            points.len()
                        ),
                    }));
                }
                Some(points.to_vec())
            }
        })
    }

    /// Weights of the zero-mean normalisation: cell volumes, or lumped
    /// (barycentric dual) vertex volumes.
    fn mean_weights(&self, complex: &Complex, location: Location, unknowns: usize) -> Vec<f64> {
        let n = complex.dim();
        match location {
            Location::Nodal => lumped_vertex_volumes(complex),
            Location::CellCentred => complex.measure(n).to_vec(),
            Location::Hybrid => {
                let mut w = complex.measure(n).to_vec();
                w.resize(unknowns, 0.0);
                w
            }
        }
    }
}

/// Every connected part of the free unknowns must be tied to a Dirichlet
/// value or a Robin/ghost row, or M is singular there. On a part C of the
/// graph of M that is tied to nothing, M·1 vanishes on C (constants are the
/// kernel of AᵀΩA); a tie shows as a row sum over C of the order of the
/// diagonal. This finds the floating part before the factorisation fails
/// with a message that cannot say where.
fn check_anchored(
    complex: &Complex,
    location: Location,
    matrix: &SparseColMat<usize, f64>,
    fixed: &[Option<f64>],
) -> Result<(), DiffusionError> {
    let size = matrix.ncols();
    let mut parent: Vec<usize> = (0..size).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let free = |i: usize| fixed.get(i).is_none_or(Option::is_none);
    for c in 0..size {
        if !free(c) {
            continue;
        }
        for (&r, &v) in matrix.row_idx()[matrix.col_range(c)]
            .iter()
            .zip(&matrix.val()[matrix.col_range(c)])
        {
            if r != c && v != 0.0 && free(r) {
                let (a, b) = (root(&mut parent, r), root(&mut parent, c));
                parent[a] = b;
            }
        }
    }
    // Per part: the largest |Σ_{j∈C} M_ij| and the largest diagonal. Rounding
    // leaves row sums of untied rows near 1e-15 of the diagonal; a tie (a
    // Dirichlet neighbour, a Robin or ghost weight) is of its order, unless
    // the data itself is that close to singular.
    let mut row_sum = vec![0.0f64; size];
    let mut diagonal = vec![0.0f64; size];
    for c in 0..size {
        for (&r, &v) in matrix.row_idx()[matrix.col_range(c)]
            .iter()
            .zip(&matrix.val()[matrix.col_range(c)])
        {
            if r == c {
                diagonal[r] = v.abs();
            }
            if free(r) && free(c) {
                row_sum[r] += v;
            }
        }
    }
    let mut tie = vec![0.0f64; size];
    let mut scale = vec![0.0f64; size];
    let mut first = vec![usize::MAX; size];
    for i in (0..size).filter(|&i| free(i)) {
        let p = root(&mut parent, i);
        if first[p] == usize::MAX {
            first[p] = i;
        }
        tie[p] = tie[p].max(row_sum[i].abs());
        scale[p] = scale[p].max(diagonal[i]);
    }
    for p in 0..size {
        if first[p] == usize::MAX || tie[p] > 1e-12 * scale[p] {
            continue;
        }
        let unknown = first[p];
        let n = complex.dim();
        let cells = complex.cell_count(n);
        let (what, point) = match location {
            Location::Nodal => ("vertex", complex.vertices().point(unknown).to_vec()),
            _ if unknown < cells => ("top cell", complex.centroid_of(n, unknown).to_vec()),
            _ => ("face", complex.centroid_of(n - 1, unknown - cells).to_vec()),
        };
        let unknown = match location {
            Location::Hybrid if unknown >= cells => unknown - cells,
            _ => unknown,
        };
        return Err(DiffusionError::FloatingPart {
            // Only on this error path: homology is not free on large meshes.
            parts: complex.betti_numbers_over(hasse_complex::Field::Z2)[0],
            what,
            unknown,
            point,
        });
    }
    Ok(())
}

/// α of a Robin condition at a point, which must be positive.
fn robin_alpha(
    bc: &BoundaryCondition,
    face: usize,
    alpha: &ScalarFn,
    x: &[f64],
) -> Result<f64, DiffusionError> {
    let a = evaluate(alpha, x, "Robin α")?;
    if a <= 0.0 {
        return Err(DiffusionError::RobinAlpha {
            tag: bc.tag.clone(),
            face,
            alpha: a,
        });
    }
    Ok(a)
}

/// A boundary condition at one unknown of a nodal or hybrid method, with
/// `weight` the part of the face it stands for: Dirichlet fixes it, Neumann
/// adds ∫g, Robin adds a ghost row of weight α·weight and value g/α.
#[allow(clippy::too_many_arguments)]
fn apply_at_unknown(
    bc: &BoundaryCondition,
    face: usize,
    unknown: usize,
    x: &[f64],
    weight: f64,
    fixed: &mut [Option<f64>],
    rhs: &mut [f64],
    ghosts: &mut Vec<(usize, f64, f64)>,
) -> Result<(), DiffusionError> {
    match &bc.kind {
        BoundaryKind::Dirichlet(g) => fixed[unknown] = Some(evaluate(g, x, "Dirichlet value")?),
        BoundaryKind::Neumann(g) => rhs[unknown] += evaluate(g, x, "Neumann value")? * weight,
        BoundaryKind::Robin { alpha, value } => {
            let a = robin_alpha(bc, face, alpha, x)?;
            ghosts.push((unknown, a * weight, evaluate(value, x, "Robin value")? / a));
        }
    }
    Ok(())
}

/// |c|/(vertices of c) summed over the top cells around each vertex.
pub fn lumped_vertex_volumes(complex: &Complex) -> Vec<f64> {
    let n = complex.dim();
    let volume = complex.measure(n);
    let mut w = crate::la::parallel::zeroed(complex.cell_count(0));
    for (c, &vol) in volume.iter().enumerate() {
        let verts = complex.cell_vertices(n, c);
        for &v in verts {
            w[v] += vol / verts.len() as f64;
        }
    }
    w
}

/// Solve M u = b with the unknowns in `fixed` held at their values: the
/// fixed columns move to the right-hand side and the fixed rows are
/// dropped, so the reduced system stays symmetric (positive definite when
/// M is). Directly by `factorization` with the fill-reducing `ordering`, or
/// by conjugate gradients when `iterative` is given (its initial guess
/// restricted to the free unknowns).
pub fn solve_with_fixed(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    fixed: &[Option<f64>],
    factorization: Factorization,
    ordering: Ordering,
    iterative: Option<&Iterative>,
) -> Result<(Vec<f64>, SolveReport, Option<CgReport>), DiffusionError> {
    let (values, report, iterations, _) = solve_fixed(
        matrix,
        rhs,
        fixed,
        factorization,
        ordering,
        iterative,
        None,
        None,
    )?;
    Ok((values, report, iterations))
}

/// A symbolic analysis made from topology before M was assembled, and the
/// pattern it was made for.
struct TopologyAnalysis {
    pattern: SymbolicSparseColMat<usize>,
    solver: DirectSolver,
}

impl TopologyAnalysis {
    /// Whether it holds for `matrix`: same pattern, entry for entry.
    fn fits(&self, matrix: &SparseColMat<usize, f64>) -> bool {
        let assembled = matrix.symbolic();
        assembled.nrows() == self.pattern.nrows()
            && assembled.col_ptr() == self.pattern.col_ptr()
            && assembled.col_nnz().is_none()
            && assembled.row_idx() == self.pattern.row_idx()
    }
}

/// [`solve_with_fixed`], with an analysis made beforehand, used by a
/// direct solve when it was made for the pattern of the system solved
/// (the free unknowns' block: see [`TopologyAnalysis::fits`]); the last
/// value says whether it was. Without such an analysis, the free
/// unknowns' `points` (given for all unknowns) go to the ordering.
#[allow(clippy::too_many_arguments)]
fn solve_fixed(
    matrix: &SparseColMat<usize, f64>,
    rhs: &[f64],
    fixed: &[Option<f64>],
    factorization: Factorization,
    ordering: Ordering,
    iterative: Option<&Iterative>,
    analysis: Option<TopologyAnalysis>,
    points: Option<UnknownPoints<'_>>,
) -> Result<(Vec<f64>, SolveReport, Option<CgReport>, bool), DiffusionError> {
    let n = rhs.len();
    let mut free_index = vec![usize::MAX; n];
    let mut free = Vec::new();
    for i in 0..n {
        if fixed[i].is_none() {
            free_index[i] = free.len();
            free.push(i);
        }
    }
    let mut reduced_rhs: Vec<f64> = free.iter().map(|&i| rhs[i]).collect();
    // b_f −= M_fd g, column after column of the fixed unknowns.
    for (j, g) in fixed.iter().enumerate().take(n) {
        if let Some(g) = *g {
            let range = matrix.col_range(j);
            let rows = &matrix.row_idx()[range.clone()];
            for (&i, &v) in rows.iter().zip(&matrix.val()[range]) {
                if free_index[i] != usize::MAX {
                    reduced_rhs[free_index[i]] -= v * g;
                }
            }
        }
    }
    let mut values: Vec<f64> = fixed.iter().map(|g| g.unwrap_or(0.0)).collect();
    if free.is_empty() {
        let report = SolveReport {
            factorization,
            ordering: None,
            unknowns: 0,
            nonzeros: 0,
            symbolic_seconds: 0.0,
            numeric_seconds: 0.0,
            solve_seconds: 0.0,
            relative_residual: 0.0,
            factor_entries: None,
            factor_flops: None,
        };
        return Ok((values, report, None, false));
    }
    // Without fixed unknowns the matrix is used as it is.
    let reduced: std::borrow::Cow<'_, SparseColMat<usize, f64>> = if free.len() == n {
        std::borrow::Cow::Borrowed(matrix)
    } else {
        std::borrow::Cow::Owned(free_block(matrix, &free, &free_index))
    };
    let analysis = analysis.filter(|a| a.fits(&reduced)).map(|a| a.solver);
    let analysed = analysis.is_some();
    let (x, report, iterations) = match iterative {
        None => {
            let (x, report) = match analysis {
                Some(analysis) => direct::solve_analysed(&analysis, &reduced, &reduced_rhs)?,
                None => {
                    let free_points: Option<Vec<f64>> =
                        points.map(|p| points_of(p, free.iter().copied()));
                    let points = free_points
                        .as_deref()
                        .zip(points)
                        .map(|(c, p)| UnknownPoints {
                            coordinates: c,
                            ..p
                        });
                    let solver = DirectSolver::analyse_pattern_at(
                        reduced.symbolic(),
                        factorization,
                        ordering,
                        points,
                    )?;
                    direct::solve_analysed(&solver, &reduced, &reduced_rhs)?
                }
            };
            (x, report, None)
        }
        Some(settings) => {
            let guess: Option<Vec<f64>> = settings.initial.as_ref().map(|all| {
                free.iter()
                    .map(|&i| all.get(i).copied().unwrap_or(0.0))
                    .collect()
            });
            let nonzeros = reduced.compute_nnz();
            let (x, cg, setup) = match &settings.preconditioner {
                Preconditioning::Jacobi => {
                    let (x, cg) = conjugate_gradient(
                        &reduced,
                        &reduced_rhs,
                        guess.as_deref(),
                        &settings.options,
                    )?;
                    (x, cg, 0.0)
                }
                Preconditioning::Multigrid { hierarchy, options } => {
                    let rows = RowMatrix::from_symmetric(&reduced)?;
                    // The row copy replaces the faer matrix for the solve.
                    drop(reduced);
                    let fixed_mask: Vec<bool> = fixed.iter().map(Option::is_some).collect();
                    let prolongations =
                        multigrid::restrict_to_free(&hierarchy.prolongations(n)?, &fixed_mask)?;
                    let mg = Multigrid::new(rows, prolongations, options)?;
                    let (x, cg) = mg.solve(&reduced_rhs, guess.as_deref(), &settings.options)?;
                    (x, cg, mg.setup_seconds)
                }
            };
            let report = SolveReport {
                factorization,
                ordering: None,
                unknowns: free.len(),
                nonzeros,
                symbolic_seconds: 0.0,
                numeric_seconds: setup,
                solve_seconds: cg.seconds,
                relative_residual: cg.relative_residual,
                factor_entries: None,
                factor_flops: None,
            };
            (x, report, Some(cg))
        }
    };
    for (k, &i) in free.iter().enumerate() {
        values[i] = x[k];
    }
    Ok((values, report, iterations, analysed))
}

/// A point of each unknown of `location`, for the geometric ordering: the
/// vertices themselves for nodal unknowns, the mean of each cell's
/// vertices for cell-centred ones (then each face's for the hybrid
/// method's face unknowns). Any point inside a cell would do, and the mean
/// costs no geometry.
fn unknown_points(complex: &Complex, location: Location) -> std::borrow::Cow<'_, [f64]> {
    let n = complex.dim();
    let vertex_means = |p: usize| -> Vec<f64> {
        let d = complex.embedding_dim();
        let mut means = vec![0.0; complex.cell_count(p) * d];
        means
            .par_chunks_mut(d.max(1))
            .enumerate()
            .for_each(|(c, mean)| {
                let vertices = complex.cell_vertices(p, c);
                for &v in vertices {
                    for (m, x) in mean.iter_mut().zip(complex.vertices().point(v)) {
                        *m += x;
                    }
                }
                for m in mean {
                    *m /= vertices.len() as f64;
                }
            });
        means
    };
    match location {
        Location::Nodal => std::borrow::Cow::Borrowed(complex.vertices().as_slice()),
        Location::CellCentred => std::borrow::Cow::Owned(vertex_means(n)),
        Location::Hybrid => {
            let mut points = vertex_means(n);
            points.extend(vertex_means(n - 1));
            std::borrow::Cow::Owned(points)
        }
    }
}

/// The coordinates of the unknowns `kept`, in that order.
fn points_of(points: UnknownPoints<'_>, kept: impl Iterator<Item = usize>) -> Vec<f64> {
    let d = points.dimension;
    kept.flat_map(|i| &points.coordinates[i * d..(i + 1) * d])
        .copied()
        .collect()
}

/// The block of `matrix` on the unknowns `free` (increasing), whose new
/// indices are `free_index` (`usize::MAX` for the others). Renumbering keeps
/// the order of the rows, so the CSC invariants of `matrix` carry over and
/// nothing is sorted; the columns are copied in parallel ranges, each
/// counted and then written in place (see `canonical::compressed_lists`).
fn free_block(
    matrix: &SparseColMat<usize, f64>,
    free: &[usize],
    free_index: &[usize],
) -> SparseColMat<usize, f64> {
    let kept_rows = |j: usize| {
        let range = matrix.col_range(j);
        matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
            .filter(|(&i, _)| free_index[i] != usize::MAX)
            .map(|(&i, &v)| (free_index[i], v))
    };
    let size = free.len();
    let parts = crate::la::parallel::ranges(size);
    let mut col_ptr = vec![0usize; size + 1];
    let counts = crate::la::parallel::split_at_ranges(&mut col_ptr[1..], &parts, |k| k);
    parts.par_iter().zip(counts).for_each(|(range, counts)| {
        for (k, count) in range.clone().zip(counts) {
            *count = kept_rows(free[k]).count();
        }
    });
    for k in 0..size {
        col_ptr[k + 1] += col_ptr[k];
    }
    let mut row_idx = vec![0usize; col_ptr[size]];
    let mut val = vec![0.0; col_ptr[size]];
    let row_pieces = crate::la::parallel::split_at_ranges(&mut row_idx, &parts, |k| col_ptr[k]);
    let val_pieces = crate::la::parallel::split_at_ranges(&mut val, &parts, |k| col_ptr[k]);
    parts
        .par_iter()
        .zip(row_pieces.into_par_iter().zip(val_pieces))
        .for_each(|(range, (rows_out, vals_out))| {
            let slots = rows_out.iter_mut().zip(vals_out.iter_mut());
            let entries = range.clone().flat_map(|k| kept_rows(free[k]));
            for ((row, value), (i, v)) in slots.zip(entries) {
                *row = i;
                *value = v;
            }
        });
    let symbolic = SymbolicSparseColMat::new_checked(size, size, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, val)
}

/// Cell-wise gradient of a discrete field, by least squares over the
/// points that carry values: the cell's vertices (nodal), the centroids of
/// the neighbouring cells (cell-centred) or of the cell's faces (hybrid).
/// Exact for linear fields (for cell-centred values wherever a cell has at
/// least d neighbours in general position).
pub fn reconstruct_gradient(complex: &Complex, solution: &Solution) -> Vec<[f64; 3]> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let cells = complex.cell_count(n);
    // Cell values stand for the exact field at their cell points.
    let centre = match solution.location {
        Location::CellCentred => solution
            .cell_points
            .as_deref()
            .unwrap_or(complex.centroid(n)),
        _ => complex.centroid(n),
    };
    let face_centre = complex.centroid(n - 1);
    let by_cell = complex.boundary_csc(n);
    let top = complex.boundary(n);
    (0..cells)
        .map(|c| {
            let mut points: Vec<(Vec<f64>, f64)> = Vec::new();
            let xc = &centre[c * d..(c + 1) * d];
            match solution.location {
                Location::Nodal => {
                    for &v in complex.cell_vertices(n, c) {
                        points.push((complex.vertices().point(v).to_vec(), solution.values[v]));
                    }
                }
                Location::Hybrid => {
                    if let Some(col) = by_cell.outer_view(c) {
                        for (f, _) in col.iter() {
                            points.push((
                                face_centre[f * d..(f + 1) * d].to_vec(),
                                solution.values[cells + f],
                            ));
                        }
                    }
                }
                Location::CellCentred => {
                    points.push((xc.to_vec(), solution.values[c]));
                    if let Some(col) = by_cell.outer_view(c) {
                        for (f, _) in col.iter() {
                            if let Some(row) = top.outer_view(f) {
                                for (other, _) in row.iter() {
                                    if other != c {
                                        points.push((
                                            centre[other * d..(other + 1) * d].to_vec(),
                                            solution.values[other],
                                        ));
                                    }
                                }
                            }
                        }
                    }
                }
            }
            least_squares_gradient(&points, d)
        })
        .collect()
}

fn least_squares_gradient(points: &[(Vec<f64>, f64)], d: usize) -> [f64; 3] {
    let m = points.len() as f64;
    let mut mean_x = vec![0.0; d];
    let mut mean_u = 0.0;
    for (x, u) in points {
        for a in 0..d {
            mean_x[a] += x[a] / m;
        }
        mean_u += u / m;
    }
    let mut normal = nalgebra::DMatrix::<f64>::zeros(d, d);
    let mut right = nalgebra::DVector::<f64>::zeros(d);
    for (x, u) in points {
        for a in 0..d {
            for b in 0..d {
                normal[(a, b)] += (x[a] - mean_x[a]) * (x[b] - mean_x[b]);
            }
            right[a] += (x[a] - mean_x[a]) * (u - mean_u);
        }
    }
    let mut g = [0.0; 3];
    // A rank-deficient fit (too few points, e.g. on an embedded surface)
    // falls back to the minimum-norm solution.
    let solution = normal
        .clone()
        .pseudo_inverse(1e-14 * normal.norm().max(f64::MIN_POSITIVE))
        .map(|p| p * right)
        .unwrap_or_else(|_| nalgebra::DVector::zeros(d));
    for a in 0..d {
        g[a] = solution[a];
    }
    g
}

/// Errors of `solution` against the exact field `u` (and its gradient, if
/// given). For pure-Neumann problems the mean of the difference is removed
/// first (the solution is only defined up to a constant).
pub fn errors(
    complex: &Complex,
    solution: &Solution,
    exact: &ScalarFn,
    exact_gradient: Option<&VectorFn>,
) -> Errors {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let (points, weights): (Vec<Vec<f64>>, Vec<f64>) = match solution.location {
        Location::Nodal => (
            (0..complex.cell_count(0))
                .map(|v| complex.vertices().point(v).to_vec())
                .collect(),
            lumped_vertex_volumes(complex),
        ),
        _ => (
            solution
                .cell_points
                .as_deref()
                .unwrap_or(complex.centroid(n))
                .chunks(d)
                .map(<[f64]>::to_vec)
                .collect(),
            complex.measure(n).to_vec(),
        ),
    };
    let field = solution.field(complex);
    let mut diff: Vec<f64> = points
        .iter()
        .zip(field)
        .map(|(x, u)| u - exact(x))
        .collect();
    if solution.pure_neumann {
        let wsum: f64 = weights.iter().sum();
        let mean: f64 = diff.iter().zip(&weights).map(|(e, w)| e * w).sum::<f64>() / wsum;
        for e in &mut diff {
            *e -= mean;
        }
    }
    let l2 = diff
        .iter()
        .zip(&weights)
        .map(|(e, w)| e * e * w)
        .sum::<f64>()
        .sqrt();
    let max = diff.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    let gradient_l2 = exact_gradient.map_or(f64::NAN, |grad| {
        let g = reconstruct_gradient(complex, solution);
        let volume = complex.measure(n);
        let centre = complex.centroid(n);
        (0..complex.cell_count(n))
            .map(|c| {
                let e = grad(&centre[c * d..(c + 1) * d]);
                let s: f64 = (0..d).map(|a| (g[c][a] - e[a]).powi(2)).sum();
                s * volume[c]
            })
            .sum::<f64>()
            .sqrt()
    });
    Errors {
        l2,
        max,
        gradient_l2,
    }
}

/// Discrete L² error of the face fluxes of a cell-centred or hybrid
/// solution against the exact flux −∫_F K∇u·n ≈ −|F| K(x_F)∇u(x_F)·n_F:
/// sqrt(Σ_F w_F ((q_F − q_F^exact)/|F|)²) with w_F = |F| d_F, d_F the
/// distance between the centroids on either side of F (cell to face on the
/// boundary, and for the half-faces of the hybrid method). Boundary faces
/// without flux (Neumann) are included: their exact flux is the data's.
/// `None` for nodal methods, whose edge cochain is not a face flux.
pub fn flux_error(
    complex: &Complex,
    solution: &Solution,
    problem: &Diffusion,
    exact_gradient: &VectorFn,
) -> Option<f64> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let area = complex.measure(n - 1);
    let face_centre = complex.centroid(n - 1);
    let cell_centre = complex.centroid(n);
    let normal = complex.normal();
    let exact_density = |f: usize| -> f64 {
        let x = &face_centre[f * d..(f + 1) * d];
        let g = exact_gradient(x);
        let k = match &problem.conductivity {
            Conductivity::Scalar(l) => metric::isotropic(l(x)),
            Conductivity::Tensor(t) => t(x),
        };
        let mut kg = [0.0; 3];
        for a in 0..d {
            for b in 0..d {
                kg[a] += k[a][b] * g[b];
            }
        }
        -(0..d).map(|a| kg[a] * normal[f * d + a]).sum::<f64>()
    };
    let distance = |x: &[f64], y: &[f64]| -> f64 {
        x.iter()
            .zip(y)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt()
    };
    let top = complex.boundary(n);
    let mut sum = 0.0;
    match solution.location {
        Location::Nodal => return None,
        Location::CellCentred => {
            for (f, row) in top.outer_iterator().enumerate() {
                let xf = &face_centre[f * d..(f + 1) * d];
                let cells: Vec<usize> = row.indices().to_vec();
                let d_f = match cells.as_slice() {
                    [k, l] => distance(
                        &cell_centre[k * d..(k + 1) * d],
                        &cell_centre[l * d..(l + 1) * d],
                    ),
                    [k] => distance(&cell_centre[k * d..(k + 1) * d], xf),
                    _ => continue,
                };
                let e = solution.flux[f] / area[f] - exact_density(f);
                sum += area[f] * d_f * e * e;
            }
        }
        Location::Hybrid => {
            // Half-face rows follow boundary_csc(n): cell by cell, its faces;
            // the sign turns the face normal into the cell's outward normal.
            let by_cell = complex.boundary_csc(n);
            let mut row = 0;
            for (k, col) in by_cell.outer_iterator().enumerate() {
                for (f, &s) in col.iter() {
                    let xf = &face_centre[f * d..(f + 1) * d];
                    let d_f = distance(&cell_centre[k * d..(k + 1) * d], xf);
                    let e = solution.flux[row] / area[f] - f64::from(s) * exact_density(f);
                    sum += area[f] * d_f * e * e;
                    row += 1;
                }
            }
        }
    }
    Some(sum.sqrt())
}

/// Per-cell conservation residual of cell-centred fluxes: for every top
/// cell, Σ_F ∂(F,c) q_F − ∫_c f (zero to rounding for FV/FD).
pub fn conservation_residual(
    complex: &Complex,
    solution: &Solution,
    source: &ScalarFn,
) -> Vec<f64> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let volume = complex.measure(n);
    let centre = complex.centroid(n);
    let by_cell = complex.boundary_csc(n);
    (0..complex.cell_count(n))
        .map(|c| {
            let out: f64 = by_cell.outer_view(c).map_or(0.0, |col| {
                col.iter()
                    .map(|(f, &s)| f64::from(s) * solution.flux[f])
                    .sum()
            });
            out - source(&centre[c * d..(c + 1) * d]) * volume[c]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::Triplet;

    #[test]
    fn the_free_block_drops_fixed_rows_and_columns_in_order() {
        // A 4×4 matrix with entry (i, j) = 10 i + j + 1 on its pattern
        // (every entry but (0, 3) and (3, 0)); unknowns 1 and 2 fixed.
        // The free block on {0, 3}, renumbered 0 and 1, keeps (0, 0) = 1
        // and (3, 3) = 34, and nothing between them.
        let mut entries = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                if (i, j) != (0, 3) && (i, j) != (3, 0) {
                    entries.push(Triplet::new(i, j, (10 * i + j + 1) as f64));
                }
            }
        }
        let m = SparseColMat::try_new_from_triplets(4, 4, &entries).unwrap();
        let free = [0, 3];
        let free_index = [0, usize::MAX, usize::MAX, 1];
        let block = free_block(&m, &free, &free_index);
        assert_eq!(block.col_ptr(), [0, 1, 2]);
        assert_eq!(block.row_idx(), [0, 1]);
        assert_eq!(block.val(), [1.0, 34.0]);
        // Only unknown 1 fixed: column 0 keeps rows 0 and 2 (renumbered 0
        // and 1; (3, 0) is not stored), column 2 rows 0, 2, 3, column 3
        // rows 2 and 3.
        let free = [0, 2, 3];
        let free_index = [0, usize::MAX, 1, 2];
        let block = free_block(&m, &free, &free_index);
        assert_eq!(block.col_ptr(), [0, 2, 5, 7]);
        assert_eq!(block.row_idx(), [0, 1, 0, 1, 2, 1, 2]);
        assert_eq!(block.val(), [1.0, 21.0, 3.0, 23.0, 33.0, 24.0, 34.0]);
    }
}
