//! The dual complex (circumcentric and barycentric) and its measures.
//!
//! The dual of a primal p-cell σ in an n-complex is an (n−p)-cell ⋆σ. Its
//! signed measure follows Hirani (2003) and VanderZee et al. (the signed
//! circumcentric dual used by PyDEC): sum over every top cell τ ⊇ σ and
//! every flag σ = σ_p < σ_{p+1} < … < σ_n = τ (each σ_k a facet of
//! σ_{k+1}) of
//!
//! ```text
//!     s(σ_p, σ_{p+1}) ⋯ s(σ_{n−1}, σ_n) · vol_{n−p}(c(σ_p), …, c(σ_n))
//! ```
//!
//! with c the circumcentre ([`DualKind::Circumcentric`]) or the centroid
//! ([`DualKind::Barycentric`]) of a cell, vol_m the m-volume of the simplex
//! spanned by m+1 points, and s(σ_k, σ_{k+1}) = +1 when c(σ_{k+1}) lies on
//! the same side of σ_k (inside the span of σ_{k+1}) as σ_{k+1} itself, −1
//! on the other side and 0 on σ_k. Barycentric duals have every s = +1. On
//! a non-well-centred mesh (an obtuse triangle) circumcentric dual measures
//! can be negative; the signed sums still add up, e.g. Σ_v |⋆v| = |K|.
//!
//! At the boundary of the domain the dual cells are the truncated ones this
//! formula gives: only the flags inside the complex count, and no extra
//! pieces lying on the boundary are added (the dual of a boundary edge of
//! a triangulation is the half-edge from its midpoint to the circumcentre).

use crate::complex::Complex;
use crate::error::{ComplexError, Result};
use crate::frame::{self, Point};
use crate::geometry::{padded, row};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Which point of each primal cell the dual complex is built on.
///
/// ```
/// use hasse_complex::{dual::DualKind, Complex, TopCells, Vertices};
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
/// let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
/// // The dual vertex of a right triangle sits on its hypotenuse (circumcentric)
/// // or at its centroid (barycentric).
/// assert_eq!(k.dual_vertices(DualKind::Circumcentric).unwrap(), &[0.5, 0.5]);
/// let c = k.dual_vertices(DualKind::Barycentric).unwrap();
/// assert!((c[0] - 1.0 / 3.0).abs() < 1e-15 && (c[1] - 1.0 / 3.0).abs() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DualKind {
    /// Circumcentres of the simplices (needs a simplicial complex); the
    /// dual cells are orthogonal to the primal ones.
    Circumcentric,
    /// Centroids of the cells (any convex cells); every dual measure is
    /// positive.
    Barycentric,
}

impl DualKind {
    fn index(self) -> usize {
        match self {
            DualKind::Circumcentric => 0,
            DualKind::Barycentric => 1,
        }
    }
}

/// Lazily computed dual measures.
#[derive(Clone, Debug, Default)]
pub(crate) struct DualCache {
    /// Indexed by [`DualKind::index`] and primal dimension p.
    measures: [[OnceLock<Vec<f64>>; 4]; 2],
}

impl Complex {
    /// Signed measure |⋆σ| of the dual (n−p)-cell of every primal p-cell σ
    /// (1 for p = n: dual vertices). See the [module documentation](self)
    /// for the definition and the treatment of the domain boundary.
    ///
    /// Circumcentric duals need every cell to be a simplex; the error names
    /// the first one that is not.
    ///
    /// ```
    /// use hasse_complex::{dual::DualKind, Complex, TopCells, Vertices};
    /// // Unit square split along the diagonal 1–2.
    /// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::simplices([[0, 1, 2], [1, 3, 2]])).unwrap();
    /// let star0 = k.dual_measure(DualKind::Circumcentric, 0).unwrap();
    /// // The dual cells of the vertices tile the square.
    /// assert!((star0.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    /// // Both circumcentres are the square's centre, so the diagonal's dual is a point.
    /// let diagonal = k.find_cell(1, &[1, 2]).unwrap();
    /// assert!(k.dual_measure(DualKind::Circumcentric, 1).unwrap()[diagonal].abs() < 1e-15);
    /// ```
    pub fn dual_measure(&self, kind: DualKind, p: usize) -> Result<&[f64]> {
        let n = self.dim();
        if p > n {
            return Err(ComplexError::DimensionOutOfRange { p, dim: n });
        }
        let slot = &self.dual.measures[kind.index()][p];
        if let Some(m) = slot.get() {
            return Ok(m);
        }
        let centres = self.dual_centres(kind)?;
        Ok(slot.get_or_init(|| {
            let walker = FlagWalker {
                complex: self,
                centres,
                p,
                signed: kind == DualKind::Circumcentric,
            };
            if p == n {
                return vec![1.0; self.cell_count(n)];
            }
            (0..self.cell_count(p))
                .into_par_iter()
                .map(|sigma| {
                    let mut chain = [[0.0; 3]; 4];
                    walker.walk(p, sigma, 1.0, &mut chain)
                })
                .collect()
        }))
    }

    /// The dual vertices, one per top cell (stride d): circumcentres
    /// (circumcentric dual) or centroids (barycentric dual).
    pub fn dual_vertices(&self, kind: DualKind) -> Result<&[f64]> {
        match kind {
            DualKind::Circumcentric => self.circumcentre(self.dim()),
            DualKind::Barycentric => Ok(self.centroid(self.dim())),
        }
    }

    /// Diagonal of the Hodge star ⋆_p: |⋆σ| / |σ| for every p-cell σ,
    /// 0 ≤ p ≤ n.
    ///
    /// ```
    /// use hasse_complex::{dual::DualKind, Complex, TopCells, Vertices};
    /// let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [2.0, 2.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    /// // ⋆₂ of a cell is 1/area; ⋆₀ of a corner is its quarter of the square.
    /// assert_eq!(k.hodge_star(DualKind::Barycentric, 2).unwrap(), vec![0.25]);
    /// assert_eq!(k.hodge_star(DualKind::Barycentric, 0).unwrap(), vec![1.0; 4]);
    /// ```
    pub fn hodge_star(&self, kind: DualKind, p: usize) -> Result<Vec<f64>> {
        let dual = self.dual_measure(kind, p)?;
        Ok(dual
            .iter()
            .zip(self.measure(p))
            .map(|(star, primal)| star / primal)
            .collect())
    }

    /// The point c(σ) of every cell, per dimension 0..=n (stride d).
    fn dual_centres(&self, kind: DualKind) -> Result<[&[f64]; 4]> {
        let n = self.dim();
        let mut centres: [&[f64]; 4] = [&[]; 4];
        match kind {
            DualKind::Circumcentric => {
                // The top level first, so the error names a top cell.
                for k in (0..=n).rev() {
                    centres[k] = self.circumcentre(k).map_err(|e| {
                        ComplexError::Invalid(format!(
                            "the circumcentric dual needs a simplicial complex: {e}; use the barycentric dual for other cells"
                        ))
                    })?;
                }
            }
            DualKind::Barycentric => {
                for (k, c) in centres.iter_mut().enumerate().take(n + 1) {
                    *c = self.centroid(k);
                }
            }
        }
        Ok(centres)
    }
}

/// Walks the flags upward from a primal cell to every top cell above it.
struct FlagWalker<'a> {
    complex: &'a Complex,
    centres: [&'a [f64]; 4],
    p: usize,
    signed: bool,
}

impl FlagWalker<'_> {
    fn centre(&self, k: usize, i: usize) -> Point {
        let d = self.complex.embedding_dim();
        padded(&self.centres[k][i * d..(i + 1) * d])
    }

    /// Signed measure contributed by every flag that continues the chain
    /// c(σ_p), …, c(σ_{k−1}) (held in `chain`) through k-cell `cell`.
    fn walk(&self, k: usize, cell: usize, sign: f64, chain: &mut [Point; 4]) -> f64 {
        let n = self.complex.dim();
        chain[k - self.p] = self.centre(k, cell);
        if k == n {
            // On a flat torus the centres of a flag are seen from the
            // first one's image (they all lie in or near one top cell).
            let points = &mut chain[..=n - self.p];
            crate::frame::unwrap_cell(self.complex.vertices(), points);
            return sign * simplex_volume(points);
        }
        let (cofaces, _) = row(self.complex.boundary(k + 1), cell);
        let mut total = 0.0;
        for &upper in cofaces {
            let s = if self.signed {
                self.side(k, cell, upper)
            } else {
                1.0
            };
            if s != 0.0 {
                total += self.walk(k + 1, upper, sign * s, chain);
            }
        }
        total
    }

    /// s(σ, τ) for a simplex σ (a k-cell) that is a facet of the simplex τ:
    /// +1 when τ's centre lies on τ's side of σ, −1 beyond σ, 0 on it.
    fn side(&self, k: usize, sigma: usize, tau: usize) -> f64 {
        let complex = self.complex;
        let lower = complex.cell_vertices(k, sigma);
        let upper = complex.cell_vertices(k + 1, tau);
        // The vertex of τ opposite σ is on τ's side of σ.
        let Some(&opposite) = upper.iter().find(|v| lower.binary_search(v).is_err()) else {
            return 1.0;
        };
        let vertices = complex.vertices();
        let first = complex.point3(lower[0]);
        let origin = Vector3::from(first);
        let at = |x: Point| Vector3::from(vertices.nearest(&x, &first));
        let mut basis = [Vector3::zeros(); 2];
        let mut found = 0;
        for &v in &lower[1..] {
            let w = reject(at(complex.point3(v)) - origin, &basis[..found]);
            let len = w.norm();
            if len > 0.0 && found < 2 {
                basis[found] = Vector3::new(w[0] / len, w[1] / len, w[2] / len);
                found += 1;
            }
        }
        let inward = reject(at(complex.point3(opposite)) - origin, &basis[..found]);
        let centre = reject(at(self.centre(k + 1, tau)) - origin, &basis[..found]);
        // The centre is on σ when its distance from σ's span is at rounding level.
        if centre.norm() <= 1e-12 * inward.norm() {
            return 0.0;
        }
        centre.dot(&inward).signum()
    }
}

/// `v` minus its components along the orthonormal `basis` (two passes).
fn reject(v: Vector3<f64>, basis: &[Vector3<f64>]) -> Vector3<f64> {
    let mut w = v;
    for _ in 0..2 {
        for b in basis {
            let c = w.dot(b);
            w = Vector3::new(w[0] - c * b[0], w[1] - c * b[1], w[2] - c * b[2]);
        }
    }
    w
}

/// m-volume of the simplex spanned by m+1 points (m ≤ 3), sqrt(det Gram)/m!.
fn simplex_volume(points: &[Point]) -> f64 {
    let edge = |i: usize| Vector3::from(points[i]) - Vector3::from(points[0]);
    match points.len() {
        0 | 1 => 1.0,
        2 => edge(1).norm(),
        3 => 0.5 * edge(1).cross(&edge(2)).norm(),
        _ => frame::det(3, &[edge(1).into(), edge(2).into(), edge(3).into()]).abs() / 6.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{TopCells, Vertices};

    #[test]
    fn simplex_volumes_of_unit_simplices() {
        let o = [0.0; 3];
        let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        assert_eq!(simplex_volume(&[o]), 1.0);
        assert_eq!(simplex_volume(&[o, [3.0, 4.0, 0.0]]), 5.0);
        assert_eq!(simplex_volume(&[o, x, y]), 0.5);
        assert_eq!(simplex_volume(&[o, x, y, z]), 1.0 / 6.0);
    }

    #[test]
    fn obtuse_triangle_has_negative_dual_edge() {
        // Apex angle at vertex 2 is obtuse: the circumcentre lies below edge {0,1}.
        let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [1.0, 0.5]]).unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
        let e = k.find_cell(1, &[0, 1]).unwrap();
        let star = k.dual_measure(DualKind::Circumcentric, 1).unwrap();
        // Circumcentre (1, −0.75): signed half-dual −0.75.
        assert!((star[e] + 0.75).abs() < 1e-15, "{}", star[e]);
        assert!(k.dual_measure(DualKind::Circumcentric, 3).is_err());
    }

    #[test]
    fn circumcentric_dual_needs_simplices() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
        let err = k
            .dual_measure(DualKind::Circumcentric, 0)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("2-cell 0") && err.contains("barycentric"),
            "{err}"
        );
        assert!(k.dual_measure(DualKind::Barycentric, 0).is_ok());
    }
}
