//! Transport in time, V u̇ + M u = b (data and velocity constant in time).
//!
//! - [`Scheme::Upwind`] with θ ∈ (0, 1]: (V/Δt + θM) u¹ equals
//!   (V/Δt − (1−θ)M) u⁰ plus b, with one LU factorisation (or a
//!   warm-started Krylov solve per step).
//!   θ = 1 (backward Euler) keeps the maximum principle for every Δt;
//!   θ < 1 keeps it while (1−θ) Δt M_cc / |c| ≤ 1, and a run past that is
//!   warned about.
//! - [`Scheme::Upwind`] with θ = 0: forward Euler, no solve; refused when
//!   Δt M_cc / |c| > 1 (M_cc = outflow + Σ diffusive transmissibilities,
//!   the positivity limit; for pure advection it is the cell Courant
//!   number Δt Σ_out F / |c|).
//! - [`Scheme::Limited`]: the face values of the upwind cell's limited
//!   linear reconstruction ([`super::limiter`]), explicit, by the two-stage
//!   SSP Runge–Kutta method u* = u + Δt L(u), u¹ = ½ u + ½ (u* + Δt L(u*)),
//!   second order in time and space on smooth data. Diffusion is explicit
//!   too. Refused when N_c Δt F_max,c / |c| + Δt D_cc / |c| > 1 (N_c faces of
//!   the cell, F_max,c its largest outflow face flux, D_cc its diagonal of
//!   the diffusion), the limit under which the update is a convex
//!   combination of face values.

use super::limiter::Reconstruction;
use super::steady::{preconditioner, TransportSystem};
use super::{KrylovMethod, LinearSolver, Peclet, Transport, TransportError};
use crate::la::direct::{DirectSolver, Factor, Factorization, SolveError};
use crate::la::iterative::{Preconditioner, RowMatrix};
use crate::la::krylov::{bicgstab, gmres, rows_of, KrylovOptions};
use crate::physics::point_text;
use faer::sparse::{SparseColMat, Triplet};
use hasse_complex::Complex;

/// The spatial scheme of a transient run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Scheme {
    /// First-order upwind face values, θ-scheme in time.
    #[default]
    Upwind,
    /// Limited linear reconstruction (Barth–Jespersen on the
    /// least-squares gradient), SSP-RK2 in time.
    Limited,
}

impl Scheme {
    /// The name used in case files (`[time] scheme`).
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::Upwind => "upwind",
            Scheme::Limited => "limited",
        }
    }
}

/// Time stepping of [`Transport::solve_transient`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeStepping {
    /// Δt > 0.
    pub dt: f64,
    /// Number of steps.
    pub steps: usize,
    /// θ ∈ [0, 1] of the upwind scheme (0: forward Euler); ignored by the
    /// limited scheme, which is explicit.
    pub theta: f64,
    /// Upwind or limited.
    pub scheme: Scheme,
    /// Keep every `keep_every`-th level (the first and the last always).
    pub keep_every: usize,
}

/// The result of a transient run.
#[derive(Clone, Debug)]
pub struct TransportTransient {
    /// (t, u per cell) of the kept levels.
    pub levels: Vec<(f64, Vec<f64>)>,
    /// Σ |c| u_c at every step, t = 0 first.
    pub mass: Vec<f64>,
    /// F_f on every (n−1)-cell.
    pub face_flux: Vec<f64>,
    /// The largest cell Courant number Δt Σ_out F / |c|.
    pub courant: f64,
    /// The cell where it is largest.
    pub courant_cell: usize,
    /// The scheme's positivity number (≤ 1 keeps the maximum principle).
    pub positivity: f64,
    /// Cell Péclet numbers.
    pub peclet: Peclet,
    /// What the user should know (a θ-scheme past its positivity limit).
    pub warnings: Vec<String>,
}

/// A positivity number this close above 1 is the rounding of a step
/// chosen at the limit (e.g. Δt = h / (2v) for the limited scheme in 1D).
const AT_LIMIT: f64 = 1.0 + 1e-12;

/// max_c value_c with its cell.
fn largest(values: impl Iterator<Item = f64>) -> (f64, usize) {
    values.enumerate().fold(
        (0.0, 0),
        |(m, k), (c, v)| if v > m { (v, c) } else { (m, k) },
    )
}

/// The diagonal of a square matrix.
fn diagonal(matrix: &SparseColMat<usize, f64>) -> Vec<f64> {
    (0..matrix.ncols())
        .map(|j| {
            let range = matrix.col_range(j);
            matrix.row_idx()[range.clone()]
                .iter()
                .zip(&matrix.val()[range])
                .find(|(&i, _)| i == j)
                .map_or(0.0, |(_, &v)| v)
        })
        .collect()
}

/// y = M x.
fn multiply(matrix: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; matrix.nrows()];
    for (j, &xj) in x.iter().enumerate() {
        let range = matrix.col_range(j);
        for (&i, &v) in matrix.row_idx()[range.clone()]
            .iter()
            .zip(&matrix.val()[range])
        {
            y[i] += v * xj;
        }
    }
    y
}

impl Transport {
    /// Integrate V u̇ + M u = b from u(0) = `initial` (at the centroids).
    ///
    /// ```
    /// use hasse_complex::generate::interval;
    /// use hasse_solver::physics::transport::{FaceFlux, Scheme, TimeStepping, Transport};
    /// use hasse_solver::physics::BoundaryKind;
    /// use std::sync::Arc;
    /// // A step entering [0, 1] at speed 1: after t = 0.5 the explicit
    /// // limited scheme keeps it in [0, 1] and the mass that came in is
    /// // the inflow 1 · t.
    /// let mesh = interval(40, 0.0, 1.0).unwrap();
    /// let problem = Transport::new(None, FaceFlux::Velocity(Arc::new(|_| [1.0, 0.0, 0.0])), Arc::new(|_| 0.0))
    ///     .with_boundary("xmin", BoundaryKind::Dirichlet(Arc::new(|_| 1.0)));
    /// let stepping = TimeStepping { dt: 0.0125, steps: 40, theta: 0.0, scheme: Scheme::Limited, keep_every: 40 };
    /// let run = problem.solve_transient(&mesh, &|_| 0.0, &stepping).unwrap();
    /// let (t, u) = run.levels.last().unwrap();
    /// assert!(u.iter().all(|v| (-1e-14..=1.0 + 1e-14).contains(v)));
    /// assert!((run.mass.last().unwrap() - t).abs() < 1e-9);
    /// ```
    pub fn solve_transient(
        &self,
        complex: &Complex,
        initial: &dyn Fn(&[f64]) -> f64,
        stepping: &TimeStepping,
    ) -> Result<TransportTransient, TransportError> {
        let TimeStepping {
            dt,
            steps,
            theta,
            scheme,
            keep_every,
        } = *stepping;
        if !(dt > 0.0 && dt.is_finite() && (0.0..=1.0).contains(&theta) && steps > 0) {
            return Err(TransportError::Stepping { dt, steps, theta });
        }
        let n = complex.dim();
        let d = complex.embedding_dim();
        let system = self.assemble(complex)?;
        let centre = complex.centroid(n);
        let at = |c: usize| &centre[c * d..(c + 1) * d];
        let cells = system.volume.len();
        let mut u = Vec::with_capacity(cells);
        for c in 0..cells {
            let value = initial(at(c));
            if !value.is_finite() {
                return Err(TransportError::NonFiniteData {
                    what: "the initial value",
                    point: at(c).to_vec(),
                });
            }
            u.push(value);
        }
        let volume = &system.volume;
        let (courant, courant_cell) =
            largest((0..cells).map(|c| dt * system.outflow[c] / volume[c]));
        let mut warnings = Vec::new();
        let diag = diagonal(&system.matrix);
        let mass_of = |u: &[f64]| u.iter().zip(volume).map(|(a, v)| a * v).sum::<f64>();
        let mut mass = vec![mass_of(&u)];
        let keep = keep_every.max(1);
        let mut levels = vec![(0.0, u.clone())];
        let record = |step: usize, u: &[f64], levels: &mut Vec<(f64, Vec<f64>)>| {
            if step % keep == 0 || step == steps {
                levels.push((step as f64 * dt, u.to_vec()));
            }
        };
        let positivity;
        match scheme {
            Scheme::Upwind => {
                let (number, cell) = largest((0..cells).map(|c| dt * diag[c] / volume[c]));
                positivity = (1.0 - theta) * number;
                if theta == 0.0 && number > AT_LIMIT {
                    return Err(TransportError::Courant {
                        scheme: "forward Euler",
                        number_name: "Δt M_cc / |c| (outflow plus diffusion)",
                        number,
                        cell,
                        point: at(cell).to_vec(),
                        dt,
                        limit: dt / number,
                    });
                }
                if theta < 1.0 && positivity > AT_LIMIT {
                    warnings.push(format!(
                        "θ = {theta}: (1 − θ) Δt M_cc / |c| = {positivity:.3} > 1 in cell {cell} at {}: the step is not positive and may oscillate; take Δt ≤ {:.3e} or θ = 1",
                        point_text(at(cell)),
                        dt / number / (1.0 - theta)
                    ));
                }
                if theta == 0.0 {
                    for step in 1..=steps {
                        let mu = multiply(&system.matrix, &u);
                        for c in 0..cells {
                            u[c] += dt * (system.rhs[c] - mu[c]) / volume[c];
                        }
                        mass.push(mass_of(&u));
                        record(step, &u, &mut levels);
                    }
                } else {
                    self.implicit(&system, theta, dt, steps, &mut u, &mut |step, u| {
                        mass.push(mass_of(u));
                        record(step, u, &mut levels);
                    })?;
                }
            }
            Scheme::Limited => {
                let reconstruction = Reconstruction::new(complex);
                let counts = reconstruction.face_counts();
                let top = complex.boundary(n);
                let by_cell = complex.boundary_csc(n);
                let diffusion_diag = system.diffusion.as_ref().map(diagonal);
                let (number, cell) = largest((0..cells).map(|c| {
                    let largest_out = by_cell
                        .outer_view(c)
                        .map(|col| {
                            col.iter()
                                .map(|(f, &s)| f64::from(s) * system.face_flux[f])
                                .fold(0.0f64, f64::max)
                        })
                        .unwrap_or(0.0);
                    let diffusive = diffusion_diag.as_ref().map_or(0.0, |k| k[c]);
                    dt * (counts[c] as f64 * largest_out + diffusive) / volume[c]
                }));
                positivity = number;
                if number > AT_LIMIT {
                    return Err(TransportError::Courant {
                        scheme: "limited (SSP-RK2)",
                        number_name: "N_c Δt F_max / |c| + Δt D_cc / |c|",
                        number,
                        cell,
                        point: at(cell).to_vec(),
                        dt,
                        limit: dt / number,
                    });
                }
                let rate = |u: &[f64]| -> Vec<f64> {
                    let mut r = reconstruction.advection(top, &system.face_flux, &system.inflow, u);
                    if let Some(k) = &system.diffusion {
                        for (a, b) in r.iter_mut().zip(multiply(k, u)) {
                            *a += b;
                        }
                    }
                    (0..u.len())
                        .map(|c| (system.rhs_without_inflow[c] - r[c]) / volume[c])
                        .collect()
                };
                for step in 1..=steps {
                    let k1 = rate(&u);
                    let stage: Vec<f64> = u.iter().zip(&k1).map(|(a, k)| a + dt * k).collect();
                    let k2 = rate(&stage);
                    for c in 0..cells {
                        u[c] = 0.5 * u[c] + 0.5 * (stage[c] + dt * k2[c]);
                    }
                    mass.push(mass_of(&u));
                    record(step, &u, &mut levels);
                }
            }
        }
        Ok(TransportTransient {
            levels,
            mass,
            face_flux: system.face_flux,
            courant,
            courant_cell,
            positivity,
            peclet: system.peclet,
            warnings,
        })
    }

    /// θ-scheme steps with one factorisation (LU) or a warm-started
    /// Krylov solve per step.
    fn implicit(
        &self,
        system: &TransportSystem,
        theta: f64,
        dt: f64,
        steps: usize,
        u: &mut [f64],
        after: &mut dyn FnMut(usize, &[f64]),
    ) -> Result<(), TransportError> {
        let cells = u.len();
        // V/Δt + θ M, as a sum: a cell without outflow or diffusion has
        // no diagonal entry in M.
        let mut scaled = system.matrix.clone();
        for v in scaled.val_mut() {
            *v *= theta;
        }
        let mass: Vec<Triplet<usize, usize, f64>> = (0..cells)
            .map(|c| Triplet::new(c, c, system.volume[c] / dt))
            .collect();
        let mass = SparseColMat::try_new_from_triplets(cells, cells, &mass)
            .map_err(|_| SolveError::OutOfMemory)?;
        let step_matrix = faer::sparse::ops::add(scaled.as_ref(), mass.as_ref())
            .map_err(|_| SolveError::OutOfMemory)?;
        enum Stepper {
            Lu(Factor),
            Krylov(
                RowMatrix,
                Box<dyn Preconditioner>,
                KrylovMethod,
                KrylovOptions,
            ),
        }
        let stepper = match &self.solver {
            LinearSolver::Lu => Stepper::Lu(
                DirectSolver::analyze(step_matrix.as_ref(), Factorization::Lu)?
                    .factorize(step_matrix.as_ref())?,
            ),
            LinearSolver::Krylov {
                method,
                options,
                preconditioner: kind,
            } => {
                let rows = rows_of(&step_matrix)?;
                // The diffusion part of the step matrix: V/Δt + θ D.
                let diffusion = match &system.diffusion {
                    Some(d) => {
                        let mut scaled = d.clone();
                        for v in scaled.val_mut() {
                            *v *= theta;
                        }
                        Some(
                            faer::sparse::ops::add(scaled.as_ref(), mass.as_ref())
                                .map_err(|_| SolveError::OutOfMemory)?,
                        )
                    }
                    None => None,
                };
                let b = preconditioner(&rows, diffusion.as_ref(), kind)?;
                Stepper::Krylov(rows, b, *method, *options)
            }
        };
        for step in 1..=steps {
            let mu = multiply(&system.matrix, u);
            let rhs: Vec<f64> = (0..cells)
                .map(|c| system.volume[c] / dt * u[c] - (1.0 - theta) * mu[c] + system.rhs[c])
                .collect();
            // Warm start: the previous level.
            let next = match &stepper {
                Stepper::Lu(factor) => factor.solve(&rhs)?,
                Stepper::Krylov(rows, b, KrylovMethod::Bicgstab, options) => {
                    bicgstab(rows, &rhs, Some(u), options, b.as_ref())?.0
                }
                Stepper::Krylov(rows, b, KrylovMethod::Gmres, options) => {
                    gmres(rows, &rhs, Some(u), options, b.as_ref())?.0
                }
            };
            u.copy_from_slice(&next);
            after(step, u);
        }
        Ok(())
    }
}
