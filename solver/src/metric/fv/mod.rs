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

mod mimetic;

pub use mimetic::{flux_mass, mimetic_hybrid, FluxMass, HybridLayout};

use super::{CellTensors, MetricError, Tensor};
use crate::operator::BlockMetric;
use hasse_complex::Complex;
use rayon::prelude::*;

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
    super::require_convex(complex, METHOD)?;
    let tensors = tensors.checked(complex.cell_count(n), complex.embedding_dim())?;
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
    super::require_convex(complex, METHOD)?;
    let d = complex.embedding_dim();
    let cells = complex.cell_count(n);
    let tensors = tensors.checked(cells, d)?;
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

/// Largest angle (radians) between the line joining two cell points and
/// the normal of their common face that [`non_orthogonality`] accepts.
///
/// On a K-orthogonal mesh (boxes with centroids, Voronoi cells with their
/// sites, well-centred triangles with their circumcentres) the angle is
/// zero and the computed one is rounding, below 1e-13 for unit-sized
/// meshes with up to 10⁶ cells per side. At an angle θ the two-point flux
/// of a linear u misses the tangential part of ∇u by a relative tan θ,
/// and that error does not shrink with h: it sets a floor under the
/// solution's error. Above 1e-6 it is geometry, and it is as large as the
/// O(h²) error of the consistent method at h = 10⁻³ (the finest shipped
/// case, 10⁶ cells), so from there on a user loses accuracy.
pub const NON_ORTHOGONALITY_TOLERANCE: f64 = 1e-6;

/// The face where the two-point flux is farthest from orthogonal (see
/// [`non_orthogonality`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceAngle {
    /// The (n−1)-cell.
    pub face: usize,
    /// Its centroid (the midpoint of an edge).
    pub midpoint: Vec<f64>,
    /// The angle in radians between the cell-point line and the normal.
    pub angle: f64,
}

/// The worst non-orthogonality of the two-point flux over the faces: for
/// an interior face F between K and L the angle between p_L − p_K and the
/// normal n_F, for a boundary face of K the angle between x_F − p_K and
/// n_F (x_F the face centroid, where the Dirichlet ghost value sits).
/// `points` are the cell points (stride d; `None`: the centroids). With
/// given points a boundary face's ghost sits at the foot of the normal
/// through p_K (see [`two_point_at`]), orthogonal by construction, so only
/// interior faces are measured.
///
/// An angle over 90° means the two points are in the wrong order across
/// the face. On an embedded surface (n = 2 < d = 3) the angle is measured
/// in the plane normal to the edge, so the bend between two cells does not
/// count; curves (n = 1) are always orthogonal. `None` when no face has
/// two cells or a boundary ghost to measure.
///
/// ```
/// use hasse_complex::generate::{kuhn, rectangle, uniform_axis};
/// use hasse_solver::metric::fv;
/// let squares = rectangle(4, 4, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// assert!(fv::non_orthogonality(&squares, None).unwrap().unwrap().angle < 1e-14);
/// // Right triangles with centroids: the leg between two of them is off
/// // by atan(1/2) (centroids (2/3, 1/3) and (4/3, 2/3) across x = 1).
/// let x = uniform_axis(4, 0.0, 1.0).unwrap();
/// let worst = fv::non_orthogonality(&kuhn(&[x.clone(), x]).unwrap(), None).unwrap().unwrap();
/// assert!((worst.angle - 0.5f64.atan()).abs() < 1e-12);
/// ```
pub fn non_orthogonality(
    complex: &Complex,
    points: Option<&[f64]>,
) -> Result<Option<FaceAngle>, MetricError> {
    const METHOD: &str = "two-point flux (TPFA)";
    let n = check_dimension(complex, METHOD)?;
    super::require_convex(complex, METHOD)?;
    let d = complex.embedding_dim();
    let cells = complex.cell_count(n);
    let given = points.is_some();
    let points = points.unwrap_or_else(|| complex.centroid(n));
    if points.len() != cells * d {
        return Err(MetricError::UnsupportedMesh {
            method: METHOD,
            needs: "one point per top cell",
            detail: format!(
                "{} coordinates given for {cells} top cells in R^{d}",
                points.len()
            ),
        });
    }
    let boundary = complex.try_boundary(n)?;
    let normals = complex.normal();
    let point = |c: usize| &points[c * d..(c + 1) * d];
    let angle_of = |face: usize| -> Option<f64> {
        let row = boundary.outer_view(face)?;
        let normal = &normals[face * d..(face + 1) * d];
        // The vector from the cell on the inner side of n_F outwards.
        let vector: Vec<f64> = match (row.nnz(), row.iter().next()) {
            (2, _) => {
                let mut out = None;
                let mut into = None;
                for (c, &sign) in row.iter() {
                    if sign > 0 {
                        out = Some(c);
                    } else {
                        into = Some(c);
                    }
                }
                let (k, l) = (out?, into?);
                point(l).iter().zip(point(k)).map(|(a, b)| a - b).collect()
            }
            (1, Some((c, &sign))) if !given => complex
                .centroid_of(n - 1, face)
                .iter()
                .zip(point(c))
                .map(|(f, p)| f64::from(sign) * (f - p))
                .collect(),
            _ => return None,
        };
        Some(angle_to_normal(complex, face, &vector, normal, n, d))
    };
    let mut worst: Option<FaceAngle> = None;
    for face in 0..boundary.rows() {
        let Some(angle) = angle_of(face) else {
            continue;
        };
        if worst.as_ref().is_none_or(|w| angle > w.angle) {
            worst = Some(FaceAngle {
                face,
                midpoint: complex.centroid_of(n - 1, face).to_vec(),
                angle,
            });
        }
    }
    Ok(worst)
}

/// The angle between `vector` and the unit `normal` of (n−1)-cell `face`:
/// the tangential part is the component along the face's own span (its
/// edge direction on a surface), the normal part the rest, signed by the
/// side of n_F it lies on.
fn angle_to_normal(
    complex: &Complex,
    face: usize,
    vector: &[f64],
    normal: &[f64],
    n: usize,
    d: usize,
) -> f64 {
    let along: f64 = vector.iter().zip(normal).map(|(v, m)| v * m).sum();
    let length2: f64 = vector.iter().map(|v| v * v).sum();
    let tangential2 = if n == d {
        vector
            .iter()
            .zip(normal)
            .map(|(v, m)| (v - along * m).powi(2))
            .sum::<f64>()
    } else if n == 2 {
        // The face is an edge: its tangent spans the face.
        let ends = complex.cell_vertices(1, face);
        let vertices = complex.vertices();
        let (a, b) = (
            vertices.point(ends[0]),
            vertices.point(ends[ends.len() - 1]),
        );
        let t: Vec<f64> = b.iter().zip(a).map(|(x, y)| x - y).collect();
        let t2: f64 = t.iter().map(|x| x * x).sum();
        if t2 > 0.0 {
            vector
                .iter()
                .zip(&t)
                .map(|(v, x)| v * x)
                .sum::<f64>()
                .powi(2)
                / t2
        } else {
            0.0
        }
    } else {
        // A point face of a curve has no tangential direction.
        0.0
    };
    let normal_part = (length2 - tangential2).max(0.0).sqrt();
    tangential2.sqrt().atan2(if along < 0.0 {
        -normal_part
    } else {
        normal_part
    })
}

/// (x_F − p)·n_{K,F}: the distance from `point` to the face plane, positive
/// when the point is on the inner side of the face for the cell with
/// incidence `sign` (n_{K,F} = sign · n_F points out of that cell).
pub(crate) fn signed_distance(x_face: &[f64], point: &[f64], normal: &[f64], sign: i8) -> f64 {
    f64::from(sign)
        * x_face
            .iter()
            .zip(point)
            .zip(normal)
            .map(|((f, p), n)| (f - p) * n)
            .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::isotropic;
    use hasse_complex::generate::rectangle;
    use hasse_complex::{TopCells, Vertices};

    #[test]
    fn two_point_on_one_square_has_boundary_sigma_two() {
        let k = rectangle(1, 1, [0.0, 1.0], [0.0, 1.0]).unwrap();
        let omega = two_point(&k, &[isotropic(3.0)]).unwrap();
        let dense = omega.to_dense();
        for (f, row) in dense.iter().enumerate() {
            assert!((row[f] - 6.0).abs() < 1e-14);
        }
    }

    /// The parallelogram of `n × n` congruent acute triangles with sides
    /// 1, √0.89, √0.89 (lattice vectors (1, 0) and (½, 0.8)): well
    /// centred, every circumcentre strictly inside its triangle and away
    /// from its centroid.
    fn acute_lattice(n: usize) -> Complex {
        let mut points = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                points.push([i as f64 + 0.5 * j as f64, 0.8 * j as f64]);
            }
        }
        // Built explicitly: the sides' points are collinear only up to
        // rounding, and a Delaunay of them may add slivers along the sides.
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                triangles.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let vertices = Vertices::from_points(&points).unwrap();
        Complex::build(vertices, TopCells::simplices(triangles)).unwrap()
    }

    #[test]
    fn non_orthogonality_is_zero_on_orthogonal_meshes() {
        // Issue 30, item 8: silent where the two-point flux is consistent.
        // The angles are rounding: cell points of unit-sized cells carry
        // errors of about 1e-16 over distances of about 0.5, so 1e-12
        // bounds them with room (and is far below
        // NON_ORTHOGONALITY_TOLERANCE).
        let graded = hasse_complex::generate::graded_axis(6, 0.0, 1.0, 1.3).unwrap();
        let even = hasse_complex::generate::uniform_axis(4, -1.0, 2.0).unwrap();
        for (i, k) in [
            rectangle(8, 8, [0.0, 1.0], [0.0, 1.0]).unwrap(),
            hasse_complex::generate::grid(&[graded.clone(), even.clone()]).unwrap(),
            hasse_complex::generate::grid(&[graded, even.clone(), even]).unwrap(),
        ]
        .iter()
        .enumerate()
        {
            let worst = non_orthogonality(k, None).unwrap().unwrap();
            assert!(worst.angle < 1e-12, "grid {i}: {worst:?}");
        }
        // Well-centred triangles with their circumcentres: the line between
        // two circumcentres is the perpendicular bisector of their edge.
        let k = acute_lattice(6);
        let c = k.circumcentre(2).unwrap().to_vec();
        let worst = non_orthogonality(&k, Some(&c)).unwrap().unwrap();
        assert!(worst.angle < 1e-12, "{worst:?}");
        // The same mesh with its centroids is not orthogonal.
        let worst = non_orthogonality(&k, None).unwrap().unwrap();
        assert!(worst.angle > NON_ORTHOGONALITY_TOLERANCE, "{worst:?}");
    }

    #[test]
    fn non_orthogonality_of_kuhn_triangles_is_the_hand_computed_angle() {
        // Centroid (2/3, 1/3)h of the lower triangle of a square; the upper
        // triangle of the square to its right has centroid (4/3, 2/3)h: the
        // line between them, (2/3, 1/3)h, is atan(1/2) off the normal (1, 0)
        // of their common leg x = h. A boundary leg, e.g. y = 0 with
        // midpoint (½, 0)h, sees the centroid at (1/6, 1/3)h from its
        // midpoint: atan(1/2) again. The diagonals are orthogonal. The
        // angle comes from an atan2 of rounded O(h) lengths: 1e-12.
        let x = hasse_complex::generate::uniform_axis(4, 0.0, 1.0).unwrap();
        let k = hasse_complex::generate::kuhn(&[x.clone(), x]).unwrap();
        let worst = non_orthogonality(&k, None).unwrap().unwrap();
        approx::assert_abs_diff_eq!(worst.angle, 0.5f64.atan(), epsilon = 1e-12);
        assert_eq!(worst.midpoint, k.centroid_of(1, worst.face));
        // A leg, not a diagonal: its ends share one coordinate.
        let ends = k.cell_vertices(1, worst.face);
        let (a, b) = (k.vertices().point(ends[0]), k.vertices().point(ends[1]));
        assert!(a[0] == b[0] || a[1] == b[1], "{a:?} {b:?}");
        // With given points the boundary ghosts sit at the feet of the
        // normals (orthogonal by construction): only interior faces count,
        // and they have the same worst angle.
        let centroids = k.centroid(2).to_vec();
        let interior = non_orthogonality(&k, Some(&centroids)).unwrap().unwrap();
        approx::assert_abs_diff_eq!(interior.angle, 0.5f64.atan(), epsilon = 1e-12);
        assert_eq!(k.boundary(2).outer_view(interior.face).unwrap().nnz(), 2);
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
