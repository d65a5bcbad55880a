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

use crate::la::direct::{DirectSolver, Factorization, SolveError};
use crate::la::fixed::FixedSplit;
use crate::la::ordering::Ordering;
use crate::metric::mass::lumped_vertex_volumes;
use crate::metric::Location;
use crate::metric::Method;
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use crate::physics::diffusion::{Diffusion, DiffusionError};
use crate::physics::regions::Regional;
use crate::physics::{non_finite_text, point_text, BoundaryKind, Conductivity, Datum, ScalarFn};
use hasse_complex::Complex;
use sprs::CsMat;
use std::sync::Arc;
use std::time::Instant;

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
    /// Symbolic analysis plus numeric factorisation of M/Δt + θK, seconds.
    pub factorization_seconds: f64,
    /// The fill-reducing ordering the factorisation used (`None` for LU or
    /// when every unknown is fixed).
    pub ordering: Option<Ordering>,
    /// Mean seconds per step (right-hand side, data and solve; not the time
    /// spent in the observer of [`Heat::run_observed`]).
    pub seconds_per_step: f64,
    /// The part of `seconds_per_step` spent in the triangular solves.
    pub solve_seconds_per_step: f64,
    /// Steps taken.
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
///         HeatEvent::Step(n) => format!("step {n}"),
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
    },
    /// Step number `n` (1-based) has been taken.
    Step(usize),
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
        }
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

    /// Take `steps` steps from u(·, t₀) = `initial`, keeping every
    /// `save_every`-th level (t₀ and the last level are always kept; 0 keeps
    /// only those two).
    pub fn run(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        steps: usize,
        save_every: usize,
    ) -> Result<History, HeatError> {
        self.run_with_progress(complex, initial, steps, save_every, &mut |_| {})
    }

    /// As [`run`](Self::run), telling `progress` the number of each step
    /// taken (for progress display on long runs).
    pub fn run_with_progress(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        steps: usize,
        save_every: usize,
        progress: &mut dyn FnMut(usize),
    ) -> Result<History, HeatError> {
        self.run_observed(complex, initial, steps, save_every, &mut |event| {
            if let HeatEvent::Step(step) = event {
                progress(step);
            }
        })
    }

    /// As [`run`](Self::run), telling `observe` each saved level as soon as
    /// it is computed and each step as it is taken, so a caller can write
    /// levels while the run goes on (an interrupted run then keeps them).
    /// The levels it is told are those of the returned [`History`], in
    /// order; a failed run has told the ones completed before the failure.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::physics::Conductivity;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::physics::heat::{Heat, HeatEvent};
    /// use std::sync::Arc;
    /// let mesh = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let heat = Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), 0.01);
    /// let mut seen = Vec::new();
    /// let history = heat
    ///     .run_observed(&mesh, &|x| x[0], 4, 2, &mut |event| {
    ///         if let HeatEvent::Level { index, time, field } = event {
    ///             seen.push((index, time, field.len()));
    ///         }
    ///     })
    ///     .unwrap();
    /// assert_eq!(seen.len(), history.times.len()); // t = 0, 0.02, 0.04
    /// assert_eq!(seen[2], (2, history.times[2], 25));
    /// ```
    pub fn run_observed(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        steps: usize,
        save_every: usize,
        observe: &mut dyn FnMut(HeatEvent<'_>),
    ) -> Result<History, HeatError> {
        self.check()?;
        let n = complex.dim();
        let d = complex.embedding_dim();
        let (theta, dt, t0) = (self.theta, self.dt, self.start);
        let first = self.at(t0).assemble(complex)?;
        let mass = self.mass(complex)?;
        let location = first.location;
        let unknowns = first.rhs.len();

        // u⁰ at the points the unknowns stand for; Dirichlet values win.
        let points: Vec<f64> = match location {
            Location::Nodal => complex.vertices().as_slice().to_vec(),
            _ => first
                .cell_points
                .clone()
                .unwrap_or_else(|| complex.centroid(n).to_vec()),
        };
        if let Some(given) = &self.initial_field {
            if given.len() != unknowns {
                return Err(HeatError::InitialField {
                    given: given.len(),
                    unknowns,
                });
            }
        }
        let mut u: Vec<f64> = Vec::with_capacity(unknowns);
        for i in 0..unknowns {
            let x = &points[i * d..(i + 1) * d];
            let v = first.fixed[i].unwrap_or_else(|| match &self.initial_field {
                Some(given) => given[i],
                None => initial(x),
            });
            if !v.is_finite() {
                return Err(HeatError::NonFinite {
                    datum: Datum::Initial,
                    point: x.to_vec(),
                    value: v,
                    time: t0,
                });
            }
            u.push(v);
        }

        // The step matrix L = M/Δt + θK in canonical form: the lumped mass
        // (A = I, Ω = diag(m)) and the stiffness (A, Ω of the diffusion
        // assembly) stacked, [I; A]ᵀ diag(m/Δt, θΩ) [I; A]. Its free block
        // is factorised once; its free-row, fixed-column entries lift the
        // Dirichlet values of every step.
        let stiffness = &first.matrix;
        let lumped = Canonical::new(
            CsMat::<i8>::eye(unknowns),
            BlockMetric::from_weights(mass.clone()),
        )?;
        let started = Instant::now();
        let step_matrix =
            Canonical::sum(&[(1.0 / dt, &lumped), (theta, &first.canonical)])?.assemble_owned();
        let split = FixedSplit::new(&first.fixed);
        let free = split.free().to_vec();
        let reduced = split.free_block(&step_matrix);
        let lift = split.coupling(&step_matrix);
        drop(step_matrix);
        // Analysed once: every step reuses this factor.
        let (factor, ordering) = if free.is_empty() {
            (None, None)
        } else {
            let solver =
                DirectSolver::analyse_with(reduced.as_ref(), self.factorization, self.ordering)?;
            (Some(solver.factorize(reduced.as_ref())?), solver.ordering())
        };
        let factorization_seconds = started.elapsed().as_secs_f64();

        let vary = self.data_vary();
        let mut times = vec![t0];
        let mut fields = vec![u.clone()];
        observe(HeatEvent::Level {
            index: 0,
            time: t0,
            field: &u,
        });
        let mut b_old = first.rhs.clone();
        let mut fixed_new: Vec<Option<f64>> = first.fixed.clone();
        let mut b_new = first.rhs.clone();
        let mut rhs = vec![0.0; free.len()];
        let mut ku = vec![0.0; unknowns];
        let mut solve_seconds = 0.0;
        // The observer may write output or draw progress: its time is the
        // caller's, not the scheme's.
        let mut observed_seconds = 0.0;
        let started = Instant::now();
        for step in 1..=steps {
            let t = t0 + step as f64 * dt;
            if vary {
                // Only the data change: Ω, M and the boundary layout are kept.
                let (rhs, fixed) = self.at(t).data(complex, &first)?;
                b_new = rhs;
                fixed_new = fixed;
            }
            // K uⁿ (full matrix: fixed unknowns contribute to free rows).
            ku.iter_mut().for_each(|v| *v = 0.0);
            for (j, &uj) in u.iter().enumerate() {
                let range = stiffness.col_range(j);
                for (&i, &v) in stiffness.row_idx()[range.clone()]
                    .iter()
                    .zip(&stiffness.val()[range])
                {
                    ku[i] += v * uj;
                }
            }
            for (k, &i) in free.iter().enumerate() {
                rhs[k] = mass[i] / dt * u[i] - (1.0 - theta) * ku[i]
                    + theta * b_new[i]
                    + (1.0 - theta) * b_old[i];
            }
            // The fixed pattern is the tags', the same at every time.
            FixedSplit::lift_into(&lift, &fixed_new, &mut rhs);
            // An unstable θ < ½ overflows, in the right-hand side or in the
            // solve. The matrix was factorised, so a non-finite solution
            // (which the solve reports as a singular matrix) is overflow too.
            let overflow = |rhs: &[f64]| {
                let k = rhs
                    .iter()
                    .position(|v| !v.is_finite())
                    .or_else(|| {
                        (0..rhs.len()).max_by(|&a, &b| rhs[a].abs().total_cmp(&rhs[b].abs()))
                    })
                    .unwrap_or(0);
                let i = free[k];
                HeatError::Overflow {
                    point: points[i * d..(i + 1) * d].to_vec(),
                    time: t,
                    theta,
                }
            };
            if rhs.iter().any(|v| !v.is_finite()) {
                return Err(overflow(&rhs));
            }
            if let Some(factor) = &factor {
                let solving = Instant::now();
                let x = match factor.solve(&rhs) {
                    Ok(x) => x,
                    Err(SolveError::Singular { .. }) => return Err(overflow(&rhs)),
                    Err(e) => return Err(e.into()),
                };
                solve_seconds += solving.elapsed().as_secs_f64();
                for (k, &i) in free.iter().enumerate() {
                    u[i] = x[k];
                }
            }
            for (i, g) in fixed_new.iter().enumerate() {
                if let Some(g) = g {
                    u[i] = *g;
                }
            }
            if vary {
                std::mem::swap(&mut b_old, &mut b_new);
            }
            if step == steps || (save_every > 0 && step % save_every == 0) {
                let observing = Instant::now();
                observe(HeatEvent::Level {
                    index: times.len(),
                    time: t,
                    field: &u,
                });
                observed_seconds += observing.elapsed().as_secs_f64();
                times.push(t);
                fields.push(u.clone());
            }
            let observing = Instant::now();
            observe(HeatEvent::Step(step));
            observed_seconds += observing.elapsed().as_secs_f64();
        }
        let per_step = |seconds: f64| {
            if steps > 0 {
                seconds / steps as f64
            } else {
                0.0
            }
        };
        let seconds_per_step = per_step(started.elapsed().as_secs_f64() - observed_seconds);
        Ok(History {
            location,
            degree: if location == Location::Nodal { 0 } else { n },
            times,
            fields,
            factorization_seconds,
            ordering,
            seconds_per_step,
            solve_seconds_per_step: per_step(solve_seconds),
            steps,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hasse_complex::generate::rectangle;

    fn heat(dt: f64, theta: f64) -> Heat {
        Heat::new(Method::Fe, Conductivity::Scalar(Arc::new(|_| 1.0)), dt).with_theta(theta)
    }

    #[test]
    fn bad_steps_and_thetas_are_refused() {
        let mesh = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let one: ScalarFn = Arc::new(|_| 1.0);
        for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                heat(dt, 1.0).run(&mesh, &*one, 1, 1),
                Err(HeatError::TimeStep { .. })
            ));
        }
        for theta in [-0.1, 1.5, f64::NAN] {
            assert!(matches!(
                heat(0.1, theta).run(&mesh, &*one, 1, 1),
                Err(HeatError::Theta { .. })
            ));
        }
        let nan: ScalarFn = Arc::new(|_| f64::NAN);
        assert!(matches!(
            heat(0.1, 1.0).run(&mesh, &*nan, 1, 1),
            Err(HeatError::NonFinite {
                datum: Datum::Initial,
                ..
            })
        ));
        let bad_source = heat(0.1, 1.0).with_source(TimeFn::Varying(Arc::new(|_, t| {
            if t > 0.15 {
                f64::NAN
            } else {
                0.0
            }
        })));
        assert!(matches!(
            bad_source.run(&mesh, &*one, 3, 1),
            Err(HeatError::Diffusion(DiffusionError::NonFinite {
                datum: Datum::Source,
                ..
            }))
        ));
        let hybrid = Heat::new(Method::FvMimetic, Conductivity::Scalar(one.clone()), 0.1);
        assert!(matches!(
            hybrid.run(&mesh, &*one, 1, 1),
            Err(HeatError::Unsupported { .. })
        ));
    }

    #[test]
    fn an_unstable_scheme_reports_the_overflow_and_the_levels_before_it() {
        // Forward Euler with Δt far above h²/4: each step multiplies the
        // highest mode by about 1 − Δt λ_max ≈ −100, so it overflows.
        let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let h = heat(0.05, 0.0).with_boundary(
            "boundary",
            HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))),
        );
        let initial = |x: &[f64]| x[0] * (1.0 - x[0]) * x[1] * (1.0 - x[1]);
        let mut levels = Vec::new();
        let result = h.run_observed(&mesh, &initial, 1000, 10, &mut |event| {
            if let HeatEvent::Level { time, field, .. } = event {
                assert!(field.iter().all(|v| v.is_finite()));
                levels.push(time);
            }
        });
        let Err(HeatError::Overflow { time, .. }) = result else {
            panic!("expected a non-finite temperature, got {result:?}");
        };
        assert!(levels.len() >= 2 && time > *levels.last().unwrap());
        assert!(time < 1000.0 * 0.05);
    }

    #[test]
    fn insulated_domain_keeps_its_heat() {
        // No flux, no source: Σ mᵢ uᵢ is conserved exactly by every θ, since
        // 1ᵀK = 0 (K·1 = 0 and K symmetric).
        let mesh = rectangle(5, 4, [0.0, 1.0], [0.0, 2.0]).unwrap();
        let initial: ScalarFn = Arc::new(|x| x[0] * x[0] + x[1]);
        for theta in [0.0, 0.5, 1.0] {
            let h = heat(0.001, theta);
            let mass = h.mass(&mesh).unwrap();
            let history = h.run(&mesh, &*initial, 20, 0).unwrap();
            let total = |u: &[f64]| u.iter().zip(&mass).map(|(a, m)| a * m).sum::<f64>();
            let (start, end) = (total(&history.fields[0]), total(&history.fields[1]));
            assert!(
                (start - end).abs() < 1e-13 * start.abs(),
                "θ = {theta}: {start} → {end}"
            );
        }
    }
}
