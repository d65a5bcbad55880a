//! SPLIT: cut convex cells by hyperplanes h·x = b (thesis §4.5, after
//! Bajaj–Pascucci), with the induced chain map ζ.
//!
//! Vertices are classified by the sign of their signed distance to the
//! plane; a cell is cut exactly when it has vertices strictly on both sides
//! (the thesis's test |c_p| ≠ f_p on the classification chains, see
//! [`classification_step`]). Cut edges get a new vertex at the
//! intersection, then cut polygons a new edge between their two crossing
//! vertices, then cut polyhedra a new polygon through their crossing edges.
//! Every piece of a convex cell cut by a plane is convex, so the result can
//! be split again.
//!
//! # Tolerance
//!
//! A vertex v counts as lying on the plane when its distance to it is at
//! most `snap × ℓ_v`, ℓ_v the shortest edge at v (a local cell size that
//! every cell around v shares, so all of them classify v the same way). A
//! plane through existing vertices or along existing faces therefore reuses
//! them instead of creating zero-length pieces, and no new vertex lands
//! closer than `snap × ℓ_v` to an existing one: that is the sliver bound.
//! `snap = 0` asks for exact classification (slivers allowed). In 3D a
//! snapped vertex is off the plane by at most that distance, so a cut
//! polygon may be non-planar by as much; measures stay additive (the
//! geometry module measures non-planar faces consistently on both sides).
//!
//! # Numbering and ζ
//!
//! A split cell keeps its index for the piece on the negative side
//! (h·x < b); the positive pieces are appended, then the new cut cells. So
//! ζ_p = [I ± …; …] and an unsplit cell maps to itself. The orientation
//! conventions of [`Complex`] hold in the result (it equals
//! `Complex::from_lar` of its own LAR), so ζ carries the sign of each piece
//! relative to its parent.
//!
//! ```
//! use hasse_complex::generate::rectangle;
//! use hasse_complex::split::{split, Hyperplane, SplitOptions};
//! let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
//! // Cut both squares by x = 0.5 + 0.25 y (only the left one is crossed).
//! let plane = Hyperplane::new(&[1.0, -0.25], 0.5).unwrap();
//! let (fine, r) = split(&k, &plane, None, SplitOptions::default()).unwrap();
//! assert_eq!(fine.cell_counts(), vec![8, 10, 3]);
//! assert_eq!(fine.euler_characteristic(), k.euler_characteristic());
//! // ∂ζ = ζ∂ on the 2-cells.
//! let left = &**fine.boundary(2) * r.zeta(2);
//! let right = r.zeta(1) * &**k.boundary(2);
//! assert_eq!(left.to_dense(), right.to_dense());
//! ```

mod cut;
pub(crate) mod makes;
mod round;
mod transfer;

pub use makes::{split_by_makes, MadeSplit};
pub use transfer::Refinement;

use crate::complex::Complex;
use crate::error::SplitError;
use sprs::CsMat;
use std::collections::HashMap;

/// An oriented hyperplane h·x = b in R^d; its positive side is h·x > b.
///
/// ```
/// use hasse_complex::split::Hyperplane;
/// let h = Hyperplane::new(&[0.0, 2.0], 1.0).unwrap(); // y = 0.5
/// assert_eq!(h.distance(&[3.0, 1.5]), 1.0);
/// assert!(Hyperplane::new(&[0.0, 0.0], 1.0).is_err());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Hyperplane {
    /// Unit normal (padded to three components).
    normal: [f64; 3],
    dim: usize,
    /// b / |h|.
    offset: f64,
}

impl Hyperplane {
    /// The plane h·x = b; `h` must be finite and non-zero, `b` finite.
    pub fn new(h: &[f64], b: f64) -> Result<Self, SplitError> {
        let norm = h.iter().map(|x| x * x).sum::<f64>().sqrt();
        if h.is_empty() || h.len() > 3 || !norm.is_finite() || norm == 0.0 {
            return Err(SplitError::BadNormal(h.to_vec()));
        }
        if !b.is_finite() {
            return Err(SplitError::BadOffset(b));
        }
        let mut normal = [0.0; 3];
        for (slot, x) in normal.iter_mut().zip(h) {
            *slot = x / norm;
        }
        Ok(Self {
            normal,
            dim: h.len(),
            offset: b / norm,
        })
    }

    /// The plane through `point` with normal `normal`.
    ///
    /// ```
    /// use hasse_complex::split::Hyperplane;
    /// let h = Hyperplane::through(&[1.0, 2.0], &[0.0, 1.0]).unwrap();
    /// assert_eq!(h.distance(&[7.0, 2.0]), 0.0);
    /// ```
    pub fn through(point: &[f64], normal: &[f64]) -> Result<Self, SplitError> {
        if point.len() != normal.len() {
            return Err(SplitError::PlaneDimension {
                expected: normal.len(),
                found: point.len(),
            });
        }
        let b: f64 = point.iter().zip(normal).map(|(x, h)| x * h).sum();
        Self::new(normal, b)
    }

    /// The plane x_axis = value.
    ///
    /// ```
    /// use hasse_complex::split::Hyperplane;
    /// let h = Hyperplane::axis(2, 1, 0.25).unwrap(); // y = 0.25 in R²
    /// assert_eq!(h.distance(&[9.0, 1.25]), 1.0);
    /// ```
    pub fn axis(dim: usize, axis: usize, value: f64) -> Result<Self, SplitError> {
        if axis >= dim || dim > 3 {
            return Err(SplitError::Invalid(format!(
                "axis {axis} does not exist in R^{dim}"
            )));
        }
        let mut h = vec![0.0; dim];
        h[axis] = 1.0;
        Self::new(&h, value)
    }

    /// Dimension of the space the plane lives in.
    ///
    /// ```
    /// use hasse_complex::split::Hyperplane;
    /// assert_eq!(Hyperplane::new(&[0.0, 0.0, 1.0], 2.0).unwrap().dim(), 3);
    /// ```
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Unit normal (h / |h|).
    ///
    /// ```
    /// use hasse_complex::split::Hyperplane;
    /// assert_eq!(Hyperplane::new(&[3.0, 4.0], 1.0).unwrap().normal(), &[0.6, 0.8]);
    /// ```
    pub fn normal(&self) -> &[f64] {
        &self.normal[..self.dim]
    }

    /// Signed distance (h·x − b)/|h| of a point (positive on the h side).
    ///
    /// ```
    /// use hasse_complex::split::Hyperplane;
    /// let h = Hyperplane::new(&[3.0, 4.0], 5.0).unwrap();
    /// assert_eq!(h.distance(&[0.0, 0.0]), -1.0);
    /// ```
    pub fn distance(&self, x: &[f64]) -> f64 {
        let mut s = -self.offset;
        for (h, x) in self.normal.iter().zip(x) {
            s += h * x;
        }
        s
    }

    fn key(&self) -> [u64; 4] {
        [
            self.normal[0].to_bits(),
            self.normal[1].to_bits(),
            self.normal[2].to_bits(),
            self.offset.to_bits(),
        ]
    }
}

/// Options of a SPLIT.
///
/// ```
/// use hasse_complex::split::SplitOptions;
/// let exact = SplitOptions { snap: 0.0 };
/// assert!(SplitOptions::default().snap > exact.snap);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitOptions {
    /// Snap tolerance relative to the local cell size (shortest edge at a
    /// vertex): vertices this close to the plane count as on it, and no new
    /// vertex is created closer than this to an existing one. In [0, 0.25).
    pub snap: f64,
}

impl Default for SplitOptions {
    /// `snap = 1e-6`: planes through vertices or along faces are recognised
    /// even when their coordinates went through arithmetic, while any cut
    /// that is meant to produce a distinct piece does.
    fn default() -> Self {
        Self { snap: 1e-6 }
    }
}

/// Split top cells of `complex` by one hyperplane: `cells` restricts the cut
/// to the given top cells (their faces are cut too, and neighbours that
/// share a cut face receive the new vertex), `None` cuts every top cell the
/// plane crosses. Returns the refined complex and the refinement (ζ and
/// the nodal interpolation).
///
/// Errors: a complex that does not fill its space (n ≠ d or n = 1), a plane
/// of the wrong dimension, a cell id out of range, a bad tolerance, or a
/// cell the tolerance makes ambiguous.
///
/// ```
/// use hasse_complex::generate::{kuhn, uniform_axis};
/// use hasse_complex::split::{split, Hyperplane, SplitOptions};
/// let x = uniform_axis(2, 0.0, 1.0).unwrap();
/// let k = kuhn(&[x.clone(), x]).unwrap();
/// // The line x = 0.5 runs along grid edges: nothing is cut.
/// let plane = Hyperplane::axis(2, 0, 0.5).unwrap();
/// let (same, _) = split(&k, &plane, None, SplitOptions::default()).unwrap();
/// assert_eq!(same.cell_counts(), k.cell_counts());
/// // x = 0.3 crosses every triangle of the left column.
/// let plane = Hyperplane::axis(2, 0, 0.3).unwrap();
/// let (fine, _) = split(&k, &plane, None, SplitOptions::default()).unwrap();
/// assert_eq!(fine.cell_count(2), k.cell_count(2) + 4);
/// ```
pub fn split(
    complex: &Complex,
    plane: &Hyperplane,
    cells: Option<&[usize]>,
    options: SplitOptions,
) -> Result<(Complex, Refinement), SplitError> {
    let n = complex.dim();
    let cuts: Vec<(usize, Hyperplane)> = match cells {
        Some(cells) => cells.iter().map(|&c| (c, plane.clone())).collect(),
        None => (0..complex.cell_count(n))
            .map(|c| (c, plane.clone()))
            .collect(),
    };
    split_cells(complex, &cuts, options)
}

/// Split each listed top cell by its own hyperplane (e.g. one plane per
/// cell through its centroid). A lower cell shared by two cells whose
/// planes would both cut it is cut by the first; the second cell is cut in
/// a later pass, after it has received the first cut's vertex, so the
/// result never depends on a lower cell being cut twice at once. Passes are
/// composed into one refinement.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::split::{split_cells, Hyperplane, SplitOptions};
/// let k = rectangle(2, 2, [0.0, 1.0], [0.0, 1.0]).unwrap();
/// // Each square cut vertically through its own centre.
/// let cuts: Vec<_> = (0..4)
///     .map(|c| (c, Hyperplane::through(k.centroid_of(2, c), &[1.0, 0.0]).unwrap()))
///     .collect();
/// let (fine, r) = split_cells(&k, &cuts, Default::default()).unwrap();
/// assert_eq!(fine.cell_count(2), 8);
/// assert_eq!(r.zeta(2).nnz(), 8);
/// ```
pub fn split_cells(
    complex: &Complex,
    cuts: &[(usize, Hyperplane)],
    options: SplitOptions,
) -> Result<(Complex, Refinement), SplitError> {
    let (n, d) = (complex.dim(), complex.embedding_dim());
    if n != d || n < 2 {
        return Err(SplitError::Unsupported {
            dim: n,
            embedding: d,
        });
    }
    if !(options.snap.is_finite() && (0.0..0.25).contains(&options.snap)) {
        return Err(SplitError::BadTolerance(options.snap));
    }
    let count = complex.cell_count(n);
    let mut planes: Vec<Hyperplane> = Vec::new();
    let mut ids: HashMap<[u64; 4], u32> = HashMap::new();
    let mut seen = vec![false; count];
    let mut pending: Vec<(usize, u32)> = Vec::with_capacity(cuts.len());
    for (c, plane) in cuts {
        if *c >= count {
            return Err(SplitError::CellOutOfRange {
                p: n,
                cell: *c,
                count,
            });
        }
        if plane.dim != d {
            return Err(SplitError::PlaneDimension {
                expected: d,
                found: plane.dim,
            });
        }
        if std::mem::replace(&mut seen[*c], true) {
            return Err(SplitError::Invalid(format!(
                "top cell {c} is listed twice; give one plane per cell"
            )));
        }
        let id = *ids.entry(plane.key()).or_insert_with(|| {
            planes.push(plane.clone());
            (planes.len() - 1) as u32
        });
        pending.push((*c, id));
    }
    let mut current = round::round(complex, &pending, &planes, options.snap)?;
    while !current.deferred.is_empty() {
        let next = round::round(&current.complex, &current.deferred, &planes, options.snap)?;
        current = round::Round {
            refinement: current.refinement.then(&next.refinement)?,
            complex: next.complex,
            deferred: next.deferred,
        };
    }
    Ok((current.complex, current.refinement))
}

/// One step of the thesis's classification chains: from the classes
/// c_{p−1} ∈ {−1, 0, 1} of the (p−1)-cells, c_p = |δ_{p−1}| c_{p−1} and
/// f_p = |δ_{p−1}| |c_{p−1}|, with δ_{p−1} = ∂_pᵀ. A p-cell straddles the
/// plane exactly when |c_p| ≠ f_p … once its straddling faces have been
/// split; the re-classification sgn(c_p) then feeds the next dimension.
///
/// ```
/// use hasse_complex::split::classification_step;
/// use sprs::CsMat;
/// // Edge v0 → v1 with v0 below and v1 above the plane.
/// let d1 = CsMat::new((2, 1), vec![0, 1, 2], vec![0, 0], vec![-1i8, 1]);
/// let (c, f) = classification_step(&d1, &[-1, 1]).unwrap();
/// assert_eq!((c, f), (vec![0], vec![2])); // |0| ≠ 2: the edge is cut
/// ```
pub fn classification_step(
    boundary: &CsMat<i8>,
    classes: &[i8],
) -> Result<(Vec<i32>, Vec<i32>), SplitError> {
    if classes.len() != boundary.rows() {
        return Err(SplitError::LengthMismatch {
            what: "classification chain",
            p: 0,
            expected: boundary.rows(),
            found: classes.len(),
        });
    }
    let mut c = vec![0i32; boundary.cols()];
    let mut f = vec![0i32; boundary.cols()];
    for (&value, (i, j)) in boundary.iter() {
        if value != 0 {
            c[j] += i32::from(classes[i]);
            f[j] += i32::from(classes[i]).abs();
        }
    }
    Ok((c, f))
}

/// Vertex classes c_0 = sgn_ε(h·x − b) of a complex with the snap rule of
/// this module (ε = `snap` × shortest edge at the vertex).
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_complex::split::{vertex_classes, Hyperplane};
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// let c0 = vertex_classes(&k, &Hyperplane::axis(2, 0, 1.0).unwrap(), 1e-6).unwrap();
/// assert_eq!(c0, vec![-1, 0, 1, -1, 0, 1]);
/// ```
pub fn vertex_classes(
    complex: &Complex,
    plane: &Hyperplane,
    snap: f64,
) -> Result<Vec<i8>, SplitError> {
    if plane.dim != complex.embedding_dim() {
        return Err(SplitError::PlaneDimension {
            expected: complex.embedding_dim(),
            found: plane.dim,
        });
    }
    if !(snap.is_finite() && (0.0..0.25).contains(&snap)) {
        return Err(SplitError::BadTolerance(snap));
    }
    let k0 = complex.cell_count(0);
    let mut shortest = vec![f64::INFINITY; k0];
    if complex.dim() >= 1 {
        for e in 0..complex.cell_count(1) {
            let ends = complex.cell_vertices(1, e);
            let (a, b) = (
                complex.vertices().point(ends[0]),
                complex.vertices().point(ends[1]),
            );
            let len = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
                .sqrt();
            shortest[ends[0]] = shortest[ends[0]].min(len);
            shortest[ends[1]] = shortest[ends[1]].min(len);
        }
    }
    Ok((0..k0)
        .map(|v| {
            let dist = plane.distance(complex.vertices().point(v));
            let eps = if shortest[v].is_finite() {
                snap * shortest[v]
            } else {
                0.0
            };
            if dist.abs() <= eps {
                0
            } else if dist > 0.0 {
                1
            } else {
                -1
            }
        })
        .collect())
}
