//! Re-solving on SPLIT-refined meshes: refine, move the solution to the
//! refined complex through the chain map, solve again, report.
//!
//! Each step refines the current complex (uniformly, adaptively by an
//! error indicator with Dörfler marking, or by a cell-division rule), moves
//! the previous solution to the refined complex (nodal values interpolate
//! on the new vertices; cell and face averages copy to their pieces), and
//! solves the refined problem by multigrid-preconditioned CG from the
//! transferred field, with the meshes of the earlier steps as coarse levels
//! (the SPLIT refinements' own transfers, [`Hierarchy::Refinements`];
//! smoothed aggregation for hybrid unknowns, which have no geometric
//! transfer). The initial mesh is solved with the problem's own solver;
//! refined levels are not factorised again: CG to a tight tolerance is the
//! refined solution.
//!
//! The transferred field is a start, not a saving: its residual on the
//! refined mesh is the interpolation error seen through the operator, a
//! high-frequency residual of the order of ‖b‖ itself, which a V-cycle
//! removes as quickly from zero. Measured on uniform refinements of a
//! Poisson problem with a smooth source that is not an eigenvector, the
//! counts from zero and from the moved field were equal (FV 8/8/9, FE
//! 1/6/6 iterations to 1e-10 at 64² … 256²), so only the moved start is
//! solved and its relative residual reported.
//!
//! Every level also reports the global value of the residual estimator
//! η = (Σ_c η_c²)^½ of [`indicators`], which needs no exact solution.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::metric::Method;
//! use hasse_solver::physics::diffusion::Diffusion;
//! use hasse_solver::physics::{BoundaryKind, Conductivity};
//! use hasse_solver::refine::{refine_and_solve, Exact, RefineSpec, Strategy};
//! use std::f64::consts::PI;
//! use std::sync::Arc;
//! let problem = Diffusion::new(
//!     Method::Fe,
//!     Conductivity::Scalar(Arc::new(|_| 1.0)),
//!     Arc::new(|x: &[f64]| 2.0 * PI * PI * (PI * x[0]).sin() * (PI * x[1]).sin()),
//! )
//! .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
//! let exact = Exact {
//!     solution: Arc::new(|x: &[f64]| (PI * x[0]).sin() * (PI * x[1]).sin()),
//!     gradient: None,
//! };
//! let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
//! let spec = RefineSpec { strategy: Strategy::Uniform, steps: 2, ..RefineSpec::default() };
//! let study = refine_and_solve(&problem, &mesh, &spec, Some(&exact), &mut |_| {}).unwrap();
//! assert_eq!(study.steps.len(), 3); // the coarse solve and two refinements
//! assert_eq!(study.levels[2].complex.cell_count(2), 16 * 16);
//! let (coarse, fine) = (study.steps[0].l2.unwrap(), study.steps[2].l2.unwrap());
//! assert!(fine < coarse / 8.0); // two halvings of h, second order
//! ```

pub mod growth;

use crate::la::iterative::CgOptions;
use crate::metric::Location;
use crate::multigrid::{Hierarchy, MultigridOptions};
use crate::physics::diffusion::{
    self, Diffusion, DiffusionError, Iterative, Preconditioning, Solution,
};
use crate::physics::{ScalarFn, VectorFn};
use hasse_complex::coarsen::{self, Coarsening};
use hasse_complex::refine;
use hasse_complex::split::Refinement;
use hasse_complex::Complex;
use std::fmt;
use std::sync::Arc;

/// How each step refines.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::diffusion::Diffusion;
/// use hasse_solver::physics::{BoundaryKind, Conductivity};
/// use hasse_solver::refine::{refine_and_solve, RefineSpec, Strategy};
/// use std::sync::Arc;
/// let problem = Diffusion::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), Arc::new(|_| 1.0))
///     .with_boundary("boundary", BoundaryKind::Dirichlet(Arc::new(|_| 0.0)));
/// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let refined = |strategy| {
///     let spec = RefineSpec { strategy, steps: 1, ..RefineSpec::default() };
///     refine_and_solve(&problem, &mesh, &spec, None, &mut |_| {}).unwrap()
/// };
/// // A square splits into 4 by both axis planes, into 2 by one wall.
/// assert_eq!(refined(Strategy::Uniform).levels[1].complex.cell_count(2), 64);
/// assert_eq!(refined(Strategy::DivideLongestAxis).levels[1].complex.cell_count(2), 32);
/// // Dörfler marking splits only the cells that carry most of the error.
/// let adaptive = refined(Strategy::Adaptive { theta: 0.3, coarsen: 0.0 });
/// let marked = adaptive.steps[0].marked.unwrap();
/// assert!(0 < marked && marked < 16);
/// assert_eq!(Strategy::Adaptive { theta: 0.3, coarsen: 0.0 }.name(), "adaptive");
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Strategy {
    /// Every top cell by the axis-aligned hyperplanes through its centroid.
    Uniform,
    /// The cells holding the fraction θ of the squared error indicator
    /// (Dörfler marking), each split like a uniform step; and, from the
    /// second step on, the sibling groups of the previous step holding
    /// the smallest part of it merged back (see [`coarsening_groups`]).
    Adaptive {
        /// θ ∈ (0, 1]: the share of Σ η_c² the marked cells hold; small θ
        /// marks few cells, 1 marks them all.
        theta: f64,
        /// ∈ [0, 1): at most this share of Σ η_c² is held by the sibling
        /// groups merged back into their parents each step; 0 never
        /// coarsens.
        coarsen: f64,
    },
    /// Every top cell divided once by the plane through its centroid normal
    /// to its longest axis (growing tissue).
    DivideLongestAxis,
    /// Every top cell divided once along its shortest wall through the
    /// centroid.
    DivideShortestWall,
}

impl Strategy {
    /// The name case files (`refine.strategy`), `hasse refine --strategy`
    /// and reports use.
    pub fn name(&self) -> &'static str {
        match self {
            Strategy::Uniform => "uniform",
            Strategy::Adaptive { .. } => "adaptive",
            Strategy::DivideLongestAxis => "divide-longest-axis",
            Strategy::DivideShortestWall => "divide-shortest-wall",
        }
    }
}

/// A refinement study's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineSpec {
    /// How each step refines (default uniform).
    pub strategy: Strategy,
    /// Refinement steps after the coarse solve.
    pub steps: usize,
    /// Tolerance of the conjugate-gradient solves on refined meshes.
    pub tolerance: f64,
}

impl Default for RefineSpec {
    fn default() -> Self {
        Self {
            strategy: Strategy::Uniform,
            steps: 1,
            tolerance: 1e-10,
        }
    }
}

/// What one level of the study found.
#[derive(Clone, Debug, PartialEq)]
pub struct StepReport {
    /// The step: 0 for the solve on the initial mesh, then 1, 2, ….
    pub step: usize,
    /// Cells per dimension of this level's complex (`cells[p]` p-cells).
    pub cells: Vec<usize>,
    /// Unknowns of the solved system.
    pub unknowns: usize,
    /// The global residual estimator η = (Σ_c η_c²)^½ over the top cells
    /// ([`indicators`]); available without an exact solution.
    pub estimator: f64,
    /// The linear solver of this level, e.g. `sparse LLᵀ (faer)` or
    /// `multigrid-CG, SPLIT hierarchy` (every earlier mesh a coarse level).
    pub solver: String,
    /// Cells marked for refinement at the end of this step (adaptive).
    pub marked: Option<usize>,
    /// Parent cells restored at the end of this step, each from its
    /// sibling pieces (adaptive with `coarsen` > 0).
    pub coarsened: Option<usize>,
    /// L² error against the exact solution, when one was given (see
    /// [`diffusion::Errors`]).
    pub l2: Option<f64>,
    /// Largest pointwise error, when an exact solution was given.
    pub max: Option<f64>,
    /// H¹-seminorm error by quadrature, when an exact gradient was given.
    pub gradient_l2: Option<f64>,
    /// The cell-wise gradient's error sampled at the centroids (see
    /// [`diffusion::Errors::gradient_sampled`]), when an exact gradient
    /// was given.
    pub gradient_sampled: Option<f64>,
    /// CG iterations of the solve (refined steps only: step 0 runs the
    /// problem's own solver, a direct one unless the problem says
    /// otherwise).
    pub iterations: Option<usize>,
    /// Relative residual ‖b − A u₀‖/‖b‖ of the solution moved from the
    /// previous level, where CG starts (refined steps only).
    pub start_residual: Option<f64>,
    /// Wall-clock seconds of the step: refining, moving the solution and
    /// the solve.
    pub seconds: f64,
}

/// The exact solution of a refined problem, for the errors of each step.
#[derive(Clone)]
pub struct Exact {
    /// u(x).
    pub solution: ScalarFn,
    /// ∇u(x), for the gradient error.
    pub gradient: Option<VectorFn>,
}

/// One level of a refinement study: the complex and the solution on it.
#[derive(Clone, Debug)]
pub struct Level {
    /// The complex of this level.
    pub complex: Complex,
    /// The solution on it (multigrid-CG from the moved solution on refined
    /// levels).
    pub solution: Solution,
}

/// The study's steps and every level, the last one the finest.
#[derive(Clone, Debug)]
pub struct RefinementStudy {
    /// One report per step, the initial solve first.
    pub steps: Vec<StepReport>,
    /// One level per step, in the same order.
    pub levels: Vec<Level>,
}

/// Why a refinement study stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RefineError {
    /// A solve on some level failed.
    #[error(transparent)]
    Solve(#[from] DiffusionError),
    /// The mesh could not be refined as asked (a cell SPLIT cannot cut, a
    /// Dörfler fraction outside (0, 1]), or a field not moved.
    #[error("{0}")]
    Refinement(String),
}

impl RefineError {
    /// Whether the input (strategy, θ, mesh) is at fault rather than a
    /// solve.
    pub fn is_input(&self) -> bool {
        matches!(self, RefineError::Refinement(_))
    }
}

fn input(e: impl fmt::Display) -> RefineError {
    RefineError::Refinement(e.to_string())
}

/// Move a solution's unknowns to the refined complex: nodal values
/// interpolate; cell values (and face values of the hybrid method) copy to
/// their pieces; a face created by the cut takes the mean of its cells.
fn transfer(
    coarse: &Complex,
    fine: &Complex,
    refinement: &Refinement,
    location: Location,
    coarse_values: &[f64],
) -> Result<Vec<f64>, RefineError> {
    let n = coarse.dim();
    let copy = |p: usize, values: &[f64]| -> Vec<f64> {
        (0..fine.cell_count(p))
            .map(|i| refinement.parent(p, i).map_or(f64::NAN, |(j, _)| values[j]))
            .collect()
    };
    match location {
        Location::Nodal => refinement.nodal(coarse_values).map_err(input),
        Location::CellCentred => Ok(copy(n, coarse_values)),
        Location::Hybrid => {
            let cells = coarse.cell_count(n);
            let mut values = copy(n, &coarse_values[..cells]);
            let mut faces = copy(n - 1, &coarse_values[cells..]);
            let by_face = fine.boundary(n);
            for (f, row) in by_face.outer_iterator().enumerate() {
                if faces[f].is_nan() {
                    let (sum, count) = row
                        .iter()
                        .fold((0.0, 0), |(s, c), (k, _)| (s + values[k], c + 1));
                    faces[f] = if count > 0 { sum / count as f64 } else { 0.0 };
                }
            }
            values.extend(faces);
            Ok(values)
        }
    }
}

/// Move a solution's unknowns back to the coarsened complex through the
/// coarsening's chain map: nodal values by injection at the kept
/// vertices, cell values (and hybrid face values) as the measure-weighted
/// mean of their pieces. Face values of the hybrid method are traces, not
/// oriented, so their mean ignores the orientation signs of ζ.
fn restrict(
    fine: &Complex,
    coarsening: &Coarsening,
    location: Location,
    values: &[f64],
) -> Result<Vec<f64>, RefineError> {
    let n = fine.dim();
    match location {
        Location::Nodal => coarsening.restrict_nodal(values).map_err(input),
        Location::CellCentred => coarsening
            .restrict_intensive(fine, n, values)
            .map_err(input),
        Location::Hybrid => {
            let cells = fine.cell_count(n);
            let mut out = coarsening
                .restrict_intensive(fine, n, &values[..cells])
                .map_err(input)?;
            let (_, coarse_counts) = coarsening.counts();
            let measure = fine.measure(n - 1);
            let mut sum = vec![0.0; coarse_counts[n - 1]];
            let mut total = vec![0.0; coarse_counts[n - 1]];
            for (f, &v) in values[cells..].iter().enumerate() {
                if let Some((g, _)) = coarsening.coarse_cell(n - 1, f) {
                    sum[g] += measure[f] * v;
                    total[g] += measure[f];
                }
            }
            out.extend(sum.iter().zip(&total).map(|(s, t)| s / t));
            Ok(out)
        }
    }
}

/// Dörfler marking for coarsening: the parents of `refinement` (the last
/// step's SPLIT) that it cut into two or more pieces, none of them in
/// `marked` (cells about to be refined), are taken in order of increasing
/// summed η² of their pieces (ties by parent) as long as the taken groups
/// hold at most `fraction` of Σ_c η_c² over all cells. Returns the chosen
/// parents, sorted. Every piece is a leaf: the pieces are top cells of the
/// complex `refinement` produced.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::refine::refine_marked;
/// use hasse_solver::refine::coarsening_groups;
/// let k = rectangle(3, 1, [0.0, 3.0], [0.0, 1.0]).unwrap();
/// let (fine, r) = refine_marked(&k, &[0, 2]).unwrap();
/// // Cell 1 was not split; squares 0 and 2 are groups of 4 pieces.
/// let mut eta = vec![0.0; fine.cell_count(2)];
/// for c in 0..fine.cell_count(2) {
///     eta[c] = match r.parent(2, c).unwrap().0 { 0 => 0.1, 1 => 2.0, _ => 0.5 };
/// }
/// // Σ η² = 4·0.01 + 4 + 4·0.25 = 5.04; group 0 holds 0.04, group 2 holds 1.
/// assert_eq!(coarsening_groups(&r, &eta, &[], 0.01), vec![0]);
/// assert_eq!(coarsening_groups(&r, &eta, &[], 0.007), Vec::<usize>::new());
/// assert_eq!(coarsening_groups(&r, &eta, &[], 0.25), vec![0, 2]);
/// ```
pub fn coarsening_groups(
    refinement: &Refinement,
    eta: &[f64],
    marked: &[usize],
    fraction: f64,
) -> Vec<usize> {
    let n = refinement.dim();
    let (coarse, _) = refinement.counts();
    let mut pieces = vec![0usize; coarse[n]];
    let mut held = vec![0.0; coarse[n]];
    let mut blocked = vec![false; coarse[n]];
    for (c, e) in eta.iter().enumerate() {
        if let Some((q, _)) = refinement.parent(n, c) {
            pieces[q] += 1;
            held[q] += e * e;
        }
    }
    for &c in marked {
        if let Some((q, _)) = refinement.parent(n, c) {
            blocked[q] = true;
        }
    }
    let total: f64 = eta.iter().map(|e| e * e).sum();
    let mut order: Vec<usize> = (0..coarse[n])
        .filter(|&q| pieces[q] >= 2 && !blocked[q])
        .collect();
    order.sort_by(|&a, &b| held[a].total_cmp(&held[b]).then(a.cmp(&b)));
    let budget = fraction * total;
    let mut acc = 0.0;
    let mut chosen = Vec::new();
    for q in order {
        if acc + held[q] > budget {
            break;
        }
        acc += held[q];
        chosen.push(q);
    }
    chosen.sort_unstable();
    chosen
}

/// Residual-type indicator per top cell: η_c² = h_c² |c| f(x_c)² +
/// ½ Σ_F |F| h_F ((g_c − g_c')·n_F)², the jumps of the cell-wise gradient
/// across interior faces F (shared with c') plus the source residual.
pub fn indicators(
    complex: &Complex,
    solution: &Solution,
    source: &dyn Fn(&[f64]) -> f64,
) -> Vec<f64> {
    let n = complex.dim();
    let d = complex.embedding_dim();
    let gradient = diffusion::reconstruct_gradient(complex, solution);
    let volume = complex.measure(n);
    let area = complex.measure(n - 1);
    let centre = complex.centroid(n);
    let normal = complex.normal();
    let cells_by_face = complex.boundary(n);
    let mut eta2: Vec<f64> = (0..complex.cell_count(n))
        .map(|c| {
            let h = volume[c].powf(1.0 / n as f64);
            let f = source(&centre[c * d..(c + 1) * d]);
            h * h * volume[c] * f * f
        })
        .collect();
    for (face, row) in cells_by_face.outer_iterator().enumerate() {
        if let [a, b] = row.indices() {
            let jump: f64 = (0..d)
                .map(|k| (gradient[*a][k] - gradient[*b][k]) * normal[face * d + k])
                .sum();
            let h_face = area[face].powf(1.0 / (n - 1).max(1) as f64);
            let share = 0.5 * area[face] * h_face * jump * jump;
            eta2[*a] += share;
            eta2[*b] += share;
        }
    }
    eta2.into_iter().map(f64::sqrt).collect()
}

/// Directions searched for the shortest wall: every 5° in 2D.
const SHORTEST_WALL_DIRECTIONS: usize = 36;

/// One step's new mesh: `complex` coarsened (adaptive with `coarsen` > 0
/// and a previous step to undo), then refined.
struct NewMesh {
    /// The refined complex and the SPLIT from `coarsened` (or the step's
    /// starting complex) to it.
    fine: Complex,
    refinement: Refinement,
    /// The coarsened complex and the maps to it from the starting complex.
    coarsened: Option<(Complex, Coarsening)>,
    marked: Option<usize>,
    groups: Option<usize>,
}

fn refine_once(
    complex: &Complex,
    strategy: Strategy,
    eta: &[f64],
    last: Option<&Refinement>,
) -> Result<NewMesh, RefineError> {
    let n = complex.dim();
    let all: Vec<usize> = (0..complex.cell_count(n)).collect();
    let plain = |(fine, refinement): (Complex, Refinement)| NewMesh {
        fine,
        refinement,
        coarsened: None,
        marked: None,
        groups: None,
    };
    match strategy {
        Strategy::Uniform => refine::uniform(complex).map(plain).map_err(input),
        Strategy::Adaptive { theta, coarsen } => {
            let marked = refine::dorfler_mark(eta, theta).map_err(input)?;
            let count = marked.len();
            let groups = match last {
                Some(last) if coarsen > 0.0 => coarsening_groups(last, eta, &marked, coarsen),
                _ => Vec::new(),
            };
            let (Some(last), false) = (last, groups.is_empty()) else {
                let (fine, refinement) = refine::refine_marked(complex, &marked).map_err(input)?;
                return Ok(NewMesh {
                    marked: Some(count),
                    groups: (coarsen > 0.0).then_some(0),
                    ..plain((fine, refinement))
                });
            };
            let (coarse, coarsening) = coarsen::coarsen(complex, last, &groups).map_err(input)?;
            // The marked cells are in no merged group: each is a cell of
            // the coarsened complex too.
            let moved: Vec<usize> = marked
                .iter()
                .filter_map(|&c| coarsening.coarse_cell(n, c).map(|(k, _)| k))
                .collect();
            let (fine, refinement) = refine::refine_marked(&coarse, &moved).map_err(input)?;
            Ok(NewMesh {
                fine,
                refinement,
                coarsened: Some((coarse, coarsening)),
                marked: Some(count),
                groups: Some(groups.len()),
            })
        }
        Strategy::DivideLongestAxis => refine::divide_longest_axis(complex, &all)
            .map(plain)
            .map_err(input),
        Strategy::DivideShortestWall => {
            refine::divide_shortest_wall(complex, &all, SHORTEST_WALL_DIRECTIONS)
                .map(plain)
                .map_err(input)
        }
    }
}

/// The name of the linear solver `problem` runs.
fn solver_name(problem: &Diffusion) -> String {
    let Some(iterative) = &problem.iterative else {
        return problem.factorization.to_string();
    };
    match &iterative.preconditioner {
        Preconditioning::Jacobi => "Jacobi-CG".into(),
        Preconditioning::Multigrid { hierarchy, .. } => match hierarchy {
            Hierarchy::Grid { .. } => "multigrid-CG, grid hierarchy".into(),
            Hierarchy::Refinements(_) => "multigrid-CG, SPLIT hierarchy".into(),
            Hierarchy::Algebraic => "multigrid-CG, smoothed aggregation".into(),
        },
    }
}

/// The level's report; `eta` are its cell indicators.
fn report(
    step: usize,
    complex: &Complex,
    exact: Option<&Exact>,
    solution: &Solution,
    eta: &[f64],
    solver: String,
    seconds: f64,
) -> StepReport {
    let errors = exact.map(|exact| {
        diffusion::errors(complex, solution, &exact.solution, exact.gradient.as_ref())
    });
    StepReport {
        step,
        cells: complex.cell_counts(),
        unknowns: solution.unknowns(),
        estimator: eta.iter().map(|e| e * e).sum::<f64>().sqrt(),
        solver,
        marked: None,
        coarsened: None,
        l2: errors.map(|e| e.l2),
        max: errors.map(|e| e.max),
        gradient_l2: errors.map(|e| e.gradient_l2).filter(|g| g.is_finite()),
        gradient_sampled: errors.map(|e| e.gradient_sampled).filter(|g| g.is_finite()),
        iterations: None,
        start_residual: None,
        seconds,
    }
}

/// Solve `problem` on `complex`, then refine `spec.steps` times, re-solving
/// after each step; `exact` gives each step's errors, `phase` hears about
/// each step.
pub fn refine_and_solve(
    problem: &Diffusion,
    complex: &Complex,
    spec: &RefineSpec,
    exact: Option<&Exact>,
    phase: &mut dyn FnMut(&str),
) -> Result<RefinementStudy, RefineError> {
    let source = problem.source.clone();
    phase("step 0: solving on the initial mesh");
    let started = std::time::Instant::now();
    let mut current = complex.clone();
    let mut solution = problem.solve(&current)?;
    let mut eta = indicators(&current, &solution, &*source);
    let mut steps = vec![report(
        0,
        &current,
        exact,
        &solution,
        &eta,
        solver_name(problem),
        started.elapsed().as_secs_f64(),
    )];
    let mut levels = Vec::new();
    let mut refinements: Vec<Refinement> = Vec::new();
    // From the initial mesh to the current one, for the hierarchy after a
    // coarsening.
    let mut total = Refinement::identity(complex);
    for step in 1..=spec.steps {
        phase(&format!("step {step}: refining ({})", spec.strategy.name()));
        let started = std::time::Instant::now();
        let new = refine_once(&current, spec.strategy, &eta, refinements.last())?;
        if let Some(last) = steps.last_mut() {
            last.marked = new.marked;
            last.coarsened = new.groups;
        }
        let (fine, refinement) = (new.fine, new.refinement);
        let guess = match &new.coarsened {
            Some((coarse, coarsening)) => {
                // Back to the coarsened mesh through the kills' chain map,
                // then on to the refined one through the SPLIT's. The
                // coarsened mesh is no refinement of the previous levels,
                // but still one of the initial mesh: the hierarchy restarts
                // from there.
                let back = restrict(&current, coarsening, solution.location, &solution.values)?;
                total = coarsening.after(&total).map_err(input)?;
                refinements = vec![total.clone()];
                transfer(coarse, &fine, &refinement, solution.location, &back)?
            }
            None => transfer(
                &current,
                &fine,
                &refinement,
                solution.location,
                &solution.values,
            )?,
        };
        total = total.compose(&refinement).map_err(input)?;
        refinements.push(refinement);
        phase(&format!(
            "step {step}: solving on {} cells",
            fine.cell_count(fine.dim())
        ));
        // The earlier meshes are the coarse levels: the refinements' own
        // transfers move cell and vertex unknowns between them. Hybrid
        // unknowns (cells and faces) have no such transfer.
        let hierarchy = match problem.location() {
            Location::Hybrid => Hierarchy::Algebraic,
            Location::Nodal | Location::CellCentred => {
                Hierarchy::Refinements(Arc::from(refinements.clone()))
            }
        };
        let solve_from = |initial: Option<Vec<f64>>| -> Result<(Solution, String), DiffusionError> {
            let mut refined = problem.clone();
            refined.iterative = Some(Iterative {
                options: CgOptions {
                    tolerance: spec.tolerance,
                    max_iterations: 100_000,
                },
                initial,
                preconditioner: Preconditioning::Multigrid {
                    hierarchy: hierarchy.clone(),
                    options: MultigridOptions::default(),
                },
            });
            let name = solver_name(&refined);
            refined.solve(&fine).map(|s| (s, name))
        };
        let (refined, solver) = solve_from(Some(guess))?;
        eta = indicators(&fine, &refined, &*source);
        let mut r = report(
            step,
            &fine,
            exact,
            &refined,
            &eta,
            solver,
            started.elapsed().as_secs_f64(),
        );
        r.iterations = refined.iterations.map(|c| c.iterations);
        r.start_residual = refined.iterations.map(|c| c.initial_residual);
        steps.push(r);
        levels.push(Level {
            complex: std::mem::replace(&mut current, fine),
            solution: std::mem::replace(&mut solution, refined),
        });
    }
    levels.push(Level {
        complex: current,
        solution,
    });
    Ok(RefinementStudy { steps, levels })
}

impl fmt::Display for StepReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let top = self.cells.last().copied().unwrap_or(0);
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4e}"));
        let count = |v: Option<usize>| v.map_or("-".to_string(), |x| x.to_string());
        write!(
            f,
            "{:>4} {:>9} {:>9} {:>11} {:>11} {:>11} {:>11} {:>6} {:>9} {:>9} {:>9}",
            self.step,
            top,
            self.unknowns,
            opt(Some(self.estimator)),
            opt(self.l2),
            opt(self.max),
            opt(self.gradient_l2),
            count(self.iterations),
            self.start_residual
                .map_or("-".to_string(), |r| format!("{r:.2e}")),
            count(self.marked),
            count(self.coarsened),
        )
    }
}

/// The header matching [`StepReport`]'s `Display`.
pub const TABLE_HEADER: &str =
    "step     cells  unknowns   estimator    L2 error   max error  grad error  iters   start r    marked coarsened";

/// Which solver ran which steps, consecutive steps with one solver
/// grouped: `step 0: sparse LLᵀ (faer); steps 1–8: multigrid-CG, SPLIT
/// hierarchy`.
pub fn solvers_line(steps: &[StepReport]) -> String {
    let mut groups: Vec<(usize, usize, &str)> = Vec::new();
    for s in steps {
        match groups.last_mut() {
            Some((_, last, name)) if *name == s.solver && *last + 1 == s.step => *last = s.step,
            _ => groups.push((s.step, s.step, &s.solver)),
        }
    }
    groups
        .iter()
        .map(|(first, last, name)| {
            if first == last {
                format!("step {first}: {name}")
            } else {
                format!("steps {first}–{last}: {name}")
            }
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The steps as JSON (stored in the output's provenance report).
pub fn steps_json(steps: &[StepReport]) -> serde_json::Value {
    steps
        .iter()
        .map(|s| {
            serde_json::json!({
                "step": s.step,
                "cells": s.cells,
                "unknowns": s.unknowns,
                "estimator": s.estimator,
                "solver": s.solver,
                "marked": s.marked,
                "coarsened": s.coarsened,
                "l2": s.l2,
                "max": s.max,
                "gradient_l2": s.gradient_l2,
                "gradient_sampled": s.gradient_sampled,
                "iterations": s.iterations,
                "start_residual": s.start_residual,
                "seconds": s.seconds,
            })
        })
        .collect()
}
