//! A growing tissue (thesis 001): vertices move with a growth velocity,
//! cells divide when they pass a size threshold, and a morphogen diffuses
//! and decays on the changing complex,
//!
//! ```text
//! ∂c/∂t − ∇·(K∇c) + λc = f.
//! ```
//!
//! Each step from t^n to t^{n+1} = t^n + Δt:
//!
//! 1. **Motion.** Every vertex moves by forward Euler, x ← x + Δt v(x, tⁿ).
//!    The morphogen moves with the tissue: each cell keeps its *amount*
//!    m_c = ∫_c c (not its concentration), so motion changes no amount.
//! 2. **Division.** Every top cell whose measure exceeds the threshold
//!    divides once, through its centroid: normal to its longest axis or
//!    along its shortest wall in 2D, at its midpoint in 1D (the SPLIT
//!    divisions of [`hasse_complex::refine`]). A parent's amount is shared
//!    among its daughters in proportion to their measures (the chain map ζ
//!    on the top cochain of integrals), the last daughter taking the
//!    remainder, so that the daughters add up to the parent to rounding of
//!    one subtraction.
//! 3. **Reaction–diffusion.** One backward-Euler step on the current
//!    geometry with cell unknowns (`fv` two-point or `fv-mimetic` hybrid):
//!    `(|σ|(1/Δt + λ) + K) c^{n+1} = m/Δt + b(t^{n+1})`, K and b the
//!    diffusion problem's own assembly (boundary conditions by tag; no
//!    condition is no flux).
//!
//! Summing the cell equations, the interior fluxes cancel (each is one
//! face's flux, counted once out of each of its two cells), so
//!
//! ```text
//! M^{n+1} − M^n = Δt (∫f − λ M^{n+1} − outflow^{n+1})
//! ```
//!
//! with M = Σ m_c and the outflow the method's own discrete boundary
//! fluxes ([`Diffusion::boundary_outflow`]); [`GrowthStep`] reports every
//! term and the residual, which is rounding (motion and division carry
//! amounts exactly by construction).
//!
//! ```
//! use hasse_complex::generate::interval;
//! use hasse_solver::metric::Method;
//! use hasse_solver::physics::heat::Heat;
//! use hasse_solver::physics::Conductivity;
//! use hasse_solver::refine::growth::{DivisionRule, Growth};
//! use std::sync::Arc;
//! // A filament of 4 cells of length 0.25 on [0, 1] growing as v = x:
//! // each step stretches every cell by 1 + Δt = 1.25, so lengths are
//! // 0.3125 after one step and 0.390625 after two, when they pass 0.35
//! // and divide.
//! let heat = Heat::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), 0.25);
//! let growth = Growth::new(heat, vec![Arc::new(|x: &[f64], _| x[0])], 0.35, DivisionRule::Midpoint);
//! let mut tissue = growth.start(&interval(4, 0.0, 1.0).unwrap(), &|_| 1.0).unwrap();
//! let first = growth.step(&mut tissue).unwrap();
//! let second = growth.step(&mut tissue).unwrap();
//! assert_eq!((first.cells, second.cells), (4, 8));
//! // No source, no decay, no flux: the mass (1 at the start) stays.
//! assert!((tissue.mass() - 1.0).abs() < 1e-14);
//! assert!(second.relative < 1e-14);
//! ```

use crate::la::direct::Factorization;
use crate::la::ordering::Ordering;
use crate::metric::{Location, Method};
use crate::physics::diffusion::{solve_with_fixed, Diffusion, DiffusionError};
use crate::physics::heat::{Heat, HeatError, SpaceTimeFn};
use faer::sparse::{SparseColMat, Triplet};
use hasse_complex::refine::{divide_longest_axis, divide_midpoint, divide_shortest_wall};
use hasse_complex::split::Refinement;
use hasse_complex::{Complex, ComplexError, SplitError, Vertices};

#[cfg(test)]
mod tests;

/// Directions tried by the shortest-wall rule (one a degree in 2D).
const WALL_DIRECTIONS: usize = 180;

/// How a cell divides (always once, through its centroid).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DivisionRule {
    /// 1D: an edge halves at its midpoint (the only rule of a filament).
    Midpoint,
    /// 2D: the line through the centroid normal to the cell's longest axis
    /// (the principal axis of its vertex cloud).
    LongestAxis,
    /// 2D: the shortest wall through the centroid.
    ShortestWall,
}

impl DivisionRule {
    /// The name case files use (`growth.rule`).
    pub fn name(&self) -> &'static str {
        match self {
            DivisionRule::Midpoint => "midpoint",
            DivisionRule::LongestAxis => "longest-axis",
            DivisionRule::ShortestWall => "shortest-wall",
        }
    }

    /// The rules that divide top cells of dimension `dim`.
    pub fn for_dimension(dim: usize) -> &'static [DivisionRule] {
        match dim {
            1 => &[DivisionRule::Midpoint],
            2 => &[DivisionRule::LongestAxis, DivisionRule::ShortestWall],
            _ => &[],
        }
    }
}

/// What can go wrong in a growth run.
#[derive(Debug, thiserror::Error)]
pub enum GrowthError {
    /// Growth divides filaments (n = 1) and tissues (n = 2) that fill their
    /// space.
    #[error("growth needs a filament in R¹ or a tissue in R² (n = d = 1 or 2); this complex has n = {dim} in R^{embedding}")]
    Dimension {
        /// n.
        dim: usize,
        /// d.
        embedding: usize,
    },
    /// One velocity component per coordinate.
    #[error("the velocity has {found} components but the vertices have {expected} coordinates")]
    Velocity {
        /// d.
        expected: usize,
        /// Given.
        found: usize,
    },
    /// The division threshold.
    #[error("the division threshold {0} must be positive and finite")]
    Threshold(f64),
    /// The decay rate.
    #[error("the decay rate λ = {0} must be finite and ≥ 0")]
    Decay(f64),
    /// The time step.
    #[error("time step Δt = {0} must be positive and finite")]
    TimeStep(f64),
    /// Only cell unknowns carry amounts.
    #[error("growth carries the morphogen's amount per cell: method {0} has no cell unknowns (use fv or fv-mimetic)")]
    Method(&'static str),
    /// A rule for the other dimension.
    #[error("the division rule {rule} does not divide {dim}-cells (use {})", DivisionRule::for_dimension(*.dim).iter().map(DivisionRule::name).collect::<Vec<_>>().join(" or "))]
    Rule {
        /// The rule's name.
        rule: &'static str,
        /// n.
        dim: usize,
    },
    /// The velocity is not finite at a vertex.
    #[error(
        "velocity component {component} is not finite at vertex {vertex} ({point:?}, t = {time})"
    )]
    NonFiniteVelocity {
        /// 0-based component.
        component: usize,
        /// The vertex.
        vertex: usize,
        /// Its position.
        point: Vec<f64>,
        /// The time.
        time: f64,
    },
    /// A step of the motion turned a cell inside out (or flattened it).
    #[error(
        "at t = {time} the motion turned cell {cell} inside out or flat: take a smaller time step"
    )]
    Inverted {
        /// The time at which the step started.
        time: f64,
        /// A top cell whose orientation changed.
        cell: usize,
    },
    /// Divisions went past the cap on the number of cells.
    #[error("the tissue has {cells} cells, more than the limit {limit}: raise the threshold or take fewer steps")]
    TooManyCells {
        /// Cells after the division.
        cells: usize,
        /// [`Growth::max_cells`].
        limit: usize,
    },
    /// Amounts and cells do not match.
    #[error("{found} amounts for {expected} cells")]
    Amounts {
        /// Top cells.
        expected: usize,
        /// Amounts.
        found: usize,
    },
    /// Building the moved complex.
    #[error(transparent)]
    Complex(#[from] ComplexError),
    /// Dividing.
    #[error(transparent)]
    Split(#[from] SplitError),
    /// Assembling or solving the diffusion step.
    #[error(transparent)]
    Diffusion(#[from] DiffusionError),
    /// Heat data.
    #[error(transparent)]
    Heat(#[from] HeatError),
    /// The step matrix.
    #[error("assembling the step matrix: {0}")]
    Assembly(String),
}

/// The growth problem: the morphogen's reaction–diffusion data (a [`Heat`]
/// problem gives the method, K, f, the boundary conditions, Δt and t₀;
/// its θ and solver choices are not used: each step is backward Euler
/// solved by LLᵀ), the decay rate, the growth velocity and the division.
#[derive(Clone)]
pub struct Growth {
    /// Method (`fv` or `fv-mimetic`), conductivity, source, boundary
    /// conditions, Δt and t₀.
    pub heat: Heat,
    /// λ ≥ 0.
    pub decay: f64,
    /// v(x, t), one function per coordinate.
    pub velocity: Vec<SpaceTimeFn>,
    /// A top cell whose measure (length or area) exceeds this divides.
    pub divide_above: f64,
    /// How it divides.
    pub rule: DivisionRule,
    /// A run stops with an error past this many top cells.
    pub max_cells: usize,
}

/// The state of a growth run: the complex, the morphogen's amount in each
/// top cell and the time.
#[derive(Clone, Debug)]
pub struct Tissue {
    /// The current complex.
    pub complex: Complex,
    /// m_c = ∫_c c, one per top cell.
    pub amount: Vec<f64>,
    /// The current time.
    pub time: f64,
    /// Steps taken.
    pub steps: usize,
}

impl Tissue {
    /// The concentration m_c / |c| of each top cell.
    pub fn concentration(&self) -> Vec<f64> {
        let n = self.complex.dim();
        self.amount
            .iter()
            .zip(self.complex.measure(n))
            .map(|(m, v)| m / v)
            .collect()
    }

    /// The total amount M = Σ m_c.
    pub fn mass(&self) -> f64 {
        self.amount.iter().sum()
    }

    /// The tissue's measure (total length or area).
    pub fn size(&self) -> f64 {
        self.complex.measure(self.complex.dim()).iter().sum()
    }
}

/// The record of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct GrowthStep {
    /// 1-based.
    pub number: usize,
    /// t^{n+1}.
    pub time: f64,
    /// Cells that divided.
    pub divided: usize,
    /// Top cells after the step.
    pub cells: usize,
    /// Euler characteristic after the step.
    pub euler: i64,
    /// Total length or area after the step.
    pub size: f64,
    /// Mⁿ, before the step.
    pub mass_before: f64,
    /// M after motion and division, before diffusion (= Mⁿ to rounding).
    pub mass_carried: f64,
    /// M^{n+1}.
    pub mass: f64,
    /// ∫f at t^{n+1}, as the method loads it.
    pub sources: f64,
    /// λ M^{n+1}.
    pub decay: f64,
    /// Σ outflow at t^{n+1} (the method's boundary fluxes).
    pub outflow: f64,
    /// M^{n+1} − Mⁿ − Δt(∫f − λM^{n+1} − outflow).
    pub residual: f64,
    /// |residual| over the largest term: Mⁿ, M^{n+1}, Δt|∫f|, ΔtλM^{n+1},
    /// Δt Σ|q| over the boundary faces.
    pub relative: f64,
    /// ‖b − Ax‖/‖b‖ of the step's linear solve.
    pub solver_residual: f64,
}

impl Growth {
    /// No decay, at most a million cells.
    pub fn new(
        heat: Heat,
        velocity: Vec<SpaceTimeFn>,
        divide_above: f64,
        rule: DivisionRule,
    ) -> Self {
        Self {
            heat,
            decay: 0.0,
            velocity,
            divide_above,
            rule,
            max_cells: 1_000_000,
        }
    }

    /// Set the decay rate λ.
    pub fn with_decay(mut self, decay: f64) -> Self {
        self.decay = decay;
        self
    }

    /// Refuse data that cannot grow on `complex` (before any step).
    pub fn check(&self, complex: &Complex) -> Result<(), GrowthError> {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        if n != d || !(1..=2).contains(&n) {
            return Err(GrowthError::Dimension {
                dim: n,
                embedding: d,
            });
        }
        if self.velocity.len() != d {
            return Err(GrowthError::Velocity {
                expected: d,
                found: self.velocity.len(),
            });
        }
        if !(self.divide_above.is_finite() && self.divide_above > 0.0) {
            return Err(GrowthError::Threshold(self.divide_above));
        }
        if !(self.decay.is_finite() && self.decay >= 0.0) {
            return Err(GrowthError::Decay(self.decay));
        }
        if !(self.heat.dt.is_finite() && self.heat.dt > 0.0) {
            return Err(GrowthError::TimeStep(self.heat.dt));
        }
        if !DivisionRule::for_dimension(n).contains(&self.rule) {
            return Err(GrowthError::Rule {
                rule: self.rule.name(),
                dim: n,
            });
        }
        if !matches!(
            self.heat.method.location(),
            Location::CellCentred | Location::Hybrid
        ) || self.heat.method == Method::Fd
        {
            return Err(GrowthError::Method(self.heat.method.name()));
        }
        Ok(())
    }

    /// The tissue at t₀: amounts c⁰(centroid)·|σ|.
    pub fn start(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
    ) -> Result<Tissue, GrowthError> {
        self.check(complex)?;
        let n = complex.dim();
        let amount = (0..complex.cell_count(n))
            .map(|c| initial(complex.centroid_of(n, c)) * complex.measure(n)[c])
            .collect();
        Ok(Tissue {
            complex: complex.clone(),
            amount,
            time: self.heat.start,
            steps: 0,
        })
    }

    /// One step: move, divide, diffuse (module docs).
    pub fn step(&self, tissue: &mut Tissue) -> Result<GrowthStep, GrowthError> {
        self.check(&tissue.complex)?;
        let n = tissue.complex.dim();
        if tissue.amount.len() != tissue.complex.cell_count(n) {
            return Err(GrowthError::Amounts {
                expected: tissue.complex.cell_count(n),
                found: tissue.amount.len(),
            });
        }
        let dt = self.heat.dt;
        let mass_before = tissue.mass();
        let moved = self.moved(&tissue.complex, tissue.time)?;
        let large: Vec<usize> = (0..moved.cell_count(n))
            .filter(|&c| moved.measure(n)[c] > self.divide_above)
            .collect();
        let (complex, amount) = if large.is_empty() {
            (moved, std::mem::take(&mut tissue.amount))
        } else {
            let (fine, r) = self.divide(&moved, &large)?;
            if fine.cell_count(n) > self.max_cells {
                return Err(GrowthError::TooManyCells {
                    cells: fine.cell_count(n),
                    limit: self.max_cells,
                });
            }
            let amount = share_amounts(&fine, &r, &tissue.amount)?;
            (fine, amount)
        };
        let mass_carried: f64 = amount.iter().sum();
        let time = tissue.time + dt;
        let diffused = self.diffuse(&complex, &amount, time)?;
        let n_cells = complex.cell_count(n);
        let new_amount: Vec<f64> = diffused
            .concentration
            .iter()
            .zip(complex.measure(n))
            .map(|(c, v)| c * v)
            .collect();
        let mass: f64 = new_amount.iter().sum();
        let decay = self.decay * mass;
        let residual = (mass - mass_before) - dt * (diffused.sources - decay - diffused.outflow);
        let scale = mass_before
            .abs()
            .max(mass.abs())
            .max(dt * diffused.sources.abs())
            .max(dt * decay.abs())
            .max(dt * diffused.face_outflow);
        tissue.steps += 1;
        let step = GrowthStep {
            number: tissue.steps,
            time,
            divided: large.len(),
            cells: n_cells,
            euler: complex.euler_characteristic(),
            size: complex.measure(n).iter().sum(),
            mass_before,
            mass_carried,
            mass,
            sources: diffused.sources,
            decay,
            outflow: diffused.outflow,
            residual,
            relative: if scale > 0.0 {
                residual.abs() / scale
            } else {
                0.0
            },
            solver_residual: diffused.solver_residual,
        };
        tissue.complex = complex;
        tissue.amount = new_amount;
        tissue.time = time;
        Ok(step)
    }

    /// `steps` steps from `complex` and c⁰ = `initial`; `observe` sees the
    /// tissue at t₀ (with `None`) and after every step (with its record).
    pub fn run(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        steps: usize,
        observe: &mut dyn FnMut(&Tissue, Option<&GrowthStep>),
    ) -> Result<Vec<GrowthStep>, GrowthError> {
        let mut tissue = self.start(complex, initial)?;
        observe(&tissue, None);
        let mut records = Vec::with_capacity(steps);
        for _ in 0..steps {
            let record = self.step(&mut tissue)?;
            observe(&tissue, Some(&record));
            records.push(record);
        }
        Ok(records)
    }

    /// The complex with every vertex moved by Δt v(x, t); the cells keep
    /// their numbering, and a cell whose orientation the motion reverses
    /// is refused (∂ would change sign).
    fn moved(&self, complex: &Complex, time: f64) -> Result<Complex, GrowthError> {
        let d = complex.embedding_dim();
        let dt = self.heat.dt;
        let mut coords = complex.vertices().as_slice().to_vec();
        for (vertex, x) in coords.chunks_mut(d).enumerate() {
            let here = x.to_vec();
            for (component, v) in self.velocity.iter().enumerate() {
                let value = v(&here, time);
                if !value.is_finite() {
                    return Err(GrowthError::NonFiniteVelocity {
                        component,
                        vertex,
                        point: here,
                        time,
                    });
                }
                x[component] += dt * value;
            }
        }
        let n = complex.dim();
        let moved = complex
            .with_vertices(Vertices::new(d, coords)?)
            .map_err(|e| match e {
                ComplexError::DegenerateCell { cell, .. } => GrowthError::Inverted { time, cell },
                other => GrowthError::Complex(other),
            })?;
        // Same cells, so the same ∂ₙ unless a cell turned over.
        let (before, after) = (complex.top_orientation(), moved.top_orientation());
        if let Some(cell) = (0..complex.cell_count(n)).find(|&c| before[c] != after[c]) {
            return Err(GrowthError::Inverted { time, cell });
        }
        Ok(moved)
    }

    /// Divide the listed top cells by the rule.
    fn divide(
        &self,
        complex: &Complex,
        cells: &[usize],
    ) -> Result<(Complex, Refinement), GrowthError> {
        Ok(match self.rule {
            DivisionRule::Midpoint => divide_midpoint(complex, cells)?,
            DivisionRule::LongestAxis => divide_longest_axis(complex, cells)?,
            DivisionRule::ShortestWall => divide_shortest_wall(complex, cells, WALL_DIRECTIONS)?,
        })
    }

    /// One backward-Euler step of the morphogen from the amounts `amount`
    /// on `complex` to t = `time`.
    fn diffuse(
        &self,
        complex: &Complex,
        amount: &[f64],
        time: f64,
    ) -> Result<Diffused, GrowthError> {
        let problem: Diffusion = self.heat.at(time);
        let n = complex.dim();
        let cells = complex.cell_count(n);
        let dt = self.heat.dt;
        let system = problem.assemble(complex)?;
        let matrix = &system.matrix;
        let size = system.rhs.len();
        // K plus the cells' mass and decay |σ|(1/Δt + λ) on the diagonal
        // (cell unknowns come first, face unknowns of fv-mimetic after).
        let mut entries = Vec::with_capacity(matrix.val().len() + cells);
        for column in 0..matrix.ncols() {
            let range = matrix.col_range(column);
            for (&row, &value) in matrix.row_idx()[range.clone()]
                .iter()
                .zip(&matrix.val()[range])
            {
                entries.push(Triplet::new(row, column, value));
            }
        }
        let measure = complex.measure(n);
        for (c, v) in measure.iter().enumerate() {
            entries.push(Triplet::new(c, c, v * (1.0 / dt + self.decay)));
        }
        let stepped = SparseColMat::<usize, f64>::try_new_from_triplets(size, size, &entries)
            .map_err(|e| GrowthError::Assembly(format!("{e:?}")))?;
        let mut rhs = system.rhs.clone();
        for (b, m) in rhs.iter_mut().zip(amount) {
            *b += m / dt;
        }
        let (values, report, _) = solve_with_fixed(
            &stepped,
            &rhs,
            &system.fixed,
            Factorization::Llt,
            Ordering::Automatic,
            None,
        )?;
        let solution = problem.solution_from_values(complex, values, 0.0)?;
        let outflow = problem.boundary_outflow(complex, &solution)?;
        Ok(Diffused {
            concentration: solution.values[..cells].to_vec(),
            sources: problem.source_total(complex)?,
            outflow: outflow.iter().sum(),
            face_outflow: outflow.iter().map(|q| q.abs()).sum(),
            solver_residual: report.relative_residual,
        })
    }
}

/// A diffusion step's result and balance terms.
struct Diffused {
    concentration: Vec<f64>,
    sources: f64,
    outflow: f64,
    face_outflow: f64,
    solver_residual: f64,
}

/// The amounts of the divided complex: each parent's amount shared among
/// its pieces in proportion to their measures, the last piece taking the
/// remainder (so the pieces add up to the parent to one rounding).
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_complex::refine::divide_midpoint;
/// use hasse_solver::refine::growth::share_amounts;
/// let k = interval(2, 0.0, 2.0).unwrap();
/// let (fine, r) = divide_midpoint(&k, &[0]).unwrap();
/// // Edge 0 (amount 3) halves into edges 0 and 2; edge 1 keeps 5.
/// assert_eq!(share_amounts(&fine, &r, &[3.0, 5.0]).unwrap(), vec![1.5, 5.0, 1.5]);
/// ```
pub fn share_amounts(
    fine: &Complex,
    refinement: &Refinement,
    amount: &[f64],
) -> Result<Vec<f64>, GrowthError> {
    let n = fine.dim();
    let zeta = refinement.zeta(n);
    if zeta.cols() != amount.len() || zeta.rows() != fine.cell_count(n) {
        return Err(GrowthError::Amounts {
            expected: zeta.cols(),
            found: amount.len(),
        });
    }
    let measure = fine.measure(n);
    let mut pieces: Vec<Vec<usize>> = vec![Vec::new(); amount.len()];
    for i in 0..zeta.rows() {
        match refinement.parent(n, i) {
            Some((j, _)) => pieces[j].push(i),
            None => {
                return Err(GrowthError::Split(SplitError::Invalid(format!(
                    "top cell {i} of the divided complex has no parent"
                ))))
            }
        }
    }
    let mut out = vec![0.0; zeta.rows()];
    for (j, of_j) in pieces.iter().enumerate() {
        let total: f64 = of_j.iter().map(|&i| measure[i]).sum();
        let mut given = 0.0;
        for (k, &i) in of_j.iter().enumerate() {
            out[i] = if k + 1 == of_j.len() {
                amount[j] - given
            } else {
                amount[j] * measure[i] / total
            };
            given += out[i];
        }
    }
    Ok(out)
}
