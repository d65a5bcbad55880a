//! Discrete exterior calculus: the nodal Laplacian δ⁰ᵀ ⋆₁ δ⁰.
//!
//! Unknowns live on vertices, A = δ⁰ = ∂₁ᵀ and Ω is the Hodge star ⋆₁
//! weighted by the coefficient. With a scalar coefficient λ_τ per top cell
//! the star is diagonal ([`hodge_metric`]),
//!
//! ```text
//!     ω_e = Σ_{τ ∋ e} λ_τ |⋆e ∩ τ| / |e|,
//! ```
//!
//! with |⋆e ∩ τ| the piece of the dual (n−1)-cell of e inside τ, measured
//! with the sign rules of `hasse_complex::dual`, so that Σ_τ |⋆e ∩ τ| is
//! `Complex::dual_measure(kind, 1)`:
//!
//! - circumcentric dual, 2D: the signed distance from the midpoint of e to
//!   the circumcentre c(τ), positive when c(τ) is on τ's side of e. It is
//!   (|e|/2)·cot θ_e (θ_e the angle opposite e), so ω_e = λ/2 · cot θ_e and
//!   δ⁰ᵀ ⋆₁ δ⁰ **is** the P1 stiffness on every triangulation, Delaunay or
//!   not (non-Delaunay edges get negative weights in both).
//! - circumcentric dual, 3D: for each of the two faces f of τ on e, the
//!   right triangle (c(e), c(f), c(τ)) with signed legs, area
//!   ½ · (|e|/2)·cot α_f · dist(f, c(τ)). This is **not** the P1
//!   stiffness: per tetrahedron the P1 weight is λ|e′| cot φ_e′ / 6, and the
//!   two agree only on special tetrahedra (regular ones, for instance), not
//!   even on all well-centred ones. Both are consistent (exact for linear
//!   u at interior vertices) and both reduce to the seven-point stencil at
//!   the interior vertices of a uniform Kuhn grid, but they differ near
//!   its boundary and on general meshes. For the P1 matrix in 3D use the
//!   Whitney star ([`whitney_metric`]).
//! - barycentric dual (any convex cells): centroids and unsigned measures,
//!   the segment c(e)–c(τ) in 2D and the triangles (c(e), c(f), c(τ)) in
//!   3D. Orthogonal, and so the five/seven-point stencil, on uniform grids.
//!
//! A tensor coefficient K on a simplex uses the Whitney (Galerkin) star
//! (⋆₁^K)_ef = ∫_τ K W_e · W_f with W_e = λ_a∇λ_b − λ_b∇λ_a the Whitney
//! 1-form of e = [a, b]: one dense block per simplex, and δ⁰ᵀ ⋆₁^K δ⁰ is
//! exactly the P1 stiffness with K in any dimension, because the gradient
//! of the Whitney 0-form φ_v is Σ_e δ⁰_ev W_e. It does not depend on the
//! dual kind.

use super::fe::{gather, k_dot, simplex_gradients, Local, Point, Topology};
use super::{CellTensors, MetricError, Tensor};
use crate::operator::BlockMetric;
use hasse_complex::{Complex, DualKind};
use nalgebra::Vector3;
use rayon::prelude::*;

/// The coefficient-weighted Hodge star ⋆₁ as a metric over the edges.
///
/// Isotropic tensors (λI in the leading d×d block) give diagonal weights
/// (one 1×1 block per edge, in edge order); other tensors give one dense
/// Whitney block per simplex. Errors: a circumcentric dual on a cell that
/// is not a simplex, or a tensor on a cell that is not a simplex
/// ([`MetricError::UnsupportedCell`]); coefficient errors as in
/// [`check_tensors`](super::check_tensors).
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::kuhn, generate::uniform_axis};
/// use hasse_solver::operator::Canonical;
/// use hasse_solver::metric::{dec, isotropic};
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// let omega = dec::hodge_metric(&k, DualKind::Circumcentric, &vec![isotropic(1.0); 8]).unwrap();
/// let m = Canonical::new(k.coboundary(0), omega).unwrap().assemble().to_dense();
/// // The five-point stencil at the centre vertex.
/// assert!((m[(4, 4)] - 4.0).abs() < 1e-14 && (m[(4, 1)] + 1.0).abs() < 1e-14);
/// ```
pub fn hodge_metric<'a>(
    complex: &Complex,
    kind: DualKind,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<BlockMetric, MetricError> {
    let tensors = tensors.into();
    let top = Topology::new(complex, "DEC Hodge star")?;
    let n = top.n;
    let cells = complex.cell_count(n);
    let tensors = tensors.checked(cells, top.d)?;
    if kind == DualKind::Circumcentric {
        if let Some(cell) = (0..cells).find(|&c| !top.is_simplex(c)) {
            return Err(MetricError::UnsupportedCell {
                method: "DEC with the circumcentric dual",
                needs: "a simplex (use the barycentric dual for other cells)",
                cell,
            });
        }
    }
    super::require_convex(complex, "DEC with the barycentric dual")?;
    let centres = Centres::new(complex, kind)?;
    let lengths = complex.measure(1);
    let locals = (0..cells)
        .into_par_iter()
        .map(|c| match isotropic_value(&tensors.get(c), top.d) {
            Some(lambda) => Ok(Local::Diagonal(
                dual_pieces(&top, &centres, c)
                    .into_iter()
                    .map(|(e, piece)| (e, lambda * piece / lengths[e]))
                    .collect(),
            )),
            None if top.is_simplex(c) => whitney_block(&top, c, &tensors.get(c)),
            None => Err(MetricError::UnsupportedCell {
                method: "DEC with a tensor coefficient",
                needs: "a simplex (the Whitney star)",
                cell: c,
            }),
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(gather(complex.cell_count(1), &locals))
}

/// The Whitney (Galerkin) star ⋆₁^K on every simplex, whatever the
/// coefficient: δ⁰ᵀ ⋆₁^K δ⁰ is the P1 stiffness with K exactly, in every
/// dimension (the diagonal circumcentric star gives it only in 2D; see the
/// [module documentation](self)). One dense block per simplex
/// (1×1, 3×3 or 6×6); cells that are not simplices are
/// [`MetricError::UnsupportedCell`].
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_solver::metric::{dec, isotropic};
/// let x = uniform_axis(1, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x.clone(), x]).unwrap();
/// let whitney = dec::whitney_metric(&k, &vec![isotropic(1.0); 6]).unwrap();
/// assert_eq!(whitney.block_count(), 6);
/// ```
pub fn whitney_metric<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<BlockMetric, MetricError> {
    let tensors = tensors.into();
    let top = Topology::new(complex, "DEC Whitney star")?;
    let cells = complex.cell_count(top.n);
    let tensors = tensors.checked(cells, top.d)?;
    let locals = (0..cells)
        .into_par_iter()
        .map(|c| {
            if top.is_simplex(c) {
                whitney_block(&top, c, &tensors.get(c))
            } else {
                Err(MetricError::UnsupportedCell {
                    method: "DEC Whitney star",
                    needs: "a simplex",
                    cell: c,
                })
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(gather(complex.cell_count(1), &locals))
}

/// The lumped load ⋆₀ f: |⋆v| f(x_v) for every vertex v.
///
/// Σ_v |⋆v| = |K|, so the total is exact for constant f. It is exact for
/// linear f when the dual cells' first moments are Σ_v |⋆v| x_v = ∫ x,
/// which holds for the barycentric dual of simplices (each vertex gets
/// |τ|/(n+1) of every simplex τ on it) and of parallelogram grids, but not
/// for the circumcentric dual in general.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::rectangle};
/// use hasse_solver::metric::dec;
/// let k = rectangle(2, 2, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let b = dec::load(&k, DualKind::Barycentric, &|_: &[f64]| 3.0).unwrap();
/// assert!((b.iter().sum::<f64>() - 6.0).abs() < 1e-14);
/// ```
pub fn load(
    complex: &Complex,
    kind: DualKind,
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
) -> Result<Vec<f64>, MetricError> {
    let star = complex.dual_measure(kind, 0)?;
    let vertices = complex.vertices();
    let values = (0..complex.cell_count(0))
        .into_par_iter()
        .map(|v| f(vertices.point(v)))
        .collect::<Vec<_>>();
    // Vertices have no top cell to name; report the first top cell on the vertex.
    if let Some(v) = values.iter().position(|x| !x.is_finite()) {
        let n = complex.dim();
        let cell = (0..complex.cell_count(n))
            .find(|&c| complex.cell_vertices(n, c).contains(&v))
            .unwrap_or(0);
        return Err(MetricError::NonFiniteSource {
            cell,
            point: vertices.point(v).to_vec(),
            value: values[v],
        });
    }
    Ok(star.iter().zip(values).map(|(s, x)| s * x).collect())
}

/// [`load`] of a source that depends on the top cell as well as the
/// position (data given per region). A vertex's dual cell straddles the
/// top cells around it, so its load is Σ_c f(c, x_v) ⋆1(v) |c| / Σ_c' |c'|
/// over the top cells c on v: each cell's datum weighted by its share of
/// the vertex's neighbourhood; f(x_v) ⋆1(v) ([`load`]) for a uniform f.
///
/// ```
/// use hasse_complex::{generate::kuhn, DualKind};
/// use hasse_solver::metric::dec;
/// // The unit square as two right triangles on the diagonal v0–v3.
/// let k = kuhn(&[vec![0.0, 1.0], vec![0.0, 1.0]]).unwrap();
/// let uniform = dec::load(&k, DualKind::Circumcentric, &|_| 3.0).unwrap();
/// let by_cell = dec::load_in_cells(&k, DualKind::Circumcentric, &|_, _| 3.0).unwrap();
/// assert!(uniform.iter().zip(&by_cell).all(|(a, b)| (a - b).abs() <= 1e-15 * a.abs()));
/// // f = 3 in triangle 0 only: vertex 0, in both (equal) triangles, gets half.
/// let half = dec::load_in_cells(&k, DualKind::Circumcentric, &|c, _| 3.0 * f64::from(c == 0)).unwrap();
/// assert!((half[0] - uniform[0] / 2.0).abs() < 1e-15);
/// ```
pub fn load_in_cells(
    complex: &Complex,
    kind: DualKind,
    f: &(dyn Fn(usize, &[f64]) -> f64 + Sync),
) -> Result<Vec<f64>, MetricError> {
    let star = complex.dual_measure(kind, 0)?;
    let n = complex.dim();
    let vertices = complex.vertices();
    let volume = complex.measure(n);
    let mut weighted = vec![0.0; complex.cell_count(0)];
    let mut around = vec![0.0; complex.cell_count(0)];
    for (c, &measure) in volume.iter().enumerate() {
        for &v in complex.cell_vertices(n, c) {
            let value = f(c, vertices.point(v));
            if !value.is_finite() {
                return Err(MetricError::NonFiniteSource {
                    cell: c,
                    point: vertices.point(v).to_vec(),
                    value,
                });
            }
            weighted[v] += value * measure;
            around[v] += measure;
        }
    }
    Ok(star
        .iter()
        .zip(weighted.iter().zip(&around))
        .map(|(s, (w, a))| if *a > 0.0 { s * w / a } else { 0.0 })
        .collect())
}

/// Largest ‖K_eff − I‖₂ (at an interior vertex) that
/// [`worst_effective_conductivity`] accepts as consistent.
///
/// Where the diagonal star is consistent (uniform and graded box grids,
/// equilateral triangles, with either dual) K_eff = I holds exactly, and
/// the computed K_eff differs from I by the rounding of a few dozen
/// products of coordinates: below 1e-13 on unit-sized meshes with up to
/// 10⁶ cells per side. A deviation above 1e-6 is geometry, not rounding,
/// and it is an error in the coefficient that does not shrink with h: the
/// solution converges to that of −∇·(K_eff∇u) = f, off by about
/// ‖K_eff − I‖ relative. At 1e-6 that error matches the O(h²) error of a
/// consistent second-order method at h = 10⁻³ (the finest shipped case,
/// 10⁶ cells), so anything above it is a loss of accuracy a user would see.
pub const EFFECTIVE_CONDUCTIVITY_TOLERANCE: f64 = 1e-6;

/// The effective conductivity of the diagonal Hodge star at one vertex
/// (see [`effective_conductivity`]).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexConductivity {
    /// The vertex.
    pub vertex: usize,
    /// Its coordinates.
    pub point: Vec<f64>,
    /// K_eff (the leading d×d block; the rest is zero).
    pub tensor: Tensor,
    /// ‖K_eff − I‖₂: the largest |eigenvalue − 1|.
    pub deviation: f64,
}

/// The effective conductivity of the unit-coefficient diagonal star ⋆₁ of
/// the `kind` dual at every vertex,
///
/// ```text
///     K_eff(v) = Σ_{e ∋ v} ω_e d_e d_eᵀ / (2 |⋆v|),     ω_e = |⋆e| / |e|,
/// ```
///
/// d_e the edge vector. It is the coefficient the nodal operator
/// δ⁰ᵀ ⋆₁ δ⁰ / ⋆₀ applies to a quadratic u at v: with Σ_e ω_e d_e = 0,
/// Σ_e ω_e (u_w − u_v) / |⋆v| = tr(K_eff ∇²u). It is also the constant
/// field's energy Σ ω_e (g·d_e)² per unit dual volume, which is what makes
/// ⋆₁ a consistent mass for Maxwell. A consistent star has K_eff = I.
///
/// Right (Kuhn) triangles with the barycentric dual have
/// K_eff = [[(1 + √5)/3, 1/3], [1/3, (1 + √5)/3]] ≈ [[1.079, 0.333],
/// [0.333, 1.079]] at every interior vertex: the axis edges get
/// ω = 2·(√5/6) (the centroid is √5/6 of a side from the middle of a leg)
/// and the diagonals ω = 2·(√2/6)/√2 = 1/3, and |⋆v| = h².
///
/// Empty when the complex does not fill its space (n < d: a surface has
/// no d×d identity to compare with). Errors: those of the dual measures.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::{kuhn, uniform_axis}};
/// use hasse_solver::metric::dec;
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// let centre = dec::effective_conductivity(&k, DualKind::Barycentric).unwrap()[4];
/// let diagonal = (1.0 + 5f64.sqrt()) / 3.0;
/// assert!((centre[0][0] - diagonal).abs() < 1e-14 && (centre[0][1] - 1.0 / 3.0).abs() < 1e-14);
/// // The circumcentric dual of the same mesh is the P1 stiffness: K_eff = I.
/// let centre = dec::effective_conductivity(&k, DualKind::Circumcentric).unwrap()[4];
/// assert!((centre[0][0] - 1.0).abs() < 1e-14 && centre[0][1].abs() < 1e-14);
/// ```
pub fn effective_conductivity(
    complex: &Complex,
    kind: DualKind,
) -> Result<Vec<Tensor>, MetricError> {
    let d = complex.embedding_dim();
    if complex.dim() != d || d == 0 {
        return Ok(Vec::new());
    }
    let star = complex.hodge_star(kind, 1)?;
    let volume = complex.dual_measure(kind, 0)?;
    let vertices = complex.vertices();
    let mut sums: Vec<Tensor> = vec![[[0.0; 3]; 3]; complex.cell_count(0)];
    for (e, omega) in star.iter().enumerate() {
        let ends = complex.cell_vertices(1, e);
        let [a, b] = ends else { continue };
        let (xa, xb) = (vertices.point(*a), vertices.point(*b));
        for v in [*a, *b] {
            for i in 0..d {
                for j in 0..d {
                    sums[v][i][j] += omega * (xb[i] - xa[i]) * (xb[j] - xa[j]);
                }
            }
        }
    }
    for (sum, dual) in sums.iter_mut().zip(volume) {
        for row in sum.iter_mut().take(d) {
            for x in row.iter_mut().take(d) {
                *x /= 2.0 * dual;
            }
        }
    }
    Ok(sums)
}

/// The interior vertex whose [`effective_conductivity`] is farthest from
/// I (largest ‖K_eff − I‖₂, the first such vertex on ties), or `None`
/// when there is no interior vertex or the complex does not fill its
/// space.
///
/// Boundary vertices are left out: their dual cell is a wedge, and there
/// even a consistent star has K_eff ≠ I (at a 120° corner of equilateral
/// triangles, where both duals are the P1 stiffness, its eigenvalues are
/// 1.25 and 0.75), so they say nothing about the method.
///
/// ```
/// use hasse_complex::{dual::DualKind, generate::{kuhn, rectangle, uniform_axis}};
/// use hasse_solver::metric::dec;
/// let grid = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let worst = dec::worst_effective_conductivity(&grid, DualKind::Barycentric).unwrap().unwrap();
/// assert!(worst.deviation < 1e-14);
/// let x = uniform_axis(4, 0.0, 1.0).unwrap();
/// let kuhn = kuhn(&[x.clone(), x]).unwrap();
/// let worst = dec::worst_effective_conductivity(&kuhn, DualKind::Barycentric).unwrap().unwrap();
/// // Eigenvalues (2 + √5)/3 and √5/3: ‖K_eff − I‖ = (√5 − 1)/3.
/// assert!((worst.deviation - (5f64.sqrt() - 1.0) / 3.0).abs() < 1e-14);
/// assert!(worst.deviation > dec::EFFECTIVE_CONDUCTIVITY_TOLERANCE);
/// ```
pub fn worst_effective_conductivity(
    complex: &Complex,
    kind: DualKind,
) -> Result<Option<VertexConductivity>, MetricError> {
    let tensors = effective_conductivity(complex, kind)?;
    if tensors.is_empty() {
        return Ok(None);
    }
    let d = complex.embedding_dim();
    let wall = complex.boundary_subcomplex();
    let mut worst: Option<VertexConductivity> = None;
    for (v, tensor) in tensors.into_iter().enumerate() {
        if wall.contains(0, v) {
            continue;
        }
        let deviation = identity_distance(&tensor, d);
        // NaN (a vanishing dual cell) counts as the worst.
        let worse = match &worst {
            None => true,
            Some(w) => deviation > w.deviation || (deviation.is_nan() && !w.deviation.is_nan()),
        };
        if worse {
            worst = Some(VertexConductivity {
                vertex: v,
                point: complex.vertices().point(v).to_vec(),
                tensor,
                deviation,
            });
        }
    }
    Ok(worst)
}

/// ‖T − I‖₂ over the leading d×d block of a symmetric T.
fn identity_distance(t: &Tensor, d: usize) -> f64 {
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    for i in 0..d {
        for j in 0..d {
            m[(i, j)] = t[i][j] - if i == j { 1.0 } else { 0.0 };
        }
    }
    if m.iter().any(|x| !x.is_finite()) {
        return f64::NAN;
    }
    m.symmetric_eigenvalues()
        .iter()
        .fold(0.0f64, |w, x| w.max(x.abs()))
}

/// λ when the leading d×d block of `t` is λI.
fn isotropic_value(t: &Tensor, d: usize) -> Option<f64> {
    let lambda = t[0][0];
    let isotropic = (0..d).all(|i| (0..d).all(|j| t[i][j] == if i == j { lambda } else { 0.0 }));
    isotropic.then_some(lambda)
}

/// The dual vertices c(σ) of every dimension 1..=n.
struct Centres<'a> {
    kind: DualKind,
    d: usize,
    /// Index p − 1, stride d.
    points: Vec<&'a [f64]>,
}

impl<'a> Centres<'a> {
    /// Circumcentric pieces need only the top circumcentres (and those
    /// only in 3D: the 2D pieces come from angles); barycentric ones need
    /// every centroid.
    fn new(complex: &'a Complex, kind: DualKind) -> Result<Self, MetricError> {
        let n = complex.dim();
        let points = (1..=n)
            .map(|p| match kind {
                DualKind::Circumcentric if p == 3 => {
                    complex.circumcentre(p).map_err(MetricError::from)
                }
                DualKind::Circumcentric => Ok(&[][..]),
                DualKind::Barycentric => Ok(complex.centroid(p)),
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            kind,
            d: complex.embedding_dim(),
            points,
        })
    }

    fn get(&self, p: usize, i: usize) -> Vector3<f64> {
        let mut x = Vector3::zeros();
        x.as_mut_slice()[..self.d]
            .copy_from_slice(&self.points[p - 1][i * self.d..(i + 1) * self.d]);
        x
    }
}

/// The vertex of simplex `upper` that is not in its facet `lower`.
fn opposite(upper: &[usize], lower: &[usize]) -> Option<usize> {
    upper
        .iter()
        .copied()
        .find(|v| lower.binary_search(v).is_err())
}

/// Signed distance from the midpoint of edge `e` to the circumcentre of
/// the triangle `triangle` (sorted vertices) that contains it, positive on
/// the triangle's side of e: (|e|/2)·cot θ with θ the angle opposite e
/// (inscribed angle theorem). Taken from the angle rather than by
/// differencing the two points: the circumcentre of a sliver is far away
/// and the difference would lose most of its digits.
fn midpoint_to_circumcentre(top: &Topology, e: usize, triangle: &[usize]) -> f64 {
    let ends = top.complex.cell_vertices(1, e);
    let Some(o) = opposite(triangle, ends) else {
        return 0.0;
    };
    let point = |v: usize| Vector3::from(top.point(v));
    let xo = point(o);
    let u = point(ends[0]) - xo;
    let v = point(ends[1]) - xo;
    let length = (u - v).norm();
    let sine = u.cross(&v).norm();
    if sine > 0.0 {
        0.5 * length * u.dot(&v) / sine
    } else {
        0.0
    }
}

/// Signed distance from the plane of face `f` to the circumcentre of the
/// tetrahedron `c`, positive on the tetrahedron's side of f.
fn face_to_circumcentre(top: &Topology, centres: &Centres, f: usize, c: usize) -> f64 {
    let face = top.complex.cell_vertices(2, f);
    let Some(o) = opposite(top.complex.cell_vertices(3, c), face) else {
        return 0.0;
    };
    let point = |v: usize| Vector3::from(top.point(v));
    let x0 = point(face[0]);
    let normal = (point(face[1]) - x0)
        .cross(&(point(face[2]) - x0))
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::zeros);
    let side = if normal.dot(&(point(o) - x0)) < 0.0 {
        -1.0
    } else {
        1.0
    };
    side * normal.dot(&(centres.get(3, c) - x0))
}

/// |⋆e ∩ τ| for every edge e of top cell τ = `c`.
fn dual_pieces(top: &Topology, centres: &Centres, c: usize) -> Vec<(usize, f64)> {
    let signed = centres.kind == DualKind::Circumcentric;
    match top.n {
        // The dual of an edge of a 1-complex is a point.
        1 => vec![(c, 1.0)],
        2 => top
            .edges_of(c)
            .into_iter()
            .map(|e| {
                let piece = if signed {
                    midpoint_to_circumcentre(top, e, top.complex.cell_vertices(2, c))
                } else {
                    (centres.get(2, c) - centres.get(1, e)).norm()
                };
                (e, piece)
            })
            .collect(),
        _ => {
            let edges = top.edges_of(c);
            let mut pieces = vec![0.0; edges.len()];
            for &f in top.facets_of(3, c).0 {
                let height = if signed {
                    face_to_circumcentre(top, centres, f, c)
                } else {
                    0.0
                };
                for &e in top.facets_of(2, f).0 {
                    // Circumcentric: a right triangle with signed legs.
                    let area = if signed {
                        let leg = midpoint_to_circumcentre(top, e, top.complex.cell_vertices(2, f));
                        0.5 * leg * height
                    } else {
                        let mid = centres.get(1, e);
                        let face = centres.get(2, f) - mid;
                        0.5 * face.cross(&(centres.get(3, c) - mid)).norm()
                    };
                    // Present: the edges of a face of c are edges of c.
                    if let Ok(k) = edges.binary_search(&e) {
                        pieces[k] += area;
                    }
                }
            }
            edges.into_iter().zip(pieces).collect()
        }
    }
}

/// ∫_τ K W_e · W_f over the edges of simplex `c`.
fn whitney_block(top: &Topology, c: usize, k: &Tensor) -> Result<Local, MetricError> {
    let vertices = top.complex.cell_vertices(top.n, c);
    let x: Vec<Point> = vertices.iter().map(|&v| top.point(v)).collect();
    let (measure, gradients) =
        simplex_gradients(&x, top.d).ok_or(MetricError::UnsupportedCell {
            method: "DEC Whitney star",
            needs: "a simplex of positive measure",
            cell: c,
        })?;
    let n = top.n as f64;
    // ∫_τ λ_i λ_j = |τ| (1 + δ_ij) / ((n+1)(n+2)).
    let mass =
        |i: usize, j: usize| measure * if i == j { 2.0 } else { 1.0 } / ((n + 1.0) * (n + 2.0));
    let g = |i: usize, j: usize| k_dot(&gradients[i], k, &gradients[j], top.d);
    let edges = top.edges_of(c);
    let ends = edges
        .iter()
        .map(|&e| top.local_ends(e, vertices, c))
        .collect::<Result<Vec<_>, _>>()?;
    let mut values = Vec::with_capacity(edges.len() * edges.len());
    for &(a, b) in &ends {
        for &(p, q) in &ends {
            values.push(
                mass(a, p) * g(b, q) - mass(a, q) * g(b, p) - mass(b, p) * g(a, q)
                    + mass(b, q) * g(a, p),
            );
        }
    }
    Ok(Local::Dense { edges, values })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::isotropic;
    use hasse_complex::{TopCells, Vertices};

    #[test]
    fn pieces_add_up_to_the_dual_measure() {
        // An obtuse triangle next to an acute one: one negative piece.
        let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [1.0, 0.5], [1.0, -1.5]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2], [0, 1, 3]])).unwrap();
        for kind in [DualKind::Circumcentric, DualKind::Barycentric] {
            let omega = hodge_metric(&k, kind, &[isotropic(1.0); 2]).unwrap();
            let dense = omega.to_dense();
            let star = k.hodge_star(kind, 1).unwrap();
            for (e, s) in star.iter().enumerate() {
                assert!((dense[e][e] - s).abs() < 1e-14, "{kind:?} edge {e}");
            }
        }
        // The obtuse triangle alone: its circumcentre (1, −0.75) is 0.75 beyond
        // edge {0,1}, so ω = λ · (−0.75) / 2.
        let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [1.0, 0.5]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        let e = k.find_cell(1, &[0, 1]).unwrap();
        let dense = hodge_metric(&k, DualKind::Circumcentric, &[isotropic(3.0)])
            .unwrap()
            .to_dense();
        assert!((dense[e][e] + 3.0 * 0.75 / 2.0).abs() < 1e-15);
    }

    #[test]
    fn corner_tetrahedron_star_is_not_the_cotangent_formula() {
        // Corner tetrahedron 0, e_x, e_y, e_z; circumcentre (½, ½, ½) lies
        // beyond the face {1, 2, 3}. Edge {0, 1}: both faces on it are right
        // triangles with circumcentres (½, ½, 0) and (½, 0, ½), legs ½ and ½,
        // so |⋆e ∩ τ| = 2 · ½ · ½ · ½ = ¼. Edge {1, 2}: the face {0, 1, 2}
        // has its circumcentre at the edge midpoint (leg 0); the face
        // {1, 2, 3} gives legs √6/6 and −√3/6 (the circumcentre is on the far
        // side of it), so |⋆e ∩ τ| = −√2/24 and ω = −1/24. P1 has 1/6 and 0.
        let v = Vertices::from_points(&[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ])
        .unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
        let dense = hodge_metric(&k, DualKind::Circumcentric, &[isotropic(1.0)])
            .unwrap()
            .to_dense();
        let whitney = crate::operator::Canonical::new(
            k.coboundary(0),
            whitney_metric(&k, &[isotropic(1.0)]).unwrap(),
        )
        .unwrap()
        .assemble()
        .to_dense();
        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let e = k.find_cell(1, &[a, b]).unwrap();
            let (star, p1) = if a == 0 {
                (0.25, 1.0 / 6.0)
            } else {
                (-1.0 / 24.0, 0.0)
            };
            assert!(
                (dense[e][e] - star).abs() < 1e-15,
                "{a}{b}: {}",
                dense[e][e]
            );
            assert!(
                (whitney[(a, b)] + p1).abs() < 1e-15,
                "{a}{b}: {}",
                whitney[(a, b)]
            );
        }
    }

    #[test]
    fn sliver_weights_keep_their_digits() {
        // θ opposite the base is 2·atan(1/t): cot θ = (1 − (1/t)²)... use the
        // exact form cot(θ) = (t² − 1)/(2t) for the apex (0, t) over [−1, 1].
        for t in [1e-3, 1e-6] {
            let v = Vertices::from_points(&[[-1.0, 0.0], [1.0, 0.0], [0.0, t]]).unwrap();
            let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
            let e = k.find_cell(1, &[0, 1]).unwrap();
            let w = hodge_metric(&k, DualKind::Circumcentric, &[isotropic(1.0)])
                .unwrap()
                .to_dense()[e][e];
            let expected = 0.5 * (t * t - 1.0) / (2.0 * t);
            assert!(
                (w - expected).abs() <= 1e-15 * expected.abs(),
                "{t}: {w} vs {expected}"
            );
        }
    }

    /// Eigenvalues of the leading 2×2 block of a symmetric tensor.
    fn eigenvalues_2d(t: &Tensor) -> [f64; 2] {
        let (a, b, c) = (t[0][0], t[0][1], t[1][1]);
        let r = (0.25 * (a - c).powi(2) + b * b).sqrt();
        [0.5 * (a + c) - r, 0.5 * (a + c) + r]
    }

    #[test]
    fn effective_conductivity_of_kuhn_triangles_is_the_hand_computed_tensor() {
        // Issue 30, item 4. Right triangles of side h = 1/4 with the
        // barycentric dual (see `effective_conductivity`): interior vertices
        // K = [[(1+√5)/3, 1/3], [1/3, (1+√5)/3]]. At the corner (0, 0) two
        // legs of one triangle each (ω = √5/6) and the shared diagonal
        // (ω = 1/3), |⋆v| = 2·(h²/2)/3 = h²/3:
        // K = [[½ + √5/4, ½], [½, ½ + √5/4]]. Entries are sums of at most
        // six products of O(1) terms, so 1e-14 is a few dozen ulps.
        let x = hasse_complex::generate::uniform_axis(4, 0.0, 1.0).unwrap();
        let k = hasse_complex::generate::kuhn(&[x.clone(), x]).unwrap();
        let tensors = effective_conductivity(&k, DualKind::Barycentric).unwrap();
        let r5 = 5f64.sqrt();
        let wall = k.boundary_subcomplex();
        for (v, t) in tensors.iter().enumerate() {
            if wall.contains(0, v) {
                continue;
            }
            approx::assert_abs_diff_eq!(t[0][0], (1.0 + r5) / 3.0, epsilon = 1e-14);
            approx::assert_abs_diff_eq!(t[1][1], (1.0 + r5) / 3.0, epsilon = 1e-14);
            approx::assert_abs_diff_eq!(t[0][1], 1.0 / 3.0, epsilon = 1e-14);
            approx::assert_abs_diff_eq!(t[1][0], 1.0 / 3.0, epsilon = 1e-14);
        }
        let corner = &tensors[0];
        approx::assert_abs_diff_eq!(corner[0][0], 0.5 + r5 / 4.0, epsilon = 1e-14);
        approx::assert_abs_diff_eq!(corner[0][1], 0.5, epsilon = 1e-14);
        // The worst interior vertex: eigenvalues (2+√5)/3 and √5/3.
        let worst = worst_effective_conductivity(&k, DualKind::Barycentric)
            .unwrap()
            .unwrap();
        approx::assert_abs_diff_eq!(worst.deviation, (r5 - 1.0) / 3.0, epsilon = 1e-14);
        assert!(!wall.contains(0, worst.vertex));
        assert_eq!(worst.point, k.vertices().point(worst.vertex));
    }

    #[test]
    fn effective_conductivity_is_the_identity_where_the_star_is_consistent() {
        // Rounding only: K_eff = I exactly in these geometries, computed
        // from a few dozen products of unit-sized numbers, so 1e-13 (far
        // below EFFECTIVE_CONDUCTIVITY_TOLERANCE) bounds it.
        let graded = hasse_complex::generate::graded_axis(6, 0.0, 1.0, 1.3).unwrap();
        let even = hasse_complex::generate::uniform_axis(5, -1.0, 2.0).unwrap();
        let grids = [
            hasse_complex::generate::rectangle(6, 4, [0.0, 3.0], [0.0, 1.0]).unwrap(),
            hasse_complex::generate::grid(&[graded.clone(), even.clone()]).unwrap(),
            hasse_complex::generate::grid(&[graded, even.clone(), even]).unwrap(),
        ];
        for (i, k) in grids.iter().enumerate() {
            let worst = worst_effective_conductivity(k, DualKind::Barycentric)
                .unwrap()
                .unwrap();
            assert!(worst.deviation < 1e-13, "grid {i}: {worst:?}");
        }
        // Equilateral triangles (a hexagon of side 2): the barycentric and
        // circumcentric duals coincide and interior vertices see six
        // edges 60° apart, Σ d dᵀ ∝ I.
        let s = 3f64.sqrt() / 2.0;
        let mut points = Vec::new();
        for i in -2i32..=2 {
            for j in -2i32..=2 {
                if (i + j).abs() <= 2 {
                    points.push([f64::from(i) + 0.5 * f64::from(j), s * f64::from(j)]);
                }
            }
        }
        let hexagon = hasse_complex::generate::delaunay(&points).unwrap();
        assert_eq!(hexagon.cell_count(2), 24);
        for kind in [DualKind::Barycentric, DualKind::Circumcentric] {
            let worst = worst_effective_conductivity(&hexagon, kind)
                .unwrap()
                .unwrap();
            assert!(worst.deviation < 1e-13, "{kind:?}: {worst:?}");
        }
        // Why boundary vertices are left out: at the 120° corner (2, 0)
        // (two triangles, edges at 120°, 180° and 240°, the middle one
        // shared) both duals give eigenvalues 0.75 and 1.25 although the
        // circumcentric star is the P1 stiffness there.
        let corner = points.iter().position(|p| *p == [2.0, 0.0]).unwrap();
        for kind in [DualKind::Barycentric, DualKind::Circumcentric] {
            let t = effective_conductivity(&hexagon, kind).unwrap()[corner];
            let [low, high] = eigenvalues_2d(&t);
            approx::assert_abs_diff_eq!(low, 0.75, epsilon = 1e-13);
            approx::assert_abs_diff_eq!(high, 1.25, epsilon = 1e-13);
        }
        // A surface has no d×d identity to compare with.
        let sphere = hasse_complex::generate::sphere(1.0, 1).unwrap();
        assert_eq!(
            worst_effective_conductivity(&sphere, DualKind::Barycentric).unwrap(),
            None
        );
    }

    #[test]
    fn tensors_on_quads_are_rejected() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
        let mut t = isotropic(1.0);
        t[0][1] = 0.1;
        t[1][0] = 0.1;
        assert!(matches!(
            hodge_metric(&k, DualKind::Barycentric, &[t]),
            Err(MetricError::UnsupportedCell { cell: 0, .. })
        ));
        assert!(matches!(
            hodge_metric(&k, DualKind::Circumcentric, &[isotropic(1.0)]),
            Err(MetricError::UnsupportedCell { cell: 0, .. })
        ));
        assert!(hodge_metric(&k, DualKind::Barycentric, &[isotropic(1.0)]).is_ok());
    }
}
