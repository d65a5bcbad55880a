//! Nodal Galerkin advection v·∇u and its streamline-upwind Petrov–Galerkin
//! (SUPG) stabilisation, as per-cell blocks of a canonical operator.
//!
//! # The weak form
//!
//! On P1 simplices and Q1 quadrilaterals or hexahedra the advective part
//! of −∇·(K∇u) + v·∇u = f is tested in its *advective* form
//!
//! ```text
//!     c(u, w) = ∫ (v·∇u) w
//!             + Σ_T τ_T ∫_T (v·∇w)(v·∇u)          (SUPG, on the operator)
//!     ℓ(w)    = Σ_T τ_T ∫_T (v·∇w) f               (SUPG, on the load)
//! ```
//!
//! The advective form needs no boundary integral: a natural condition on
//! a face then prescribes the diffusive flux K∇u·n = g alone, the usual
//! outflow condition of advection–diffusion, and the same meaning the
//! Neumann and Robin conditions of nodal FE diffusion have. The
//! conservative form −∫ u v·∇w + ∫_∂ (v·n) u w differs from it by
//! ∫ (∇·v) u w, zero for a divergence-free v, and by nothing else where
//! w = 0 (Dirichlet vertices) or v·n = 0.
//!
//! The SUPG element residual is v·∇u − ∇·(K∇u) − f. The diffusive part
//! ∇·(K∇u_h) vanishes inside a P1 cell (u_h is linear there) and is dropped;
//! on a Q1 cell it is dropped too: for a scalar K on an axis-aligned box
//! it is zero (a multilinear function has no pure second derivatives), on
//! other cells and for a tensor K it is a term of size τ_T K |∇²u_h| that
//! the usual bilinear SUPG leaves out (Brooks & Hughes 1982, §3.3.4),
//! which keeps the method consistent to O(h) in that residual.
//!
//! # τ and the element length
//!
//! With v̄ the mean velocity of cell T (quadrature), the length of T in
//! the flow direction is
//!
//! ```text
//!     h_T = 2 |v̄| / mean_T Σ_i |v̄·∇φ_i|
//! ```
//!
//! (Tezduyar & Park 1986): on a simplex, whose ∇λ_i are constant and sum
//! to zero, it is the longest chord of T parallel to v̄; on an axis-aligned
//! box with v̄ along an axis it is the box's side along that axis. Then
//!
//! ```text
//!     Pe_T = |v̄| h_T / (2 K_v),  K_v = v̄ᵀ K v̄ / |v̄|²,
//!     τ_T  = h_T / (2 |v̄|) · (coth Pe_T − 1/Pe_T)
//! ```
//!
//! the choice that makes the 1D linear element nodally exact for
//! −εu″ + a u′ = 0 (Christie et al. 1976; Brooks & Hughes 1982). A cell
//! without flow (v̄ = 0) gets τ = 0.
//!
//! # Canonical form
//!
//! The local matrices are neither symmetric nor zero in their column sums
//! (Σ_i φ_i = 1 makes 1ᵀC the cell's inflow minus outflow), so they are
//! not blocks over the edges of δ⁰. They are written over the cell–vertex
//! incidences: P is the 0/1 matrix with one row per nonzero of the
//! characteristic matrix M_n (a pair (cell, vertex of the cell), in M_n's
//! order) and a 1 at that vertex, and Ω has one dense block per cell over
//! that cell's rows, so that
//!
//! ```text
//!     C = Pᵀ Ω P = Σ_T P_Tᵀ Ω_T P_T
//! ```
//!
//! is the assembled advection (+ SUPG) matrix: topology in P, exact
//! integers, and the velocity, τ and quadrature in Ω. A time derivative
//! is tested the same way, ∫ u̇ (w + τ_T v·∇w), a second metric on the
//! same P (the consistent mass plus its SUPG part).

use super::field::{nodal_rule, Degree};
use super::load::{evaluate, LoadFn};
use super::{MetricError, Topology};
use crate::metric::CellTensors;
use crate::operator::BlockMetric;
use hasse_complex::Complex;
use rayon::prelude::*;
use sprs::CsMat;

/// A velocity field v(x), padded to three components.
pub type VelocityFn<'v> = &'v (dyn Fn(&[f64]) -> [f64; 3] + Sync);

/// Whether the advection is stabilised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Stabilisation {
    /// Streamline-upwind Petrov–Galerkin with the optimal τ.
    #[default]
    Supg,
    /// Plain Galerkin (oscillates when the element Péclet number exceeds 1).
    None,
}

impl Stabilisation {
    /// The name used in case files (`problem.stabilisation`).
    pub fn name(&self) -> &'static str {
        match self {
            Stabilisation::Supg => "supg",
            Stabilisation::None => "none",
        }
    }
}

/// Why the advection metric could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AdvectionError {
    /// The mesh, the conductivity or the source was refused.
    #[error(transparent)]
    Metric(#[from] MetricError),
    /// The velocity is NaN or infinite at a quadrature point.
    #[error("the velocity is not finite at {point:?} (in top cell {cell})")]
    NonFiniteVelocity {
        /// The top cell.
        cell: usize,
        /// The quadrature point.
        point: Vec<f64>,
    },
}

/// The advection operator of one mesh: C = Pᵀ Ω P, the SUPG load and the
/// per-cell figures behind them.
#[derive(Clone, Debug)]
pub struct Advection {
    /// P: one row per (cell, vertex) pair of M_n, a 1 at the vertex.
    pub incidence: CsMat<i8>,
    /// Ω: one dense block per top cell over its rows of P.
    pub metric: BlockMetric,
    /// The Petrov–Galerkin mass ∫ (φ_i + τ_T v·∇φ_i) φ_j of a time
    /// derivative, one dense block per top cell over the same rows of P.
    pub mass: BlockMetric,
    /// τ_T Σ ∫_T (v·∇φ_i) f per vertex (zero without SUPG or source).
    pub load: Vec<f64>,
    /// τ_T per top cell (zero without SUPG).
    pub tau: Vec<f64>,
    /// h_T, the length in the flow direction, per top cell.
    pub length: Vec<f64>,
    /// Pe_T = |v̄| h_T / (2 K_v) per top cell.
    pub peclet: Vec<f64>,
}

/// ξ(Pe) = coth Pe − 1/Pe, the upwinding function of the optimal τ: its
/// Taylor series below Pe = 0.1 (where the difference would cancel), the
/// closed form above.
///
/// ```
/// use hasse_solver::metric::fe::advection::upwind_function;
/// // coth 1 − 1 = 0.3130352854993313 (to 16 digits).
/// assert!((upwind_function(1.0) - 0.3130352854993313).abs() < 1e-15);
/// // Below 0.1 the series x/3 − x³/45 + …: at x = 10⁻⁴ its third term is
/// // 2·10⁻²³.
/// let x = 1e-4f64;
/// assert!((upwind_function(x) - (x / 3.0 - x.powi(3) / 45.0)).abs() < 1e-20);
/// assert_eq!(upwind_function(1e3), 1.0 - 1e-3);
/// ```
pub fn upwind_function(pe: f64) -> f64 {
    if pe < 0.1 {
        // x/3 − x³/45 + 2x⁵/945 − x⁷/4725 + 2x⁹/93555 (Bernoulli numbers):
        // the next term is below 10⁻¹⁵ of the sum.
        let x2 = pe * pe;
        pe * (1.0 / 3.0
            + x2 * (-1.0 / 45.0 + x2 * (2.0 / 945.0 + x2 * (-1.0 / 4725.0 + x2 * 2.0 / 93555.0))))
    } else {
        1.0 / pe.tanh() - 1.0 / pe
    }
}

/// τ = h/(2|v|) ξ(Pe) with Pe = |v| h/(2K); zero without flow or length.
///
/// ```
/// use hasse_solver::metric::fe::advection::supg_tau;
/// // Advection-dominated: τ → h/(2|v|); diffusion-dominated: τ → h²/(12K).
/// assert!((supg_tau(1.0, 0.1, 1e-9) - 0.05).abs() < 1e-9);
/// assert!((supg_tau(1.0, 0.1, 1e3) - 0.01 / 12e3).abs() < 1e-15);
/// assert_eq!(supg_tau(0.0, 0.1, 1.0), 0.0);
/// ```
pub fn supg_tau(speed: f64, h: f64, k: f64) -> f64 {
    if speed <= 0.0 || h <= 0.0 {
        return 0.0;
    }
    let pe = speed * h / (2.0 * k);
    h / (2.0 * speed) * upwind_function(pe)
}

/// P: the cell–vertex incidence, one row per nonzero of the characteristic
/// matrix M_n (in its CSR order), with a 1 at that vertex.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::fe::advection::cell_vertex_incidence;
/// // Two squares share two vertices: 8 rows over 6 vertices, and Pᵀ P is
/// // the number of cells at each vertex.
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let p = cell_vertex_incidence(&k).unwrap();
/// assert_eq!(p.shape(), (8, 6));
/// let mut count = vec![0; 6];
/// for (_, (_, v)) in p.iter() { count[v] += 1; }
/// assert_eq!(count.iter().filter(|&&c| c == 2).count(), 2);
/// ```
pub fn cell_vertex_incidence(complex: &Complex) -> Result<CsMat<i8>, MetricError> {
    let n = complex.dim();
    let characteristic = complex.lar().characteristic(n)?;
    let rows = characteristic.nnz();
    Ok(CsMat::new(
        (rows, complex.cell_count(0)),
        (0..=rows).collect(),
        characteristic.indices().to_vec(),
        vec![1i8; rows],
    ))
}

/// One cell's block and figures.
struct CellBlock {
    values: Vec<f64>,
    mass: Vec<f64>,
    load: Vec<f64>,
    tau: f64,
    length: f64,
    peclet: f64,
}

/// The advection metric of v·∇u on the nodal elements of `complex` (P1
/// simplices, Q1 quadrilaterals and hexahedra filling their space), with
/// the SUPG terms when `stabilisation` asks for them. `tensors` is K per
/// top cell (for Pe_T and τ_T); `source` is f, whose SUPG load is
/// returned (a Galerkin load ∫ f φ_i is [`super::load()`]'s). See the
/// [module documentation](self).
///
/// ```
/// use hasse_complex::generate::interval;
/// use hasse_solver::metric::fe::advection::{advection_metric, Stabilisation};
/// use hasse_solver::operator::Canonical;
/// // v = 1 on [0, 1] in two cells, Galerkin: row i of C is (u_{i+1} − u_{i−1})/2.
/// let k = interval(2, 0.0, 1.0).unwrap();
/// let a = advection_metric(&k, &|_| [1.0, 0.0, 0.0], &[1.0, 1.0], None, Stabilisation::None).unwrap();
/// let c = Canonical::new(a.incidence, a.metric).unwrap().assemble().to_dense();
/// assert!((c[(1, 2)] - 0.5).abs() < 1e-15 && (c[(1, 0)] + 0.5).abs() < 1e-15);
/// assert!(c[(1, 1)].abs() < 1e-15);
/// ```
pub fn advection_metric<'a>(
    complex: &Complex,
    velocity: VelocityFn,
    tensors: impl Into<CellTensors<'a>>,
    source: Option<LoadFn>,
    stabilisation: Stabilisation,
) -> Result<Advection, AdvectionError> {
    let top = Topology::new(complex, "FE advection")?;
    let (n, d) = (top.n, top.d);
    let cells = complex.cell_count(n);
    let tensors = tensors.into().checked(cells, d)?;
    let blocks = (0..cells)
        .into_par_iter()
        .map(|c| cell_block(&top, c, velocity, &tensors, source, stabilisation))
        .collect::<Vec<Result<_, _>>>()
        .into_iter()
        .collect::<Result<Vec<CellBlock>, AdvectionError>>()?;
    let incidence = cell_vertex_incidence(complex)?;
    let characteristic = complex.lar().characteristic(n).map_err(MetricError::from)?;
    let offsets = characteristic.indptr().to_proper().to_vec();
    let mut metric = BlockMetric::new(incidence.rows());
    let mut mass = BlockMetric::new(incidence.rows());
    let mut load = vec![0.0; complex.cell_count(0)];
    let mut rows = Vec::new();
    for (c, block) in blocks.iter().enumerate() {
        rows.clear();
        rows.extend(offsets[c]..offsets[c + 1]);
        metric.push_block(&rows, &rows, &block.values);
        mass.push_block(&rows, &rows, &block.mass);
        for (&v, l) in characteristic.indices()[offsets[c]..offsets[c + 1]]
            .iter()
            .zip(&block.load)
        {
            load[v] += l;
        }
    }
    Ok(Advection {
        incidence,
        metric,
        mass,
        load,
        tau: blocks.iter().map(|b| b.tau).collect(),
        length: blocks.iter().map(|b| b.length).collect(),
        peclet: blocks.iter().map(|b| b.peclet).collect(),
    })
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Ω_T, the SUPG load shares and τ_T, h_T, Pe_T of cell `c`.
fn cell_block(
    top: &Topology,
    c: usize,
    velocity: VelocityFn,
    tensors: &CellTensors,
    source: Option<LoadFn>,
    stabilisation: Stabilisation,
) -> Result<CellBlock, AdvectionError> {
    let (n, d) = (top.n, top.d);
    let nodal = top.is_simplex(c) || (n == d && top.element_order(c).is_some());
    let points = if nodal {
        // Degree 5 (3 points per axis): exact for the products of a linear
        // velocity with the Q1 shape functions and their gradients.
        nodal_rule(top, c, Degree::Quintic)
    } else {
        Vec::new()
    };
    if points.is_empty() {
        return Err(MetricError::UnsupportedCell {
            method: "FE advection (SUPG)",
            needs: "a simplex (P1) or a quadrilateral or hexahedron filling its space (Q1) of positive measure",
            cell: c,
        }
        .into());
    }
    let m = points[0].values.len();
    let mut v_at = Vec::with_capacity(points.len());
    let (mut measure, mut mean) = (0.0, [0.0; 3]);
    for p in &points {
        let v = velocity(&p.x[..d]);
        if v.iter().any(|x| !x.is_finite()) {
            return Err(AdvectionError::NonFiniteVelocity {
                cell: c,
                point: p.x[..d].to_vec(),
            });
        }
        measure += p.weight;
        for (a, va) in mean.iter_mut().zip(&v) {
            *a += p.weight * va;
        }
        v_at.push(v);
    }
    for a in &mut mean {
        *a /= measure;
    }
    let speed = dot(&mean, &mean).sqrt();
    let spread: f64 = points
        .iter()
        .map(|p| p.weight * p.gradients.iter().map(|g| dot(&mean, g).abs()).sum::<f64>())
        .sum::<f64>()
        / measure;
    let length = if spread > 0.0 {
        2.0 * speed / spread
    } else {
        0.0
    };
    let k = tensors.get(c);
    let k_along = if speed > 0.0 {
        (0..d)
            .map(|i| mean[i] * (0..d).map(|j| k[i][j] * mean[j]).sum::<f64>())
            .sum::<f64>()
            / (speed * speed)
    } else {
        (0..d).map(|i| k[i][i]).sum::<f64>() / d as f64
    };
    let peclet = if length > 0.0 {
        speed * length / (2.0 * k_along)
    } else {
        0.0
    };
    let tau = match stabilisation {
        Stabilisation::Supg => supg_tau(speed, length, k_along),
        Stabilisation::None => 0.0,
    };
    let mut values = vec![0.0; m * m];
    let mut mass = vec![0.0; m * m];
    let mut load = vec![0.0; m];
    let mut streamline = vec![0.0; m];
    for (p, v) in points.iter().zip(&v_at) {
        for (s, g) in streamline.iter_mut().zip(&p.gradients) {
            *s = dot(v, g);
        }
        for i in 0..m {
            // Test function φ_i + τ v·∇φ_i against v·∇φ_j.
            let test = p.weight * (p.values[i] + tau * streamline[i]);
            for j in 0..m {
                values[i * m + j] += test * streamline[j];
                mass[i * m + j] += test * p.values[j];
            }
        }
        if let (Some(f), true) = (source, tau > 0.0) {
            let value = p.weight * tau * evaluate(f, &p.x, d, c)?;
            for (l, s) in load.iter_mut().zip(&streamline) {
                *l += value * s;
            }
        }
    }
    Ok(CellBlock {
        values,
        mass,
        load,
        tau,
        length,
        peclet,
    })
}
