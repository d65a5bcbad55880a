//! Mixed Darcy flow: flux on (n−1)-cells, pressure on n-cells.
//!
//! The problem u = −K∇p, ∇·u = f is solved in mixed form. The unknowns are
//!
//! - u_F, one per (n−1)-cell F: the **total** flux ∫_F u·n_F through F
//!   along its normal n_F (the orientation of `Complex::normal`, so that
//!   ∂ₙ(F, c) n_F points out of the top cell c);
//! - p_c, one per top cell c: the pressure at the cell's point (centroid,
//!   or circumcentre for the circumcentric DEC mass).
//!
//! With the divergence D = ∂ₙᵀ ((D u)_c = Σ_F ∂ₙ(F, c) u_F, the net
//! outflow of c, exact integer topology) the discrete system is the
//! symmetric saddle point
//!
//! ```text
//!     [ M_u  B ] [u]   [ g ]        B = −∂ₙ (faces × cells)
//!     [ Bᵀ   0 ] [p] = [ −F ]       F_c = ∫_c f,  g_F = −∂ₙ(F, c) p_D(x_F)
//! ```
//!
//! The first row is the weak Darcy law (K⁻¹u, v) − (p, ∇·v) = −∫_∂Ω p_D v·n
//! for the lowest-order flux basis v_F (unit total flux through F), the
//! second row is exact local mass conservation −D u = −F. The sign of B
//! (−∂ₙ rather than ∂ₙ) is what makes the matrix symmetric with the
//! natural sign of the Darcy law: Bᵀ = −D appears in the cell rows.
//!
//! Boundary conditions:
//! - pressure (natural): enters the right-hand side as g_F above (with a
//!   total flux unknown, the face integral −∫_F p_D v_F·n is −∂ₙ(F,c) p_D
//!   for a face-constant p_D, evaluated at the face centroid);
//! - flux (essential): the outward total flux q_F is prescribed, so
//!   u_F = ∂ₙ(F, c) q_F is known; its row and column are removed and the
//!   column moved to the right-hand side, which keeps the system
//!   symmetric;
//! - boundary faces listed in neither are no-flow (q_F = 0), as in
//!   [`crate::physics::diffusion`].
//!
//! Without any pressure face the pressure is fixed only up to a constant:
//! the data must be compatible (Σ_c F_c = Σ_F q_F) and one Lagrange
//! multiplier imposes Σ_c |c| p_c = 0 (one more row and column).
//!
//! Flux masses M_u ([`FluxMass`]):
//! - [`FluxMass::Dec`]: the diagonal ⋆_{n−1}⁻¹-type mass
//!   M_FF = Σ_{c ∋ F} s_{c,F} / (κ_c |F|), s_{c,F} the signed distance
//!   from the cell's dual vertex (circumcentre or centroid) to the plane
//!   of F and κ_c = n_Fᵀ K_c n_F. For a constant scalar K this is
//!   |⋆F| / (K |F|) with |⋆F| the dual edge; per cell pieces give the
//!   harmonic (series) average across a coefficient jump. It is the
//!   inverse of the two-point transmissibility of [`fv::two_point_at`].
//!   Consistent only on orthogonal meshes: uniform boxes (barycentric dual)
//!   and Delaunay triangulations (circumcentric dual).
//! - [`FluxMass::Mimetic`]: the lowest-order mimetic (RT0-type) inner
//!   product, one dense |∂c| × |∂c| block per cell, consistent on every
//!   convex cell with planar faces. In outward total fluxes,
//!
//!   ```text
//!       M_c = (1/|c|) X K⁻¹ Xᵀ + (I − P_N) S (I − P_N)
//!   ```
//!
//!   with X rows (x_F − x_c)ᵀ (face minus cell centroid), N rows
//!   |F| n_{c,F}ᵀ (outward area normals), P_N the orthogonal projector on
//!   span(N) and S = diag(d_{c,F} / (κ_{c,F} |F|)) the two-point half
//!   resistances. The divergence theorem gives Xᵀ N = |c| I, hence the
//!   consistency M_c N = X K⁻¹: for a constant field u₀ with fluxes N u₀,
//!   Vᵀ M_c N u₀ = Σ_F V_F (x_F − x_c)ᵀ K⁻¹ u₀ = ∫_c K⁻¹u₀·v for every v
//!   of constant divergence. The stabilisation vanishes on span(N) and
//!   makes M_c positive definite (X K⁻¹ Xᵀ vanishes only on ker Xᵀ, which
//!   meets span(N) only in 0). On a box with a diagonal K, M_c = S exactly,
//!   i.e. the mimetic mass reduces to the two-point one.
//!
//! The system is symmetric indefinite (as many positive eigenvalues as
//! free faces, as many negative ones as cells), so LLᵀ does not apply.
//! Which symmetric factorisation is right was checked, not assumed
//! (`cargo run -p hasse-solver --example darcy_factorizations -- 64 0.2`):
//! under faer's default AMD ordering both unpivoted LDLᵀ and faer's LBLᵀ
//! fail on the mimetic system with a zero pivot — LBLᵀ pivots only inside
//! a supernode (intranodal Bunch–Kaufman), and AMD readily eliminates a
//! cell pressure, whose diagonal is 0, before the faces that would make
//! its pivot nonzero — while LU succeeds. [`solve`] therefore uses faer's
//! LDLᵀ with a constrained AMD ordering ([`saddle_ordering`]): each
//! pressure is eliminated only after all of its free faces, which makes
//! every leading principal submatrix nonsingular (proof there), keeps the
//! symmetric factor (about half of LU's work and memory) and keeps most of
//! AMD's fill reduction. [`DarcySystem::solve`] runs any factorisation of
//! [`crate::la::direct`] on the same matrix for comparison.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_solver::physics::darcy::{self, BoundaryConditions};
//! use hasse_solver::metric::fv::FluxMass;
//! use hasse_solver::metric::isotropic;
//! // p = 1 − x on the unit square: pressure 1 on the left, 0 on the
//! // right, no flow through top and bottom. u = (1, 0).
//! let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
//! let bc = BoundaryConditions::from_fn(&k, |x| {
//!     if x[0] < 1e-12 { Some(darcy::FaceCondition::Pressure(1.0)) }
//!     else if x[0] > 1.0 - 1e-12 { Some(darcy::FaceCondition::Pressure(0.0)) }
//!     else { None }
//! });
//! let s = darcy::solve(&k, &[isotropic(1.0); 16], FluxMass::Mimetic, &[0.0; 16], &bc).unwrap();
//! for c in 0..16 {
//!     let x = k.centroid_of(2, c)[0];
//!     assert!((s.pressure[c] - (1.0 - x)).abs() < 1e-12);
//! }
//! // Net outflow of every cell is zero.
//! assert!(darcy::divergence(&k, &s.flux).iter().all(|d| d.abs() < 1e-12));
//! ```
//!
//! [`fv::two_point_at`]: crate::metric::fv::two_point_at

use crate::la::direct::{self, Factorization, SolveError, SolveReport};
use crate::la::fixed::FixedSplit;
use crate::metric::fv::{self, FluxMass};
use crate::metric::{MetricError, Tensor};
use crate::operator::block::{Block, BlockError, BlockSystem, Symmetry};
use crate::operator::{BlockMetric, Canonical, CanonicalError};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering,
};
use faer::sparse::SparseColMat;
use faer::{Conj, Mat, Par, Side};
use hasse_complex::Complex;
use sprs::CsMat;
use std::sync::Arc;
use std::time::Instant;

/// A condition on one boundary (n−1)-cell.
///
/// Fluxes count outward: a negative flux is inflow.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::{fv::FluxMass, isotropic};
/// use hasse_solver::physics::darcy::{self, BoundaryConditions, FaceCondition};
/// // Inflow u·n = −1 on the left, p = 0 on the right: u = (1, 0),
/// // p = 1 − x. The left faces have |F| = ¼, so a total flux of −¼ each
/// // is the same condition.
/// let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let solve = |inflow: FaceCondition| {
///     let bc = BoundaryConditions::from_fn(&k, |x| {
///         if x[0] == 0.0 { Some(inflow) } else if x[0] == 1.0 { Some(FaceCondition::Pressure(0.0)) } else { None }
///     });
///     darcy::solve(&k, &[isotropic(1.0); 16], FluxMass::Mimetic, &[0.0; 16], &bc).unwrap()
/// };
/// let density = solve(FaceCondition::FluxDensity(-1.0));
/// let total = solve(FaceCondition::Flux(-0.25));
/// for c in 0..16 {
///     let x = k.centroid_of(2, c)[0];
///     assert!((density.pressure[c] - (1.0 - x)).abs() < 1e-12);
///     assert!((total.pressure[c] - density.pressure[c]).abs() < 1e-12);
/// }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaceCondition {
    /// Pressure p_D on the face (natural condition).
    Pressure(f64),
    /// Outward total flux ∫_F u·n_out through the face (essential).
    Flux(f64),
    /// Outward normal velocity u·n_out on the face (essential):
    /// [`BoundaryConditions::from_fn`] turns it into the total flux
    /// q_F = (u·n_out) |F|.
    FluxDensity(f64),
}

/// Pressure and flux conditions on boundary (n−1)-cells, by face number.
/// Boundary faces in neither list are no-flow.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::physics::darcy::{BoundaryConditions, FaceCondition};
/// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// // Pressure 1 on the left edge (two faces), everything else no-flow.
/// let bc = BoundaryConditions::from_fn(&k, |x| (x[0] == 0.0).then_some(FaceCondition::Pressure(1.0)));
/// assert_eq!(bc.pressure.len(), 2);
/// assert!(bc.flux.is_empty());
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoundaryConditions {
    /// (face, p_D).
    pub pressure: Vec<(usize, f64)>,
    /// (face, outward total flux q_F).
    pub flux: Vec<(usize, f64)>,
}

impl BoundaryConditions {
    /// Conditions chosen per boundary face from its centroid; `None` leaves
    /// the face no-flow.
    pub fn from_fn(
        complex: &Complex,
        mut condition: impl FnMut(&[f64]) -> Option<FaceCondition>,
    ) -> Self {
        let mut bc = Self::default();
        let n = complex.dim();
        for face in boundary_faces(complex) {
            match condition(complex.centroid_of(n - 1, face)) {
                Some(FaceCondition::Pressure(v)) => bc.pressure.push((face, v)),
                Some(FaceCondition::Flux(v)) => bc.flux.push((face, v)),
                Some(FaceCondition::FluxDensity(v)) => {
                    bc.flux.push((face, v * complex.measure(n - 1)[face]))
                }
                None => {}
            }
        }
        bc
    }
}

/// Why a Darcy problem could not be set up or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DarcyError {
    /// Permeability (non-positive, non-finite, wrong count) or geometry.
    #[error(transparent)]
    Metric(#[from] MetricError),
    /// A and Ω of a block do not fit together.
    #[error(transparent)]
    Canonical(#[from] CanonicalError),
    /// The saddle-point blocks could not be put together.
    #[error(transparent)]
    Block(#[from] BlockError),
    /// The factorisation or solve failed (a zero pivot of an unsuited
    /// factorisation, a singular system).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The complex does not fill its space (a surface in R³, say): its
    /// faces have no normal flux.
    #[error("mixed Darcy needs a complex that fills its space (n = d ≥ 1); this one is {n}-dimensional in R^{d}")]
    NotVolume {
        /// Dimension of the complex.
        n: usize,
        /// Dimension of the space it lies in.
        d: usize,
    },
    /// The source has not one integral per top cell.
    #[error("{found} source integrals given for {expected} top cells")]
    SourceCount {
        /// Top cells of the mesh.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A condition names a face number beyond the (n−1)-cells.
    #[error("{kind} condition on face {face}, but the complex has only {faces} (n−1)-cells")]
    FaceOutOfRange {
        /// `"pressure"` or `"flux"`.
        kind: &'static str,
        /// The face number given.
        face: usize,
        /// Number of (n−1)-cells.
        faces: usize,
    },
    /// A condition is on a face inside the domain.
    #[error("{kind} condition on face {face}, which is an interior face (it lies on {cells} top cells); boundary conditions go on boundary faces only")]
    InteriorFace {
        /// `"pressure"` or `"flux"`.
        kind: &'static str,
        /// The face.
        face: usize,
        /// Number of top cells on it.
        cells: usize,
    },
    /// A face appears twice among the conditions.
    #[error("face {face} has more than one boundary condition")]
    RepeatedFace {
        /// The face.
        face: usize,
    },
    /// A prescribed pressure or flux is NaN or ±∞.
    #[error("{kind} value on face {face} is not finite")]
    NonFinite {
        /// `"pressure"` or `"flux"`.
        kind: &'static str,
        /// The face.
        face: usize,
    },
    /// Without a pressure face, mass conservation needs the sources to
    /// equal the total outflow, and they do not.
    #[error("no pressure is prescribed anywhere, so the sources must balance the boundary outflow: Σ ∫f = {sources:e} but Σ q = {outflow:e}")]
    Incompatible {
        /// Σ_c ∫_c f.
        sources: f64,
        /// Σ_F q_F over the flux faces.
        outflow: f64,
    },
}

/// The solved fields and the linear-solve report.
#[derive(Clone, Debug, PartialEq)]
pub struct DarcySolution {
    /// u_F: total flux through every (n−1)-cell along its normal n_F.
    pub flux: Vec<f64>,
    /// p_c: pressure of every top cell (at [`DarcySolution::points`]).
    pub pressure: Vec<f64>,
    /// Where each p_c lives (stride d): dual vertices of the mass's kind.
    pub points: Vec<f64>,
    /// The linear solve: sizes, seconds and relative residual.
    pub report: SolveReport,
}

/// The boundary (n−1)-cells: those on exactly one top cell.
pub fn boundary_faces(complex: &Complex) -> Vec<usize> {
    complex
        .boundary(complex.dim())
        .outer_iterator()
        .enumerate()
        .filter(|(_, row)| row.nnz() == 1)
        .map(|(i, _)| i)
        .collect()
}

/// Net outflow (D u)_c = Σ_F ∂ₙ(F, c) u_F of every top cell.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// // A unit flux out through every face: u_F = ∂(F, c) (u runs along n_F,
/// // which points out of c exactly when ∂(F, c) = +1). Net outflow 4.
/// let outward: Vec<f64> = (0..4).map(|f| f64::from(*k.boundary(2).get(f, 0).unwrap())).collect();
/// assert_eq!(hasse_solver::physics::darcy::divergence(&k, &outward), vec![4.0]);
/// ```
pub fn divergence(complex: &Complex, flux: &[f64]) -> Vec<f64> {
    let n = complex.dim();
    let mut out = vec![0.0; complex.cell_count(n)];
    for (face, row) in complex.boundary(n).outer_iterator().enumerate() {
        for (c, &s) in row.iter() {
            out[c] += f64::from(s) * flux[face];
        }
    }
    out
}

/// Cell integrals ∫_c f by the centroid rule |c| f(x_c) (second order,
/// exact for linear f).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// assert_eq!(hasse_solver::physics::darcy::cell_integrals(&k, |x| x[0]), vec![0.5, 1.5]);
/// ```
pub fn cell_integrals(complex: &Complex, f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    let n = complex.dim();
    (0..complex.cell_count(n))
        .map(|c| complex.measure(n)[c] * f(complex.centroid_of(n, c)))
        .collect()
}

/// The flux mass M_u = Aᵀ Ω A over the (n−1)-cells as a canonical
/// operator: the metric of [`fv::flux_mass`] (the diagonal DEC mass on A =
/// I, or the mimetic cell blocks on the half-face incidence).
///
/// ```
/// use hasse_complex::{generate::rectangle, DualKind};
/// use hasse_solver::metric::fv::FluxMass;
/// use hasse_solver::metric::isotropic;
/// use hasse_solver::physics::darcy::flux_mass;
/// // Two unit squares, K = 2: the shared face has dual edge 1, so
/// // M = 1 / (2 · 1); a boundary face has half a dual edge: 1/4.
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let m = flux_mass(&k, &[isotropic(2.0); 2], FluxMass::Dec(DualKind::Barycentric)).unwrap().assemble();
/// let shared = k.boundary(2).outer_iterator().position(|r| r.nnz() == 2).unwrap();
/// let dense = m.to_dense();
/// assert!((0..7).all(|f| (dense[(f, f)] - if f == shared { 0.5 } else { 0.25 }).abs() < 1e-15));
/// ```
pub fn flux_mass(
    complex: &Complex,
    tensors: &[Tensor],
    mass: FluxMass,
) -> Result<Canonical, DarcyError> {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    if n == 0 || n != d {
        return Err(DarcyError::NotVolume { n, d });
    }
    let (incidence, metric) = fv::flux_mass(complex, tensors, mass)?;
    Ok(Canonical::new(incidence, metric)?)
}

/// Validate the face lists; returns per face its condition.
fn classify(
    complex: &Complex,
    bc: &BoundaryConditions,
) -> Result<Vec<Option<FaceCondition>>, DarcyError> {
    let n = complex.dim();
    let boundary = complex.boundary(n);
    let faces = boundary.rows();
    let mut out = vec![None; faces];
    let lists = [("pressure", &bc.pressure, true), ("flux", &bc.flux, false)];
    for (kind, list, is_pressure) in lists {
        for &(face, value) in list.iter() {
            if face >= faces {
                return Err(DarcyError::FaceOutOfRange { kind, face, faces });
            }
            let cells = boundary.outer_view(face).map_or(0, |r| r.nnz());
            if cells != 1 {
                return Err(DarcyError::InteriorFace { kind, face, cells });
            }
            if !value.is_finite() {
                return Err(DarcyError::NonFinite { kind, face });
            }
            if out[face].is_some() {
                return Err(DarcyError::RepeatedFace { face });
            }
            out[face] = Some(if is_pressure {
                FaceCondition::Pressure(value)
            } else {
                FaceCondition::Flux(value)
            });
        }
    }
    Ok(out)
}

/// The assembled saddle-point system of one Darcy problem: unknowns are
/// the free face fluxes (faces without a prescribed flux, in face order),
/// then the cell pressures, then (pure-flux problems only) the multiplier
/// of the mean-pressure constraint.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::la::direct::Factorization;
/// use hasse_solver::metric::{fv::FluxMass, isotropic};
/// use hasse_solver::physics::darcy::{self, BoundaryConditions, FaceCondition};
/// let k = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let bc = BoundaryConditions::from_fn(&k, |x| (x[0] == 0.0 || x[0] == 1.0).then_some(FaceCondition::Pressure(x[0])));
/// let system = darcy::assemble(&k, &[isotropic(1.0); 16], FluxMass::Mimetic, &[0.0; 16], &bc).unwrap();
/// // 40 faces, of which the 8 no-flow faces at the bottom and top are known.
/// assert_eq!((system.free_faces, system.cells, system.matrix.nrows()), (32, 16, 48));
/// // The constrained LDLᵀ and LU give the same solution.
/// let (ldlt, lu) = (system.solve_ldlt().unwrap(), system.solve(Factorization::Lu).unwrap());
/// assert!(ldlt.pressure.iter().zip(&lu.pressure).all(|(a, b)| (a - b).abs() < 1e-12));
/// ```
pub struct DarcySystem {
    /// The symmetric indefinite matrix [[M_u, B], [Bᵀ, 0]] (both triangles).
    pub matrix: SparseColMat<usize, f64>,
    /// The right-hand side, with the known fluxes eliminated.
    pub rhs: Vec<f64>,
    /// Number of free face fluxes (rows `0..free_faces`).
    pub free_faces: usize,
    /// Number of pressure unknowns (rows `free_faces..free_faces + cells`).
    pub cells: usize,
    /// Per unknown of the whole system (faces, cells, multiplier): the
    /// prescribed flux u_F along n_F, or `None` when free.
    fixed: Vec<Option<f64>>,
    split: FixedSplit,
    faces: usize,
    points: Vec<f64>,
}

impl DarcySystem {
    /// Split a solution vector of [`DarcySystem::matrix`] into face fluxes
    /// (prescribed ones filled in) and cell pressures.
    pub fn unpack(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut all = self.split.lift(x, &self.fixed);
        all.truncate(self.faces + self.cells);
        let pressure = all.split_off(self.faces);
        (all, pressure)
    }

    /// Solve with faer's unpivoted sparse LDLᵀ under a constrained
    /// fill-reducing ordering (see [`saddle_ordering`]); this is what
    /// [`solve`] uses.
    pub fn solve_ldlt(&self) -> Result<DarcySolution, DarcyError> {
        let started = Instant::now();
        let a = self.matrix.as_ref();
        let size = a.nrows();
        let (forward, inverse) = saddle_ordering(self);
        let perm = PermRef::new_checked(&forward, &inverse, size);
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        let symbolic_seconds = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let par = Par::Seq;
        let mut values = vec![0.0; symbolic.len_val()];
        let mut buffer = MemBuffer::try_new(
            symbolic
                .factorize_numeric_ldlt_scratch::<f64>(par, Default::default())
                .or(symbolic.solve_in_place_scratch::<f64>(1, par)),
        )
        .map_err(|_| SolveError::OutOfMemory)?;
        let singular = SolveError::Singular { method: "LDLᵀ" };
        let ldlt = symbolic
            .factorize_numeric_ldlt(
                &mut values,
                a,
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|_| singular.clone())?;
        let numeric_seconds = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let mut x = Mat::from_fn(size, 1, |i, _| self.rhs[i]);
        ldlt.solve_in_place_with_conj(Conj::No, x.as_mut(), par, MemStack::new(&mut buffer));
        let x: Vec<f64> = (0..size).map(|i| x[(i, 0)]).collect();
        if x.iter().any(|v| !v.is_finite()) {
            return Err(singular.into());
        }
        let report = SolveReport {
            factorization: Factorization::Ldlt,
            // The constrained ordering above, not one of ordering::Ordering.
            ordering: None,
            unknowns: size,
            nonzeros: a.compute_nnz(),
            symbolic_seconds,
            numeric_seconds,
            solve_seconds: started.elapsed().as_secs_f64(),
            relative_residual: direct::relative_residual(a, &x, &self.rhs),
            factor_entries: None,
            factor_flops: None,
        };
        let (flux, pressure) = self.unpack(&x);
        Ok(DarcySolution {
            flux,
            pressure,
            points: self.points.clone(),
            report,
        })
    }

    /// Factorise with `kind` through [`crate::la::direct`] (AMD ordering) and
    /// solve. faer's LBLᵀ pivots only inside a supernode, so under AMD it
    /// can still meet a zero pressure pivot; see the module documentation.
    pub fn solve(&self, kind: Factorization) -> Result<DarcySolution, DarcyError> {
        let (x, report) = direct::solve(&self.matrix, &self.rhs, kind)?;
        let (flux, pressure) = self.unpack(&x);
        Ok(DarcySolution {
            flux,
            pressure,
            points: self.points.clone(),
            report,
        })
    }
}

/// Assemble and solve the mixed Darcy problem with faer's LDLᵀ under the
/// constrained ordering of [`saddle_ordering`].
///
/// `tensors`: the permeability K per top cell (symmetric positive
/// definite, checked); `source`: F_c = ∫_c f per top cell (see
/// [`cell_integrals`]); `bc`: pressure and flux faces. The report carries
/// the relative residual.
///
/// Errors: [`DarcyError`] for bad coefficients, faces, data or a singular
/// system.
pub fn solve(
    complex: &Complex,
    tensors: &[Tensor],
    mass: FluxMass,
    source: &[f64],
    bc: &BoundaryConditions,
) -> Result<DarcySolution, DarcyError> {
    assemble(complex, tensors, mass, source, bc)?.solve_ldlt()
}

/// The elimination order used by [`DarcySystem::solve_ldlt`] as
/// (forward, inverse) permutations: faer's approximate minimum degree
/// order of the whole matrix, except that each cell pressure is delayed
/// until all of its free faces have been eliminated (and the mean
/// multiplier of a pure-flux problem goes just before the last pressure).
///
/// Why this makes unpivoted LDLᵀ safe: every leading principal submatrix
/// is then [[M_UU, B_UP], [B_UPᵀ, 0]] with M_UU a principal submatrix of
/// the SPD mass and every column of B_UP = −∂ₙ carrying all its free
/// faces, so B_UP has full column rank (∂ₙ restricted to the free faces is
/// injective as long as some face carries a pressure condition) and the
/// submatrix is nonsingular. Face pivots come out positive and pressure
/// pivots negative (Schur complements −B_UPᵀ M_UU⁻¹ B_UP): the inertia of
/// a saddle point.
pub fn saddle_ordering(system: &DarcySystem) -> (Vec<usize>, Vec<usize>) {
    let a = system.matrix.as_ref();
    let size = a.nrows();
    let (free, cells) = (system.free_faces, system.cells);
    let mut amd = vec![0usize; size];
    let mut amd_inv = vec![0usize; size];
    let amd_ok = MemBuffer::try_new(amd::order_scratch::<usize>(size, a.compute_nnz()))
        .ok()
        .and_then(|mut buffer| {
            amd::order(
                &mut amd,
                &mut amd_inv,
                a.symbolic(),
                Default::default(),
                MemStack::new(&mut buffer),
            )
            .ok()
        })
        .is_some();
    if !amd_ok {
        // Natural order is valid too (every face before every pressure),
        // only with more fill.
        amd = (0..size).collect();
    }
    // Free faces of each cell still to be eliminated.
    let mut pending: Vec<usize> = (0..cells)
        .map(|c| {
            let j = free + c;
            a.row_idx()[a.col_range(j)]
                .iter()
                .filter(|&&i| i < free)
                .count()
        })
        .collect();
    let mut waiting = vec![false; cells];
    let mut order = Vec::with_capacity(size);
    let lambda = (size > free + cells).then_some(free + cells);
    for &j in &amd {
        if Some(j) == lambda {
            continue;
        }
        if j >= free {
            let c = j - free;
            if pending[c] == 0 {
                order.push(j);
            } else {
                waiting[c] = true;
            }
            continue;
        }
        order.push(j);
        for &i in &a.row_idx()[a.col_range(j)] {
            if i >= free && i < free + cells {
                let c = i - free;
                pending[c] -= 1;
                if pending[c] == 0 && waiting[c] {
                    waiting[c] = false;
                    order.push(i);
                }
            }
        }
    }
    // Cells without free faces (only possible with no pressure anywhere).
    order.extend((0..cells).filter(|&c| waiting[c]).map(|c| free + c));
    if let Some(l) = lambda {
        let last = order.iter().rposition(|&j| j >= free).unwrap_or(0);
        order.insert(last, l);
    }
    let mut inverse = vec![0; size];
    for (k, &j) in order.iter().enumerate() {
        inverse[j] = k;
    }
    (order, inverse)
}

/// Assemble the saddle-point system (see [`solve`] for the arguments).
///
/// Every block is a canonical operator over all faces and cells: the flux
/// mass ([`flux_mass`]), the coupling B = Iᵀ(−I)∂ₙ = −∂ₙ, and for a
/// problem without pressure faces the constraint row Iᵀ diag(|c|) 1. The
/// known fluxes (flux faces and no-flow faces) are then eliminated by
/// [`FixedSplit`], which keeps the matrix symmetric.
pub fn assemble(
    complex: &Complex,
    tensors: &[Tensor],
    mass: FluxMass,
    source: &[f64],
    bc: &BoundaryConditions,
) -> Result<DarcySystem, DarcyError> {
    let mass_operator = flux_mass(complex, tensors, mass)?;
    let n = complex.dim();
    let cells = complex.cell_count(n);
    if source.len() != cells {
        return Err(DarcyError::SourceCount {
            expected: cells,
            found: source.len(),
        });
    }
    let conditions = classify(complex, bc)?;
    let boundary = complex.boundary(n);
    let faces = boundary.rows();

    // Known fluxes: flux faces and unlisted (no-flow) boundary faces.
    let mut fixed: Vec<Option<f64>> = vec![None; faces];
    let mut pressure_faces = 0usize;
    let mut outflow = 0.0;
    for (face, row) in boundary.outer_iterator().enumerate() {
        let [sign] = row.data() else {
            continue;
        };
        let sign = f64::from(*sign);
        match conditions[face] {
            Some(FaceCondition::Pressure(_)) => pressure_faces += 1,
            // `classify` stores totals only (Flux), never FluxDensity.
            Some(FaceCondition::Flux(q) | FaceCondition::FluxDensity(q)) => {
                fixed[face] = Some(sign * q);
                outflow += q;
            }
            None => fixed[face] = Some(0.0),
        }
    }
    let mean_constraint = pressure_faces == 0;
    if mean_constraint {
        let sources: f64 = source.iter().sum();
        let scale = source.iter().map(|v| v.abs()).sum::<f64>()
            + bc.flux.iter().map(|(_, q)| q.abs()).sum::<f64>();
        if (sources - outflow).abs() > 1e-10 * scale.max(f64::MIN_POSITIVE) {
            return Err(DarcyError::Incompatible { sources, outflow });
        }
    }

    // [[M_u, B, 0], [Bᵀ, 0, w], [0, wᵀ, 0]] over faces, cells and the
    // multiplier, each block Aᵀ Ω B.
    let coupling = Canonical::coupling(
        CsMat::<i8>::eye(faces),
        BlockMetric::from_weights(vec![-1.0; faces]),
        Arc::clone(complex.boundary(n)),
    )?;
    let mut fields = vec![faces, cells];
    let mut blocks: Vec<(usize, usize, Block)> =
        vec![(0, 0, mass_operator.into()), (0, 1, coupling.into())];
    if mean_constraint {
        let ones = CsMat::new(
            (cells, 1),
            (0..=cells).collect(),
            vec![0; cells],
            vec![1i8; cells],
        );
        let weights = BlockMetric::from_weights(complex.measure(n).to_vec());
        let constraint = Canonical::coupling(CsMat::<i8>::eye(cells), weights, ones)?;
        fields.push(1);
        blocks.push((1, 2, constraint.into()));
    }
    let whole = BlockSystem::new(&fields, Symmetry::Symmetric, blocks)?.matrix();

    // The right-hand side: −∫_∂Ω p_D v·n on pressure faces, −F on cells.
    let size = whole.nrows();
    let mut rhs = vec![0.0; size];
    for (face, row) in boundary.outer_iterator().enumerate() {
        if let (Some(FaceCondition::Pressure(p)), [sign]) = (conditions[face], row.data()) {
            rhs[face] -= f64::from(*sign) * p;
        }
    }
    for c in 0..cells {
        rhs[faces + c] -= source[c];
    }
    fixed.resize(size, None);
    let split = FixedSplit::new(&fixed);
    let rhs = split.reduced_rhs(&whole, &rhs, &fixed);
    let matrix = split.free_block(&whole);
    let points = match mass {
        FluxMass::Dec(kind) => complex
            .dual_vertices(kind)
            .map_err(MetricError::from)?
            .to_vec(),
        FluxMass::Mimetic => complex.centroid(n).to_vec(),
    };
    Ok(DarcySystem {
        matrix,
        rhs,
        free_faces: split.free().len() - (size - faces),
        cells,
        fixed,
        split,
        faces,
        points,
    })
}
