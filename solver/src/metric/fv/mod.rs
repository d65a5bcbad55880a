//! Finite-volume metrics for cell-centred unknowns: the two-point flux
//! approximation (TPFA) and the mimetic finite difference method in hybrid
//! form.
//!
//! Both write the diffusion operator −∇·(K∇u) as Aᵀ Ω A with an exact
//! integer A and the geometry and the coefficient in Ω:
//!
//! - [`two_point`]: A = ∂ₙ (rows: every (n−1)-cell), Ω diagonal. Cheap and
//!   monotone, but consistent only on K-orthogonal meshes (the line between
//!   two cell centroids is K-orthogonal to their common face, e.g.
//!   axis-aligned boxes with a diagonal tensor, or a Voronoi mesh with a
//!   scalar coefficient).
//! - [`two_point_at`]: the same with the cell unknowns at given points
//!   (circumcentres of a Delaunay triangulation, sites of a Voronoi mesh),
//!   where the mesh is orthogonal by construction.
//! - [`mimetic_hybrid`]: A is the half-face incidence (cell minus face),
//!   Ω block diagonal with one dense block per cell. Exact for linear
//!   solutions on any mesh of convex cells with planar faces (distorted
//!   quadrilaterals and hexahedra, polygons, SPLIT cut cells).
//!
//! Both take one coefficient tensor per top cell and use the cached
//! geometry of the complex: measures, centroids and the unit normals of the
//! (n−1)-cells, oriented so that ∂ₙ(F, K) n_F points out of K.

use super::{check_tensors, CellTensors, MetricError, Tensor};
use crate::operator::BlockMetric;
use hasse_complex::Complex;
use nalgebra::DMatrix;
use rayon::prelude::*;
use sprs::CsMat;

/// nᵀ K n over the first `d` components.
fn normal_component(tensor: &Tensor, n: &[f64]) -> f64 {
    n.iter()
        .enumerate()
        .map(|(i, ni)| {
            ni * n
                .iter()
                .enumerate()
                .map(|(j, nj)| tensor[i][j] * nj)
                .sum::<f64>()
        })
        .sum()
}

/// |(x_F − x_K)·n_F|: the distance from the cell centroid to the plane of
/// the face, measured along the face normal.
fn face_distance(x_face: &[f64], x_cell: &[f64], normal: &[f64]) -> f64 {
    x_face
        .iter()
        .zip(x_cell)
        .zip(normal)
        .map(|((f, c), n)| (f - c) * n)
        .sum::<f64>()
        .abs()
}

/// Shared geometry of one (face, cell) pair.
struct HalfFace<'a> {
    area: f64,
    normal: &'a [f64],
    x_face: &'a [f64],
    x_cell: &'a [f64],
}

/// The primal geometry half-faces are made of, fetched from the complex's
/// caches once rather than per face.
struct FaceGeometry<'a> {
    d: usize,
    areas: &'a [f64],
    normals: &'a [f64],
    face_centroids: &'a [f64],
    cell_centroids: &'a [f64],
}

impl<'a> FaceGeometry<'a> {
    fn new(complex: &'a Complex) -> Self {
        let n = complex.dim();
        FaceGeometry {
            d: complex.embedding_dim(),
            areas: complex.measure(n - 1),
            normals: complex.normal(),
            face_centroids: complex.centroid(n - 1),
            cell_centroids: complex.centroid(n),
        }
    }

    /// The half-face of top cell `cell` on (n−1)-cell `face`.
    fn half(&self, face: usize, cell: usize) -> HalfFace<'a> {
        let d = self.d;
        HalfFace {
            area: self.areas[face],
            normal: &self.normals[face * d..(face + 1) * d],
            x_face: &self.face_centroids[face * d..(face + 1) * d],
            x_cell: &self.cell_centroids[cell * d..(cell + 1) * d],
        }
    }
}

impl HalfFace<'_> {
    /// d_{K,F} / κ_{K,F}: the resistance of the half cell between the
    /// centroid and the face, per unit face area. A centroid on the face
    /// plane (a degenerate or non-convex cell) has no such resistance.
    fn resistance(
        &self,
        tensor: &Tensor,
        cell: usize,
        method: &'static str,
    ) -> Result<f64, MetricError> {
        let distance = face_distance(self.x_face, self.x_cell, self.normal);
        let kappa = normal_component(tensor, self.normal);
        if !(distance > 0.0 && distance.is_finite() && kappa > 0.0) {
            return Err(MetricError::UnsupportedCell {
                method,
                needs: "a convex cell whose centroid lies strictly inside (off every face plane)",
                cell,
            });
        }
        Ok(distance / kappa)
    }
}

/// Reject complexes without (n−1)-cells to carry fluxes.
fn check_dimension(complex: &Complex, method: &'static str) -> Result<usize, MetricError> {
    let n = complex.dim();
    if n == 0 {
        return Err(MetricError::UnsupportedMesh {
            method,
            needs: "cells of dimension at least 1",
            detail: "the complex has only vertices".into(),
        });
    }
    Ok(n)
}

/// Two-point flux approximation on A = ∂ₙ: one diagonal entry per
/// (n−1)-cell, boundary faces included.
///
/// For an interior face F between top cells K and L,
/// σ_F = |F| / (d_K/κ_K + d_L/κ_L), with d_K = |(x_F − x_K)·n_F| the
/// distance from K's centroid to the plane of F and κ_K = n_Fᵀ K_K n_F: the
/// half transmissibilities |F|κ/d of the two sides in series (harmonic
/// averaging of the coefficient). On a boundary face of K,
/// σ_F = |F| κ_K / d_K: the boundary row of A then acts as a Dirichlet
/// "ghost" value located on the face itself, so Aᵀ Ω A carries zero
/// Dirichlet data and non-zero data enters as Aᵀ Ω w with
/// w_F = ∂ₙ(F, K) u(x_F).
///
/// The flux σ_F (u_K − u_L) is exact for linear u only when x_L − x_K is
/// K-orthogonal to F (axis-aligned boxes with a diagonal tensor, Voronoi
/// cells with a scalar coefficient). On distorted meshes TPFA is not
/// consistent and does not converge; use [`mimetic_hybrid`] there.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::{fv, isotropic};
/// // Two 1×1 squares side by side: the shared edge has σ = 1·1/(½ + ½).
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let omega = fv::two_point(&k, &[isotropic(1.0); 2]).unwrap();
/// let sigma: Vec<f64> = omega.to_dense().iter().enumerate().map(|(i, r)| r[i]).collect();
/// let shared = k.boundary(2).outer_iterator().position(|r| r.nnz() == 2).unwrap();
/// assert!((sigma[shared] - 1.0).abs() < 1e-14);
/// // Boundary edges: σ = 1·1/½ = 2.
/// assert!(sigma.iter().enumerate().all(|(f, s)| f == shared || (s - 2.0).abs() < 1e-14));
/// ```
pub fn two_point<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<BlockMetric, MetricError> {
    let tensors = tensors.into();
    const METHOD: &str = "two-point flux (TPFA)";
    let n = check_dimension(complex, METHOD)?;
    check_tensors(tensors, complex.cell_count(n), complex.embedding_dim())?;
    let boundary = complex.try_boundary(n)?;
    let faces = boundary.rows();
    let geometry = FaceGeometry::new(complex);
    let sigma_of = |face: usize| {
        let range = boundary.indptr().outer_inds_sz(face);
        let cells = &boundary.indices()[range];
        if cells.len() > 2 {
            return Err(MetricError::UnsupportedMesh {
                method: METHOD,
                needs: "every (n−1)-cell shared by at most two top cells",
                detail: format!("(n−1)-cell {face} lies on {} top cells", cells.len()),
            });
        }
        let mut resistance = 0.0;
        let mut area = 0.0;
        for &cell in cells {
            let half = geometry.half(face, cell);
            resistance += half.resistance(&tensors.get(cell), cell, METHOD)?;
            area = half.area;
        }
        // A face on no top cell carries no flux.
        Ok(if cells.is_empty() {
            0.0
        } else {
            area / resistance
        })
    };
    let mut sigma = vec![0.0; faces];
    let all_good = sigma
        .par_iter_mut()
        .enumerate()
        .try_for_each(|(face, out)| sigma_of(face).map(|value| *out = value));
    if all_good.is_err() {
        // Report the first bad face, whichever thread met one.
        if let Some(error) = (0..faces).find_map(|face| sigma_of(face).err()) {
            return Err(error);
        }
    }
    Ok(BlockMetric::from_weights(sigma))
}

/// Two-point flux approximation with the cell unknowns at given points
/// instead of the centroids: `points` holds one point per top cell (stride
/// d), e.g. the circumcentres of a Delaunay triangulation or the sites of a
/// Voronoi mesh, for which the line between two neighbouring points is
/// orthogonal to their common face and the two-point flux is consistent.
///
/// With n_{K,F} the normal of F pointing out of K and
/// s_{K,F} = (x_F − p_K)·n_{K,F} the *signed* distance from K's point to
/// the plane of F, σ_F = |F| / Σ_K s_{K,F}/κ_K over the one or two top
/// cells on F (κ_K = n_Fᵀ K_K n_F). A circumcentre may lie outside its
/// triangle; only the sum over the two sides has to be positive, which is
/// the Delaunay condition (the two circumcentres lie in the right order
/// along the edge's perpendicular bisector). On a boundary face the point
/// must lie strictly on the inner side. A face where this fails
/// (cocircular neighbours, an obtuse angle opposite a boundary edge) is
/// reported by number.
///
/// The Dirichlet value of a boundary face then belongs at the orthogonal
/// projection p_K + s_{K,F} n_{K,F} of the cell point onto the face plane
/// (for a circumcentre: the midpoint of the boundary edge), and the cell
/// value approximates u(p_K); [`crate::physics::diffusion`] does both when asked
/// for these cell points.
///
/// ```
/// use hasse_complex::{Complex, TopCells, Vertices};
/// use hasse_solver::metric::{fv, isotropic};
/// // Two right triangles on the unit square: both circumcentres are the
/// // midpoint of the shared diagonal, so that face is singular...
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
/// let k = Complex::build(v, TopCells::simplices([[0, 1, 2], [1, 3, 2]])).unwrap();
/// let c = k.circumcentre(2).unwrap().to_vec();
/// assert!(fv::two_point_at(&k, &[isotropic(1.0); 2], &c).is_err());
/// // ...while an equilateral-ish pair is fine: the boundary edges have
/// // σ = |F| / (distance from circumcentre to edge).
/// let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [1.0, 1.5], [1.0, -1.5]]).unwrap();
/// let k = Complex::build(v, TopCells::simplices([[0, 1, 2], [0, 3, 1]])).unwrap();
/// let c = k.circumcentre(2).unwrap().to_vec();
/// let sigma = fv::two_point_at(&k, &[isotropic(1.0); 2], &c).unwrap().to_dense();
/// let shared = k.find_cell(1, &[0, 1]).unwrap();
/// // Circumcentres at (1, ±5/12): σ = 2 / (5/12 + 5/12).
/// assert!((sigma[shared][shared] - 2.4).abs() < 1e-12);
/// ```
pub fn two_point_at<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
    points: &[f64],
) -> Result<BlockMetric, MetricError> {
    let tensors = tensors.into();
    const METHOD: &str = "two-point flux (TPFA) at given cell points";
    let n = check_dimension(complex, METHOD)?;
    let d = complex.embedding_dim();
    let cells = complex.cell_count(n);
    check_tensors(tensors, cells, d)?;
    if points.len() != cells * d || points.iter().any(|x| !x.is_finite()) {
        return Err(MetricError::UnsupportedMesh {
            method: METHOD,
            needs: "one finite point per top cell",
            detail: format!(
                "{} coordinates given for {cells} top cells in R^{d}",
                points.len()
            ),
        });
    }
    let boundary = complex.try_boundary(n)?;
    let _ = (
        complex.measure(n - 1),
        complex.normal(),
        complex.centroid(n - 1),
    );
    let sigma = (0..boundary.rows())
        .into_par_iter()
        .map(|face| {
            let row = boundary.outer_view(face).map(|r| r.iter().map(|(c, &s)| (c, s)).collect::<Vec<_>>()).unwrap_or_default();
            if row.len() > 2 {
                return Err(MetricError::UnsupportedMesh {
                    method: METHOD,
                    needs: "every (n−1)-cell shared by at most two top cells",
                    detail: format!("(n−1)-cell {face} lies on {} top cells", row.len()),
                });
            }
            if row.is_empty() {
                return Ok(0.0);
            }
            let normal = &complex.normal()[face * d..(face + 1) * d];
            let x_face = complex.centroid_of(n - 1, face);
            let mut resistance = 0.0;
            for &(cell, sign) in &row {
                let s = signed_distance(x_face, &points[cell * d..(cell + 1) * d], normal, sign);
                resistance += s / normal_component(&tensors.get(cell), normal);
            }
            if !(resistance > 0.0 && resistance.is_finite()) {
                return Err(MetricError::UnsupportedMesh {
                    method: METHOD,
                    needs: "cell points in order across every face (for circumcentres: a Delaunay mesh without cocircular neighbours and without an obtuse angle opposite a boundary edge)",
                    detail: format!(
                        "(n−1)-cell {face}: the signed distances of its cell points sum to {resistance:e}"
                    ),
                });
            }
            Ok(complex.measure(n - 1)[face] / resistance)
        })
        .collect::<Result<Vec<f64>, MetricError>>()?;
    Ok(BlockMetric::diagonal(&sigma))
}

/// (x_F − p)·n_{K,F}: the distance from `point` to the face plane, positive
/// when the point is on the inner side of the face for the cell with
/// incidence `sign` (n_{K,F} = sign · n_F points out of that cell).
pub fn signed_distance(x_face: &[f64], point: &[f64], normal: &[f64], sign: i8) -> f64 {
    f64::from(sign)
        * x_face
            .iter()
            .zip(point)
            .zip(normal)
            .map(|((f, p), n)| (f - p) * n)
            .sum::<f64>()
}

/// Sizes of the hybrid unknown vector: cell values in columns
/// `0..cells`, then face values in columns `cells..cells + faces`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HybridLayout {
    /// Number of top cells (cell unknowns u_K).
    pub cells: usize,
    /// Number of (n−1)-cells (face unknowns λ_F).
    pub faces: usize,
}

impl HybridLayout {
    /// Total number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.cells + self.faces
    }

    /// Column of the face unknown λ_F.
    pub fn face_column(&self, face: usize) -> usize {
        self.cells + face
    }
}

/// The mimetic transmissibility matrix T_K of one cell and its half-face
/// geometry, used by [`mimetic_hybrid`] and its tests.
///
/// `outward` holds the rows |F| n_{K,F}ᵀ (N), `offsets` the rows
/// (x_F − x_K)ᵀ (D), `resistances` d_{K,F}/κ_{K,F}; all are m × d with
/// m = |∂K|.
fn transmissibility(
    tensor: &Tensor,
    volume: f64,
    outward: &DMatrix<f64>,
    offsets: &DMatrix<f64>,
    areas: &[f64],
    resistances: &[f64],
    cell: usize,
) -> Result<DMatrix<f64>, MetricError> {
    let (m, d) = outward.shape();
    let k = DMatrix::from_fn(d, d, |i, j| 0.5 * (tensor[i][j] + tensor[j][i]));
    // Consistency: NᵀD = |K| I (the divergence theorem for linear
    // functions), so T₀ D = N K — exact fluxes for linear u.
    let consistency = outward * &k * outward.transpose() / volume;
    // Orthonormal basis Q of span(D); the stabilisation must vanish on it.
    let qr = offsets.clone().qr();
    let r = qr.r();
    let diagonal: Vec<f64> = (0..d).map(|i| r[(i, i)].abs()).collect();
    let largest = diagonal.iter().fold(0.0f64, |a, &b| a.max(b));
    // A zero or NaN diagonal of R means D lost rank: a degenerate cell.
    if diagonal.iter().any(|&v| v.is_nan() || v <= 1e-12 * largest) {
        return Err(MetricError::UnsupportedCell {
            method: "mimetic finite differences",
            needs: "a non-degenerate cell (face centroids spanning the space)",
            cell,
        });
    }
    let q = qr.q();
    let projector = DMatrix::<f64>::identity(m, m) - &q * q.transpose();
    // Stabilisation W = diag(|F| κ_F / d_F), the two-point half
    // transmissibilities: it has the scale of T₀ on every cell shape, and
    // on a box with a diagonal tensor T₀ + (I − QQᵀ) W (I − QQᵀ) is exactly
    // W, so the method reduces to TPFA where TPFA is consistent.
    let w = DMatrix::from_fn(m, m, |i, j| {
        if i == j {
            areas[i] / resistances[i]
        } else {
            0.0
        }
    });
    let t = consistency + &projector * w * &projector;
    // Symmetrise away rounding so the block is symmetric bit for bit.
    Ok((&t + t.transpose()) * 0.5)
}

/// Mimetic finite differences (lowest order) in hybrid form, consistent on
/// every mesh of convex cells with planar faces.
///
/// Unknowns are cell values u_K (columns `0..cells`) and face values λ_F
/// (columns `cells..cells + faces`, see [`HybridLayout`]). The returned
/// incidence A has one row per half-face (K, F ∈ ∂K), cells in order and
/// each cell's faces in the order of column K of `boundary_csc(n)`, with
/// +1 in column K and −1 in column `cells + F`: (A x)_{K,F} = u_K − λ_F.
///
/// Ω is block diagonal, one |∂K| × |∂K| block T_K per cell (block K of the
/// metric), mapping u_K 1 − λ_K to the outward fluxes of −K∇u through the
/// faces of K:
///
/// T_K = (1/|K|) N K Nᵀ + (I − QQᵀ) W (I − QQᵀ),
///
/// with N rows |F| n_{K,F}ᵀ (outward), D rows (x_F − x_K)ᵀ (face and cell
/// centroids), Q an orthonormal basis of span(D) and
/// W = diag(|F| κ_{K,F} / d_{K,F}) the two-point half transmissibilities.
/// The divergence theorem gives Nᵀ D = |K| I for planar faces, hence the
/// consistency condition T_K D = N K: the fluxes are exact whenever u is
/// linear in K. T_K is symmetric positive definite: the first term
/// vanishes only on ker Nᵀ, the second only on span(D), and the two meet
/// only in 0 because Nᵀ D = |K| I. So Aᵀ Ω A is symmetric positive
/// semi-definite with the constants as kernel (on a connected mesh).
///
/// Row K of Aᵀ Ω A is the flux balance of cell K; row `cells + F` is minus
/// the sum of the half-face fluxes through F, i.e. flux continuity on an
/// interior face. Dirichlet data fix λ_F on boundary faces; a Neumann flux
/// g_F enters the right-hand side of row `cells + F`.
///
/// On axis-aligned boxes with a diagonal tensor, T_K = W: eliminating the
/// face unknowns gives the two-point scheme [`two_point`].
///
/// Non-planar faces (e.g. the warped quadrilateral faces of a randomly
/// perturbed hexahedral grid) are described by the geometry module's unit
/// normal and fan area, for which Nᵀ D = |K| I holds only up to the face
/// warping. Exactness is then lost in proportion to warping / h: no
/// symmetric T_K can satisfy T_K D = N K unless (Nᵀ D)ᵀ K is symmetric,
/// with one point per face. Meshes from smooth mappings (warping O(h²))
/// keep first-order consistency; meshes warped by O(h) at every level do
/// not converge for linear solutions.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::operator::Canonical;
/// use hasse_solver::metric::{fv, isotropic};
/// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// let (a, omega, layout) = fv::mimetic_hybrid(&k, &[isotropic(1.0); 4]).unwrap();
/// assert_eq!((layout.cells, layout.faces), (4, 12));
/// assert_eq!(a.rows(), 16); // four half-faces per square
/// let op = Canonical::new(a, omega).unwrap();
/// // Constants are in the kernel: u_K = λ_F = 1 carries no flux.
/// assert!(op.apply(&vec![1.0; layout.unknowns()]).iter().all(|v| v.abs() < 1e-12));
/// ```
pub fn mimetic_hybrid<'a>(
    complex: &Complex,
    tensors: impl Into<CellTensors<'a>>,
) -> Result<(CsMat<i8>, BlockMetric, HybridLayout), MetricError> {
    let tensors = tensors.into();
    const METHOD: &str = "mimetic finite differences";
    let n = check_dimension(complex, METHOD)?;
    let d = complex.embedding_dim();
    if n != d {
        return Err(MetricError::UnsupportedMesh {
            method: METHOD,
            needs: "a complex that fills its space (n = d)",
            detail: format!("the complex is {n}-dimensional in R^{d}"),
        });
    }
    let cells = complex.cell_count(n);
    check_tensors(tensors, cells, d)?;
    let faces = complex.try_boundary(n)?.rows();
    let layout = HybridLayout { cells, faces };
    let by_cell = complex.boundary_csc(n);
    let indptr = by_cell.indptr();
    let _ = complex.measure(n);
    let geometry = FaceGeometry::new(complex);
    let _ = (complex.centroid(n), complex.centroid(n - 1));

    let blocks = (0..cells)
        .into_par_iter()
        .map(|cell| {
            let range = indptr.outer_inds_sz(cell);
            let cell_faces = &by_cell.indices()[range.clone()];
            let signs = &by_cell.data()[range];
            let m = cell_faces.len();
            let mut outward = DMatrix::zeros(m, d);
            let mut offsets = DMatrix::zeros(m, d);
            let mut areas = Vec::with_capacity(m);
            let mut resistances = Vec::with_capacity(m);
            for (i, (&face, &sign)) in cell_faces.iter().zip(signs).enumerate() {
                let half = geometry.half(face, cell);
                for a in 0..d {
                    outward[(i, a)] = f64::from(sign) * half.area * half.normal[a];
                    offsets[(i, a)] = half.x_face[a] - half.x_cell[a];
                }
                areas.push(half.area);
                resistances.push(half.resistance(&tensors.get(cell), cell, METHOD)?);
            }
            transmissibility(
                &tensors.get(cell),
                complex.measure(n)[cell],
                &outward,
                &offsets,
                &areas,
                &resistances,
                cell,
            )
        })
        .collect::<Result<Vec<_>, MetricError>>()?;

    let half_faces = by_cell.nnz();
    let mut omega = BlockMetric::new(half_faces);
    let mut rows: Vec<usize> = Vec::new();
    for (cell, t) in blocks.iter().enumerate() {
        rows.clear();
        rows.extend(indptr.outer_inds_sz(cell));
        // nalgebra is column-major; the block is symmetric, so its
        // column-major storage is also its row-major storage.
        omega.push_symmetric(&rows, t.as_slice());
    }

    let mut row_ptr = Vec::with_capacity(half_faces + 1);
    let mut columns = Vec::with_capacity(2 * half_faces);
    let mut values = Vec::with_capacity(2 * half_faces);
    row_ptr.push(0);
    for cell in 0..cells {
        for &face in &by_cell.indices()[indptr.outer_inds_sz(cell)] {
            columns.extend_from_slice(&[cell, layout.face_column(face)]);
            values.extend_from_slice(&[1i8, -1]);
            row_ptr.push(columns.len());
        }
    }
    let a = CsMat::new((half_faces, layout.unknowns()), row_ptr, columns, values);
    Ok((a, omega, layout))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::isotropic;
    use hasse_complex::generate::{perturb, rectangle};
    use hasse_complex::{TopCells, Vertices};

    /// N, D, areas, resistances of cell `cell`, recomputed from geometry.
    fn cell_geometry(
        complex: &Complex,
        tensor: &Tensor,
        cell: usize,
    ) -> (DMatrix<f64>, DMatrix<f64>, Vec<f64>, Vec<f64>) {
        let (n, d) = (complex.dim(), complex.embedding_dim());
        let csc = complex.boundary_csc(n);
        let col = csc.outer_view(cell).unwrap();
        let m = col.nnz();
        let (mut nn, mut dd) = (DMatrix::zeros(m, d), DMatrix::zeros(m, d));
        let (mut areas, mut res) = (vec![], vec![]);
        let geometry = FaceGeometry::new(complex);
        for (i, (face, &s)) in col.iter().enumerate() {
            let h = geometry.half(face, cell);
            for a in 0..d {
                nn[(i, a)] = f64::from(s) * h.area * h.normal[a];
                dd[(i, a)] = h.x_face[a] - h.x_cell[a];
            }
            areas.push(h.area);
            res.push(h.resistance(tensor, cell, "test").unwrap());
        }
        (nn, dd, areas, res)
    }

    #[test]
    fn divergence_theorem_gives_n_transpose_d_equal_volume_identity() {
        let k = perturb(&rectangle(3, 3, [0.0, 1.0], [0.0, 1.0]).unwrap(), 0.3, 4).unwrap();
        for cell in 0..k.cell_count(2) {
            let (nn, dd, _, _) = cell_geometry(&k, &isotropic(1.0), cell);
            let g = nn.transpose() * dd / k.measure(2)[cell];
            assert!((g - DMatrix::identity(2, 2)).amax() < 1e-13, "cell {cell}");
        }
    }

    #[test]
    fn transmissibility_is_exact_for_linear_functions_on_a_pentagon() {
        let v =
            Vertices::from_points(&[[0.0, 0.0], [2.0, 0.2], [2.5, 1.5], [1.0, 2.2], [-0.3, 1.1]])
                .unwrap();
        let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3, 4]])).unwrap();
        let tensor = [[2.0, 0.6, 0.0], [0.6, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let (nn, dd, areas, res) = cell_geometry(&k, &tensor, 0);
        let t = transmissibility(&tensor, k.measure(2)[0], &nn, &dd, &areas, &res, 0).unwrap();
        let kk = DMatrix::from_fn(2, 2, |i, j| tensor[i][j]);
        assert!((&t * &dd - &nn * kk).amax() < 1e-12);
        // Symmetric positive definite.
        assert!((&t - t.transpose()).amax() == 0.0);
        assert!(t.clone().symmetric_eigen().eigenvalues.min() > 0.0);
    }

    #[test]
    fn transmissibility_of_a_rectangle_with_diagonal_tensor_is_two_point() {
        // hx = 2, hy = 0.5, K = diag(3, 5): TPFA half transmissibilities are
        // |F| κ / (h/2): x-faces 0.5·3/1 = 1.5, y-faces 2·5/0.25 = 40.
        let k = rectangle(1, 1, [0.0, 2.0], [0.0, 0.5]).unwrap();
        let tensor = [[3.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 1.0]];
        let (nn, dd, areas, res) = cell_geometry(&k, &tensor, 0);
        let t = transmissibility(&tensor, 1.0, &nn, &dd, &areas, &res, 0).unwrap();
        for i in 0..4 {
            let expected = if nn[(i, 0)].abs() > 0.0 { 1.5 } else { 40.0 };
            for j in 0..4 {
                let e = if i == j { expected } else { 0.0 };
                assert!((t[(i, j)] - e).abs() < 1e-12, "T[{i}][{j}] = {}", t[(i, j)]);
            }
        }
    }

    #[test]
    fn two_point_on_one_square_has_boundary_sigma_two() {
        let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let omega = two_point(&k, &[isotropic(3.0)]).unwrap();
        let dense = omega.to_dense();
        for (f, row) in dense.iter().enumerate() {
            assert!((row[f] - 6.0).abs() < 1e-14);
        }
    }

    #[test]
    fn bad_coefficients_and_meshes_are_reported() {
        let k = rectangle(2, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        assert_eq!(
            two_point(&k, &[isotropic(1.0)]).unwrap_err(),
            MetricError::CoefficientCount { count: 1, cells: 2 }
        );
        assert!(matches!(
            mimetic_hybrid(&k, &[isotropic(1.0), isotropic(-1.0)]).unwrap_err(),
            MetricError::NotPositive { cell: 1, .. }
        ));
        let v =
            Vertices::from_points(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap();
        let surface = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        assert!(matches!(
            mimetic_hybrid(&surface, &[isotropic(1.0)]).unwrap_err(),
            MetricError::UnsupportedMesh { .. }
        ));
        // TPFA works on an embedded surface (in-plane normals).
        assert!(two_point(&surface, &[isotropic(1.0)]).is_ok());
    }
}
