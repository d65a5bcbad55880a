//! The heat balance of one step, from the method's own discrete fluxes.
//!
//! Summed over the free unknowns, the θ-scheme's equations read
//!
//! ```text
//! Σ m_i (u_i^{n+1} − u_i^n)/Δt + θ·outflow(t_{n+1}) + (1−θ)·outflow(t_n)
//!     = θ·∫f(t_{n+1}) + (1−θ)·∫f(t_n),
//! ```
//!
//! with the outflow of [`Diffusion::boundary_outflow`] at each level: the
//! interior fluxes cancel (cell-centred), and for nodal methods the
//! residual flux of a Dirichlet vertex carries what its equation does not
//! (its own stored heat included), so the balance closes to the solver's
//! residual, not to the discretisation error.

use super::{Heat, HeatError};
use crate::metric::Location;
use crate::physics::diffusion::Solution;
use hasse_complex::Complex;

/// The terms of one step's heat balance (see the module docs), each a
/// rate (per unit time).
#[derive(Clone, Debug, PartialEq)]
pub struct StepBalance {
    /// The start and end times of the step.
    pub times: (f64, f64),
    /// Σ m_i Δu_i / Δt over the free unknowns: the stored heat's rate of
    /// change.
    pub stored: f64,
    /// θ·outflow(t_{n+1}) + (1−θ)·outflow(t_n), summed over the boundary.
    pub outflow: f64,
    /// θ·∫f(t_{n+1}) + (1−θ)·∫f(t_n).
    pub sources: f64,
    /// stored + outflow − sources.
    pub imbalance: f64,
    /// |imbalance| over the largest of |stored|, Σ|outflow| per face and
    /// |sources|.
    pub relative: f64,
}

impl Heat {
    /// The field `values` at time `t` as a [`Solution`] of the steady
    /// problem at t, with the method's fluxes (the data at t give the
    /// Dirichlet values and the boundary fluxes).
    pub fn level_solution(
        &self,
        complex: &Complex,
        t: f64,
        values: &[f64],
    ) -> Result<Solution, HeatError> {
        Ok(self
            .at(t)
            .solution_from_values(complex, values.to_vec(), 0.0)?)
    }

    /// The flux −K∇u·n leaving the domain through each (n−1)-cell at a
    /// level (t, u), as [`crate::physics::diffusion::Diffusion::boundary_outflow`]
    /// gives it for the steady problem at t. For nodal methods the flux
    /// through Dirichlet faces includes the rate of heat stored in their
    /// vertices' dual cells, which the balance of [`Heat::step_balance`]
    /// needs and which vanishes as h → 0.
    pub fn level_outflow(
        &self,
        complex: &Complex,
        t: f64,
        values: &[f64],
    ) -> Result<Vec<f64>, HeatError> {
        let solution = self.level_solution(complex, t, values)?;
        Ok(self.at(t).boundary_outflow(complex, &solution)?)
    }

    /// The balance of the step from (t₀, u⁰) to (t₁, u¹), two consecutive
    /// levels of a run (see the module docs).
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// use hasse_solver::metric::Method;
    /// use hasse_solver::physics::heat::{Heat, HeatBoundary, TimeFn};
    /// use hasse_solver::physics::Conductivity;
    /// use std::sync::Arc;
    /// // Heated by a source, cooled through a boundary held at 0.
    /// let mesh = rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap();
    /// let heat = Heat::new(Method::Fv, Conductivity::Scalar(Arc::new(|_| 1.0)), 0.01)
    ///     .with_source(TimeFn::Steady(Arc::new(|_| 1.0)))
    ///     .with_boundary("boundary", HeatBoundary::Dirichlet(TimeFn::Steady(Arc::new(|_| 0.0))));
    /// let history = heat.run(&mesh, &|_| 0.0, 3, 1).unwrap();
    /// let (t, u) = (&history.times, &history.fields);
    /// let balance = heat.step_balance(&mesh, (t[2], &u[2]), (t[3], &u[3])).unwrap();
    /// assert!((balance.sources - 1.0).abs() < 1e-12);
    /// assert!(balance.relative < 1e-12);
    /// ```
    pub fn step_balance(
        &self,
        complex: &Complex,
        before: (f64, &[f64]),
        after: (f64, &[f64]),
    ) -> Result<StepBalance, HeatError> {
        let ((t0, u0), (t1, u1)) = (before, after);
        let theta = self.theta;
        let dt = t1 - t0;
        let mass = self.mass(complex)?;
        let mut rates = Vec::with_capacity(2);
        for (t, u) in [(t0, u0), (t1, u1)] {
            let problem = self.at(t);
            let solution = self.level_solution(complex, t, u)?;
            let outflow = problem.boundary_outflow(complex, &solution)?;
            rates.push((outflow, problem.source_total(complex)?));
        }
        // Dirichlet unknowns (nodal methods) hold their data: their
        // equations are not among the scheme's, and the outflow holds
        // what they store.
        let fixed = match self.at(t1).location() {
            Location::Nodal => self.at(t1).assemble(complex)?.fixed,
            _ => vec![None; u1.len()],
        };
        let stored: f64 = (0..u1.len())
            .filter(|&i| fixed[i].is_none())
            .map(|i| mass[i] * (u1[i] - u0[i]) / dt)
            .sum();
        let mix = |a: f64, b: f64| theta * b + (1.0 - theta) * a;
        let outflow = mix(rates[0].0.iter().sum(), rates[1].0.iter().sum());
        let sources = mix(rates[0].1, rates[1].1);
        let face_scale = mix(
            rates[0].0.iter().map(|q| q.abs()).sum(),
            rates[1].0.iter().map(|q| q.abs()).sum(),
        );
        let imbalance = stored + outflow - sources;
        let scale = stored.abs().max(face_scale).max(sources.abs());
        Ok(StepBalance {
            times: (t0, t1),
            stored,
            outflow,
            sources,
            imbalance,
            relative: if scale > 0.0 {
                imbalance.abs() / scale
            } else {
                0.0
            },
        })
    }
}
