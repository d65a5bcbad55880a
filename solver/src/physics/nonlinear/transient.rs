//! The nonlinear problem in time, V ∂u/∂t − ∇·(k(u)∇u) + r(u) = f, by the
//! θ-scheme of the heat problem with Newton's method in every step.

use super::newton::{self, TimeStep, Workspace};
use super::{NonlinearDiffusion, NonlinearError, System};
use hasse_complex::Complex;

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
    /// Symbolic analyses of the Jacobian made (one for the whole run: the
    /// step's Jacobian V/Δt + θ J has the steady one's pattern).
    pub symbolic_analyses: usize,
}

impl NonlinearDiffusion {
    /// Integrate V ∂u/∂t + F(u) = 0 (F the steady residual) from u(0) =
    /// `initial` (at the unknowns' points; Dirichlet values where they
    /// hold) by V (u − u⁰)/Δt + θ F(u) + (1 − θ) F(u⁰) = 0, each step
    /// solved by the problem's iteration from u⁰. Data do not depend on t.
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
        let TimeStepping { dt, steps, theta } = *stepping;
        if !(dt > 0.0 && dt.is_finite() && theta > 0.0 && theta <= 1.0 && steps > 0) {
            return Err(NonlinearError::Stepping { dt, steps, theta });
        }
        let system = System::new(self, complex)?;
        let d = system.dimension;
        let start: Vec<f64> = system.unknown_points.chunks(d).map(initial).collect();
        let mut u = newton::lifted(&system, Some(&start));
        let mut work = Workspace::new(&system);
        let mut levels = vec![(0.0, u.clone())];
        let mut iterations = Vec::with_capacity(steps);
        let mut previous_forcing = newton::forcing(self, &system, &u);
        for n in 1..=steps {
            let step = TimeStep {
                rate: 1.0 / dt,
                theta,
                previous: &u,
                previous_forcing: &previous_forcing,
            };
            // Each step starts from the last level.
            let converged = newton::iterate(self, &system, &mut work, u.clone(), Some(&step))
                .map_err(|error| NonlinearError::AtTimeStep {
                    step: n,
                    time: n as f64 * dt,
                    error: Box::new(error),
                })?;
            iterations.push(converged.history.len() - 1);
            u = converged.u;
            previous_forcing = converged.forcing;
            levels.push((n as f64 * dt, u.clone()));
        }
        Ok(NonlinearTransient {
            levels,
            iterations,
            symbolic_analyses: work.analyses,
        })
    }
}
