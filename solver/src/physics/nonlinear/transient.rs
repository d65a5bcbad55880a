//! The nonlinear problem in time, V ∂u/∂t − ∇·(k(u)∇u) + r(u) = f(x, t),
//! by the θ-scheme of the heat problem with Newton's method in every step.
//!
//! With F(u, t) = Aᵀ Ω(u) (A u − w(t)) + V r(u) − b(t) the steady residual
//! of the module documentation with the source and boundary data taken at
//! time t (the ghosts w(t) and Dirichlet values of the fixed unknowns from
//! g_D(·, t), the load b(t) from f(·, t) and the Neumann data g_N(·, t)),
//! and tⁿ = t₀ + n Δt, every step solves
//!
//! ```text
//!     V (uⁿ⁺¹ − uⁿ)/Δt + θ F(uⁿ⁺¹, tⁿ⁺¹) + (1 − θ) F(uⁿ, tⁿ) = 0
//! ```
//!
//! for the free unknowns of uⁿ⁺¹, its fixed ones held at g_D(·, tⁿ⁺¹) (the
//! linear heat problem's scheme, [`crate::physics::heat`], with F affine
//! there). F(uⁿ, tⁿ) is the previous step's converged residual, so each
//! level's data are assembled once; data constant in t are assembled once
//! for the run. Newton's Jacobian of a step is V/Δt + θ ∂F/∂u, on the
//! steady Jacobian's pattern and the run's one symbolic analysis.

use super::newton::{self, TimeStep, Workspace};
use super::{NonlinearDiffusion, NonlinearError, System};
use crate::physics::heat::{HeatBoundary, TimeFn};
use crate::physics::{BoundaryCondition, BoundaryKind, ScalarFn};
use hasse_complex::Complex;
use std::sync::Arc;

/// Time stepping of [`NonlinearDiffusion::solve_transient`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeStepping {
    /// Δt > 0.
    pub dt: f64,
    /// Number of steps (the end time is `steps · dt`).
    pub steps: usize,
    /// θ ∈ (0, 1]: 1 backward Euler (first order), ½ Crank–Nicolson
    /// (second order).
    pub theta: f64,
}

/// The levels of a transient solve.
#[derive(Clone, Debug)]
pub struct NonlinearTransient {
    /// (t, u on every unknown) for t = 0, Δt, …, steps·Δt.
    pub levels: Vec<(f64, Vec<f64>)>,
    /// Newton (or Picard) iterations of each step.
    pub iterations: Vec<usize>,
    /// ‖R(u_k)‖ for k = 0, 1, … of each step (the step's residual, with
    /// its V/Δt and (1 − θ) F(uⁿ, tⁿ) terms), the last one converged.
    pub histories: Vec<Vec<f64>>,
    /// Symbolic analyses of the Jacobian made (one for the whole run: the
    /// step's Jacobian V/Δt + θ J has the steady one's pattern).
    pub symbolic_analyses: usize,
}

/// Source and boundary data of a transient run that may depend on t, in
/// place of the problem's own [`NonlinearDiffusion::source`] and
/// [`NonlinearDiffusion::boundary`] (a Robin condition is refused as in
/// the steady problem).
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::Method;
/// use hasse_solver::physics::heat::{HeatBoundary, TimeFn};
/// use hasse_solver::physics::nonlinear::{Coefficient, NonlinearDiffusion, TimeStepping, TransientData};
/// use std::sync::Arc;
/// // u = t solves u_t − ((1 + u²) u')' = 1 with u = t at both ends; the
/// // θ-scheme is exact for a solution linear in t and constant in x.
/// let mesh = interval(8, 0.0, 1.0).unwrap();
/// let k = Coefficient::new(Arc::new(|u, _| 1.0 + u * u), Arc::new(|u, _| 2.0 * u));
/// let problem = NonlinearDiffusion::new(Method::Fe, k, Arc::new(|_| 0.0));
/// let data = TransientData {
///     start: 1.0,
///     source: TimeFn::Steady(Arc::new(|_| 1.0)),
///     boundary: ["xmin", "xmax"]
///         .map(|tag| (tag.to_string(), HeatBoundary::Dirichlet(TimeFn::Varying(Arc::new(|_, t| t)))))
///         .to_vec(),
/// };
/// let stepping = TimeStepping { dt: 0.1, steps: 5, theta: 0.5 };
/// let run = problem.solve_transient_with(&mesh, &|_| 1.0, &stepping, &data).unwrap();
/// for (t, u) in &run.levels {
///     assert!(u.iter().all(|v| (v - t).abs() < 1e-9));
/// }
/// assert!((run.levels[5].0 - 1.5).abs() < 1e-12);
/// ```
#[derive(Clone)]
pub struct TransientData {
    /// t₀, the time of the initial level.
    pub start: f64,
    /// f(x, t).
    pub source: TimeFn,
    /// (tag, condition with data in x and t), applied in order.
    pub boundary: Vec<(String, HeatBoundary)>,
}

/// g(·, t).
fn at(g: &TimeFn, t: f64) -> ScalarFn {
    match g {
        TimeFn::Steady(g) => Arc::clone(g),
        TimeFn::Varying(g) => {
            let g = Arc::clone(g);
            Arc::new(move |x: &[f64]| g(x, t))
        }
    }
}

impl TransientData {
    /// The problem's own source and boundary data, constant in time, from
    /// t₀ = 0.
    pub fn steady(problem: &NonlinearDiffusion) -> Self {
        let steady = |g: &ScalarFn| TimeFn::Steady(Arc::clone(g));
        Self {
            start: 0.0,
            source: steady(&problem.source),
            boundary: problem
                .boundary
                .iter()
                .map(|bc| {
                    let kind = match &bc.kind {
                        BoundaryKind::Dirichlet(g) => HeatBoundary::Dirichlet(steady(g)),
                        BoundaryKind::Neumann(g) => HeatBoundary::Neumann(steady(g)),
                        BoundaryKind::Robin { alpha, value } => HeatBoundary::Robin {
                            alpha: Arc::clone(alpha),
                            value: steady(value),
                        },
                    };
                    (bc.tag.clone(), kind)
                })
                .collect(),
        }
    }

    /// Whether some datum uses t (then every level re-assembles the load).
    pub fn varies(&self) -> bool {
        let varying = |g: &TimeFn| matches!(g, TimeFn::Varying(_));
        varying(&self.source)
            || self.boundary.iter().any(|(_, kind)| match kind {
                HeatBoundary::Dirichlet(g) | HeatBoundary::Neumann(g) => varying(g),
                HeatBoundary::Robin { value, .. } => varying(value),
            })
    }

    /// `problem` with these data at time t.
    pub fn problem_at(&self, problem: &NonlinearDiffusion, t: f64) -> NonlinearDiffusion {
        let mut at_t = problem.clone();
        at_t.source = at(&self.source, t);
        at_t.boundary = self
            .boundary
            .iter()
            .map(|(tag, kind)| BoundaryCondition {
                tag: tag.clone(),
                kind: match kind {
                    HeatBoundary::Dirichlet(g) => BoundaryKind::Dirichlet(at(g, t)),
                    HeatBoundary::Neumann(g) => BoundaryKind::Neumann(at(g, t)),
                    HeatBoundary::Robin { alpha, value } => BoundaryKind::Robin {
                        alpha: Arc::clone(alpha),
                        value: at(value, t),
                    },
                },
            })
            .collect();
        at_t
    }
}

impl NonlinearDiffusion {
    /// Integrate V ∂u/∂t + F(u) = 0 (F the steady residual) from u(0) =
    /// `initial` (at the unknowns' points; Dirichlet values where they
    /// hold) by V (u − u⁰)/Δt + θ F(u) + (1 − θ) F(u⁰) = 0, each step
    /// solved by the problem's iteration from u⁰, with the problem's data
    /// (constant in t); [`NonlinearDiffusion::solve_transient_with`] takes
    /// data in t.
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::physics::nonlinear::{Coefficient, NonlinearDiffusion, TimeStepping};
    /// use std::sync::Arc;
    /// // Insulated ends and a uniform start: u' = −u³, u = 1/√(1 + 2t).
    /// let mesh = interval(4, 0.0, 1.0).unwrap();
    /// let problem = NonlinearDiffusion::new(Method::Fv, Coefficient::constant(1.0), Arc::new(|_| 0.0))
    ///     .with_reaction(Coefficient::new(Arc::new(|u, _| u * u * u), Arc::new(|u, _| 3.0 * u * u)));
    /// let stepping = TimeStepping { dt: 0.01, steps: 100, theta: 0.5 };
    /// let run = problem.solve_transient(&mesh, &|_| 1.0, &stepping).unwrap();
    /// let (t, u) = run.levels.last().unwrap();
    /// assert!((u[0] - 1.0 / (1.0 + 2.0 * t).sqrt()).abs() < 1e-5);
    /// assert_eq!(run.symbolic_analyses, 1);
    /// ```
    pub fn solve_transient(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        stepping: &TimeStepping,
    ) -> Result<NonlinearTransient, NonlinearError> {
        self.solve_transient_with(complex, initial, stepping, &TransientData::steady(self))
    }

    /// As [`NonlinearDiffusion::solve_transient`] with source and boundary
    /// data in x and t from `data` (the problem's own are not used) and
    /// levels at tⁿ = t₀ + n Δt: V (uⁿ⁺¹ − uⁿ)/Δt + θ F(uⁿ⁺¹, tⁿ⁺¹) +
    /// (1 − θ) F(uⁿ, tⁿ) = 0 with F(·, t) assembled from the data at t (see
    /// [`crate::physics::nonlinear`]); the fixed unknowns of uⁿ⁺¹ hold
    /// g_D(·, tⁿ⁺¹).
    pub fn solve_transient_with(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        stepping: &TimeStepping,
        data: &TransientData,
    ) -> Result<NonlinearTransient, NonlinearError> {
        let TimeStepping { dt, steps, theta } = *stepping;
        if !(dt > 0.0 && dt.is_finite() && theta > 0.0 && theta <= 1.0 && steps > 0) {
            return Err(NonlinearError::Stepping { dt, steps, theta });
        }
        let start = data.start;
        let mut system = System::new(&data.problem_at(self, start), complex)?;
        let varies = data.varies();
        let d = system.dimension;
        let first: Vec<f64> = system.unknown_points.chunks(d).map(initial).collect();
        let mut u = newton::lifted(&system, Some(&first));
        let mut work = Workspace::new(&system);
        let mut levels = vec![(start, u.clone())];
        let mut iterations = Vec::with_capacity(steps);
        let mut histories = Vec::with_capacity(steps);
        // F(uⁿ, tⁿ), with the data of tⁿ.
        let mut previous_forcing = newton::forcing(self, &system, &u);
        for n in 1..=steps {
            let time = start + n as f64 * dt;
            let at_step = |error: NonlinearError| NonlinearError::AtTimeStep {
                step: n,
                time,
                error: Box::new(error),
            };
            let guess = if varies {
                // The data of tⁿ⁺¹; the step starts from uⁿ with the new
                // Dirichlet values.
                system.set_data(
                    System::data(&data.problem_at(self, time), complex).map_err(at_step)?,
                );
                newton::lifted(&system, Some(&u))
            } else {
                u.clone()
            };
            let step = TimeStep {
                rate: 1.0 / dt,
                theta,
                previous: &u,
                previous_forcing: &previous_forcing,
            };
            let converged =
                newton::iterate(self, &system, &mut work, guess, Some(&step)).map_err(at_step)?;
            iterations.push(converged.history.len() - 1);
            histories.push(converged.history);
            u = converged.u;
            previous_forcing = converged.forcing;
            levels.push((time, u.clone()));
        }
        Ok(NonlinearTransient {
            levels,
            iterations,
            histories,
            symbolic_analyses: work.analyses,
        })
    }
}
