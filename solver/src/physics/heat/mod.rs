//! Transient heat ∂u/∂t − ∇·(K∇u) = f(x, t) by the θ-scheme.
//!
//! Space is the diffusion problem's canonical form: the stiffness K = Aᵀ Ω A
//! and the load b(t) come from [`Diffusion::assemble`], so every method and
//! boundary condition of [`crate::physics::diffusion`] is available unchanged. Time
//! adds a lumped (diagonal) mass: the barycentric vertex volumes for nodal
//! unknowns (FE, DEC), the cell volumes for cell-centred ones (FV, FD). With
//! a constant step Δt every step solves
//!
//! ```text
//! (M/Δt + θ K) u^{n+1} = (M/Δt − (1−θ) K) u^n + θ b^{n+1} + (1−θ) b^n
//! ```
//!
//! on the free unknowns, the Dirichlet values at t^{n+1} moved to the
//! right-hand side (symmetric elimination), so the matrix is the same at
//! every step and is factorised once. θ = 1 is backward Euler (first
//! order, L-stable), θ = ½ Crank–Nicolson (second order, A-stable).

mod balance;
mod projection;
mod stepping;
mod system;
#[cfg(test)]
mod tests;

pub use balance::StepBalance;

use crate::la::direct::{Factorization, SolveError};
use crate::la::iterative::CgError;
use crate::la::ordering::Ordering;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::Location;
use crate::metric::Method;
use crate::multigrid::{MultigridError, SolverChoice};
use crate::operator::CanonicalError;
use crate::physics::diffusion::{Diffusion, DiffusionError, Iterative};
use crate::physics::regions::Regional;
use crate::physics::{non_finite_text, point_text, BoundaryKind, Conductivity, Datum, ScalarFn};
use hasse_complex::Complex;
use std::sync::Arc;

/// A scalar function of position and time.
pub type SpaceTimeFn = Arc<dyn Fn(&[f64], f64) -> f64 + Send + Sync>;

/// Data that may depend on time. Steady data are assembled once; varying
/// data are re-assembled at every time level.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::heat::{Heat, HeatBoundary, TimeFn};
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// // u = t solves ∂u/∂t − Δu = 1 with u = t on the boundary, and the
/// // θ-scheme is exact for it (it is linear in t and constant in x).
/// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let heat = Heat::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), 0.1)
///     .with_source(TimeFn::Steady(Arc::new(|_| 1.0)))
///     .with_boundary("boundary", HeatBoundary::Dirichlet(TimeFn::Varying(Arc::new(|_, t| t))));
/// let history = heat.run(&mesh, &|_| 0.0, 5, 1).unwrap();
/// for (t, u) in history.times.iter().zip(&history.fields) {
///     assert!(u.iter().all(|v| (v - t).abs() < 1e-12));
/// }
/// ```
#[derive(Clone)]
pub enum TimeFn {
    /// g(x), the same at every time.
    Steady(ScalarFn),
    /// g(x, t).
    Varying(SpaceTimeFn),
}

impl TimeFn {
    fn at(&self, t: f64) -> ScalarFn {
        match self {
            TimeFn::Steady(g) => g.clone(),
            TimeFn::Varying(g) => {
                let g = g.clone();
                Arc::new(move |x: &[f64]| g(x, t))
            }
        }
    }

    fn varies(&self) -> bool {
        matches!(self, TimeFn::Varying(_))
    }
}

/// A boundary condition of the heat problem (see [`BoundaryKind`]); the
/// Robin coefficient α enters the matrix and so may not depend on time.
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::heat::{Heat, HeatBoundary, TimeFn};
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// // A bar at u = 0 exchanging heat through both ends with an exterior
/// // at g/α = 0.5 (K∇u·n + 2u = 1) settles at u = 0.5.
/// let mesh = interval(8, 0.0, 1.0).unwrap();
/// let robin = HeatBoundary::Robin { alpha: Arc::new(|_| 2.0), value: TimeFn::Steady(Arc::new(|_| 1.0)) };
/// let heat = Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), 10.0)
///     .with_boundary("boundary", robin);
/// let history = heat.run(&mesh, &|_| 0.0, 20, 0).unwrap();
/// assert!(history.fields[1].iter().all(|u| (u - 0.5).abs() < 1e-9));
/// ```
#[derive(Clone)]
pub enum HeatBoundary {
    /// u = g(x, t).
    Dirichlet(TimeFn),
    /// K∇u·n = g(x, t), n outward: g > 0 heats the domain.
    Neumann(TimeFn),
    /// K∇u·n + α u = g(x, t), α > 0.
    Robin {
        /// The transfer coefficient α(x), constant in time.
        alpha: ScalarFn,
        /// g, the right-hand side of the condition.
        value: TimeFn,
    },
}

/// Why a transient run could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeatError {
    /// [`Heat::initial_field`] has not one value per unknown.
    #[error("the initial field has {given} values, but the problem has {unknowns} unknowns")]
    InitialField {
        /// Values given.
        given: usize,
        /// Unknowns of the problem on this mesh.
        unknowns: usize,
    },
    /// [`Heat::dt`] is zero, negative, NaN or infinite.
    #[error("time step Δt = {dt} must be positive and finite")]
    TimeStep {
        /// The step given.
        dt: f64,
    },
    /// [`Heat::theta`] lies outside [0, 1], where the θ-scheme is no
    /// consistent mix of the two time levels.
    #[error("θ = {theta} must lie in [0, 1] (1: backward Euler, ½: Crank–Nicolson)")]
    Theta {
        /// The θ given.
        theta: f64,
    },
    /// [`Heat::start`] is NaN or infinite.
    #[error("start time t₀ = {t0} is not finite")]
    StartTime {
        /// The start time given.
        t0: f64,
    },
    /// A given function (the initial value) is NaN or ±∞ at a point.
    #[error("{datum} is not finite ({}) at {} (t = {time})", non_finite_text(*.value), point_text(.point))]
    NonFinite {
        /// Which input gave the value.
        datum: Datum,
        /// Where it was evaluated.
        point: Vec<f64>,
        /// The value (NaN or ±∞).
        value: f64,
        /// The time level it was evaluated at.
        time: f64,
    },
    /// The temperature itself overflowed: an unstable scheme (θ < ½ with
    /// a step above the stability limit), not a wrong datum.
    #[error("the temperature is not finite at {} at t = {time}: the θ-scheme with θ = {theta} is only conditionally stable (θ < ½ needs Δt below about h²/(2K) per dimension); use θ ≥ ½ or a smaller time step", point_text(.point))]
    Overflow {
        /// Where the first non-finite value lives.
        point: Vec<f64>,
        /// The time level it appeared at.
        time: f64,
        /// The scheme's θ.
        theta: f64,
    },
    /// The method's unknowns have no lumped mass (the hybrid mimetic
    /// method's face unknowns stand for no volume).
    #[error("the {method} method has no mass matrix here: transient heat needs nodal or cell-centred unknowns")]
    Unsupported {
        /// The method's name.
        method: &'static str,
    },
    /// The spatial problem (conductivity, tags, boundary data, sources)
    /// could not be assembled.
    #[error(transparent)]
    Diffusion(#[from] DiffusionError),
    /// The factorisation of M/Δt + θK or a solve with it failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The operator M/Δt + θK could not be formed.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// Conjugate gradients on M/Δt + θK failed (no convergence within the
    /// iteration limit, or a matrix that is not positive definite).
    #[error("conjugate gradients on M/Δt + θK: {0}")]
    Cg(CgError),
    /// The multigrid preconditioner of M/Δt + θK could not be built or
    /// its iteration failed.
    #[error(transparent)]
    Multigrid(#[from] MultigridError),
    /// [`Adaptive::tolerance`] is not a positive finite number.
    #[error("the adaptive time-step tolerance must be positive and finite, found {tolerance}")]
    AdaptiveTolerance {
        /// The tolerance given.
        tolerance: f64,
    },
    /// Adaptive steps need an implicit scheme whose error the estimate
    /// knows: θ in [½, 1].
    #[error("adaptive time steps need θ in [½, 1] (backward Euler to Crank–Nicolson), found θ = {theta}")]
    AdaptiveTheta {
        /// The θ given.
        theta: f64,
    },
    /// The step size control halved the step 30 times below Δt₀ without
    /// meeting the tolerance (data discontinuous in time, or a tolerance
    /// near rounding).
    #[error("at t = {time} the step Δt = {dt:e} still has an estimated local error {estimate:e} above the tolerance {tolerance:e}: the time-step control gives up (is the data discontinuous in time, or the tolerance near rounding?)")]
    StepTooSmall {
        /// Where the control gave up.
        time: f64,
        /// The smallest step tried.
        dt: f64,
        /// Its relative error estimate.
        estimate: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },
}

/// Adaptive time steps for θ in [½, 1]: each step's local error is
/// estimated from an explicit predictor of the same order (see the
/// stepping module) and kept below `tolerance` relative to the size of
/// the solution, max(‖uⁿ‖∞, ‖uⁿ⁺¹‖∞). Step sizes are Δt₀·2ʲ (Δt₀ the
/// problem's `dt`): a rejected step is retried at half the size (or
/// less), an accepted one whose error would stay within the tolerance at
/// twice the size lets the next step double, and the last step is
/// shortened to land on the end time t₀ + steps·Δt₀. Each size is
/// factorised (or its multigrid built) once.
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::heat::{Adaptive, Heat, HeatBoundary, TimeFn};
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// // Two modes decaying at rates π² and 64π²: once the fast one has died
/// // out, the slow one lets the steps grow.
/// let mesh = interval(64, 0.0, 1.0).unwrap();
/// let heat = Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), 1e-4)
///     .with_theta(0.5)
///     .with_boundary("boundary", HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))))
///     .with_adaptive(Adaptive { tolerance: 1e-4 });
/// let pi = std::f64::consts::PI;
/// let initial = |x: &[f64]| (pi * x[0]).sin() + (8.0 * pi * x[0]).sin();
/// let history = heat.run(&mesh, &initial, 2000, 0).unwrap();
/// let report = history.adaptive.unwrap();
/// assert!((history.times.last().unwrap() - 0.2).abs() < 1e-12);
/// assert!(history.steps < 200); // far fewer than the 2000 steps of Δt₀
/// let largest = report.step_sizes.iter().fold(0.0f64, |m, &h| m.max(h));
/// assert!(largest >= 8.0 * report.step_sizes[0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// The relative local error allowed per step.
    pub tolerance: f64,
}

/// What the step-size control of an adaptive run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AdaptiveReport {
    /// The size of every accepted step, in order.
    pub step_sizes: Vec<f64>,
    /// The relative local error estimate of every accepted step.
    pub estimates: Vec<f64>,
    /// Steps rejected and retried smaller.
    pub rejected: usize,
    /// Distinct step sizes, each factorised or set up once.
    pub systems: usize,
}

/// Conjugate-gradient iterations of an iterative run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepIterations {
    /// Over all solves.
    pub total: usize,
    /// The most any one solve took.
    pub max: usize,
    /// Solves made (steps, plus retried adaptive steps).
    pub solves: usize,
}

impl StepIterations {
    fn add(&mut self, iterations: usize) {
        self.total += iterations;
        self.max = self.max.max(iterations);
        self.solves += 1;
    }

    /// Mean iterations per solve.
    pub fn mean(&self) -> f64 {
        if self.solves == 0 {
            0.0
        } else {
            self.total as f64 / self.solves as f64
        }
    }
}

/// The transient heat problem: method, conductivity, data and θ-scheme.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::Conductivity;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::heat::{Heat, HeatBoundary, TimeFn};
/// use std::sync::Arc;
/// // Cooling from u = 1 towards the boundary value 0.
/// let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let heat = Heat::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), 0.01)
///     .with_boundary("boundary", HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))));
/// let history = heat.run(&mesh, &|_| 1.0, 10, 5).unwrap();
/// assert_eq!(history.times.len(), 3); // t = 0, 0.05, 0.1
/// assert!((history.times[2] - 0.1).abs() < 1e-15);
/// // The maximum principle: values decay and stay in [0, 1].
/// assert!(history.fields[2].iter().all(|&u| u > 0.0 && u < 1.0));
/// // Cell-centred unknowns: the fields are 2-cochains, one value a square.
/// assert_eq!((history.degree, history.fields[1].len()), (2, 64));
/// ```
#[derive(Clone)]
pub struct Heat {
    /// The spatial discretisation (nodal or cell-centred).
    pub method: Method,
    /// K, constant in time.
    pub conductivity: Conductivity,
    /// f(x, t).
    pub source: TimeFn,
    /// f(x, t) per region of top cells, replacing [`Heat::source`] when
    /// set ([`Diffusion::with_source_by_region`] says how each method
    /// integrates it).
    pub source_by_region: Option<Arc<Regional<TimeFn>>>,
    /// u⁰ as values of the unknowns (a restart from a saved level),
    /// instead of the initial function of [`Heat::run`]; Dirichlet values
    /// at t₀ still win.
    pub initial_field: Option<Vec<f64>>,
    /// Applied in order, as in [`Diffusion::boundary`].
    pub boundary: Vec<(String, HeatBoundary)>,
    /// 1: backward Euler (default), ½: Crank–Nicolson, 0: forward Euler.
    pub theta: f64,
    /// The constant time step.
    pub dt: f64,
    /// Start time t₀.
    pub start: f64,
    /// Factorisation of M/Δt + θK (default LLᵀ: it is SPD).
    pub factorization: Factorization,
    /// Its fill-reducing ordering (default automatic).
    pub ordering: Ordering,
    /// Conjugate gradients instead of a factorisation, started at every
    /// step from the previous levels (see [`Heat::with_solver`] and
    /// [`Heat::projection`]).
    pub iterative: Option<Iterative>,
    /// Adaptive step sizes instead of the constant `dt`.
    pub adaptive: Option<Adaptive>,
    /// Where the conjugate gradients of an iterative run start: with
    /// `projection` = k ≥ 1, the field closest to the new level in the
    /// energy norm of M/Δt + θK among the combinations of the last levels
    /// of the same step size (Fischer's projection, at most k of them,
    /// restarting from the newest when full); with 0, uⁿ extrapolated
    /// linearly along the last step. Default [`Heat::PROJECTION`]. The
    /// tolerance is the same either way; only the iterations differ.
    pub projection: usize,
}

/// The computed time levels and how long they took.
#[derive(Clone, Debug)]
pub struct History {
    /// Where the unknowns of the fields live.
    pub location: Location,
    /// Degree of the cochain the fields are: 0 (nodal) or n (cell-centred).
    pub degree: usize,
    /// Saved times, t₀ first.
    pub times: Vec<f64>,
    /// The field at each saved time (all unknowns, fixed ones included).
    pub fields: Vec<Vec<f64>>,
    /// Building the step solver: symbolic analysis plus numeric
    /// factorisation of M/Δt + θK, or its multigrid setup (for every step
    /// size of an adaptive run), seconds.
    pub factorization_seconds: f64,
    /// How the steps were solved, e.g. "direct LLᵀ" or "CG with geometric
    /// multigrid".
    pub solver: String,
    /// Conjugate-gradient iterations, when the steps were solved
    /// iteratively.
    pub iterations: Option<StepIterations>,
    /// The step-size control's record, for an adaptive run.
    pub adaptive: Option<AdaptiveReport>,
    /// The fill-reducing ordering the factorisation used (`None` for LU or
    /// when every unknown is fixed).
    pub ordering: Option<Ordering>,
    /// Mean seconds per step (right-hand side, data and solve; not the time
    /// spent in the observer of [`Heat::run_observed`]).
    pub seconds_per_step: f64,
    /// The part of `seconds_per_step` spent in the triangular solves.
    pub solve_seconds_per_step: f64,
    /// Steps taken (accepted steps, for an adaptive run).
    pub steps: usize,
}

/// What [`Heat::run_observed`] reports while it runs.
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::heat::{Heat, HeatEvent};
/// use hasse_solver::physics::Conductivity;
/// use std::sync::Arc;
/// let mesh = interval(4, 0.0, 1.0).unwrap();
/// let heat = Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), 0.1);
/// let mut events = Vec::new();
/// heat.run_observed(&mesh, &|_| 1.0, 2, 1, &mut |event| {
///     events.push(match event {
///         HeatEvent::Level { index, .. } => format!("level {index}"),
///         HeatEvent::Step { number, .. } => format!("step {number}"),
///     })
/// })
/// .unwrap();
/// // Each saved level is told before the step that produced it.
/// assert_eq!(events, ["level 0", "level 1", "step 1", "level 2", "step 2"]);
/// ```
#[derive(Clone, Copy, Debug)]
pub enum HeatEvent<'a> {
    /// Saved level `index` (0 is t₀) at `time`, with all unknowns as in
    /// [`History::fields`]; told before the step's [`HeatEvent::Step`].
    Level {
        /// Position among the saved levels.
        index: usize,
        /// Its time t.
        time: f64,
        /// u at t, every unknown.
        field: &'a [f64],
        /// The level one step before (its time and field), from which
        /// this one was computed; `None` for t₀. With it the step's
        /// balance can be checked ([`Heat::step_balance`]).
        previous: Option<(f64, &'a [f64])>,
    },
    /// A step has been taken (an accepted step, in an adaptive run).
    Step {
        /// Its number, 1-based.
        number: usize,
        /// The time it reached.
        time: f64,
    },
}

impl Heat {
    /// No source, no boundary conditions (homogeneous Neumann), backward
    /// Euler from t₀ = 0 with step `dt`, LLᵀ.
    pub fn new(method: Method, conductivity: Conductivity, dt: f64) -> Self {
        Self {
            method,
            conductivity,
            source: TimeFn::Steady(Arc::new(|_| 0.0)),
            source_by_region: None,
            initial_field: None,
            boundary: Vec::new(),
            theta: 1.0,
            dt,
            start: 0.0,
            factorization: Factorization::Llt,
            ordering: Ordering::Automatic,
            iterative: None,
            adaptive: None,
            projection: Self::PROJECTION,
        }
    }

    /// The default [`Heat::projection`]: levels kept for the start of
    /// iterative steps.
    pub const PROJECTION: usize = 8;

    /// Choose how every step's system M/Δt + θK is solved, as
    /// [`Diffusion::with_solver`] does for a steady problem:
    /// [`SolverChoice::Direct`] factorises it once (per step size),
    /// [`SolverChoice::Multigrid`] builds a multigrid preconditioner once
    /// and runs conjugate gradients to `tolerance` at every step, started
    /// from the previous levels (see [`Heat::projection`]),
    /// [`SolverChoice::Auto`] applies
    /// [`crate::multigrid::automatic`] to this method's unknowns on `complex`.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::multigrid::{Hierarchy, SolverChoice};
    /// use hasse_solver::physics::heat::{Heat, HeatBoundary, TimeFn};
    /// use hasse_solver::physics::Conductivity;
    /// use std::sync::Arc;
    /// let mesh = rectangle(32, 32, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let heat = |choice| {
    ///     Heat::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), 1e-3)
    ///         .with_boundary("boundary", HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))))
    ///         .with_solver(choice, 1e-10, &mesh)
    ///         .run(&mesh, &|x| x[0] * (1.0 - x[0]), 10, 0)
    ///         .unwrap()
    /// };
    /// let direct = heat(SolverChoice::Direct);
    /// let multigrid = heat(SolverChoice::Multigrid(Hierarchy::Grid { cells: vec![32, 32] }));
    /// // Warm-started from the previous level, a few iterations per step.
    /// assert!(multigrid.iterations.unwrap().max <= 6);
    /// for (a, b) in direct.fields[1].iter().zip(&multigrid.fields[1]) {
    ///     assert!((a - b).abs() < 1e-9);
    /// }
    /// ```
    pub fn with_solver(mut self, choice: SolverChoice, tolerance: f64, complex: &Complex) -> Self {
        let location = self.at(self.start).location();
        self.iterative = Iterative::chosen(choice, tolerance, location, complex);
        self
    }

    /// Step with adaptive step sizes (see [`Adaptive`]).
    pub fn with_adaptive(mut self, adaptive: Adaptive) -> Self {
        self.adaptive = Some(adaptive);
        self
    }

    /// Set the source f.
    pub fn with_source(mut self, source: TimeFn) -> Self {
        self.source = source;
        self
    }

    /// Set a source per region of top cells.
    pub fn with_source_by_region(mut self, source: Regional<TimeFn>) -> Self {
        self.source_by_region = Some(Arc::new(source));
        self
    }

    /// Add a boundary condition on a tag.
    pub fn with_boundary(mut self, tag: &str, kind: HeatBoundary) -> Self {
        self.boundary.push((tag.to_string(), kind));
        self
    }

    /// Set θ.
    pub fn with_theta(mut self, theta: f64) -> Self {
        self.theta = theta;
        self
    }

    /// The steady problem −∇·(K∇u) = f(·, t) with the boundary data at t.
    pub fn at(&self, t: f64) -> Diffusion {
        let mut problem = Diffusion::new(self.method, self.conductivity.clone(), self.source.at(t));
        problem.factorization = self.factorization;
        problem.ordering = self.ordering;
        if let Some(regional) = &self.source_by_region {
            problem.source_by_region = Some(Arc::new(regional.map(|f| f.at(t))));
        }
        for (tag, kind) in &self.boundary {
            let kind = match kind {
                HeatBoundary::Dirichlet(g) => BoundaryKind::Dirichlet(g.at(t)),
                HeatBoundary::Neumann(g) => BoundaryKind::Neumann(g.at(t)),
                HeatBoundary::Robin { alpha, value } => BoundaryKind::Robin {
                    alpha: alpha.clone(),
                    value: value.at(t),
                },
            };
            problem = problem.with_boundary(tag, kind);
        }
        problem
    }

    fn data_vary(&self) -> bool {
        self.source.varies()
            || self.source_by_region.as_ref().is_some_and(|r| {
                r.pieces().iter().any(|(_, f)| f.varies())
                    || r.default().is_some_and(TimeFn::varies)
            })
            || self.boundary.iter().any(|(_, kind)| match kind {
                HeatBoundary::Dirichlet(g) | HeatBoundary::Neumann(g) => g.varies(),
                HeatBoundary::Robin { value, .. } => value.varies(),
            })
    }

    /// The lumped mass of each unknown.
    pub fn mass(&self, complex: &Complex) -> Result<Vec<f64>, HeatError> {
        let n = complex.dim();
        match self.at(self.start).location() {
            Location::Nodal => Ok(lumped_vertex_volumes(complex)),
            Location::CellCentred => Ok(complex.measure(n).to_vec()),
            Location::Hybrid => Err(HeatError::Unsupported {
                method: self.method.name(),
            }),
        }
    }

    fn check(&self) -> Result<(), HeatError> {
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(HeatError::TimeStep { dt: self.dt });
        }
        if !(0.0..=1.0).contains(&self.theta) {
            // NaN fails `contains` too.
            return Err(HeatError::Theta { theta: self.theta });
        }
        if !self.start.is_finite() {
            return Err(HeatError::StartTime { t0: self.start });
        }
        Ok(())
    }
}
