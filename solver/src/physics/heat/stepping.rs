//! The time loop of the θ-scheme: constant steps, or adaptive steps chosen
//! by an embedded estimate of the local error (see [`Adaptive`]).

use super::projection::Projection;
use super::system::{StepFailure, StepSolver, StepSystem};
use super::{Adaptive, AdaptiveReport, Heat, HeatError, HeatEvent, History, StepIterations};
use crate::la::fixed::FixedSplit;
use crate::la::iterative::{CgWork, RowMatrix};
use crate::metric::Location;
use crate::operator::{BlockMetric, Canonical};
use crate::physics::Datum;
use hasse_complex::Complex;
use sprs::CsMat;
use std::time::Instant;

impl Heat {
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
            if let HeatEvent::Step { number, .. } = event {
                progress(number);
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
    ///         if let HeatEvent::Level { index, time, field, .. } = event {
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
        // is solved at every step; its free-row, fixed-column entries lift
        // the Dirichlet values of every step.
        let lumped = Canonical::new(
            CsMat::<i8>::eye(unknowns),
            BlockMetric::from_weights(mass.clone()),
        )?;
        let split = FixedSplit::new(&first.fixed);
        let free = split.free().to_vec();
        let mut solver = match &self.iterative {
            Some(settings) => StepSolver::Iterative { settings },
            None => StepSolver::Direct {
                factorization: self.factorization,
                ordering: self.ordering,
                analysis: None,
            },
        };
        let cg_options = self.iterative.as_ref().map(|s| s.options);
        let mut systems = vec![StepSystem::new(
            dt,
            theta,
            &lumped,
            &first.canonical,
            &split,
            &mut solver,
        )?];
        let mut setup_seconds = systems[0].setup_seconds;
        // K uⁿ with the full stiffness: fixed unknowns contribute to free
        // rows. Stored by rows once, so each product is one parallel pass.
        let stiffness = RowMatrix::from_symmetric(&first.matrix).map_err(HeatError::Cg)?;

        let vary = self.data_vary();
        let mut times = vec![t0];
        let mut fields = vec![u.clone()];
        observe(HeatEvent::Level {
            index: 0,
            time: t0,
            field: &u,
            previous: None,
        });
        let mut b_old = first.rhs.clone();
        let mut b_new = first.rhs.clone();
        let mut fixed_new: Vec<Option<f64>> = first.fixed.clone();
        let mut rhs = vec![0.0; free.len()];
        let mut ku = vec![0.0; unknowns];
        // The vectors of every step, allocated once: the solution on the
        // free unknowns (the iterative start on entry to the solve), the
        // next level, the solve's own vectors.
        let mut x = vec![0.0; free.len()];
        let mut u_next = u.clone();
        let mut cg_work = CgWork::default();
        // Fischer's projection start for iterative steps (see the
        // projection module), unless `projection` is 0.
        let mut projection = match &self.iterative {
            Some(_) if self.projection > 0 => Some(Projection::new(self.projection)),
            _ => None,
        };
        let mut solve_seconds = 0.0;
        let mut iterations = StepIterations::default();
        let mut controller = match self.adaptive {
            Some(adaptive) => Some(Controller::new(adaptive, theta, dt)?),
            None => None,
        };
        let end = t0 + steps as f64 * dt;
        // The observer may write output or draw progress: its time is the
        // caller's, not the scheme's. (Step systems set up on the way, for
        // new step sizes, are counted here too: they are setup.)
        let mut excluded_seconds = 0.0;
        let started = Instant::now();
        let mut t = t0;
        let mut step = 0;
        // The last step's size and its starting level on the free
        // unknowns, for the extrapolated start of iterative steps (when
        // the projection is off).
        let mut previous: Option<(f64, Vec<f64>)> = None;
        // K uⁿ enters the right-hand side with the factor 1 − θ and the
        // error estimate of adaptive steps: backward Euler at constant
        // steps needs no product.
        let needs_ku = theta != 1.0 || controller.is_some();
        loop {
            // The step size and the time it reaches.
            let (mut h, mut t_new) = match &controller {
                None if step == steps => break,
                None => (dt, t0 + (step + 1) as f64 * dt),
                Some(_) if t >= end - 1e-12 * end.abs().max(dt) => break,
                Some(c) => c.step_to(t, end),
            };
            if needs_ku {
                stiffness.multiply(&u, &mut ku);
            }
            // uⁿ' = M⁻¹(bⁿ − K uⁿ) on the free unknowns, for the error
            // estimate of adaptive steps.
            let derivative: Vec<f64> = match &controller {
                Some(_) => free.iter().map(|&i| (b_old[i] - ku[i]) / mass[i]).collect(),
                None => Vec::new(),
            };
            // Tried until the step is accepted (always, at constant Δt).
            loop {
                if vary {
                    // Only the data change: Ω, M and the boundary layout are kept.
                    let (rhs, fixed) = self.at(t_new).data(complex, &first)?;
                    b_new = rhs;
                    fixed_new = fixed;
                }
                for (k, &i) in free.iter().enumerate() {
                    rhs[k] = mass[i] / h * u[i] - (1.0 - theta) * ku[i]
                        + theta * b_new[i]
                        + (1.0 - theta) * b_old[i];
                }
                let system = match systems.iter().position(|s| s.dt == h) {
                    Some(k) => &systems[k],
                    None => {
                        let system = StepSystem::new(
                            h,
                            theta,
                            &lumped,
                            &first.canonical,
                            &split,
                            &mut solver,
                        )?;
                        setup_seconds += system.setup_seconds;
                        // Reported as setup, not as stepping.
                        excluded_seconds += system.setup_seconds;
                        systems.push(system);
                        &systems[systems.len() - 1]
                    }
                };
                // The fixed pattern is the tags', the same at every time.
                system.lift_into(&fixed_new, &mut rhs);
                // An unstable θ < ½ overflows, in the right-hand side or in
                // the solve.
                let overflow = |rhs: &[f64]| {
                    let k = rhs
                        .iter()
                        .position(|v| !v.is_finite())
                        .or_else(|| {
                            (0..rhs.len()).max_by(|&a, &b| rhs[a].abs().total_cmp(&rhs[b].abs()))
                        })
                        .unwrap_or(0);
                    let i = free.get(k).copied().unwrap_or(0);
                    HeatError::Overflow {
                        point: points[i * d..(i + 1) * d].to_vec(),
                        time: t_new,
                        theta,
                    }
                };
                if rhs.iter().any(|v| !v.is_finite()) {
                    return Err(overflow(&rhs));
                }
                // Where CG starts. With the projection: the level closest
                // to the answer in the energy norm within the span of the
                // last levels of this step size (uⁿ alone, its product
                // formed once, when the span is new). Without: uⁿ
                // extrapolated along the last step, uⁿ + (h/h_prev)(uⁿ −
                // uⁿ⁻¹), whose error is O(h²) where uⁿ's is O(h); the
                // first step starts from u⁰. A direct solve reads no start.
                let multiply = |v: &[f64], y: &mut [f64]| {
                    system.multiply(v, y);
                };
                match (&mut projection, &previous) {
                    (Some(p), _) => {
                        if !p.for_step(h) {
                            free.iter().zip(x.iter_mut()).for_each(|(&i, x)| *x = u[i]);
                            p.add(&x, &[], &[], &multiply);
                        }
                        p.guess(&rhs, &mut x);
                    }
                    (None, Some((h_prev, u_prev))) if self.iterative.is_some() => {
                        let r = h / h_prev;
                        for ((x, &i), p) in x.iter_mut().zip(&free).zip(u_prev) {
                            *x = u[i] + r * (u[i] - p);
                        }
                    }
                    _ => free.iter().zip(x.iter_mut()).for_each(|(&i, x)| *x = u[i]),
                }
                let solving = Instant::now();
                let taken = match system.solve(&rhs, &mut x, cg_options.as_ref(), &mut cg_work) {
                    Ok(taken) => taken,
                    Err(StepFailure::Overflow) => return Err(overflow(&rhs)),
                    Err(StepFailure::Error(e)) => return Err(e),
                };
                solve_seconds += solving.elapsed().as_secs_f64();
                if let Some(taken) = taken {
                    iterations.add(taken);
                }
                // A start that needed no iteration is the level, and it
                // lies in the span already: nothing to add.
                if let (Some(p), Some(1..)) = (projection.as_mut(), taken) {
                    p.add(&x, &rhs, cg_work.residual(), &multiply);
                }
                u_next.copy_from_slice(&u);
                for (k, &i) in free.iter().enumerate() {
                    u_next[i] = x[k];
                }
                for (i, g) in fixed_new.iter().enumerate() {
                    if let Some(g) = g {
                        u_next[i] = *g;
                    }
                }
                let Some(c) = controller.as_mut() else {
                    break;
                };
                let estimate = c.estimate(h, &free, &u, &u_next, &derivative);
                if c.accept(estimate, t_new)? {
                    c.record(h, estimate, derivative);
                    break;
                }
                (h, t_new) = c.step_to(t, end);
            }
            // u becomes uⁿ⁺¹ and u_next keeps uⁿ until the next step
            // overwrites it.
            std::mem::swap(&mut u, &mut u_next);
            let u_old = &u_next;
            let t_old = std::mem::replace(&mut t, t_new);
            if self.iterative.is_some() && projection.is_none() {
                let kept = previous.get_or_insert_with(|| (h, vec![0.0; free.len()]));
                kept.0 = h;
                for (p, &i) in kept.1.iter_mut().zip(&free) {
                    *p = u_old[i];
                }
            }
            step += 1;
            if vary {
                std::mem::swap(&mut b_old, &mut b_new);
            }
            let last = match &controller {
                None => step == steps,
                Some(_) => t >= end - 1e-12 * end.abs().max(dt),
            };
            if last || (save_every > 0 && step % save_every == 0) {
                let observing = Instant::now();
                observe(HeatEvent::Level {
                    index: times.len(),
                    time: t,
                    field: &u,
                    previous: Some((t_old, u_old)),
                });
                excluded_seconds += observing.elapsed().as_secs_f64();
                times.push(t);
                fields.push(u.clone());
            }
            let observing = Instant::now();
            observe(HeatEvent::Step {
                number: step,
                time: t,
            });
            excluded_seconds += observing.elapsed().as_secs_f64();
        }
        let per_step = |seconds: f64| {
            if step > 0 {
                seconds / step as f64
            } else {
                0.0
            }
        };
        let seconds_per_step = per_step(started.elapsed().as_secs_f64() - excluded_seconds);
        Ok(History {
            location,
            degree: if location == Location::Nodal { 0 } else { n },
            times,
            fields,
            factorization_seconds: setup_seconds,
            ordering: solver.ordering(),
            solver: solver.name(),
            seconds_per_step,
            solve_seconds_per_step: per_step(solve_seconds),
            steps: step,
            iterations: self.iterative.as_ref().map(|_| iterations),
            adaptive: controller.map(|c| c.report(systems.len())),
        })
    }
}

/// The step-size control of [`Adaptive`]: sizes Δt₀·2ʲ, so that each is
/// factorised (or set up) once however often the control returns to it.
struct Controller {
    tolerance: f64,
    theta: f64,
    base: f64,
    level: i32,
    /// The previous accepted step: its size and uⁿ⁻¹' (for the
    /// Crank–Nicolson estimate).
    previous: Option<(f64, Vec<f64>)>,
    report: AdaptiveReport,
}

/// Halvings below Δt₀ before the run gives up (Δt₀ / 2³⁰ ≈ 10⁻⁹ Δt₀).
const MAX_HALVINGS: i32 = 30;

impl Controller {
    fn new(adaptive: Adaptive, theta: f64, dt: f64) -> Result<Self, HeatError> {
        if !(adaptive.tolerance.is_finite() && adaptive.tolerance > 0.0) {
            return Err(HeatError::AdaptiveTolerance {
                tolerance: adaptive.tolerance,
            });
        }
        if theta < 0.5 {
            return Err(HeatError::AdaptiveTheta { theta });
        }
        Ok(Self {
            tolerance: adaptive.tolerance,
            theta,
            base: dt,
            level: 0,
            previous: None,
            report: AdaptiveReport::default(),
        })
    }

    /// The next step from `t`: Δt₀·2ʲ, shortened to land on `end`.
    fn step_to(&self, t: f64, end: f64) -> (f64, f64) {
        let h = self.base * 2f64.powi(self.level);
        if t + h >= end - 1e-12 * end.abs().max(h) {
            (end - t, end)
        } else {
            (h, t + h)
        }
    }

    /// Whether the estimate uses the second-order (Crank–Nicolson) pair.
    fn second_order(&self) -> bool {
        self.theta == 0.5 && self.previous.is_some()
    }

    /// The local error of the step uⁿ → uⁿ⁺¹ of size `h`, relative to
    /// max(‖uⁿ‖∞, ‖uⁿ⁺¹‖∞): the difference from an explicit predictor of
    /// the same order, scaled by the ratio of the two schemes' error
    /// constants. θ ≠ ½: forward Euler, u_θ − u_FE ≈ θh²u″ and the θ-scheme
    /// errs by (θ − ½)h²u″. Crank–Nicolson: the variable-step
    /// Adams–Bashforth-2 predictor, whose difference from CN is
    /// 3(1 + h_{n−1}/h) times CN's error (Gresho and Sani); its first step,
    /// with no previous derivative, uses the forward-Euler difference
    /// halved, an overestimate.
    fn estimate(&self, h: f64, free: &[usize], u: &[f64], u_new: &[f64], du: &[f64]) -> f64 {
        let mut error: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for (k, &i) in free.iter().enumerate() {
            let e = match &self.previous {
                Some((h_prev, du_prev)) if self.theta == 0.5 => {
                    let r = h / h_prev;
                    let predicted = u[i] + 0.5 * h * ((2.0 + r) * du[k] - r * du_prev[k]);
                    (u_new[i] - predicted) / (3.0 * (1.0 + 1.0 / r))
                }
                _ => {
                    let c = if self.theta == 0.5 {
                        0.5
                    } else {
                        (self.theta - 0.5) / self.theta
                    };
                    c * (u_new[i] - (u[i] + h * du[k]))
                }
            };
            error = error.max(e.abs());
            scale = scale.max(u[i].abs()).max(u_new[i].abs());
        }
        if scale > 0.0 {
            error / scale
        } else {
            0.0
        }
    }

    /// Accept the step or halve (at least) the level; refuses once the
    /// step has fallen [`MAX_HALVINGS`] halvings below Δt₀.
    fn accept(&mut self, estimate: f64, time: f64) -> Result<bool, HeatError> {
        let order = if self.second_order() { 2.0 } else { 1.0 };
        if estimate <= self.tolerance {
            // Doubling multiplies the local error by 2^(p+1): grow only
            // when that stays safely within the tolerance.
            if estimate * 2f64.powf(order + 1.0) <= 0.8 * self.tolerance {
                self.level += 1;
            }
            return Ok(true);
        }
        self.report.rejected += 1;
        let factor = 0.9 * (self.tolerance / estimate).powf(1.0 / (order + 1.0));
        let drop = (-factor.log2()).ceil().max(1.0) as i32;
        self.level -= drop;
        if self.level < -MAX_HALVINGS {
            return Err(HeatError::StepTooSmall {
                time,
                dt: self.base * 2f64.powi(self.level + drop),
                estimate,
                tolerance: self.tolerance,
            });
        }
        Ok(false)
    }

    fn record(&mut self, h: f64, estimate: f64, derivative: Vec<f64>) {
        self.report.step_sizes.push(h);
        self.report.estimates.push(estimate);
        self.previous = Some((h, derivative));
    }

    fn report(mut self, systems: usize) -> AdaptiveReport {
        self.report.systems = systems;
        self.report
    }
}
